// SPDX-License-Identifier: MIT
// Tests the runtime file from the baker's side: a real bake (a random world, grid and octree) exported
// answers every query as the HDF5 loader does, and `pvsbake export` and `pvsbake bake --runtime-output`
// write it (the same bytes), or fail with exit 2 and no file.
#include "driver/bake.h"
#include "driver/cli.h"
#include "io/bake_file.h"
#include "io/gltf_writer.h"
#include "samples/random_world.h"
#include "samples/world_edit.h"
#include "tests/runtime_file_checks.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace pvs {
namespace {

using test::round_trip;

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// pvsbake's command line in this process: its exit status.
int run_pvsbake(std::vector<std::string> args) {
    args.insert(args.begin(), "pvsbake");
    std::vector<const char*> argv;
    for (const std::string& a : args) argv.push_back(a.c_str());
    std::ostringstream out;
    std::FILE* log = std::tmpfile();
    const int status = run_cli(int(argv.size()), argv.data(), out, log);
    std::fclose(log);
    return status;
}

TEST(RuntimeExport, ARealBakeAnswersAsTheHdf5Loader) {
    for (const CellKind kind : {CellKind::kGrid, CellKind::kOctree}) {
        SCOPED_TRACE(kind == CellKind::kGrid ? "grid" : "octree");
        const RandomWorld random = make_random_world(2, 0);
        BakeConfig config;
        config.cells.kind = kind;
        config.verify.enabled = false;
        config.run.threads = 2;
        Context ctx = quiet_context();
        const BakeData bake = bake_world(ctx, config, random.world, "random.glb", "");
        ASSERT_GT(bake.cells.size(), 0u);
        round_trip(bake, 13);
    }
}

// The bundled sample world, a grid and an octree (quick sampled bakes): every query the same.
TEST(RuntimeExport, TheSampleWorldAnswersAsTheHdf5Loader) {
    test::TempDir dir;
    for (const std::string cells : {"grid", "octree"}) {
        SCOPED_TRACE(cells);
        const std::string h5 = dir.file(cells + ".h5");
        ASSERT_EQ(run_pvsbake({"bake", test::sample_world(), "-o", h5, "--cells", cells, "--mode", "sampled",
                               "--no-verify", "-q", "--eyes", "4", "--rays", "256"}),
                  0);
        BakeData bake = read_bake_file(h5);
        uint64_t culled = 0;
        round_trip(bake, 17, &culled);
        EXPECT_GT(culled, 0u) << "the ranked occluders should cull some object of the PVS from some eye";
    }
}

TEST(RuntimeExport, ExportAndBakeWriteIt) {
    test::TempDir dir;
    const std::string h5 = dir.file("b.h5"), out = dir.file("level.pvsr");
    write_bake_file(h5, test::coherent_bake(40, {3, 2, 3}, false, true, 6));
    EXPECT_EQ(run_pvsbake({"export", h5, "-o", out, "-q"}), 0);
    const std::string written = test::read_file(out);
    EXPECT_EQ(written, runtime_file_bytes(h5));
    // A missing bake: exit 2 and no file.
    EXPECT_EQ(run_pvsbake({"export", dir.file("none.h5"), "-o", dir.file("x.pvsr"), "-q"}), 2);
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.pvsr")));
    // From bake: the same bytes as exporting its bake file.
    const std::string world = dir.file("random.glb");
    write_glb(edited_world(make_random_world(4, 0).world, {}), world);
    const std::string baked = dir.file("r.h5"), level = dir.file("r.pvsr");
    ASSERT_EQ(run_pvsbake({"bake", world, "-o", baked, "--runtime-output", level, "--no-verify", "-q",
                           "--cell-size", "4"}),
              0);
    EXPECT_EQ(test::read_file(level), runtime_file_bytes(baked));
}

}  // namespace
}  // namespace pvs
