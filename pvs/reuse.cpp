// SPDX-License-Identifier: MIT
// The incremental re-bake: the geometry print and the plan of which (cell, object) pairs keep their bit
// (docs/ALGORITHMS.md#reuse).
#include "pvs/reuse.h"

#include "pvs/conservative.h"
#include "pvs/convex_cap.h"

#include <fmt/format.h>
#define XXH_STATIC_LINKING_ONLY  // XXH3_state_t on the stack
#include <xxhash.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>

namespace pvs {

namespace {

constexpr uint32_t kTileVoxels = 16;  // voxels along a tile's edge, doubled while there are too many
constexpr uint64_t kMaxTiles = uint64_t(1) << 20;
constexpr size_t kMaxChangedBoxes = 64;  // the changed tiles are merged into at most this many boxes

// Element kinds, so that equal numbers of different kinds hash differently.
enum Tag : uint64_t { kTriangle = 1, kShrunkBox = 2, kPanel = 3, kSlanted = 4, kMask = 5, kCap = 6 };

class Hasher {
public:
    explicit Hasher(uint64_t tag) { XXH3_64bits_reset_withSeed(&state_, tag); }
    template <class T>
    Hasher& add(const T& v) {
        XXH3_64bits_update(&state_, &v, sizeof(T));
        return *this;
    }
    uint64_t digest() { return XXH3_64bits_digest(&state_); }

private:
    XXH3_state_t state_;
};

uint64_t box_hash(uint64_t tag, uint64_t level, const Aabb& b) {
    return Hasher(tag).add(level).add(b.min).add(b.max).digest();
}

// Adds an element's hash to every tile its closed bounds meet, and to `outside` when they reach beyond the
// tiles. A sum, so the order of elements does not matter.
void add_element(GeometryPrint& p, const Aabb& b, uint64_t h) {
    if (b.is_empty()) return;
    const glm::vec3 lo = (b.min - p.origin) / p.tile_m, hi = (b.max - p.origin) / p.tile_m;
    int ilo[3], ihi[3];
    bool beyond = false;
    for (int a = 0; a < 3; ++a) {
        if (!(lo[a] >= 0.0f) || !(hi[a] <= float(p.dims[a]))) beyond = true;
        ilo[a] = std::clamp(int(std::floor(std::max(lo[a], -1.0f))), 0, p.dims[a] - 1);
        ihi[a] = std::clamp(int(std::floor(std::min(hi[a], float(p.dims[a])))), 0, p.dims[a] - 1);
        if (!(hi[a] >= 0.0f) || !(lo[a] <= float(p.dims[a]))) {
            p.outside += h;  // wholly outside
            return;
        }
    }
    if (beyond) p.outside += h;
    for (int z = ilo[2]; z <= ihi[2]; ++z)
        for (int y = ilo[1]; y <= ihi[1]; ++y)
            for (int x = ilo[0]; x <= ihi[0]; ++x)
                p.tiles[size_t(x) + size_t(p.dims.x) * (size_t(y) + size_t(p.dims.y) * size_t(z))] += h;
}

// n <= 64 bits of a mask from linear voxel index `start`.
uint64_t mask_bits(const VoxelMask& m, uint64_t start, uint32_t n) {
    const uint64_t w = start >> 6, s = start & 63;
    uint64_t v = m.bits[w] >> s;
    if (s + n > 64 && w + 1 < m.bits.size()) v |= m.bits[w + 1] << (64 - s);
    return n == 64 ? v : v & ((uint64_t(1) << n) - 1);
}

// Adds each tile's voxels of `m` (on the eyes' grid, tiles of `t` voxels) to its hash.
void add_mask(GeometryPrint& p, const VoxelMask& m, uint64_t which, uint32_t t) {
    std::vector<uint64_t> acc(p.tiles.size(), which);
    // A layer of tiles per task: its rows feed only its tiles, each in the order z, y of one thread.
#pragma omp parallel for schedule(dynamic, 1)
    for (int tz = 0; tz < p.dims.z; ++tz) {
        for (int z = tz * int(t); z < std::min(m.dims.z, (tz + 1) * int(t)); ++z) {
            for (int y = 0; y < m.dims.y; ++y) {
                const uint64_t row = uint64_t(m.dims.x) * (uint64_t(y) + uint64_t(m.dims.y) * uint64_t(z));
                const size_t tile_row =
                    size_t(p.dims.x) * (size_t(y / int(t)) + size_t(p.dims.y) * size_t(tz));
                for (int tx = 0; tx < p.dims.x; ++tx) {
                    uint64_t& a = acc[tile_row + size_t(tx)];
                    const uint32_t x_end = std::min(uint32_t(tx + 1) * t, uint32_t(m.dims.x));
                    for (uint32_t x = uint32_t(tx) * t; x < x_end; x += 64) {
                        const uint32_t n = std::min(64u, x_end - x);
                        const uint64_t bits = mask_bits(m, row + x, n);
                        a = XXH3_64bits_withSeed(&bits, sizeof bits, a);
                    }
                }
            }
        }
    }
    for (size_t i = 0; i < acc.size(); ++i) p.tiles[i] += Hasher(kMask).add(acc[i]).digest();
}

bool same_grid(const VoxelMask& a, const VoxelMask& b) {
    return a.origin == b.origin && a.voxel_size_m == b.voxel_size_m && a.dims == b.dims;
}

// Bounds of the changed tiles, in tile coordinates [lo, hi] inclusive.
struct TileBox {
    glm::ivec3 lo, hi;
    double volume() const {
        return double(hi.x - lo.x + 1) * double(hi.y - lo.y + 1) * double(hi.z - lo.z + 1);
    }
    TileBox joined(const TileBox& o) const { return {glm::min(lo, o.lo), glm::max(hi, o.hi)}; }
};

// The changed tiles as at most kMaxChangedBoxes boxes holding them all: the bounds of each 26-connected
// group, then (when there are too many) the least growing unions.
std::vector<TileBox> changed_boxes(const GeometryPrint& p, const std::vector<uint8_t>& changed) {
    std::vector<TileBox> boxes;
    std::vector<uint8_t> seen(changed.size(), 0);
    std::vector<uint64_t> stack;
    const auto at = [&](uint64_t i) {
        return glm::ivec3(int(i % uint64_t(p.dims.x)), int((i / uint64_t(p.dims.x)) % uint64_t(p.dims.y)),
                          int(i / (uint64_t(p.dims.x) * uint64_t(p.dims.y))));
    };
    for (uint64_t i = 0; i < changed.size(); ++i) {
        if (!changed[i] || seen[i]) continue;
        TileBox box{at(i), at(i)};
        stack.assign(1, i);
        seen[i] = 1;
        while (!stack.empty()) {
            const glm::ivec3 c = at(stack.back());
            stack.pop_back();
            box.lo = glm::min(box.lo, c);
            box.hi = glm::max(box.hi, c);
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const glm::ivec3 n = c + glm::ivec3(dx, dy, dz);
                        if (glm::any(glm::lessThan(n, glm::ivec3(0))) ||
                            glm::any(glm::greaterThanEqual(n, p.dims)))
                            continue;
                        const uint64_t j =
                            uint64_t(n.x) +
                            uint64_t(p.dims.x) * (uint64_t(n.y) + uint64_t(p.dims.y) * uint64_t(n.z));
                        if (changed[j] && !seen[j]) {
                            seen[j] = 1;
                            stack.push_back(j);
                        }
                    }
        }
        boxes.push_back(box);
    }
    // Too many groups: first unite those in the same coarse block, then the pair that grows least.
    for (int block = 8; boxes.size() > 8 * kMaxChangedBoxes; block *= 2) {
        std::map<std::array<int, 3>, TileBox> merged;
        for (const TileBox& b : boxes) {
            const std::array<int, 3> key{b.lo.x / block, b.lo.y / block, b.lo.z / block};
            auto [it, fresh] = merged.emplace(key, b);
            if (!fresh) it->second = it->second.joined(b);
        }
        boxes.clear();
        for (const auto& [key, b] : merged) boxes.push_back(b);
    }
    while (boxes.size() > kMaxChangedBoxes) {
        size_t best_i = 0, best_j = 1;
        double best = std::numeric_limits<double>::infinity();
        for (size_t i = 0; i < boxes.size(); ++i)
            for (size_t j = i + 1; j < boxes.size(); ++j) {
                const double grow =
                    boxes[i].joined(boxes[j]).volume() - boxes[i].volume() - boxes[j].volume();
                if (grow < best) {
                    best = grow;
                    best_i = i;
                    best_j = j;
                }
            }
        boxes[best_i] = boxes[best_i].joined(boxes[best_j]);
        boxes.erase(boxes.begin() + std::ptrdiff_t(best_j));
    }
    return boxes;
}

}  // namespace

GeometryPrint geometry_print(const ConservativeConfig& config, const World& world,
                             const ShrunkOccluders& occluders, const VoxelMask& eyes) {
    GeometryPrint p;
    if (eyes.empty() || eyes.voxel_size_m <= 0.0f) return p;
    uint32_t t = kTileVoxels;
    const auto tiles_of = [&](uint32_t edge) { return glm::ivec3((eyes.dims + int(edge) - 1) / int(edge)); };
    while (uint64_t(tiles_of(t).x) * uint64_t(tiles_of(t).y) * uint64_t(tiles_of(t).z) > kMaxTiles) t *= 2;
    p.origin = eyes.origin;
    p.tile_m = eyes.voxel_size_m * float(t);
    p.dims = tiles_of(t);
    p.tiles.assign(size_t(p.dims.x) * size_t(p.dims.y) * size_t(p.dims.z), 0);

    Hasher header(0);
    header.add(eyes.origin).add(eyes.voxel_size_m).add(eyes.dims).add(t);
    header.add(uint64_t(occluders.epsilon_m.size()));
    for (double e : occluders.epsilon_m) header.add(e);
    // The masks on another grid than the eyes' are printed whole, in the header.
    const std::array<const VoxelMask*, 3> masks{&eyes, &occluders.solid, &occluders.free};
    for (uint64_t m = 0; m < masks.size(); ++m) {
        if (masks[m]->empty() || same_grid(*masks[m], eyes)) {
            if (!masks[m]->empty()) add_mask(p, *masks[m], m, t);
            header.add(uint64_t(masks[m]->empty()));
        } else {
            header.add(masks[m]->origin).add(masks[m]->voxel_size_m).add(masks[m]->dims);
            header.add(XXH3_64bits(masks[m]->bits.data(), masks[m]->bits.size() * sizeof(uint64_t)));
        }
    }
    p.header = std::max<uint64_t>(header.digest(), 1);  // 0 means no print

    for (size_t i = 0; i < world.triangles.size(); ++i) {
        const Triangle& tri = world.triangles[i];
        Aabb b;
        Hasher h(kTriangle);
        for (uint32_t v : tri.v) {
            b.extend(world.positions[v]);
            h.add(world.positions[v]);
        }
        h.add(world.triangle_opaque[i]);
        if (i < world.triangle_double_sided.size()) h.add(world.triangle_double_sided[i]);
        add_element(p, b, h.digest());
    }
    for (size_t level = 0; level < occluders.boxes.size(); ++level)
        for (const Aabb& b : occluders.boxes[level]) add_element(p, b, box_hash(kShrunkBox, level, b));
    for (const Aabb& b : occluders.panels) add_element(p, b, box_hash(kPanel, 0, b));
    for (const SlantedPanel& s : occluders.slanted) {
        Hasher h(kSlanted);
        h.add(s.normal).add(s.offset).add(s.thickness);
        for (const glm::dvec3& c : s.corners) h.add(c);
        add_element(p, s.bounds, h.digest());
    }

    // The shaft pass's convex caps: a cap is used where a line meets its first polygon, but it reaches as
    // far as its neighbours, so it is printed in every tile its hull's bounds meet.
    if (config.shaft_budget > 0 && config.shaft_caps)
        for (const ConvexCap& cap : build_caps(cap_polygons(occluders.panels, occluders.slanted))) {
            if (cap.empty()) continue;
            Hasher h(kCap);
            for (size_t f = 0; f < cap.normal.size(); ++f)
                h.add(cap.normal[f]).add(cap.offset[f]).add(uint64_t(cap.opaque[f]));
            add_element(p, cap.bounds, h.digest());
        }

    const bool indexed = config.shaft_budget > 0;  // the shaft pass seeds its lines by the object's index
    p.objects.reserve(world.objects.size());
    for (size_t o = 0; o < world.objects.size(); ++o) {
        const WorldObject& obj = world.objects[o];
        Hasher h(0);
        h.add(obj.flags).add(obj.triangle_count).add(obj.bounds.min).add(obj.bounds.max);
        if (indexed) h.add(uint64_t(o));
        for (uint32_t i = obj.first_triangle; i < obj.first_triangle + obj.triangle_count; ++i) {
            for (uint32_t v : world.triangles[i].v) h.add(world.positions[v]);
            h.add(world.triangle_opaque[i]);
        }
        p.objects.push_back(h.digest());
    }
    return p;
}

double reach_margin_m(const ConservativeConfig& config, const GeometryPrint& print, float voxel_size_m) {
    const glm::vec3 span = glm::vec3(print.dims) * print.tile_m;
    const double longest = double(std::max({span.x, span.y, span.z}));
    // A depth-cube pixel spans 2 / resolution in face coordinates; a pixel is touched when its closed
    // square meets the object's rectangle, so its rays stray by at most that much per unit of depth, and
    // only depths before the object's matter. Doubled for the rounding widenings.
    return 2.0 * double(voxel_size_m) + 1e-3 + longest * 4.0 / double(std::max(config.cube_resolution, 1));
}

ReusePlan plan_reuse(Context& ctx, const ConservativeConfig& config, const World& world, const CellSet& cells,
                     const GeometryPrint& now, const ReuseSource& old) {
    const auto start = std::chrono::steady_clock::now();
    const uint32_t n_objects = uint32_t(world.objects.size());
    ReusePlan plan;
    plan.settled = PvsSet::make(uint32_t(cells.size()), n_objects);
    plan.listed = PvsSet::make(uint32_t(cells.size()), n_objects);
    ReuseFigures& f = plan.figures;
    f.pairs = uint64_t(cells.size()) * n_objects;
    const auto done = [&]() -> ReusePlan {
        f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return std::move(plan);
    };
    if (old.print.empty()) {
        plan.whole = "the old bake has no geometry print (made by a pvsbake before format 1.6)";
        return done();
    }
    if (now.empty() || old.print.header != now.header || old.print.tiles.size() != now.tiles.size()) {
        plan.whole = "the voxel grid or the epsilon ladder differs (the world's bounds changed)";
        return done();
    }
    if (old.print.outside != now.outside) {
        plan.whole = "geometry outside the voxel grid changed";
        return done();
    }
    if (old.pvs.cell_count != old.cells.size() || old.pvs.object_count != old.print.objects.size()) {
        plan.whole = "the old bake's rows do not match its cells and objects";
        return done();
    }

    // Objects: the new object k is the old object of the same print (the i-th of equal prints, the i-th).
    std::map<uint64_t, std::vector<uint32_t>> old_by_print;
    for (uint32_t o = 0; o < old.print.objects.size(); ++o) old_by_print[old.print.objects[o]].push_back(o);
    std::map<uint64_t, size_t> taken;
    std::vector<int64_t> old_object(n_objects, -1);
    for (uint32_t o = 0; o < n_objects; ++o) {
        const auto it = old_by_print.find(now.objects[o]);
        if (it == old_by_print.end()) continue;
        size_t& next = taken[now.objects[o]];
        if (next < it->second.size()) old_object[o] = it->second[next++];
    }
    f.objects_matched =
        uint64_t(std::count_if(old_object.begin(), old_object.end(), [](int64_t v) { return v >= 0; }));

    // Cells: the same box.
    std::map<std::array<float, 6>, uint32_t> old_cell_of;
    for (uint32_t c = 0; c < old.cells.size(); ++c) {
        const Aabb& b = old.cells.cells[c].bounds;
        old_cell_of.emplace(std::array<float, 6>{b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z}, c);
    }

    // Where the print changed, as boxes grown by the reach margin.
    std::vector<uint8_t> changed(now.tiles.size(), 0);
    for (size_t i = 0; i < now.tiles.size(); ++i)
        if (now.tiles[i] != old.print.tiles[i]) {
            changed[i] = 1;
            ++f.changed_tiles;
        }
    const float margin = float(reach_margin_m(config, now, cells.eyes.voxel_size_m));
    std::vector<Aabb> zones;
    for (const TileBox& b : changed_boxes(now, changed))
        zones.push_back(Aabb::of(now.origin + glm::vec3(b.lo) * now.tile_m - margin,
                                 now.origin + glm::vec3(b.hi + 1) * now.tile_m + margin));
    f.changed_boxes = zones.size();

    const auto old_cell = [&](uint32_t c) {
        const Aabb& cell = cells.cells[c].bounds;
        const auto it =
            old_cell_of.find({cell.min.x, cell.min.y, cell.min.z, cell.max.x, cell.max.y, cell.max.z});
        return it == old_cell_of.end() ? int64_t(-1) : int64_t(it->second);
    };
    // With shaft blocks (docs/ALGORITHMS.md#shaft-hierarchy) a cell's bit for an object also depends on the
    // other cells of its block: a pair is kept only when every cell of the block is found, and the box it
    // must keep clear of the edit spans the block's grid positions, so a block's cells are settled alike.
    std::vector<Aabb> reach_of(cells.size());
    std::vector<uint8_t> block_found(cells.size(), 1);
    for (uint32_t c = 0; c < cells.size(); ++c) reach_of[c] = cells.cells[c].bounds;
    const int k = config.shaft_budget > 0 ? config.shaft_block : 1;
    if (k > 1 && cells.kind == CellSet::Kind::kGrid) {
        for (const std::vector<uint32_t>& block : grid_shaft_blocks(cells, k)) {
            const float edge = cells.cell_size_m * float(k);
            const glm::vec3 lo =
                cells.origin +
                glm::floor((cells.cells[block[0]].bounds.center() - cells.origin) / edge) * edge;
            // Grown by a millimetre against the rounding of lo: a bigger box only keeps fewer pairs.
            const Aabb box = Aabb::of(lo - 1e-3f, lo + edge + 1e-3f);
            bool found = true;
            for (uint32_t c : block) found = found && old_cell(c) >= 0;
            for (uint32_t c : block) {
                reach_of[c].extend(box);
                block_found[c] = found ? 1 : 0;
            }
        }
    }

    uint64_t kept = 0, matched = 0, whole = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : kept, matched, whole)
    for (int64_t ci = 0; ci < int64_t(cells.size()); ++ci) {
        const uint32_t c = uint32_t(ci);
        const int64_t oc = old_cell(c);
        if (oc < 0) continue;
        ++matched;
        if (!block_found[c]) continue;
        const Aabb& cell = reach_of[c];
        const uint64_t* old_row = old.pvs.row(uint32_t(oc));
        uint64_t* settled = plan.settled.row(c);
        uint64_t* listed = plan.listed.row(c);
        uint32_t n_kept = 0;
        for (uint32_t o = 0; o < n_objects; ++o) {
            if (old_object[o] < 0) continue;
            const Aabb& b = world.objects[o].bounds;
            Aabb reach = cell;
            reach.extend(b);
            if (std::any_of(zones.begin(), zones.end(), [&](const Aabb& z) { return z.overlaps(reach); }))
                continue;
            const uint64_t oo = uint64_t(old_object[o]);
            settled[o >> 6] |= uint64_t(1) << (o & 63);
            if ((old_row[oo >> 6] >> (oo & 63)) & 1u) listed[o >> 6] |= uint64_t(1) << (o & 63);
            ++n_kept;
        }
        kept += n_kept;
        if (n_kept == n_objects) ++whole;
    }
    f.kept = kept;
    f.cells_matched = matched;
    f.cells_whole = whole;
    ctx.info(fmt::format(
        "reuse: {} of {} cells and {} of {} objects found in the old bake; {} tiles of {:.2f} m changed "
        "({} boxes); {:.2f} M of {:.2f} M (cell, object) pairs kept ({:.1f}%), {} cells whole",
        matched, cells.size(), f.objects_matched, n_objects, f.changed_tiles, double(now.tile_m),
        f.changed_boxes, double(kept) * 1e-6, double(f.pairs) * 1e-6,
        f.pairs ? 100.0 * double(kept) / double(f.pairs) : 0.0, whole));
    return done();
}

}  // namespace pvs
