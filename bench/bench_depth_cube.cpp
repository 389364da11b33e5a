// SPDX-License-Identifier: MIT
// bench_depth_cube: speed of the conservative depth cube map (pvs/depth_cube.h), one thread.
//
//   bench_depth_cube [--repeats R]
//
// One sample = clear + add 300 random boxes + test 3000 occludee boxes, around a random eye, at resolution
// 64 and 128: median over R samples (different scenes, fixed seeds). Then the reference against the fast
// kernel on a smaller case (100 occluders, 200 occludees, resolution 32), same scenes, ratio in one run.
// Prints one JSON object.
#include "bench/bench_util.h"
#include "core/random.h"
#include "pvs/depth_cube.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <vector>

namespace {

using pvs::bench::median;
using pvs::bench::seconds_since;

struct Scene {
    glm::vec3 eye;
    std::vector<pvs::Aabb> occluders, occludees;
};

// A 150 m cube of walls (4..20 m) and blocks (1..8 m), occludees of 0.2..3 m, the eye somewhere inside:
// roughly half the occludees end up hidden.
Scene make_scene(uint64_t seed, int n_occluders, int n_occludees) {
    pvs::Rng rng(seed, 1);
    auto r3 = [&](float lo, float hi) {
        return glm::vec3(lo + (hi - lo) * rng.uniform(), lo + (hi - lo) * rng.uniform(),
                         lo + (hi - lo) * rng.uniform());
    };
    Scene s;
    s.eye = r3(30, 120);
    for (int k = 0; k < n_occluders; ++k) {
        glm::vec3 size = r3(1, 8);
        if (rng.uniform() < 0.6f) {
            size = r3(4, 20);
            size[rng.below(3)] = 0.3f + rng.uniform();
        }
        const glm::vec3 c = r3(0, 150);
        const pvs::Aabb b = pvs::Aabb::of(c - 0.5f * size, c + 0.5f * size);
        if (!b.contains(s.eye)) s.occluders.push_back(b);
    }
    for (int k = 0; k < n_occludees; ++k) {
        const glm::vec3 size = r3(0.2f, 3.0f), c = r3(0, 150);
        s.occludees.push_back(pvs::Aabb::of(c - 0.5f * size, c + 0.5f * size));
    }
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    int repeats = 5;
    for (int a = 1; a + 1 < argc; a += 2) {
        if (!std::strcmp(argv[a], "--repeats")) repeats = std::max(1, std::atoi(argv[a + 1]));
    }
    nlohmann::ordered_json out;
    out["bench"] = "depth_cube";
    out["repeats"] = repeats;
    out["threads"] = 1;

    nlohmann::ordered_json fast = nlohmann::ordered_json::array();
    for (int resolution : {64, 128}) {
        std::vector<double> total_s, raster_s, test_s;
        int hidden = 0, tested = 0;
        pvs::DepthCube cube(resolution);
        for (int rep = 0; rep < repeats; ++rep) {
            const Scene s = make_scene(100 + rep, 300, 3000);
            const auto t0 = std::chrono::steady_clock::now();
            cube.clear(s.eye);
            for (const pvs::Aabb& b : s.occluders) cube.add_occluder(b);
            const double t_raster = seconds_since(t0);
            int h = 0;
            for (const pvs::Aabb& b : s.occludees) h += cube.is_hidden(b);
            total_s.push_back(seconds_since(t0));
            raster_s.push_back(t_raster);
            test_s.push_back(total_s.back() - t_raster);
            hidden += h;
            tested += int(s.occludees.size());
        }
        nlohmann::ordered_json q;
        q["resolution"] = resolution;
        q["occluders"] = 300;
        q["occludees"] = 3000;
        q["median_total_ms"] = 1e3 * median(total_s);
        q["median_add_occluders_ms"] = 1e3 * median(raster_s);
        q["median_test_occludees_ms"] = 1e3 * median(test_s);
        q["us_per_occluder"] = 1e6 * median(raster_s) / 300;
        q["us_per_occludee"] = 1e6 * median(test_s) / 3000;
        q["hidden_share"] = tested ? double(hidden) / tested : 0.0;
        fast.push_back(q);
    }
    out["fast"] = fast;

    // Reference against fast on a small case: same scenes, ratio of medians.
    const int ref_resolution = 32, ref_occluders = 100, ref_occludees = 200;
    std::vector<double> fast_s, ref_s;
    int agree = 0, total = 0;
    pvs::DepthCube cube(ref_resolution);
    for (int rep = 0; rep < repeats; ++rep) {
        const Scene s = make_scene(200 + rep, ref_occluders, ref_occludees);
        auto t0 = std::chrono::steady_clock::now();
        cube.clear(s.eye);
        for (const pvs::Aabb& b : s.occluders) cube.add_occluder(b);
        std::vector<char> fast_answer;
        for (const pvs::Aabb& b : s.occludees) fast_answer.push_back(cube.is_hidden(b));
        fast_s.push_back(seconds_since(t0));
        t0 = std::chrono::steady_clock::now();
        std::vector<char> ref_answer;
        for (const pvs::Aabb& b : s.occludees) {
            ref_answer.push_back(pvs::is_hidden_reference(s.occluders, s.eye, b, ref_resolution));
        }
        ref_s.push_back(seconds_since(t0));
        for (size_t k = 0; k < fast_answer.size(); ++k) agree += fast_answer[k] == ref_answer[k];
        total += int(fast_answer.size());
    }
    nlohmann::ordered_json ref;
    ref["resolution"] = ref_resolution;
    ref["occluders"] = ref_occluders;
    ref["occludees"] = ref_occludees;
    ref["median_fast_ms"] = 1e3 * median(fast_s);
    ref["median_reference_ms"] = 1e3 * median(ref_s);
    ref["reference_over_fast"] = median(fast_s) > 0 ? median(ref_s) / median(fast_s) : 0.0;
    ref["answers_identical"] = agree == total;
    out["reference"] = ref;
    std::cout << out.dump(2) << std::endl;
    return 0;
}
