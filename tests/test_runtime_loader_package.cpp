// SPDX-License-Identifier: MIT
// Tests of the runtime loader that need the whole build: a real bake made by the pvsbake command reads
// back identically through the loader, and the installed CMake package (cmake --install) builds a consumer
// in C and C++ with find_package(pvsbake) + target_link_libraries(... pvsbake::loader).
#include "io/bake_file.h"
#include "tests/bake_fixtures.h"
#include "tests/test_util.h"

#include <pvsbake/loader.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace pvs {
namespace {

namespace fs = std::filesystem;

// A real bake of the sample world, made by the pvsbake command: the loader reads what read_bake_file reads.
TEST(RuntimeLoader, RealBakeOfTheSampleWorld) {
    test::TempDir dir;
    const std::string out = dir.file("rooms.h5");
    const std::string cmd = std::string(PVSBAKE_BINARY) + " bake " + test::sample_world() + " -o " + out +
                            " --mode sampled --no-verify --quiet";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const BakeData bake = read_bake_file(out);
    pvsbake::Bake loaded;
    test::load_ok(loaded, out);
    test::expect_loaded_equals(loaded, bake);  // the ranked occluders too
    test::expect_same_lookup(loaded, bake.cells, 21);
    ASSERT_FALSE(bake.ranked.empty());
    EXPECT_GT(bake.ranked.entries.size(), bake.cells.size());  // more than one per cell on average
    // Memory against the compressed rows (docs/FORMAT.md has the figures of real worlds).
    const pvsbake::PvsStats& s = loaded.pvs_stats();
    EXPECT_LT(s.bytes_code, s.bytes_raw);
}

// cmake --install, then a consumer project (C and C++) built with find_package(pvsbake) against the prefix.
TEST(RuntimeLoaderPackage, InstallsAndBuildsAConsumer) {
    test::TempDir dir;
    const std::string prefix = dir.file("prefix");
    ASSERT_EQ(std::system(("cmake --install " + std::string(PVSBAKE_BUILD_DIR) + " --prefix " + prefix +
                           " > " + dir.file("install.log"))
                              .c_str()),
              0);
    EXPECT_TRUE(fs::exists(prefix + "/include/pvsbake/loader.h"));
    EXPECT_TRUE(fs::exists(prefix + "/include/pvsbake/loader_c.h"));
    EXPECT_TRUE(fs::exists(prefix + "/lib/cmake/pvsbake/pvsbakeConfig.cmake"));
    const std::string src = dir.file("consumer");
    fs::create_directory(src);
    test::write_file(src + "/CMakeLists.txt",
                     "cmake_minimum_required(VERSION 3.20)\nproject(consumer C CXX)\n"
                     "find_package(pvsbake 0.1 REQUIRED)\n"
                     "add_executable(consumer main.c count.cpp)\n"
                     "target_link_libraries(consumer PRIVATE pvsbake::loader)\n");
    test::write_file(
        src + "/main.c",
        "#include <pvsbake/loader_c.h>\n#include <stdio.h>\n"
        "unsigned count_visible(const char* path);\n"
        "int main(int argc, char** argv) {\n"
        "  pvsbake_bake* b = NULL; char msg[256];\n"
        "  if (pvsbake_load(argv[1], &b, msg, sizeof msg) != PVSBAKE_OK) { puts(msg); return 1; }\n"
        "  printf(\"cells %u objects %u visible %u\\n\", pvsbake_cell_count(b), pvsbake_object_count(b),\n"
        "         count_visible(argv[1]));\n"
        "  pvsbake_free(b); return 0;\n}\n");
    test::write_file(
        src + "/count.cpp",
        "#include <pvsbake/loader.h>\n"
        "extern \"C\" unsigned count_visible(const char* path) {\n"
        "  pvsbake::Bake b; if (!b.load(path)) return 0;\n"
        "  unsigned n = 0; for (uint32_t c = 0; c < b.cell_count(); ++c) n += b.visible_count(c);\n"
        "  return n;\n}\n");
    const std::string build = dir.file("consumer-build");
    const std::string log = " >> " + dir.file("consumer.log") + " 2>&1";
    ASSERT_EQ(
        std::system(
            ("cmake -S " + src + " -B " + build + " -G Ninja -DCMAKE_PREFIX_PATH=" + prefix + log).c_str()),
        0)
        << test::read_file(dir.file("consumer.log"));
    ASSERT_EQ(std::system(("cmake --build " + build + log).c_str()), 0)
        << test::read_file(dir.file("consumer.log"));
    const BakeData bake = test::coherent_bake(25, {2, 2, 2}, false, false, 3);
    write_bake_file(dir.file("b.h5"), bake);
    uint64_t visible = 0;
    for (uint32_t c = 0; c < bake.cells.size(); ++c) visible += bake.pvs.count(c);
    const std::string out = dir.file("run.txt");
    ASSERT_EQ(std::system((build + "/consumer " + dir.file("b.h5") + " > " + out).c_str()), 0);
    EXPECT_EQ(test::read_file(out), "cells " + std::to_string(bake.cells.size()) + " objects 25 visible " +
                                        std::to_string(visible) + "\n");
}

}  // namespace
}  // namespace pvs
