// SPDX-License-Identifier: MIT
// pvsbake voxels: a dense voxel grid over the world and conservative voxelization of its opaque
// triangles (after Akenine-Möller, "Fast 3D Triangle-Box Overlap Testing", JGT 2001;
// docs/ALGORITHMS.md#voxelization).
//
// Conventions: glTF axes, metres. Voxel (x, y, z) is the closed box
//   [origin + (x, y, z) * size, origin + (x + 1, y + 1, z + 1) * size];
// its index is x + dims.x * (y + dims.y * z) (x fastest, as for cells).
// Conservative: a voxel is TOUCHED when an opaque triangle overlaps its closed box (separating-axis
// test, never centre sampling), tested on the box grown by a tiny relative epsilon so rounding can
// only add touched voxels. Touched voxels stop the flood of free space; a crack between triangles
// narrower than a voxel is therefore sealed in voxels though sight may pass it: users of the flood
// must not trust a voxel seal for visibility (see voxels/flood.h).
#pragma once

#include "core/context.h"
#include "core/math.h"
#include "core/world.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

namespace pvs {

// The largest grid make_voxel_grid() accepts (a clear error beyond it): 1 G voxels, 128 MiB a bit layer.
constexpr uint64_t kMaxVoxels = uint64_t(1) << 30;

struct VoxelGrid {
    glm::vec3 origin{0.0f};
    float voxel_size_m = 0.0f;
    glm::ivec3 dims{0};

    uint64_t count() const { return uint64_t(dims.x) * uint64_t(dims.y) * uint64_t(dims.z); }
    uint64_t index(int x, int y, int z) const {
        return uint64_t(x) + uint64_t(dims.x) * (uint64_t(y) + uint64_t(dims.y) * uint64_t(z));
    }
    glm::ivec3 coords(uint64_t i) const {
        const uint64_t x = i % uint64_t(dims.x), yz = i / uint64_t(dims.x);
        return {int(x), int(yz % uint64_t(dims.y)), int(yz / uint64_t(dims.y))};
    }
    bool inside(glm::ivec3 c) const {
        return c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x < dims.x && c.y < dims.y && c.z < dims.z;
    }
    // The voxel holding p (clamped to the grid).
    glm::ivec3 voxel_of(glm::vec3 p) const {
        return glm::clamp(glm::ivec3(glm::floor((p - origin) / voxel_size_m)), glm::ivec3(0), dims - 1);
    }
    Aabb voxel_box(glm::ivec3 c) const {
        const glm::vec3 lo = origin + glm::vec3(c) * voxel_size_m;
        return Aabb::of(lo, lo + glm::vec3(voxel_size_m));
    }
    glm::vec3 voxel_center(glm::ivec3 c) const { return origin + (glm::vec3(c) + 0.5f) * voxel_size_m; }
    Aabb bounds() const { return Aabb::of(origin, origin + glm::vec3(dims) * voxel_size_m); }
};

// Word-wise passes over bit volumes (64 voxels a word), on all threads for volumes of at least
// kParallelWords words. Each word's result depends on that word alone, so the results do not depend on
// the thread count.
constexpr size_t kParallelWords = size_t(1) << 14;

// f(w) for every word index w < n; f may write word w of its volumes only.
template <class F>
void for_each_word(size_t n, F&& f) {
#pragma omp parallel for schedule(static) if (n >= kParallelWords)
    for (int64_t w = 0; w < int64_t(n); ++w) f(size_t(w));
}

// The sum of f(w) over the word indices w < n.
template <class F>
uint64_t sum_words(size_t n, F&& f) {
    uint64_t sum = 0;
#pragma omp parallel for schedule(static) reduction(+ : sum) if (n >= kParallelWords)
    for (int64_t w = 0; w < int64_t(n); ++w) sum += f(size_t(w));
    return sum;
}

// The voxel indices (64 w + bit) of the bits set in f(w) over w < n, ascending. f is called twice a word
// (a count, then the fill) and must give the same word both times.
template <class F>
std::vector<uint64_t> set_bit_indices(size_t n, F&& f) {
    constexpr size_t kRun = 4096;  // words per run: each run's count, then its indices at its offset
    const size_t runs = (n + kRun - 1) / kRun;
    std::vector<uint64_t> offset(runs + 1, 0);
#pragma omp parallel for schedule(static) if (n >= kParallelWords)
    for (int64_t r = 0; r < int64_t(runs); ++r) {
        uint64_t c = 0;
        for (size_t w = size_t(r) * kRun, end = std::min(n, w + kRun); w < end; ++w)
            c += uint64_t(__builtin_popcountll(f(w)));
        offset[size_t(r) + 1] = c;
    }
    for (size_t r = 0; r < runs; ++r) offset[r + 1] += offset[r];
    std::vector<uint64_t> out(offset[runs]);
#pragma omp parallel for schedule(static) if (n >= kParallelWords)
    for (int64_t r = 0; r < int64_t(runs); ++r) {
        uint64_t* o = out.data() + offset[size_t(r)];
        for (size_t w = size_t(r) * kRun, end = std::min(n, w + kRun); w < end; ++w)
            for (uint64_t bits = f(w); bits; bits &= bits - 1)
                *o++ = uint64_t(w) * 64 + uint64_t(__builtin_ctzll(bits));
    }
    return out;
}

// One bit per voxel.
struct BitVolume {
    std::vector<uint64_t> words;

    void reset(uint64_t bits) { words.assign((bits + 63) / 64, 0); }
    bool get(uint64_t i) const { return (words[i >> 6] >> (i & 63)) & 1u; }
    void set(uint64_t i) { words[i >> 6] |= uint64_t(1) << (i & 63); }
    // set(), safe while other threads set bits of the same volume (an atomic OR; read only after they stop).
    void set_atomic(uint64_t i) {
        std::atomic_ref<uint64_t>(words[i >> 6]).fetch_or(uint64_t(1) << (i & 63), std::memory_order_relaxed);
    }
    void clear(uint64_t i) { words[i >> 6] &= ~(uint64_t(1) << (i & 63)); }
    uint64_t count() const {
        return sum_words(words.size(), [&](size_t w) { return uint64_t(__builtin_popcountll(words[w])); });
    }
};

// A grid of voxels of `voxel_size_m` over `bounds` grown by `pad_voxels` on every side (so the space
// around the world is free and a flood can reach the grid's border). Throws pvs::Error (bad input)
// naming --voxel-size when it would exceed kMaxVoxels.
VoxelGrid make_voxel_grid(const Aabb& bounds, double voxel_size_m, int pad_voxels);

// The voxels make_voxel_grid(bounds, voxel_size_m, pad_voxels) would make (saturating: never overflows).
double voxel_grid_count(const Aabb& bounds, double voxel_size_m, int pad_voxels);

// The padding of a world's voxel grid: kVoidPadM of empty space around the world, at least 2 voxels.
constexpr double kVoidPadM = 1.0;  // [Units: m]
int void_pad_voxels(double voxel_size_m);

// The default voxel size for a world: `preferred_m`, or the least coarser size (within 1%) whose grid,
// padded by void_pad_voxels(), holds at most `max_voxels`. Any shape: a world a thousand kilometres long
// and a few metres wide gets voxels whose padded grid is within the cap.
double default_voxel_size(const Aabb& bounds, double preferred_m, uint64_t max_voxels);

// Does the triangle overlap the closed box (center, half size)? Exact separating-axis test (13 axes).
bool triangle_box_overlap(glm::vec3 box_center, glm::vec3 box_half, glm::vec3 a, glm::vec3 b, glm::vec3 c);

// The set grown by `radius` voxels in the Chebyshev metric (the 26-neighbourhood applied `radius`
// times): separable, per axis O(log radius) word-wise shifts of the whole volume.
BitVolume dilate(const VoxelGrid& grid, const BitVolume& in, int radius);

// Clears every voxel within k of the grid's faces (a coordinate < k or >= dims - k). Word-wise.
void clear_border(const VoxelGrid& grid, BitVolume& volume, int k);

// Marks every voxel an opaque triangle touches. When `upward` is given, also marks the voxels touched by
// opaque triangles facing up (normal.y >= min_up_cos; floors a player can stand on); when `see_through` is
// given, the voxels see-through triangles touch (glass a player cannot walk through). Parallel (OpenMP).
void voxelize_opaque(Context& ctx, const World& world, const VoxelGrid& grid, BitVolume& touched,
                     BitVolume* upward = nullptr, float min_up_cos = 0.5f, BitVolume* see_through = nullptr);

}  // namespace pvs
