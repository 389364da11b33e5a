// SPDX-License-Identifier: MIT
// Stratified eye points in a cell and stratified directions over the sphere.
#include "cells/eyes.h"

#include "core/random.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace pvs {

namespace {

// Calls visit(i) for every set voxel i of `mask` that overlaps the box with volume (a voxel only touching
// a face does not count), in index order, until visit returns true. Returns whether one did.
template <class Visit>
bool visit_set_voxels_in(const VoxelMask& mask, const Aabb& box, Visit&& visit) {
    if (mask.empty()) return false;
    const float s = mask.voxel_size_m;
    glm::ivec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = std::max(0, int(std::floor((box.min[a] - mask.origin[a]) / s)));
        hi[a] = std::min(mask.dims[a] - 1, int(std::ceil((box.max[a] - mask.origin[a]) / s)) - 1);
    }
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) {
                const uint64_t i =
                    uint64_t(x) + uint64_t(mask.dims.x) * (uint64_t(y) + uint64_t(mask.dims.y) * uint64_t(z));
                if (mask.get(i) && visit(i)) return true;
            }
    return false;
}

// The voxel coordinates of index i of the mask, as floats.
glm::vec3 voxel_coords(const VoxelMask& mask, uint64_t i) {
    const uint64_t x = i % uint64_t(mask.dims.x), yz = i / uint64_t(mask.dims.x);
    return {float(x), float(yz % uint64_t(mask.dims.y)), float(yz / uint64_t(mask.dims.y))};
}

}  // namespace

bool mask_meets_box(const VoxelMask& mask, const Aabb& box) {
    return visit_set_voxels_in(mask, box, [](uint64_t) { return true; });
}

Aabb eye_region(const VoxelMask& eyes, const Aabb& box) {
    if (eyes.empty()) return box;
    Aabb region;
    visit_set_voxels_in(eyes, box, [&](uint64_t i) {
        const glm::vec3 v = voxel_coords(eyes, i);
        region.extend(eyes.origin + v * eyes.voxel_size_m);
        region.extend(eyes.origin + (v + 1.0f) * eyes.voxel_size_m);
        return false;
    });
    if (region.is_empty()) return region;
    region.min = glm::max(region.min, box.min);
    region.max = glm::min(region.max, box.max);
    return region;
}

std::vector<uint64_t> eye_voxels_in(const VoxelMask& eyes, const Aabb& region) {
    std::vector<uint64_t> voxels;
    if (eyes.empty()) return voxels;
    visit_set_voxels_in(eyes, region, [&](uint64_t i) {
        voxels.push_back(i);
        return false;
    });
    return voxels;
}

void sample_eye_points_in(const VoxelMask& eyes, const Aabb& region, uint64_t stream, uint32_t count,
                          uint64_t seed, std::vector<glm::vec3>& out) {
    if (count == 0) return;
    sample_eye_points_from(eyes, region, eyes.empty() ? std::vector<uint64_t>() : eye_voxels_in(eyes, region),
                           stream, count, seed, out);
}

void sample_eye_points_from(const VoxelMask& eyes, const Aabb& region, const std::vector<uint64_t>& voxels,
                            uint64_t stream, uint32_t count, uint64_t seed, std::vector<glm::vec3>& out) {
    if (count == 0) return;
    Rng rng(seed, 0x4559450000000000ULL ^ stream);
    if (!eyes.empty()) {
        // Eyes only in the eye space: uniform points of (eye voxel ∩ box), the box's eye voxels split into
        // `count` runs in index order with one random voxel per run. No eye voxel meets the box: no eyes
        // (never a point that might be inside solid).
        const VoxelMask& m = eyes;
        const uint64_t n = voxels.size();
        for (uint32_t k = 0; k < count && n > 0; ++k) {
            const uint64_t a = uint64_t(k) * n / count, b = std::max(a + 1, uint64_t(k + 1) * n / count);
            const uint64_t i = voxels[std::min<uint64_t>(n - 1, a + uint64_t(rng.uniform() * float(b - a)))];
            const glm::vec3 v = voxel_coords(m, i);
            const glm::vec3 lo = glm::max(m.origin + v * m.voxel_size_m, region.min);
            const glm::vec3 hi = glm::min(m.origin + (v + 1.0f) * m.voxel_size_m, region.max);
            const glm::vec3 jitter(rng.uniform(), rng.uniform(), rng.uniform());
            out.push_back(glm::clamp(lo + (hi - lo) * jitter, lo, hi));
        }
        return;
    }
    uint32_t k = 1;
    while (k * k * k < count) ++k;
    const uint32_t strata = k * k * k;
    // Shuffle the strata and take the first `count`, so any count spreads over the whole region.
    std::vector<uint32_t> order(strata);
    std::iota(order.begin(), order.end(), 0u);
    for (uint32_t i = strata - 1; i > 0; --i) std::swap(order[i], order[rng.below(i + 1)]);
    const glm::vec3 size = region.size();
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t s = order[i];
        const glm::vec3 stratum(float(s % k), float((s / k) % k), float(s / (k * k)));
        const glm::vec3 jitter(rng.uniform(), rng.uniform(), rng.uniform());
        glm::vec3 p = region.min + size * ((stratum + jitter) / float(k));
        out.push_back(glm::clamp(p, region.min, region.max));
    }
}

void sample_sphere_directions(uint32_t count, uint64_t seed, uint64_t stream, std::vector<glm::vec3>& out) {
    if (count == 0) return;
    Rng rng(seed, 0x4449520000000000ULL ^ stream);
    // a strata in cos(theta) by b in phi, a*b >= count, phi strata twice as many (square-ish on the sphere).
    const uint32_t a = std::max(1u, uint32_t(std::lround(std::sqrt(double(count) / 2.0))));
    const uint32_t b = (count + a - 1) / a;
    constexpr float kTwoPi = 6.28318530717958647692f;
    // A random rotation of phi per stream keeps strata boundaries from lining up across eyes.
    const float phi0 = rng.uniform() * kTwoPi;
    // Strata are emitted in 4 x 4 tiles, so consecutive rays (Embree's packets of 8 or 16) point close
    // together: coherent streams trace faster. The set of strata is the same as in row order.
    constexpr uint32_t kTile = 4;
    const size_t first = out.size();
    out.reserve(first + count);
    for (uint32_t tv = 0; tv < b; tv += kTile)
        for (uint32_t tu = 0; tu < a; tu += kTile)
            for (uint32_t iv = tv; iv < std::min(b, tv + kTile); ++iv)
                for (uint32_t iu = tu; iu < std::min(a, tu + kTile); ++iu) {
                    if (iv * a + iu >= count) continue;
                    const float z = 1.0f - 2.0f * ((float(iu) + rng.uniform()) / float(a));
                    const float phi = phi0 + kTwoPi * ((float(iv) + rng.uniform()) / float(b));
                    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
                    out.emplace_back(r * std::cos(phi), z, r * std::sin(phi));
                }
}
}  // namespace pvs
