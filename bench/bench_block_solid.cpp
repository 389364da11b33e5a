// SPDX-License-Identifier: MIT
// bench_block_solid: how much solid sight leaves when it starts from one block of the eye space instead of
// from all of it (open levels).
//
//   bench_block_solid WORLD.glb [--play-height H] [--voxel-size V] [--block B] [--range R]
//                     [--audit EYES [--audit-points P] [--epsilon E] [--reach R2]]
//
// The conservative solver's occluders live in the solid: voxels no straight line of sight from the eye
// space reaches (voxels/flood.h sight_reach), less the voxels opaque triangles touch. One eye that sees
// into a hollow wall (through a gap to the outside, or over a wall that lost its top face) unmakes that
// wall as an occluder for every cell. Occluders per block of cells would only need the block's own eyes
// to miss it. For every block (B x B metres in x and z, all heights) holding eyes, this prints the solid
// within R metres of the block when sight starts from all eyes, and when it starts from the block's eyes
// only. JSON on stdout.
// --audit EYES also builds the bake's occluders per block (occluders/synthesis.h, blocks of B metres,
// --reach R2 around them, --epsilon E) and audits them (audit_block_occluders): EYES fresh eye points per
// block, P random points in every box of its set; "audit_reached" counts rays that get inside one (each is
// a failure of the argument).
#include "cells/view_volume.h"
#include "core/context.h"
#include "io/gltf_loader.h"
#include "occluders/synthesis.h"
#include "rays/ray_scene.h"
#include "voxels/flood.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

using namespace pvs;

int main(int argc, char** argv) {
    if (argc < 2) {
        std::cerr << "usage: bench_block_solid WORLD.glb [--play-height H] [--voxel-size V] [--block B] "
                     "[--range R]\n";
        return 2;
    }
    ViewVolumeConfig vc;
    vc.voxel_size_m = 0.25;
    float block = 16.0f, range = 24.0f;
    uint32_t audit_eyes = 0, audit_points = 2;
    double epsilon = 0.25, reach = OccluderConfig{}.block_reach_m;
    for (int i = 2; i + 1 < argc; i += 2) {
        const std::string k = argv[i];
        const double v = std::atof(argv[i + 1]);
        if (k == "--play-height")
            vc.play_height_m = v;
        else if (k == "--voxel-size")
            vc.voxel_size_m = v;
        else if (k == "--block")
            block = float(v);
        else if (k == "--range")
            range = float(v);
        else if (k == "--audit")
            audit_eyes = uint32_t(v);
        else if (k == "--audit-points")
            audit_points = uint32_t(v);
        else if (k == "--epsilon")
            epsilon = v;
        else if (k == "--reach")
            reach = v;
        else {
            std::cerr << "bench_block_solid: unknown option " << k << "\n";
            return 2;
        }
    }
    if (!(block > 0.0f) || !(range >= 0.0f) || !(epsilon > 0.0) || !(reach >= 0.0)) {
        std::cerr << "bench_block_solid: --block and --epsilon must be > 0, --range and --reach >= 0\n";
        return 2;
    }
    try {
        Context ctx(Context::Options{LogLevel::kWarning, true, nullptr});
        const World w = load_world(ctx, argv[1]);
        const ViewVolume v = build_view_volume(ctx, vc, w);
        const VoxelGrid& g = v.grid;
        BitVolume all;
        all.reset(g.count());
        all.words = v.eyes.bits;
        const BitVolume reach_all = sight_reach(g, v.touched, all);
        const double voxel_m3 = double(g.voxel_size_m) * g.voxel_size_m * g.voxel_size_m;
        const auto centre = [&](int x, int y, int z) {
            return g.origin + (glm::vec3(x, y, z) + 0.5f) * g.voxel_size_m;
        };
        const auto solid_m3 = [&](const BitVolume& reached, const Aabb& near) {
            uint64_t n = 0;
            for (int z = 0; z < g.dims.z; ++z)
                for (int y = 0; y < g.dims.y; ++y)
                    for (int x = 0; x < g.dims.x; ++x) {
                        const uint64_t i = g.index(x, y, z);
                        if (!reached.get(i) && !v.touched.get(i) && near.contains(centre(x, y, z))) ++n;
                    }
            return double(n) * voxel_m3;
        };
        nlohmann::json blocks = nlohmann::json::array();
        double sum_all = 0.0, sum_block = 0.0;
        for (float bx = w.bounds.min.x; bx < w.bounds.max.x; bx += block)
            for (float bz = w.bounds.min.z; bz < w.bounds.max.z; bz += block) {
                BitVolume src;
                src.reset(g.count());
                uint64_t n = 0;
                for (int z = 0; z < g.dims.z; ++z)
                    for (int y = 0; y < g.dims.y; ++y)
                        for (int x = 0; x < g.dims.x; ++x) {
                            const glm::vec3 c = centre(x, y, z);
                            const uint64_t i = g.index(x, y, z);
                            if (c.x >= bx && c.x < bx + block && c.z >= bz && c.z < bz + block &&
                                all.get(i)) {
                                src.set(i);
                                ++n;
                            }
                        }
                if (n == 0) continue;
                const BitVolume reached = sight_reach(g, v.touched, src);
                const Aabb near = Aabb::of({bx - range, w.bounds.min.y - 1.0f, bz - range},
                                           {bx + block + range, w.bounds.max.y + 1.0f, bz + block + range});
                const double s_all = solid_m3(reach_all, near), s_block = solid_m3(reached, near);
                sum_all += s_all;
                sum_block += s_block;
                blocks.push_back({{"x", bx},
                                  {"z", bz},
                                  {"eye_voxels", n},
                                  {"solid_from_all_eyes_m3", s_all},
                                  {"solid_from_block_eyes_m3", s_block},
                                  {"ratio", s_block / std::max(1.0, s_all)}});
            }
        std::vector<double> ratios;
        for (const auto& b : blocks) ratios.push_back(b["ratio"].get<double>());
        std::sort(ratios.begin(), ratios.end());
        nlohmann::json out = {{"bench", "block_solid"},
                              {"world", argv[1]},
                              {"voxel_size_m", g.voxel_size_m},
                              {"play_height_m", vc.play_height_m},
                              {"block_m", block},
                              {"range_m", range},
                              {"blocks", blocks},
                              {"median_ratio", ratios.empty() ? 0.0 : ratios[ratios.size() / 2]},
                              {"min_ratio", ratios.empty() ? 0.0 : ratios.front()},
                              {"sum_ratio", sum_block / std::max(1.0, sum_all)}};
        if (audit_eyes > 0) {
            RayScene scene(ctx, w);
            OccluderConfig oc;
            oc.block_reach_m = reach;
            OccluderFigures f;
            ShrunkOccluders shrunk;
            synthesize_occluders(ctx, oc, w, v, scene, f, epsilon, 4, &shrunk);
            const BlockFigures bf =
                synthesize_block_occluders(ctx, oc, w, v, scene, v.view_bounds.min, block, shrunk);
            const BlockAudit a = audit_block_occluders(v, scene, shrunk, audit_eyes, audit_points, 99);
            out["audit"] = {{"epsilon_m", epsilon},
                            {"reach_m", reach},
                            {"blocks_with_own_occluders", bf.blocks_used},
                            {"own_boxes", bf.boxes},
                            {"boxes_dropped_by_second_check", bf.boxes_dropped},
                            {"synthesis_seconds", bf.seconds},
                            {"audit_eyes_per_block", audit_eyes},
                            {"audit_points_per_box", audit_points},
                            {"audit_rays", a.rays},
                            {"audit_reached", a.reached},
                            {"audit_first", a.first}};
        }
        std::cout << out.dump(2) << "\n";
    } catch (const std::exception& e) {
        std::cerr << "bench_block_solid: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
