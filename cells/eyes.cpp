// Stratified eye points in a cell and stratified directions over the sphere.
#include "cells/eyes.h"

#include "core/random.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace pvs {

Aabb eye_region(const CellSet& cells, uint32_t cell) { return cells.cells[cell].bounds; }

void sample_eye_points(const CellSet& cells, uint32_t cell, uint32_t count, uint64_t seed,
                       std::vector<glm::vec3>& out) {
    if (count == 0) return;
    const Aabb region = eye_region(cells, cell);
    Rng rng(seed, 0x4559450000000000ULL ^ cell);
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
