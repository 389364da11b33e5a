// SPDX-License-Identifier: MIT
// make_random_world: writes one of the property tests' random closed box worlds (samples/random_world.h) to
// a .glb (through edited_world, samples/world_edit.h, with no edit), so that the command-line tools and benchmarks (bench_truth) can bake and measure it.
//
//   make_random_world OUT.glb [--seed S] [--attempt A]
//
// Deterministic: the same seed and attempt give the same bytes.
#include "io/gltf_writer.h"
#include "samples/random_world.h"
#include "samples/world_edit.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv) {
    CLI::App app{"make_random_world: write a random closed box world of the property tests as .glb"};
    std::string out_path;
    uint64_t seed = 1, attempt = 0;
    app.add_option("out", out_path, "the world to write (.glb)")->required();
    app.add_option("--seed", seed, "which world (the property tests draw seeds 1, 2, ...)");
    app.add_option("--attempt", attempt,
                   "another world of the same seed (the tests draw the next attempt when no view volume can "
                   "be built from a world's seeds)");
    CLI11_PARSE(app, argc, argv);
    try {
        const pvs::RandomWorld random = pvs::make_random_world(seed, attempt);
        pvs::write_glb(pvs::edited_world(random.world, {}), out_path);  // the world as it is
        std::fprintf(stderr, "wrote %s: %zu objects, %zu triangles, %zu view seeds\n", out_path.c_str(),
                     random.world.objects.size(), random.world.triangles.size(),
                     random.world.view_seeds.size());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
