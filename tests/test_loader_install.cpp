// SPDX-License-Identifier: MIT
// The runtime loader as games consume it, from an installed prefix (cmake --install): a game in C only
// (CMake, static and shared library), a game in C++ (CMake), a C build with plain pkg-config, a Python
// script through ctypes checked against `pvsbake query`, and the shared library's exported symbols.
// docs/LOADER.md, "Install and link" and "Stability". Consumer sources are in tests/install/.
#include "io/bake_file.h"
#include "tests/bake_fixtures.h"
#include "tests/test_util.h"

#include <pvsbake/loader.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace pvs {
namespace {

namespace fs = std::filesystem;

// Runs a shell command with its output appended to log; its exit status (-1 when it did not run).
int shell(const std::string& command, const std::string& log) {
    const int r = std::system((command + " >> " + log + " 2>&1").c_str());
    return r == -1 ? -1 : WEXITSTATUS(r);
}

// A temp folder with the project installed in prefix/, and a small bake in bake.h5 with the line every
// consumer of tests/install/ prints for it.
class Installed : public ::testing::Test {
protected:
    void SetUp() override {
        log = dir.file("log.txt");
        prefix = dir.file("prefix");
        ASSERT_EQ(shell("cmake --install " + std::string(PVSBAKE_BUILD_DIR) + " --prefix " + prefix, log), 0)
            << test::read_file(log);
        lib = prefix + "/lib";
        ASSERT_TRUE(fs::exists(lib + "/libpvsbake_loader.a"));
        ASSERT_TRUE(fs::exists(lib + "/" + PVSBAKE_LOADER_SONAME));
        ASSERT_TRUE(fs::exists(lib + "/libpvsbake_loader.so"));  // the link-time name
        ASSERT_TRUE(fs::exists(lib + "/pkgconfig/pvsbake-loader.pc"));
        bake = dir.file("bake.h5");
        write_bake_file(bake, test::coherent_bake(150, {3, 2, 4}, false, false, 7));
        expected = expected_line(bake);
    }

    // "cells C objects O visible V sum S found F" (tests/install/game.c), computed here.
    static std::string expected_line(const std::string& path) {
        pvsbake::Bake b;
        test::load_ok(b, path);
        uint64_t visible = 0, sum = 0;
        uint32_t found = 0;
        for (uint32_t c = 0; c < b.cell_count(); ++c) {
            b.for_each_visible(c, [&](uint32_t o) {
                ++visible;
                sum += uint64_t(c + 1) * (o + 1);
            });
            const pvsbake::Box x = b.cell_bounds(c);
            found += b.find_cell((x.min[0] + x.max[0]) / 2, (x.min[1] + x.max[1]) / 2,
                                 (x.min[2] + x.max[2]) / 2) == int32_t(c);
        }
        return "cells " + std::to_string(b.cell_count()) + " objects " + std::to_string(b.object_count()) +
               " visible " + std::to_string(visible) + " sum " + std::to_string(sum) + " found " +
               std::to_string(found) + "\n";
    }

    // Builds the CMake project tests/install/<project> against the prefix.
    void build_cmake(const std::string& project, const std::string& build) {
        const std::string src = test::source_file("tests/install/" + project);
        ASSERT_EQ(shell("cmake -S " + src + " -B " + build + " -G Ninja -DCMAKE_BUILD_TYPE=Release" +
                            " -DCMAKE_PREFIX_PATH=" + prefix,
                        log),
                  0)
            << test::read_file(log);
        ASSERT_EQ(shell("cmake --build " + build, log), 0) << test::read_file(log);
    }

    // Runs a built game on the bake and checks its line.
    void expect_game(const std::string& game, const std::string& env = "") {
        const std::string out = dir.file("out.txt");
        ASSERT_EQ(std::system((env + game + " " + bake + " > " + out + " 2>> " + log).c_str()), 0)
            << game << ": " << test::read_file(log);
        EXPECT_EQ(test::read_file(out), expected) << game;
    }

    // The dynamic libraries a program needs (readelf -d).
    std::string needed(const std::string& program) {
        const std::string out = dir.file("needed.txt");
        std::system(("readelf -d " + program + " | grep NEEDED > " + out).c_str());
        return test::read_file(out);
    }

    test::TempDir dir;
    std::string log, prefix, lib, bake, expected;
};

// A game with project(game C), no C++ enabled, links pvsbake::loader (static: the target brings the C++
// runtime) and pvsbake::loader_shared, and walks every cell's PVS.
TEST_F(Installed, COnlyCMakeGameLinksStaticAndShared) {
    const std::string build = dir.file("c_game");
    build_cmake("c_game", build);
    expect_game(build + "/game_static");
    expect_game(build + "/game_shared");
    EXPECT_EQ(needed(build + "/game_static").find("libpvsbake_loader"), std::string::npos);
    EXPECT_NE(needed(build + "/game_shared").find(PVSBAKE_LOADER_SONAME), std::string::npos);
}

// A C++17 game links pvsbake::loader and gets the same answers from the C++ and the C API.
TEST_F(Installed, CxxCMakeGame) {
    const std::string build = dir.file("cxx_game");
    build_cmake("cxx_game", build);
    expect_game(build + "/game_cxx");
}

// A build that is not CMake: cc $(pkg-config --cflags --libs pvsbake-loader) links the shared library;
// the static one links with what `pkg-config --static` adds (as docs/LOADER.md says).
TEST_F(Installed, PkgConfigGame) {
    const std::string pc = "PKG_CONFIG_PATH=" + lib + "/pkgconfig ";
    const std::string src = test::source_file("tests/install/game.c");
    const std::string shared = dir.file("game_pc"), fixed = dir.file("game_pc_static");
    ASSERT_EQ(shell(pc + "sh -c 'cc -std=c99 -Wall -Werror " + src + " -o " + shared +
                        " $(pkg-config --cflags --libs pvsbake-loader)'",
                    log),
              0)
        << test::read_file(log);
    ASSERT_EQ(shell(pc + "sh -c 'cc -std=c99 -Wall -Werror " + src + " -o " + fixed +
                        " $(pkg-config --cflags --static --libs pvsbake-loader |"
                        " sed s/-lpvsbake_loader/-l:libpvsbake_loader.a/)'",
                    log),
              0)
        << test::read_file(log);
    expect_game(shared, "LD_LIBRARY_PATH=" + lib + " ");
    expect_game(fixed);
    EXPECT_NE(needed(shared).find(PVSBAKE_LOADER_SONAME), std::string::npos);
    EXPECT_EQ(needed(fixed).find("libpvsbake_loader"), std::string::npos);
    // The .pc file finds its prefix from where it lies: a moved install still works.
    const std::string moved = dir.file("moved");
    fs::rename(prefix, moved);
    const std::string out = dir.file("cflags.txt");
    ASSERT_EQ(std::system(("PKG_CONFIG_PATH=" + moved +
                           "/lib/pkgconfig pkg-config --cflags --libs pvsbake-loader > " + out)
                              .c_str()),
              0);
    EXPECT_NE(test::read_file(out).find(moved + "/lib/pkgconfig/../../include"), std::string::npos)
        << test::read_file(out);
}

// A Python script loads the shared library with ctypes, finds the cells of random points and walks their
// PVS; every answer equals `pvsbake query --json` on the same point, on a grid and an octree bake of the
// sample world; and the same through the installed C99 runtime's shared library on the bakes' runtime files,
// the walk of what a game draws from each point (the PVS less what the cell's ranked occluders hide) too.
TEST_F(Installed, PythonCtypesMatchesQuery) {
    const std::string script = test::source_file("tests/install/ctypes_query.py");
    const std::string shared = lib + "/" + PVSBAKE_LOADER_SONAME;
    for (const std::string cells : {"grid", "octree"}) {
        const std::string out = dir.file(cells + ".h5");
        ASSERT_EQ(shell(std::string(PVSBAKE_BINARY) + " bake " + test::sample_world() + " -o " + out +
                            " --cells " + cells + " --mode sampled --no-verify --quiet --eyes 4 --rays 256",
                        log),
                  0)
            << test::read_file(log);
        const std::string level = dir.file(cells + ".pvsr");
        ASSERT_EQ(shell(std::string(PVSBAKE_BINARY) + " export " + out + " -o " + level + " --quiet", log), 0)
            << test::read_file(log);
        const int points = test::in_ci() ? 40 : 100;
        EXPECT_EQ(shell("python3 " + script + " " + shared + " " + out + " " + PVSBAKE_BINARY + " " +
                            std::to_string(points) + " 11 " + lib + "/libpvsbake_runtime.so " + level,
                        log),
                  0)
            << test::read_file(log);
    }
    std::printf("%s", test::read_file(log).c_str());
}

// The shared library exports the functions of the C API headers and nothing else (no C++ symbol), under
// its soname.
TEST_F(Installed, SharedLibraryExportsOnlyTheCApi) {
    const std::string headers =
        prefix + "/include/pvsbake/loader_c.h " + prefix + "/include/pvsbake/occlusion_c.h";
    EXPECT_EQ(shell("python3 " + test::source_file("tests/install/check_exports.py") + " " + lib + "/" +
                        PVSBAKE_LOADER_SONAME + " " + PVSBAKE_LOADER_SONAME + " " + headers,
                    log),
              0)
        << test::read_file(log);
}

}  // namespace
}  // namespace pvs
