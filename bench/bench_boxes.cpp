// SPDX-License-Identifier: MIT
// bench_boxes: occluder synthesis (occluders/boxes.h) on random blob grids, against its reference.
//
//   bench_boxes [--repeats R] [--sizes 64,128,256] [--seed S]
//
// Two families of grids of N^3 voxels (0.25 m): "blobs" (random solid boxes, holes and noise voxels) and
// "carved" (a full grid with rooms and corridors carved out: the solid outside a sealed level). Times
// grow_boxes with the default BoxConfig (median of the repeats) and reports the boxes grown and kept and
// the share of solid the kept boxes cover. On the first (smallest) grid of each family it also times
// grow_boxes_reference once, checks that both give the same boxes and gives the ratio. Prints one JSON
// object.
#include "bench/bench_util.h"
#include "core/random.h"
#include "occluders/boxes.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

namespace {

using pvs::bench::median;
using pvs::bench::seconds_since;

void fill(const pvs::VoxelGrid& g, pvs::BitVolume& v, glm::ivec3 lo, glm::ivec3 hi, bool value) {
    lo = glm::max(lo, glm::ivec3(0));
    hi = glm::min(hi, g.dims - 1);
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) {
                if (value)
                    v.set(g.index(x, y, z));
                else
                    v.clear(g.index(x, y, z));
            }
}

// "blobs": 60 random boxes (edges up to N/3), minus small random holes, plus 0.5% noise voxels.
pvs::BitVolume random_blobs(const pvs::VoxelGrid& g, uint64_t seed) {
    pvs::Rng rng(seed, uint64_t(g.dims.x));
    pvs::BitVolume v;
    v.reset(g.count());
    const int n = g.dims.x;
    auto corner = [&] {
        return glm::ivec3(int(rng.below(uint32_t(n))), int(rng.below(uint32_t(n))),
                          int(rng.below(uint32_t(n))));
    };
    auto extent = [&](int most) {
        return glm::ivec3(int(rng.below(uint32_t(most))), int(rng.below(uint32_t(most))),
                          int(rng.below(uint32_t(most))));
    };
    const int blobs = 60, holes = 40 * n / 16;
    for (int b = 0; b < blobs; ++b) {
        const glm::ivec3 lo = corner();
        fill(g, v, lo, lo + extent(n / 3), true);
    }
    for (int h = 0; h < holes; ++h) {
        const glm::ivec3 lo = corner();
        fill(g, v, lo, lo + extent(std::max(2, n / 32)), false);
    }
    for (uint64_t i = 0; i < g.count(); ++i) {
        if (rng.below(1000) < 5) v.set(i);
    }
    return v;
}

// "carved": the solid of a sealed level (everything the flood of free space does not reach): a full
// grid with 40 rooms (edges N/16..N/4) and 120 corridors (N/64 + 1 wide, up to N/2 long) carved out.
pvs::BitVolume carved_level(const pvs::VoxelGrid& g, uint64_t seed) {
    pvs::Rng rng(seed, uint64_t(g.dims.x) + 1000);
    pvs::BitVolume v;
    v.reset(g.count());
    const int n = g.dims.x;
    fill(g, v, glm::ivec3(0), g.dims - 1, true);
    auto below = [&](int m) { return int(rng.below(uint32_t(std::max(1, m)))); };
    for (int r = 0; r < 40; ++r) {
        const glm::ivec3 lo(below(n), below(n), below(n));
        const glm::ivec3 e(n / 16 + below(n / 4 - n / 16), n / 16 + below(n / 4 - n / 16),
                           n / 16 + below(n / 4 - n / 16));
        fill(g, v, lo, lo + e, false);
    }
    for (int c = 0; c < 120; ++c) {
        const glm::ivec3 lo(below(n), below(n), below(n));
        glm::ivec3 e(n / 64);
        e[below(3)] = below(n / 2);
        fill(g, v, lo, lo + e, false);
    }
    return v;
}

}  // namespace

int main(int argc, char** argv) {
    int repeats = 3;
    uint64_t seed = 1;
    std::vector<int> sizes = {64, 128, 256};
    for (int a = 1; a + 1 < argc; a += 2) {
        if (!std::strcmp(argv[a], "--repeats")) {
            repeats = std::max(1, std::atoi(argv[a + 1]));
        } else if (!std::strcmp(argv[a], "--seed")) {
            seed = std::strtoull(argv[a + 1], nullptr, 10);
        } else if (!std::strcmp(argv[a], "--sizes")) {
            sizes.clear();
            for (const char* p = argv[a + 1]; *p;) {
                sizes.push_back(std::max(1, std::atoi(p)));
                p = std::strchr(p, ',') ? std::strchr(p, ',') + 1 : p + std::strlen(p);
            }
        } else {
            std::fprintf(stderr, "usage: bench_boxes [--repeats R] [--sizes 64,128,256] [--seed S]\n");
            return 2;
        }
    }
    pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
    const pvs::BoxConfig config;

    nlohmann::ordered_json out;
    out["bench"] = "boxes";
    out["repeats"] = repeats;
    out["seed"] = seed;
    out["voxel_size_m"] = 0.25;
    out["max_boxes"] = config.max_boxes;
    out["min_box_volume_m3"] = config.min_box_volume_m3;
    out["min_added_share"] = config.min_added_share;
    nlohmann::ordered_json grids = nlohmann::ordered_json::array();
    for (const char* family : {"blobs", "carved"})
        for (size_t k = 0; k < sizes.size(); ++k) {
            const int n = sizes[k];
            pvs::VoxelGrid g;
            g.voxel_size_m = 0.25f;
            g.dims = glm::ivec3(n);
            const bool blobs = !std::strcmp(family, "blobs");
            const pvs::BitVolume solid = blobs ? random_blobs(g, seed) : carved_level(g, seed);
            std::vector<double> times;
            std::vector<pvs::VoxelBox> boxes;
            pvs::BoxStats stats;
            for (int r = 0; r < repeats; ++r) {
                const auto t0 = std::chrono::steady_clock::now();
                boxes = pvs::grow_boxes(ctx, g, solid, config, &stats);
                times.push_back(seconds_since(t0));
            }
            nlohmann::ordered_json q;
            q["family"] = family;
            q["edge_voxels"] = n;
            q["voxels"] = g.count();
            q["solid_voxels"] = stats.solid_voxels;
            q["grow_boxes_s"] = median(times);
            q["grown"] = stats.grown;
            q["kept"] = stats.kept;
            q["covered_voxels"] = stats.covered_voxels;
            q["coverage"] =
                stats.solid_voxels ? double(stats.covered_voxels) / double(stats.solid_voxels) : 0.0;
            q["largest_box_voxels"] = boxes.empty() ? 0 : boxes.front().volume();
            if (k == 0) {
                const auto t0 = std::chrono::steady_clock::now();
                const std::vector<pvs::VoxelBox> reference = pvs::grow_boxes_reference(g, solid, config);
                const double reference_s = seconds_since(t0);
                q["reference_s"] = reference_s;
                q["reference_over_fast"] = reference_s / median(times);
                q["reference_matches"] = reference == boxes;
            }
            grids.push_back(q);
        }
    out["grids"] = grids;
    std::cout << out.dump(2) << std::endl;
    return 0;
}
