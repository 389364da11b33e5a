// SPDX-License-Identifier: MIT
// make_runtime_seeds OUT_DIR: a few small runtime files for the fuzz target's corpus (grid and octree, with
// and without masks, ranked occluders, polygon occluders, horizon lists and object parts), exported from the
// loader tests' synthetic bakes.
#include "io/bake_file.h"
#include "io/runtime_file.h"
#include "tests/bake_fixtures.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: make_runtime_seeds OUT_DIR\n");
        return 2;
    }
    const std::filesystem::path out = argv[1];
    std::filesystem::create_directories(out);
    int n = 0;
    for (const bool octree : {false, true})
        for (const bool view : {false, true})
            for (const uint32_t objects : {0u, 9u, 70u}) {
                pvs::BakeData bake =
                    pvs::test::coherent_bake(objects, {2, 1, 2}, octree, view, 3 + uint32_t(n), objects == 9,
                                             /*every_position=*/objects == 70);
                if (view) {  // a small mask: a small seed
                    bake.cells.view.voxel_size_m = 1.5f;
                    bake.cells.view.dims = bake.cells.dims + 1;
                    const uint64_t voxels = bake.cells.view.count();
                    bake.cells.view.bits.assign(size_t((voxels + 63) / 64), 0);
                    for (uint64_t v = 0; v < voxels; ++v)
                        if (v % 3 != 1) bake.cells.view.bits[v / 64] |= uint64_t(1) << (v % 64);
                    bake.cells.eyes = bake.cells.view;
                }
                const std::string h5 = (out / ("seed.h5")).string();
                pvs::write_bake_file(h5, bake);
                const std::string bytes = pvs::runtime_file_bytes(h5);
                std::ofstream((out / ("seed_" + std::to_string(n++) + ".pvsr")).string(), std::ios::binary) << bytes;
                std::filesystem::remove(h5);
            }
    for (const int kind : {0, 1, 2}) {  // ranked boxes through palettes (2.0), horizon lists (2.1; per cell:
                                        // 5.2; with the cells' tests: 5.3) and object parts (2.2)
        pvs::BakeData bake = pvs::test::coherent_bake(12, {13, 2, 13}, false, false, 29);
        pvs::test::rank_many_boxes(bake, 600, 24, 3);
        pvs::test::add_horizon_lists(bake, kind > 0, kind == 2);
        pvs::test::add_object_parts(bake);
        const std::string h5 = (out / ("seed.h5")).string();
        pvs::write_bake_file(h5, bake);
        const std::string bytes = pvs::runtime_file_bytes(h5);
        std::ofstream((out / ("seed_" + std::to_string(n++) + ".pvsr")).string(), std::ios::binary) << bytes;
        std::filesystem::remove(h5);
    }
    std::printf("make_runtime_seeds: %d seeds in %s\n", n, argv[1]);
    return 0;
}
