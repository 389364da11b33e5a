// SPDX-License-Identifier: MIT
// libFuzzer target: the world loader (io/gltf_loader.h, from memory) and the checks that follow it before
// any voxel is made (cells/world_extent.h: the voxel grid within its caps, the farthest-reaching objects).
//
// Any bytes must give either a World whose invariants hold (every index in range, every position finite and
// inside the bounds, object ranges inside the triangles) or pvs::Error of kind bad input with a one-line
// message; a voxel grid, when one is accepted, within max_voxels. Anything else aborts (a finding).
// Built with Clang: -fsanitize=fuzzer,address,undefined (tests/CMakeLists.txt); the runs and their figures:
// docs/RESULTS.md ("Worlds as artists export them").
#include "cells/world_extent.h"
#include "core/context.h"
#include "core/error.h"
#include "io/gltf_loader.h"

#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

[[noreturn]] void finding(const char* what) {
    std::fprintf(stderr, "fuzz_world: %s\n", what);
    std::abort();
}

void check_world(const pvs::World& w) {
    if (w.triangles.empty()) finding("a world without triangles was accepted");
    for (const pvs::Triangle& t : w.triangles)
        for (uint32_t v : t.v)
            if (v >= w.positions.size()) finding("a triangle names a vertex out of range");
    for (const glm::vec3& p : w.positions) {
        if (!pvs::is_finite(p)) finding("a position is not finite");
        if (!w.bounds.contains(p)) finding("a position lies outside the world's bounds");
    }
    if (w.triangle_opaque.size() != w.triangles.size()) finding("opacity flags do not match the triangles");
    uint64_t next = 0;
    for (const pvs::WorldObject& o : w.objects) {
        if (o.first_triangle != next) finding("objects' triangle ranges are not contiguous");
        next += o.triangle_count;
    }
    if (next != w.triangles.size()) finding("objects' triangle ranges do not cover the triangles");
}

void check_voxels(const pvs::World& w) {
    pvs::ViewVolumeConfig config;
    config.max_voxels = 50'000'000;
    config.cell_edge_m = 2.0;
    try {
        const pvs::VoxelGrid grid = pvs::view_voxel_grid(config, w, 0.0625, 0);
        if (grid.count() > pvs::kMaxVoxels) finding("a voxel grid past the grid's own limit was accepted");
    } catch (const pvs::Error& e) {
        if (e.kind() != pvs::ErrorKind::kBadInput) finding("the voxel grid failed with an error other than bad input");
    }
    (void)pvs::farthest_objects(w, 3);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static pvs::Context ctx(pvs::Context::Options{.sink = nullptr});
    pvs::World world;
    try {
        world = pvs::load_world_from_memory(ctx, "fuzz.glb", std::string(reinterpret_cast<const char*>(data), size));
    } catch (const pvs::Error& e) {
        if (e.kind() != pvs::ErrorKind::kBadInput) finding(e.what());
        if (std::string(e.what()).find('\n') != std::string::npos) finding("a message of several lines");
        return 0;
    }
    check_world(world);
    check_voxels(world);
    return 0;
}
