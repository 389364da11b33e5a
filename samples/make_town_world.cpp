// SPDX-License-Identifier: MIT
// make_town_world: writes a generated town (samples/town_world.h) as .glb: the big open level "a big world is
// not a fault" is measured on (docs/RESULTS.md).
//
//   make_town_world OUT.glb [--size 330] [--height 46] [--seed 1]
//
// Deterministic: the same options give the same bytes.
#include "io/gltf_writer.h"
#include "samples/town_world.h"
#include "samples/world_edit.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv) {
    CLI::App app{"make_town_world: write a generated town (a big open level) as .glb"};
    std::string out_path;
    pvs::TownParams params;
    app.add_option("out", out_path, "the world to write (.glb)")->required();
    app.add_option("--size", params.size_m, "the ground's edge along x and z [m]")
        ->check(CLI::Range(50.0, 5000.0));
    app.add_option("--height", params.max_height_m, "the tallest building [m]")
        ->check(CLI::Range(7.0, 500.0));
    app.add_option("--seed", params.seed, "which town");
    CLI11_PARSE(app, argc, argv);
    try {
        const pvs::World town = pvs::make_town_world(params);
        pvs::write_glb(pvs::edited_world(town, {}), out_path);
        std::fprintf(stderr, "wrote %s: %zu objects, %zu triangles, %zu view seeds\n", out_path.c_str(),
                     town.objects.size(), town.triangles.size(), town.view_seeds.size());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
