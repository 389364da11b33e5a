// SPDX-License-Identifier: MIT
// bench_vis_compare: a bake's PVS against the map compiler's own PVS and against dense rays, at the same
// eye points.
//
//   bench_vis_compare WORLD.glb BAKE.h5 [--vis WORLD.vis.json] [--eyes N] [--rays R] [--seed S]
//                     [--lower-bound-eyes E]
//
// Eye points: random points of the bake's eye space that the compiler's BSP (the .vis.json beside the
// world) also calls playable. At each: the share of the world's triangles in the objects the bake's cell
// lists, the share the compiler's cluster PVS lets through (cluster_visible_triangle_fraction), the share
// in the objects R rays over the sphere actually reach from that point (a floor no cell-based PVS can go
// below), and the share the lower bound of the same cell lets through: the AGGRESSIVE sampled PVS of the
// bake's own cells with E eye points each (default 64; what `pvsbake bake --mode sampled --eyes E` lists
// for them, 250 M rays at most; 0 = not computed): what the cells really see, as far as E eyes tell, and so
// what no conservative PVS of these cells can go below. Prints JSON: means, medians, the ratios bake /
// compiler and bake / lower bound, and the share of the bake's eye voxels the compiler calls solid or
// outside.
#include "bench/bench_util.h"
#include "cells/eyes.h"
#include "core/random.h"
#include "io/bake_file.h"
#include "io/gltf_loader.h"
#include "rays/ray_sampler.h"
#include "rays/ray_scene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

using pvs::bench::mean;
using pvs::bench::median;

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(
            stderr,
            "usage: bench_vis_compare WORLD.glb BAKE.h5 [--vis V.json] [--eyes N] [--rays R] [--seed S] "
            "[--lower-bound-eyes E]\n");
        return 2;
    }
    const std::string world_path = argv[1], bake_path = argv[2];
    std::string vis_path = world_path.substr(0, world_path.rfind('.')) + ".vis.json";
    uint32_t n_eyes = 200, n_rays = 100000, lower_bound_eyes = 64;
    uint64_t seed = 1;
    for (int a = 3; a + 1 < argc; a += 2) {
        if (!std::strcmp(argv[a], "--vis"))
            vis_path = argv[a + 1];
        else if (!std::strcmp(argv[a], "--eyes"))
            n_eyes = uint32_t(std::atoi(argv[a + 1]));
        else if (!std::strcmp(argv[a], "--rays"))
            n_rays = uint32_t(std::atoi(argv[a + 1]));
        else if (!std::strcmp(argv[a], "--seed"))
            seed = std::strtoull(argv[a + 1], nullptr, 10);
        else if (!std::strcmp(argv[a], "--lower-bound-eyes"))
            lower_bound_eyes = uint32_t(std::atoi(argv[a + 1]));
    }
    try {
        pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
        const pvs::World world = pvs::load_world(ctx, world_path);
        const pvs::BakeData bake = pvs::read_bake_file(bake_path);
        if (bake.objects.size() != world.objects.size()) {
            std::fprintf(stderr, "error: %s was not baked from %s\n", bake_path.c_str(), world_path.c_str());
            return 2;
        }
        std::ifstream in(vis_path);
        if (!in) {
            std::fprintf(stderr, "error: %s: cannot read the compiler's visibility\n", vis_path.c_str());
            return 2;
        }
        const pvs::bench::CompilerVis vis = pvs::bench::CompilerVis::from_json(nlohmann::json::parse(in));
        auto cluster_of = [&](glm::vec3 p) { return vis.cluster_of(p); };
        const double total = double(world.triangles.size());
        pvs::RayScene scene(ctx, world);
        // The lower bound: the sampled PVS of the bake's cells (rays/ray_sampler.h), as the CLI's sampled
        // mode makes it with --eyes lower_bound_eyes.
        pvs::SampledPvs lower;
        if (lower_bound_eyes > 0) {
            pvs::SampledPvsConfig sampled;
            sampled.rays.eyes_per_cell = lower_bound_eyes;
            lower = pvs::bake_sampled_pvs(ctx, sampled, world, scene, bake.cells);
        }
        std::vector<glm::vec3> dirs;
        pvs::sample_sphere_directions(n_rays, seed, 0, dirs);
        pvs::Rng rng(seed, 3);
        std::vector<double> ours, compiler, seen, ratio, bound, over_bound;
        const pvs::Aabb box = world.bounds;
        for (uint32_t tries = 0; ours.size() < n_eyes && tries < 1000 * n_eyes; ++tries) {
            const glm::vec3 p = box.min + box.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
            if (!bake.cells.eyes.empty() && !bake.cells.eyes.contains(p)) continue;
            const int32_t cell = bake.cells.find(p);
            if (cell < 0) continue;
            const int cluster = cluster_of(p);
            if (cluster < 0 || !vis.has_fraction(cluster)) continue;
            double listed = 0.0, bound_listed = 0.0;
            for (uint32_t o = 0; o < bake.objects.size(); ++o) {
                if (bake.pvs.test(uint32_t(cell), o)) listed += bake.objects[o].triangle_count;
                if (lower_bound_eyes > 0 && lower.pvs.test(uint32_t(cell), o))
                    bound_listed += bake.objects[o].triangle_count;
            }
            std::vector<pvs::RayTouch> touches;
            scene.trace(p, dirs.data(), uint32_t(dirs.size()), touches);
            std::vector<uint8_t> hit(world.objects.size(), 0);
            for (const pvs::RayTouch& t : touches) hit[t.object] = 1;
            double visible = 0.0;
            for (size_t o = 0; o < hit.size(); ++o)
                if (hit[o]) visible += world.objects[o].triangle_count;
            const double c = vis.fraction_of(cluster);
            ours.push_back(listed / total);
            compiler.push_back(c);
            seen.push_back(visible / total);
            if (c > 0) ratio.push_back(listed / total / c);
            if (lower_bound_eyes > 0) {
                bound.push_back(bound_listed / total);
                if (bound_listed > 0) over_bound.push_back(listed / bound_listed);
            }
        }
        // How much of the bake's eye space the compiler calls solid or outside (cluster -1): eyes there,
        // inside walls or out in the void of a leaking level, see the backs of everything.
        uint64_t eye_voxels = 0, eye_voxels_outside = 0;
        const pvs::VoxelMask& em = bake.cells.eyes;
        for (int z = 0; z < em.dims.z; ++z)
            for (int y = 0; y < em.dims.y; ++y)
                for (int x = 0; x < em.dims.x; ++x) {
                    const uint64_t i =
                        uint64_t(x) + uint64_t(em.dims.x) * (uint64_t(y) + uint64_t(em.dims.y) * uint64_t(z));
                    if (!em.get(i)) continue;
                    ++eye_voxels;
                    eye_voxels_outside +=
                        cluster_of(em.origin + (glm::vec3(x, y, z) + 0.5f) * em.voxel_size_m) < 0;
                }
        nlohmann::ordered_json out;
        out["bench"] = "vis_compare";
        out["world"] = world_path;
        out["bake"] = bake_path;
        out["pvs_kind"] = bake.conservative ? "conservative" : "aggressive";
        out["eyes"] = ours.size();
        out["rays_per_eye"] = n_rays;
        out["bake_triangle_share_mean"] = mean(ours);
        out["bake_triangle_share_median"] = median(ours);
        out["compiler_triangle_share_mean"] = mean(compiler);
        out["compiler_triangle_share_median"] = median(compiler);
        out["rays_triangle_share_mean"] = mean(seen);
        out["bake_over_compiler_of_means"] = mean(compiler) > 0 ? mean(ours) / mean(compiler) : 0.0;
        out["bake_over_compiler_median"] = median(ratio);
        out["lower_bound_eyes_per_cell"] = lower_bound_eyes;
        if (lower_bound_eyes > 0) {
            out["lower_bound_rays_per_eye"] = lower.rays_per_eye;
            out["lower_bound_triangle_share_mean"] = mean(bound);
            out["lower_bound_triangle_share_median"] = median(bound);
            out["lower_bound_over_compiler_of_means"] =
                mean(compiler) > 0 ? mean(bound) / mean(compiler) : 0.0;
            out["bake_over_lower_bound_of_means"] = mean(bound) > 0 ? mean(ours) / mean(bound) : 0.0;
            out["bake_over_lower_bound_median"] = median(over_bound);
            out["lower_bound_seconds"] = lower.seconds;
        }
        out["eye_voxels"] = eye_voxels;
        out["eye_voxels_in_compiler_solid_share"] =
            eye_voxels ? double(eye_voxels_outside) / double(eye_voxels) : 0.0;
        std::cout << out.dump(2) << std::endl;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}
