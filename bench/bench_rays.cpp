// SPDX-License-Identifier: MIT
// bench_rays: ray throughput of the verifier's tracing against plain Embree loops, on one scene in one run.
//
//   bench_rays WORLD.glb [--rays N] [--repeats R] [--threads T]
//
// For each build quality (low, medium, high): the scene build time, then the same eye points and
// directions traced by
//   stream     RayScene::trace: rtcIntersect1M coherent streams of 256, see-through filter (what we use)
//   intersect1 RayScene::trace_reference: one rtcIntersect1 per ray, same filter (same answer)
//   repeated1  RayScene::trace_repeated: rtcIntersect1 restarted past each see-through hit (same answer)
//   occluded1  a plain rtcOccluded1 loop (a cheaper question: is anything hit at all?)
// all parallel over eyes with OpenMP. Prints one JSON object: medians of the repeats in M rays/s, and
// ratios to occluded1 taken in the same run.
#include "bench/bench_util.h"
#include "cells/eyes.h"
#include "core/random.h"
#include "io/gltf_loader.h"
#include "rays/ray_scene.h"

#include <omp.h>
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

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: bench_rays WORLD.glb [--rays N] [--repeats R] [--threads T]\n");
        return 2;
    }
    const std::string world_path = argv[1];
    uint64_t total_rays = 4'000'000;
    int repeats = 3, threads = 0;
    for (int a = 2; a + 1 < argc; a += 2) {
        if (!std::strcmp(argv[a], "--rays"))
            total_rays = std::strtoull(argv[a + 1], nullptr, 10);
        else if (!std::strcmp(argv[a], "--repeats"))
            repeats = std::max(1, std::atoi(argv[a + 1]));
        else if (!std::strcmp(argv[a], "--threads"))
            threads = std::atoi(argv[a + 1]);
    }
    if (threads > 0) omp_set_num_threads(threads);
    pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
    const pvs::World world = pvs::load_world(ctx, world_path);

    // Eye points spread over the world bounds, 1024 rays each over the sphere.
    constexpr uint32_t kRaysPerEye = 1024;
    const uint32_t eyes = uint32_t(std::max<uint64_t>(1, total_rays / kRaysPerEye));
    std::vector<glm::vec3> eye_points(eyes), dirs;
    pvs::Rng rng(1, 2);
    for (auto& e : eye_points) {
        e = world.bounds.min + world.bounds.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
    }
    for (uint32_t e = 0; e < eyes; ++e) pvs::sample_sphere_directions(kRaysPerEye, 3, e, dirs);
    const double rays = double(eyes) * kRaysPerEye;

    nlohmann::ordered_json out;
    out["bench"] = "rays";
    out["world"] = world_path;
    out["triangles"] = world.triangles.size();
    out["rays"] = rays;
    out["threads"] = omp_get_max_threads();
    out["repeats"] = repeats;
    const std::pair<const char*, pvs::BuildQuality> qualities[] = {{"low", pvs::BuildQuality::kLow},
                                                                   {"medium", pvs::BuildQuality::kMedium},
                                                                   {"high", pvs::BuildQuality::kHigh}};
    for (const auto& [name, quality] : qualities) {
        const auto t0 = std::chrono::steady_clock::now();
        pvs::RayScene scene(ctx, world, quality, threads);
        const double build_s = seconds_since(t0);
        std::vector<double> stream, single, repeated, occluded;
        uint64_t touches_stream = 0, touches_single = 0, touches_repeated = 0;
        // Times one way of tracing every eye's rays; returns M rays/s and records the touches seen.
        using TraceFn =
            void (pvs::RayScene::*)(glm::vec3, const glm::vec3*, uint32_t, std::vector<pvs::RayTouch>&) const;
        auto measure = [&](TraceFn fn, uint64_t& touches_seen) {
            const auto t = std::chrono::steady_clock::now();
            uint64_t n = 0;
#pragma omp parallel reduction(+ : n)
            {
                std::vector<pvs::RayTouch> touches;
#pragma omp for schedule(dynamic, 8)
                for (int64_t e = 0; e < int64_t(eyes); ++e) {
                    touches.clear();
                    (scene.*fn)(eye_points[e], dirs.data() + size_t(e) * kRaysPerEye, kRaysPerEye, touches);
                    n += touches.size();
                }
            }
            touches_seen = n;
            return rays / seconds_since(t) * 1e-6;
        };
        for (int r = 0; r < repeats; ++r) {
            stream.push_back(measure(&pvs::RayScene::trace, touches_stream));
            single.push_back(measure(&pvs::RayScene::trace_reference, touches_single));
            repeated.push_back(measure(&pvs::RayScene::trace_repeated, touches_repeated));
            const auto t = std::chrono::steady_clock::now();
            uint64_t hits = 0;
#pragma omp parallel for schedule(dynamic, 8) reduction(+ : hits)
            for (int64_t e = 0; e < int64_t(eyes); ++e) {
                hits += scene.occluded_baseline(eye_points[e], dirs.data() + size_t(e) * kRaysPerEye,
                                                kRaysPerEye);
            }
            occluded.push_back(rays / seconds_since(t) * 1e-6);
        }
        nlohmann::ordered_json q;
        q["build_s"] = build_s;
        q["stream_mrays_s"] = median(stream);
        q["intersect1_mrays_s"] = median(single);
        q["repeated1_mrays_s"] = median(repeated);
        q["occluded1_mrays_s"] = median(occluded);
        q["stream_over_occluded1"] = median(stream) / median(occluded);
        q["stream_over_intersect1"] = median(stream) / median(single);
        q["touches_stream"] = touches_stream;
        q["touches_intersect1"] = touches_single;
        q["touches_repeated1"] = touches_repeated;
        out[name] = q;
    }
    std::cout << out.dump(2) << std::endl;
    return 0;
}
