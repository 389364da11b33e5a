// SPDX-License-Identifier: MIT
// Occluder synthesis by greedy box growth in the solid voxels, then sort and cut (after Andújar et al.,
// "Integrating Occlusion Culling and Levels of Detail through Hardly-Visible Sets", 2000, and the
// occluder-skin idea of the largest boxes of inner voxels). The algorithm is described in boxes.h.
//
// Speed: "is this layer all solid" is O(1) with a 3D summed-area table of the NON-solid voxels. Its sums
// are kept modulo 2^16 (2 bytes a voxel instead of 4): a box whose count is not 0 modulo 2^16 surely has
// a non-solid voxel, and a box of fewer than 2^16 voxels whose count is 0 modulo 2^16 is surely all
// solid. A larger box whose count is 0 modulo 2^16 is split in two along its longest axis and each half
// checked again, so the answer is exact (no hashing, no probability). Seeds are found by a scan in
// blocks of 64 voxels with stale upper bounds of the cube sizes they hold (two levels), so each seed size
// costs a scan of one byte per 4096 voxels; the cube sizes of covered voxels are set to 0. The scan, the
// clearing and the cut run on all threads around the growth in seed order (docs/ALGORITHMS.md#boxes).
#include "occluders/boxes.h"

#include "core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>

namespace pvs {

namespace {

constexpr uint64_t kWrap = uint64_t(1) << 16;            // the summed-area table's modulus
constexpr uint64_t kBlock = 64;                          // voxels per first-level block of the seed scan
constexpr uint64_t kParallelVoxels = uint64_t(1) << 21;  // smaller grids build their table, cubes and bounds
                                                         // on one thread
constexpr int kTileRows = 16;  // the seed cubes' wavefront runs over tiles of kTileRows^2 rows (y, z)

void validate(const BoxConfig& config) {
    if (config.max_boxes < 1) {
        throw bad_input(fmt::format("grow_boxes: --max-occluders must be >= 1 (got {})", config.max_boxes));
    }
    if (!(config.min_box_volume_m3 >= 0.0) || !std::isfinite(config.min_box_volume_m3)) {
        throw bad_input(fmt::format("grow_boxes: --min-occluder-volume must be >= 0 m3 and finite (got {})",
                                    config.min_box_volume_m3));
    }
    if (!(config.min_added_share >= 0.0 && config.min_added_share <= 1.0)) {
        throw bad_input(
            fmt::format("grow_boxes: min_added_share must be in 0..1 (got {})", config.min_added_share));
    }
}

void check_input(const char* function, const VoxelGrid& grid, const BitVolume& solid) {
    if (grid.dims.x < 0 || grid.dims.y < 0 || grid.dims.z < 0) {
        throw internal_error(fmt::format("{}: negative grid dims {} x {} x {}", function, grid.dims.x,
                                         grid.dims.y, grid.dims.z));
    }
    if (uint64_t(solid.words.size()) * 64 < grid.count()) {
        throw internal_error(fmt::format("{}: the solid volume holds {} bits for a grid of {} voxels",
                                         function, uint64_t(solid.words.size()) * 64, grid.count()));
    }
}

double volume_m3(const VoxelGrid& grid, uint64_t voxels) {
    const double s = double(grid.voxel_size_m);
    return double(voxels) * s * s * s;
}

// Does this box (volume `volume`) add enough over the boxes kept before it?
bool adds_enough(uint64_t added, uint64_t volume, double share) {
    return added > 0 && double(added) >= share * double(volume);
}

uint64_t solid_count(const VoxelGrid& grid, const BitVolume& solid) {
    const uint64_t n = grid.count(), full = n / 64;
    uint64_t c = 0;
    for (uint64_t w = 0; w < full; ++w) c += uint64_t(__builtin_popcountll(solid.words[w]));
    if (n % 64) c += uint64_t(__builtin_popcountll(solid.words[full] & ((uint64_t(1) << (n % 64)) - 1)));
    return c;
}

// ---- the fast path ------------------------------------------------------------------------------------

// 3D summed-area table of non-solid voxels modulo 2^16: sums at (x, y, z) for x in 0..dims.x (and so on)
// count the non-solid voxels of [0, x) x [0, y) x [0, z).
struct EmptySums {
    glm::ivec3 dims{0};
    uint64_t sx = 0, sxy = 0;          // strides of y and z
    std::unique_ptr<uint16_t[]> sums;  // (dims.x + 1) * (dims.y + 1) * (dims.z + 1)

    uint32_t at(int x, int y, int z) const {
        return sums[uint64_t(x) + sx * uint64_t(y) + sxy * uint64_t(z)];
    }

    // Non-solid voxels of lo..hi (inclusive), modulo 2^16.
    uint32_t count_mod(glm::ivec3 lo, glm::ivec3 hi) const {
        const glm::ivec3 a = lo, b = hi + 1;
        const uint32_t c = at(b.x, b.y, b.z) - at(a.x, b.y, b.z) - at(b.x, a.y, b.z) - at(b.x, b.y, a.z) +
                           at(a.x, a.y, b.z) + at(a.x, b.y, a.z) + at(b.x, a.y, a.z) - at(a.x, a.y, a.z);
        return c & uint32_t(kWrap - 1);
    }

    // Exact: is every voxel of lo..hi solid?
    bool all_solid(glm::ivec3 lo, glm::ivec3 hi) const {
        if (count_mod(lo, hi) != 0) return false;
        const glm::ivec3 n = hi - lo + 1;
        if (uint64_t(n.x) * uint64_t(n.y) * uint64_t(n.z) < kWrap) return true;
        // 0 modulo 2^16 but big enough to hold 2^16 non-solid voxels: check the halves.
        const int axis = n.x >= n.y && n.x >= n.z ? 0 : (n.y >= n.z ? 1 : 2);
        glm::ivec3 hi0 = hi, lo1 = lo;
        hi0[axis] = lo[axis] + n[axis] / 2 - 1;
        lo1[axis] = hi0[axis] + 1;
        return all_solid(lo, hi0) && all_solid(lo1, hi);
    }
};

EmptySums build_empty_sums(const VoxelGrid& grid, const BitVolume& solid) {
    EmptySums t;
    t.dims = grid.dims;
    const int nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;
    t.sx = uint64_t(nx) + 1;
    t.sxy = t.sx * (uint64_t(ny) + 1);
    t.sums.reset(new uint16_t[t.sxy * (uint64_t(nz) + 1)]);  // every entry is written below
    uint16_t* s = t.sums.get();
    const uint64_t sx = t.sx, sxy = t.sxy;
    const bool parallel = grid.count() >= kParallelVoxels;
#pragma omp parallel if (parallel)
    {
        // The zero borders: the slice z = 0 and the row y = 0 of every slice (x = 0 is set with its row).
#pragma omp for schedule(static) nowait
        for (int z = 1; z <= nz; ++z) std::memset(s + sxy * uint64_t(z), 0, sx * sizeof(uint16_t));
#pragma omp single nowait
        std::memset(s, 0, sxy * sizeof(uint16_t));
        // Along x and y at once, a slice z per task: each row's running counts plus the row before it.
#pragma omp for schedule(static)
        for (int z = 0; z < nz; ++z) {
            for (int y = 0; y < ny; ++y) {
                const uint64_t src = grid.index(0, y, z);
                uint16_t* row = s + sx * uint64_t(y + 1) + sxy * uint64_t(z + 1);
                const uint16_t* prev = row - sx;  // the row before, this task's (y = 0: no row, below)
                uint16_t run = 0;
                row[0] = 0;
                if (y == 0) {
                    for (int x = 0; x < nx; ++x)
                        row[x + 1] = run = uint16_t(run + (solid.get(src + uint64_t(x)) ? 0 : 1));
                    continue;
                }
                for (int x = 0; x < nx; ++x) {
                    run = uint16_t(run + (solid.get(src + uint64_t(x)) ? 0 : 1));
                    row[x + 1] = uint16_t(run + prev[x + 1]);
                }
            }
        }
        // Along z: add the previous slice to each slice.
#pragma omp for schedule(static)
        for (int y = 1; y <= ny; ++y) {
            for (int z = 2; z <= nz; ++z) {
                uint16_t* row = s + sx * uint64_t(y) + sxy * uint64_t(z);
                const uint16_t* prev = row - sxy;
                for (uint64_t x = 0; x < sx; ++x) row[x] = uint16_t(row[x] + prev[x]);
            }
        }
    }
    return t;
}

// For every voxel, the edge of the largest all-solid cube with the voxel as its min corner, capped at
// kMaxSeedCube (0 for non-solid voxels):
//   cube(p) = solid(p) ? 1 + min over the 7 voxels p + e, e in {0, 1}^3 \ {0}, of cube(p + e) : 0
// (the cube of edge k at p is p and the seven cubes of edge k - 1 at the p + e). Capping commutes with
// the recurrence, so the capped values are exact up to the cap. A row (y, z) needs the rows (y + 1, z),
// (y, z + 1) and (y + 1, z + 1), so tiles of rows run as a wavefront: the tiles on one anti-diagonal
// ty + tz are independent once those of the next are done (one barrier per diagonal of tiles). Each
// value is the recurrence's, so the cubes do not depend on the thread count.
void seed_cube_row(const VoxelGrid& grid, const BitVolume& solid, uint8_t* cube, int y, int z) {
    const int nx = grid.dims.x;
    const uint64_t base = grid.index(0, y, z);
    uint8_t* c = cube + base;
    if (y + 1 >= grid.dims.y || z + 1 >= grid.dims.z) {
        for (int x = 0; x < nx; ++x) c[x] = solid.get(base + uint64_t(x)) ? 1 : 0;
        return;
    }
    const uint8_t* cy = cube + grid.index(0, y + 1, z);
    const uint8_t* cz = cube + grid.index(0, y, z + 1);
    const uint8_t* cyz = cube + grid.index(0, y + 1, z + 1);
    c[nx - 1] = solid.get(base + uint64_t(nx - 1)) ? 1 : 0;
    for (int x = nx - 2; x >= 0; --x) {
        if (!solid.get(base + uint64_t(x))) {
            c[x] = 0;
            continue;
        }
        const uint8_t m = std::min({c[x + 1], cy[x], cy[x + 1], cz[x], cz[x + 1], cyz[x], cyz[x + 1]});
        c[x] = m >= kMaxSeedCube ? uint8_t(kMaxSeedCube) : uint8_t(m + 1);
    }
}

std::unique_ptr<uint8_t[]> build_seed_cubes(const VoxelGrid& grid, const BitVolume& solid) {
    const int ny = grid.dims.y, nz = grid.dims.z;
    std::unique_ptr<uint8_t[]> cube(new uint8_t[grid.count()]);  // every entry is written below
    const int tiles_y = (ny + kTileRows - 1) / kTileRows, tiles_z = (nz + kTileRows - 1) / kTileRows;
    const bool parallel = grid.count() >= kParallelVoxels;
#pragma omp parallel if (parallel)
    for (int d = tiles_y - 1 + tiles_z - 1; d >= 0; --d) {
        const int tz_lo = std::max(0, d - (tiles_y - 1)), tz_hi = std::min(tiles_z - 1, d);
#pragma omp for schedule(dynamic, 1)
        for (int tz = tz_lo; tz <= tz_hi; ++tz) {
            const int ty = d - tz;
            for (int z = std::min(nz, (tz + 1) * kTileRows) - 1; z >= tz * kTileRows; --z)
                for (int y = std::min(ny, (ty + 1) * kTileRows) - 1; y >= ty * kTileRows; --y)
                    seed_cube_row(grid, solid, cube.get(), y, z);
        }
    }
    return cube;
}

// Grows the box from the cube of edge `edge` at `seed`: one layer at a time, round-robin over
// +x, -x, +y, -y, +z, -z, while the layer is inside the grid and all solid. The same box, faster
// (docs/ALGORITHMS.md#boxes): a direction that fails once fails for good (its next layer only ever widens),
// so it is not tried again; and once every direction left lies on one axis, the two no longer change each
// other's layers, so each grows to its end at once (by doubling, then halving, the slab it adds).
VoxelBox grow_from(const EmptySums& sums, glm::ivec3 seed, int edge) {
    VoxelBox b{seed, seed + (edge - 1)};
    bool alive[6] = {true, true, true, true, true, true};
    // The slab of `n` layers beyond the box's face in direction `dir` (inside the grid: checked by callers).
    const auto slab = [&](int dir, int from, int n, glm::ivec3& lo, glm::ivec3& hi) {
        const int axis = dir / 2;
        lo = b.lo;
        hi = b.hi;
        if (dir % 2 == 0) {
            lo[axis] = b.hi[axis] + 1 + from;
            hi[axis] = b.hi[axis] + from + n;
        } else {
            hi[axis] = b.lo[axis] - 1 - from;
            lo[axis] = b.lo[axis] - from - n;
        }
    };
    // Layers left in the grid beyond the face in direction `dir`.
    const auto room = [&](int dir) {
        const int axis = dir / 2;
        return dir % 2 == 0 ? sums.dims[axis] - 1 - b.hi[axis] : b.lo[axis];
    };
    for (bool grew = true; grew;) {
        grew = false;
        int axes = 0, last_axis = 0;
        for (int a = 0; a < 3; ++a)
            if (alive[2 * a] || alive[2 * a + 1]) ++axes, last_axis = a;
        if (axes == 1) {
            for (int dir = 2 * last_axis; dir < 2 * last_axis + 2; ++dir) {
                if (!alive[dir]) continue;
                // Layers [0, done) beyond the face are solid; find how many more are.
                int done = 0, step = 1;
                bool halving = false;  // a slab failed: the end lies within the next `2 step` layers
                glm::ivec3 lo, hi;
                while (step > 0) {
                    const int n = std::min(step, room(dir) - done);
                    bool solid = false;
                    if (n > 0) {
                        slab(dir, done, n, lo, hi);
                        solid = sums.all_solid(lo, hi);
                    }
                    if (solid) {
                        done += n;
                        if (n < step) break;  // the grid's edge
                        step = halving ? step / 2 : step * 2;
                    } else {
                        halving = true;
                        step /= 2;
                    }
                }
                if (done > 0) {
                    slab(dir, 0, done, lo, hi);
                    b.lo = glm::min(b.lo, lo);
                    b.hi = glm::max(b.hi, hi);
                }
            }
            break;
        }
        for (int dir = 0; dir < 6; ++dir) {
            if (!alive[dir]) continue;
            glm::ivec3 lo, hi;
            if (room(dir) == 0) {
                alive[dir] = false;
                continue;
            }
            slab(dir, 0, 1, lo, hi);
            if (!sums.all_solid(lo, hi)) {
                alive[dir] = false;
                continue;
            }
            b.lo = glm::min(b.lo, lo);
            b.hi = glm::max(b.hi, hi);
            grew = true;
        }
    }
    return b;
}

// Bits lo..hi (inclusive) of a bit volume: how many are set, and set them.
uint64_t count_bits(const BitVolume& bits, uint64_t lo, uint64_t hi) {
    const uint64_t w0 = lo >> 6, w1 = hi >> 6;
    const uint64_t m0 = ~uint64_t(0) << (lo & 63), m1 = ~uint64_t(0) >> (63 - (hi & 63));
    if (w0 == w1) return uint64_t(__builtin_popcountll(bits.words[w0] & m0 & m1));
    uint64_t c = uint64_t(__builtin_popcountll(bits.words[w0] & m0)) +
                 uint64_t(__builtin_popcountll(bits.words[w1] & m1));
    for (uint64_t w = w0 + 1; w < w1; ++w) c += uint64_t(__builtin_popcountll(bits.words[w]));
    return c;
}

// The end words of the range may hold bits of other rows (set by other threads at once): they are ORed
// atomically; the words between hold this row's bits only.
void set_bits_shared(BitVolume& bits, uint64_t lo, uint64_t hi) {
    const uint64_t w0 = lo >> 6, w1 = hi >> 6;
    const uint64_t m0 = ~uint64_t(0) << (lo & 63), m1 = ~uint64_t(0) >> (63 - (hi & 63));
    const auto set = [&](uint64_t w, uint64_t m) {
        std::atomic_ref<uint64_t>(bits.words[w]).fetch_or(m, std::memory_order_relaxed);
    };
    if (w0 == w1) {
        set(w0, m0 & m1);
        return;
    }
    set(w0, m0);
    set(w1, m1);
    for (uint64_t w = w0 + 1; w < w1; ++w) bits.words[w] = ~uint64_t(0);
}

// The voxels of a and b both hold.
VoxelBox intersection(const VoxelBox& a, const VoxelBox& b) {
    return VoxelBox{glm::max(a.lo, b.lo), glm::min(a.hi, b.hi)};
}

// Boxes filed by the cells of a coarse grid (at most kBucketsPerAxis per axis) they meet, to find the one
// sharing most voxels with a box without testing them all.
constexpr int kBucketsPerAxis = 16;
class BoxBuckets {
public:
    explicit BoxBuckets(glm::ivec3 dims)
        : size_(glm::max((dims + kBucketsPerAxis - 1) / kBucketsPerAxis, glm::ivec3(1))),
          cells_(size_t(kBucketsPerAxis) * kBucketsPerAxis * kBucketsPerAxis) {}

    void add(const VoxelBox& box) {
        const uint32_t id = uint32_t(boxes_.size());
        boxes_.push_back(box);
        seen_.push_back(0);
        visit(box, [&](std::vector<uint32_t>& cell) { cell.push_back(id); });
    }

    // The filed box sharing most voxels with `box` (nullptr when none shares any; the first filed of
    // equals, so the answer does not depend on the filing).
    const VoxelBox* most_overlapping(const VoxelBox& box, uint64_t& shared) {
        ++stamp_;
        shared = 0;
        uint32_t best = UINT32_MAX;
        visit(box, [&](std::vector<uint32_t>& cell) {
            for (const uint32_t id : cell) {
                if (seen_[id] == stamp_) continue;
                seen_[id] = stamp_;
                const uint64_t v = intersection(box, boxes_[id]).volume();
                if (v > shared || (v == shared && v > 0 && id < best)) {
                    shared = v;
                    best = id;
                }
            }
        });
        return best == UINT32_MAX ? nullptr : &boxes_[best];
    }

private:
    template <class F>
    void visit(const VoxelBox& box, F&& f) {
        const glm::ivec3 lo = glm::clamp(box.lo / size_, glm::ivec3(0), glm::ivec3(kBucketsPerAxis - 1));
        const glm::ivec3 hi = glm::clamp(box.hi / size_, glm::ivec3(0), glm::ivec3(kBucketsPerAxis - 1));
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x)
                    f(cells_[size_t(x) +
                             size_t(kBucketsPerAxis) * (size_t(y) + size_t(kBucketsPerAxis) * z)]);
    }

    glm::ivec3 size_;
    std::vector<std::vector<uint32_t>> cells_;
    std::vector<VoxelBox> boxes_;
    std::vector<uint32_t> seen_;
    uint32_t stamp_ = 0;
};

// Rows along x of a box: what walking it row by row costs, more than its voxels do.
uint64_t rows_of(const VoxelBox& b) {
    return b.volume() ? uint64_t(b.hi.y - b.lo.y + 1) * uint64_t(b.hi.z - b.lo.z + 1) : 0;
}

// `box` less `cut` as at most six disjoint boxes (slabs below and above along z, then y, then x), when they
// have fewer rows along x than the box; else the whole box. Returns how many.
int box_minus(const VoxelBox& box, const VoxelBox* cut, std::array<VoxelBox, 6>& out) {
    out[0] = box;
    if (!cut) return 1;
    const VoxelBox in = intersection(box, *cut);
    int n = 0;
    VoxelBox rest = box;
    for (int a = 2; a >= 0; --a) {
        if (rest.lo[a] < in.lo[a]) {
            out[size_t(n)] = rest;
            out[size_t(n++)].hi[a] = in.lo[a] - 1;
        }
        if (rest.hi[a] > in.hi[a]) {
            out[size_t(n)] = rest;
            out[size_t(n++)].lo[a] = in.hi[a] + 1;
        }
        rest.lo[a] = in.lo[a];
        rest.hi[a] = in.hi[a];
    }
    uint64_t rows = 0;
    for (int p = 0; p < n; ++p) rows += rows_of(out[size_t(p)]);
    if (rows < rows_of(box)) return n;
    out[0] = box;
    return 1;
}

uint8_t block_max(const uint8_t* v, uint64_t n) {
    uint8_t m = 0;
    for (uint64_t i = 0; i < n; ++i) m = std::max(m, v[i]);
    return m;
}

// Sets the cube sizes of voxels lo..hi (inclusive) to 0, skipping the blocks of 64 whose bound in `l1` is
// already 0, and setting that bound to 0 for each whole block cleared. A box grown later often lies mostly
// in boxes grown before it (growth goes through covered voxels), so most of its blocks are skipped.
void clear_cubes(uint8_t* cube, uint8_t* l1, uint64_t lo, uint64_t hi) {
    uint64_t b0 = lo / kBlock, b1 = hi / kBlock;
    if (b0 == b1) {
        if (l1[b0]) std::memset(cube + lo, 0, size_t(hi - lo + 1));
        return;
    }
    if (lo % kBlock) {
        if (l1[b0]) std::memset(cube + lo, 0, size_t((b0 + 1) * kBlock - lo));
        ++b0;
    }
    if ((hi + 1) % kBlock) {
        if (l1[b1]) std::memset(cube + b1 * kBlock, 0, size_t(hi + 1 - b1 * kBlock));
        --b1;  // b1 was at least b0 + 1 here, so no wrap
    }
    for (uint64_t b = b0; b <= b1; ++b) {
        if (!l1[b]) continue;
        std::memset(cube + b * kBlock, 0, size_t(kBlock));
        l1[b] = 0;
    }
}

// Groups of kBlock blocks per window of the seed scan: the seeds of one size in a window are found on all
// threads at once (about 4.2 M voxels: few parallel regions, and at most 4.2 M seeds held at once).
constexpr uint64_t kWindowGroups = 1024;
// Boxes grown before their voxels are cleared from the cubes, on all threads.
constexpr size_t kBatchBoxes = 64;
// A batch of fewer rows is cleared on one thread.
constexpr uint64_t kParallelRows = 4096;

// Groups of kBlock blocks per chunk of a window: threads take chunks as they finish (seeds cluster, so even
// runs of groups would leave threads idle), each into its own list.
constexpr uint64_t kChunkGroups = 16;

// The voxels of groups g0..g1 (of kBlock blocks of kBlock voxels) whose cube size is s: chunk c's list holds
// those of groups g0 + c kChunkGroups onwards, in index order, so the lists in chunk order are the seeds in
// index order. Tightens the bounds of the blocks and groups it scans (a bound is of the cubes as they are
// now, so it stays an upper bound).
void collect_seeds(const uint8_t* cube, std::vector<uint8_t>& l1, std::vector<uint8_t>& l2, uint64_t n,
                   uint8_t s, uint64_t g0, uint64_t g1, bool parallel,
                   std::vector<std::vector<uint64_t>>& chunks) {
    const uint64_t n1 = l1.size();
    const int64_t n_chunks = int64_t((g1 - g0 + kChunkGroups - 1) / kChunkGroups);
    if (chunks.size() < size_t(n_chunks)) chunks.resize(size_t(n_chunks));
    for (std::vector<uint64_t>& c : chunks) c.clear();
    if (block_max(&l2[g0], g1 - g0) < s) return;  // no seed of this size in the window
#pragma omp parallel for schedule(dynamic, 1) if (parallel)
    for (int64_t c = 0; c < n_chunks; ++c) {
        std::vector<uint64_t>& mine = chunks[size_t(c)];
        const uint64_t c_end = std::min(g1, g0 + uint64_t(c + 1) * kChunkGroups);
        for (uint64_t g = g0 + uint64_t(c) * kChunkGroups; g < c_end; ++g) {
            if (l2[g] < s) continue;
            const uint64_t b_end = std::min(n1, (g + 1) * kBlock);
            for (uint64_t b = g * kBlock; b < b_end; ++b) {
                if (l1[b] < s) continue;
                const uint64_t i_end = std::min(n, (b + 1) * kBlock);
                for (uint64_t i = b * kBlock; i < i_end; ++i)
                    if (cube[i] == s) mine.push_back(i);
                l1[b] = block_max(&cube[b * kBlock], i_end - b * kBlock);
            }
            l2[g] = block_max(&l1[g * kBlock], b_end - g * kBlock);
        }
    }
}

// Boxes grown but not yet cleared from the cubes: the parts of each to clear (box_minus), and the boxes to
// test seeds against meanwhile.
class ClearBatch {
public:
    bool covers(glm::ivec3 p) const {
        for (const VoxelBox& b : boxes_)
            if (glm::all(glm::greaterThanEqual(p, b.lo)) && glm::all(glm::lessThanEqual(p, b.hi)))
                return true;
        return false;
    }
    void add(const VoxelBox& box, const VoxelBox* parts, int count) {
        boxes_.push_back(box);
        for (int p = 0; p < count; ++p) {
            parts_.push_back(parts[p]);
            rows_ += rows_of(parts[p]);
        }
    }
    bool full() const { return boxes_.size() >= kBatchBoxes; }

    // Clears the parts from the cubes, a layer z per task: a row's clear writes the block bounds only of
    // blocks inside the row, so tasks never write the same byte.
    void clear(const VoxelGrid& grid, uint8_t* cube, uint8_t* l1, bool parallel) {
        if (parts_.empty()) return;
        int z_lo = parts_[0].lo.z, z_hi = parts_[0].hi.z;
        for (const VoxelBox& b : parts_) z_lo = std::min(z_lo, b.lo.z), z_hi = std::max(z_hi, b.hi.z);
#pragma omp parallel for schedule(dynamic, 1) if (parallel && rows_ >= kParallelRows)
        for (int z = z_lo; z <= z_hi; ++z) {
            for (const VoxelBox& b : parts_) {
                if (z < b.lo.z || z > b.hi.z) continue;
                for (int y = b.lo.y; y <= b.hi.y; ++y)
                    clear_cubes(cube, l1, grid.index(b.lo.x, y, z), grid.index(b.hi.x, y, z));
            }
        }
        boxes_.clear();
        parts_.clear();
        rows_ = 0;
    }

private:
    std::vector<VoxelBox> boxes_, parts_;
    uint64_t rows_ = 0;
};

}  // namespace

std::vector<VoxelBox> grow_boxes(Context& ctx, const VoxelGrid& grid, const BitVolume& solid,
                                 const BoxConfig& config, BoxStats* stats) {
    ScopedTimer timer(ctx, "boxes");
    validate(config);
    check_input("grow_boxes", grid, solid);
    BoxStats st;
    std::vector<VoxelBox> kept;
    const uint64_t n = grid.count();
    if (n == 0) {
        if (stats) *stats = st;
        return kept;
    }
    st.solid_voxels = solid_count(grid, solid);

    // 1. Seeds and the summed-area table.
    std::vector<VoxelBox> grown;  // those of at least min_box_volume_m3, in grown order
    {
        const EmptySums sums = build_empty_sums(grid, solid);
        const std::unique_ptr<uint8_t[]> cube = build_seed_cubes(grid, solid);
        // Which cube sizes occur, and upper bounds of the cube sizes in blocks of 64 voxels (l1) and of 64
        // blocks (l2). The bounds only go stale upward (covering sets cube sizes to 0) and are made exact
        // again when scanned.
        std::array<uint8_t, kMaxSeedCube + 1> sizes{};
        const uint64_t n1 = (n + kBlock - 1) / kBlock, n2 = (n1 + kBlock - 1) / kBlock;
        std::vector<uint8_t> l1(n1), l2(n2);
        const bool parallel = n >= kParallelVoxels;
#pragma omp parallel if (parallel)
        {
            std::array<uint8_t, kMaxSeedCube + 1> seen{};
#pragma omp for schedule(static)
            for (uint64_t b = 0; b < n1; ++b) {
                const uint8_t* v = &cube[b * kBlock];
                const uint64_t len = std::min(kBlock, n - b * kBlock);
                uint8_t m = 0;
                for (uint64_t i = 0; i < len; ++i) {
                    seen[v[i]] = 1;
                    m = std::max(m, v[i]);
                }
                l1[b] = m;
            }
#pragma omp critical(grow_boxes_sizes)
            for (size_t k = 0; k < seen.size(); ++k) sizes[k] |= seen[k];
#pragma omp for schedule(static)
            for (uint64_t g = 0; g < n2; ++g)
                l2[g] = block_max(&l1[g * kBlock], std::min(kBlock, n1 - g * kBlock));
        }

        // 2. and 3. Growth from the seeds in order, until the stop rule. For each seed size, a window of
        // voxels at a time: its seeds are found on all threads, then taken in index order on one thread;
        // the boxes grown are cleared from the cubes in batches on all threads, and until then a seed is
        // tested against the batch (docs/ALGORITHMS.md#boxes). So every seed is taken or skipped as one
        // thread taking them one by one and clearing each box at once would: the same boxes.
        const uint64_t cap = uint64_t(kGrowFactor) * config.max_boxes;
        bool stop = false;
        BoxBuckets covering(grid.dims);  // every box grown
        ClearBatch batch;
        std::vector<std::vector<uint64_t>> chunks;  // a window's seeds of one size (collect_seeds)
        ctx.progress_begin("boxes", 0, "boxes");
        for (int s = kMaxSeedCube; s >= 1 && !stop; --s) {
            if (!sizes[size_t(s)]) continue;
            for (uint64_t g0 = 0; g0 < n2 && !stop; g0 += kWindowGroups) {
                const uint64_t g1 = std::min(n2, g0 + kWindowGroups);
                collect_seeds(cube.get(), l1, l2, n, uint8_t(s), g0, g1, parallel, chunks);
                for (const std::vector<uint64_t>& seeds : chunks) {
                    for (const uint64_t i : seeds) {
                        if (cube[i] != s) continue;  // cleared by a box of an earlier batch
                        const glm::ivec3 at = grid.coords(i);
                        if (batch.covers(at)) continue;
                        const VoxelBox box = grow_from(sums, at, s);
                        ++st.grown;
                        // Cover: no voxel of the box seeds again. The box grown before that shares most of it
                        // is clear already, or is in the batch (growth goes through covered voxels), so only
                        // the rest is cleared.
                        uint64_t shared = 0;
                        std::array<VoxelBox, 6> rest;
                        const int parts = box_minus(box, covering.most_overlapping(box, shared), rest);
                        batch.add(box, rest.data(), parts);
                        covering.add(box);
                        if (volume_m3(grid, box.volume()) >= config.min_box_volume_m3) {
                            ctx.progress_advance(1);
                            grown.push_back(box);
                            stop = grown.size() >= cap;
                            if (stop) break;
                        }
                        if (batch.full()) batch.clear(grid, cube.get(), l1.data(), parallel);
                    }
                    if (stop) break;
                }
                batch.clear(grid, cube.get(), l1.data(), parallel);
            }
        }
        ctx.progress_end();
    }  // frees the table and the cubes before the cut

    // 4. Sort and cut.
    std::stable_sort(grown.begin(), grown.end(),
                     [](const VoxelBox& a, const VoxelBox& b) { return a.volume() > b.volume(); });
    BitVolume cover;
    cover.reset(n);
    BoxBuckets kept_boxes(grid.dims);
    for (const VoxelBox& box : grown) {
        if (kept.size() >= config.max_boxes) break;
        const uint64_t volume = box.volume();
        if (volume_m3(grid, volume) < config.min_box_volume_m3) continue;
        // What kept boxes cover of it: all it shares with the kept box sharing most, and what the cover
        // holds of the rest.
        uint64_t covered = 0;
        std::array<VoxelBox, 6> rest;
        const int parts = box_minus(box, kept_boxes.most_overlapping(box, covered), rest);
        if (parts == 1 && rest[0] == box) covered = 0;  // not cut: the rows count the shared voxels too
        // A big box's rows are counted and set on all threads, a layer z per task (a row's words are set
        // whole only inside the row; the words it shares with other rows are set atomically).
        uint64_t rows = 0;
        int z_lo = rest[0].lo.z, z_hi = rest[0].hi.z;
        for (int p = 0; p < parts; ++p) {
            rows += rows_of(rest[size_t(p)]);
            z_lo = std::min(z_lo, rest[size_t(p)].lo.z);
            z_hi = std::max(z_hi, rest[size_t(p)].hi.z);
        }
        const bool parallel_rows = n >= kParallelVoxels && rows >= kParallelRows;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : covered) if (parallel_rows)
        for (int z = z_lo; z <= z_hi; ++z) {
            for (int p = 0; p < parts; ++p) {
                const VoxelBox& b = rest[size_t(p)];
                if (z < b.lo.z || z > b.hi.z) continue;
                for (int y = b.lo.y; y <= b.hi.y; ++y)
                    covered += count_bits(cover, grid.index(b.lo.x, y, z), grid.index(b.hi.x, y, z));
            }
        }
        if (!adds_enough(volume - covered, volume, config.min_added_share)) continue;
        kept.push_back(box);
        kept_boxes.add(box);
        st.covered_voxels += volume - covered;
#pragma omp parallel for schedule(dynamic, 1) if (parallel_rows)
        for (int z = z_lo; z <= z_hi; ++z) {
            for (int p = 0; p < parts; ++p) {
                const VoxelBox& b = rest[size_t(p)];
                if (z < b.lo.z || z > b.hi.z) continue;
                for (int y = b.lo.y; y <= b.hi.y; ++y)
                    set_bits_shared(cover, grid.index(b.lo.x, y, z), grid.index(b.hi.x, y, z));
            }
        }
    }
    st.kept = uint32_t(kept.size());
    st.seconds = timer.seconds();
    ctx.debug(fmt::format(
        "boxes: {} solid voxels, {} boxes grown, {} kept covering {} voxels ({:.1f}%) in {:.3f} s",
        st.solid_voxels, st.grown, st.kept, st.covered_voxels,
        st.solid_voxels ? 100.0 * double(st.covered_voxels) / double(st.solid_voxels) : 0.0, st.seconds));
    if (stats) *stats = st;
    return kept;
}

// ---- the reference ------------------------------------------------------------------------------------

std::vector<VoxelBox> grow_boxes_reference(const VoxelGrid& grid, const BitVolume& solid,
                                           const BoxConfig& config) {
    validate(config);
    check_input("grow_boxes_reference", grid, solid);
    const glm::ivec3 dims = grid.dims;
    auto is_solid = [&](glm::ivec3 p) { return grid.inside(p) && solid.get(grid.index(p.x, p.y, p.z)); };
    auto all_solid = [&](glm::ivec3 lo, glm::ivec3 hi) {
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x)
                    if (!is_solid({x, y, z})) return false;
        return true;
    };

    // Seeds: the cube at each voxel grows while its next shell (the voxels whose largest offset from
    // the corner is k) is solid; ordered by edge, then index.
    struct Seed {
        int edge;
        uint64_t index;
    };
    std::vector<Seed> seeds;
    for (uint64_t i = 0; i < grid.count(); ++i) {
        const glm::ivec3 p = grid.coords(i);
        int k = 0;
        while (k < kMaxSeedCube) {
            bool shell_solid = true;
            for (int dz = 0; dz <= k && shell_solid; ++dz) {
                for (int dy = 0; dy <= k && shell_solid; ++dy) {
                    const bool whole_row = dz == k || dy == k;  // else only dx == k is on the shell
                    for (int dx = whole_row ? 0 : k; dx <= k && shell_solid; ++dx) {
                        shell_solid = is_solid(p + glm::ivec3(dx, dy, dz));
                    }
                }
            }
            if (!shell_solid) break;
            ++k;
        }
        if (k > 0) seeds.push_back({k, i});
    }
    std::sort(seeds.begin(), seeds.end(), [](const Seed& a, const Seed& b) {
        return a.edge != b.edge ? a.edge > b.edge : a.index < b.index;
    });

    // Growth.
    std::vector<bool> covered(grid.count(), false);
    std::vector<VoxelBox> grown;
    const size_t cap = size_t(kGrowFactor) * config.max_boxes;
    for (const Seed& seed : seeds) {
        if (grown.size() >= cap) break;
        if (covered[seed.index]) continue;
        const glm::ivec3 p = grid.coords(seed.index);
        VoxelBox b{p, p + (seed.edge - 1)};
        bool grew = true;
        while (grew) {
            grew = false;
            for (int dir = 0; dir < 6; ++dir) {
                const int axis = dir / 2;
                const int side = dir % 2 == 0 ? b.hi[axis] + 1 : b.lo[axis] - 1;  // the layer's coordinate
                if (side < 0 || side >= dims[axis]) continue;
                VoxelBox layer = b;
                layer.lo[axis] = layer.hi[axis] = side;
                if (!all_solid(layer.lo, layer.hi)) continue;
                (dir % 2 == 0 ? b.hi : b.lo)[axis] = side;
                grew = true;
            }
        }
        for (int z = b.lo.z; z <= b.hi.z; ++z)
            for (int y = b.lo.y; y <= b.hi.y; ++y)
                for (int x = b.lo.x; x <= b.hi.x; ++x) covered[grid.index(x, y, z)] = true;
        if (volume_m3(grid, b.volume()) >= config.min_box_volume_m3) grown.push_back(b);
    }

    // Sort and cut.
    std::stable_sort(grown.begin(), grown.end(),
                     [](const VoxelBox& a, const VoxelBox& b) { return a.volume() > b.volume(); });
    std::vector<bool> kept_cover(grid.count(), false);
    std::vector<VoxelBox> kept;
    for (const VoxelBox& b : grown) {
        if (kept.size() >= config.max_boxes) break;
        if (volume_m3(grid, b.volume()) < config.min_box_volume_m3) continue;
        uint64_t added = 0;
        for (int z = b.lo.z; z <= b.hi.z; ++z)
            for (int y = b.lo.y; y <= b.hi.y; ++y)
                for (int x = b.lo.x; x <= b.hi.x; ++x) added += kept_cover[grid.index(x, y, z)] ? 0 : 1;
        if (!adds_enough(added, b.volume(), config.min_added_share)) continue;
        kept.push_back(b);
        for (int z = b.lo.z; z <= b.hi.z; ++z)
            for (int y = b.lo.y; y <= b.hi.y; ++y)
                for (int x = b.lo.x; x <= b.hi.x; ++x) kept_cover[grid.index(x, y, z)] = true;
    }
    return kept;
}

Aabb box_bounds(const VoxelGrid& grid, const VoxelBox& box) {
    return Aabb::of(grid.voxel_box(box.lo).min, grid.voxel_box(box.hi).max);
}

TrimFigures trim_off_rejected(std::vector<VoxelBox>& boxes, std::vector<uint8_t>& rejected,
                              uint64_t min_voxels) {
    TrimFigures figures;
    const auto overlap = [](const VoxelBox& a, const VoxelBox& b) {
        return glm::all(glm::lessThanEqual(glm::max(a.lo, b.lo), glm::min(a.hi, b.hi)));
    };
    const std::vector<uint8_t> was_rejected = rejected;
    for (size_t k = 0; k < boxes.size(); ++k) {
        if (was_rejected[k]) continue;
        VoxelBox& box = boxes[k];
        bool cut = false;
        for (size_t r = 0; r < boxes.size() && box.volume() > 0; ++r) {
            if (!was_rejected[r] || !overlap(box, boxes[r])) continue;
            VoxelBox best{{0, 0, 0}, {-1, -1, -1}};
            for (int axis = 0; axis < 3; ++axis) {
                VoxelBox below = box, above = box;
                below.hi[axis] = boxes[r].lo[axis] - 1;
                above.lo[axis] = boxes[r].hi[axis] + 1;
                for (const VoxelBox& slab : {below, above})
                    if (slab.volume() > best.volume()) best = slab;
            }
            box = best;
            cut = true;
        }
        if (!cut) continue;
        ++figures.trimmed;
        if (box.volume() < std::max<uint64_t>(min_voxels, 1)) {
            rejected[k] = 1;
            ++figures.trimmed_away;
        }
    }
    return figures;
}

}  // namespace pvs
