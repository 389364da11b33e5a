// SPDX-License-Identifier: MIT
// pvsbake example: a game loop over a bake. Loads the bake at "level load", then every frame moves a
// camera along a smooth path through the world's cells (a Catmull-Rom spline through the centres of
// neighbouring cells, going straight where it can), looks up the camera's cell, sets the occlusion culler
// (pvsbake/occlusion.h) up with the cell's ranked occluders and the horizon with the cell's list of horizon
// occluders, and walks what to draw: the cell's PVS less what either hides from the eye. It prints how many
// objects and triangles it would draw against the PVS and all of them. Outside the view volume a game draws
// everything; outside the eye space (the rim around it, up to and into thin walls) it draws the whole PVS.
// Moving objects (people and vehicles, which no PVS can list) walk through the view volume, and the same
// culler tests their boxes; the example prints how many it culled and what the culling cost.
//
//   pvsbake_walkthrough BAKE.h5|LEVEL.pvsr [--frames N] [--objects M] [--seed S] [--quiet]
//
// A bake file goes through the HDF5 loader (pvsbake::loader: pvsbake/loader.h, pvsbake/occlusion.h); a
// runtime file (`pvsbake export`) through the C99 runtime (runtime/pvsr.hpp), which a game ships without
// HDF5. Both give the same frames.
#include "walk.h"

#include <pvsbake/loader.h>
#include <pvsbake/occlusion.h>
#include <pvsr.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace {

using pvsbake::walk::Vec3;

// A runtime file as the loop below uses a level: pvsr::Level with the HDF5 loader's boxes, and its culler.
struct RuntimeLevel {
    std::vector<uint64_t> bytes;  // the file, 8-byte aligned (a game would map it)
    pvsr::Level level;
    uint32_t cell_count() const { return level.cell_count(); }
    uint32_t object_count() const { return level.object_count(); }
    uint64_t total_triangles() const { return level.total_triangles(); }
    uint32_t object_triangles(uint32_t o) const { return level.object_triangles(o); }
    const char* mode_label() const { return level.mode_label(); }
    std::string mode() const { return std::string(level.string("mode")); }
    const char* kind() const { return level.cell_kind() == 0 ? "grid" : "octree"; }
    int32_t find_cell(float x, float y, float z) const { return level.find_cell(x, y, z); }
    bool in_eye_space(float x, float y, float z) const { return level.in_eye_space(x, y, z); }
    pvsbake::Box cell_bounds(uint32_t c) const {
        float b[6] = {0, 0, 0, 0, 0, 0};
        level.cell_bounds(c, b);
        return pvsbake::Box{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
    }
    template <class F>
    void for_each_visible(uint32_t c, F&& visit) const {
        level.for_each_visible(c, visit);
    }
};

// The culler of the cell's ranked occluders, and the horizon of its list of horizon occluders (when the file
// has lists): an object is drawn unless either proves its box hidden.
struct RuntimeCuller {
    pvsr::Culler culler;
    pvsr::Horizon horizon{256};
    uint32_t horizon_given = 0;
    void begin_cell(const RuntimeLevel& l, uint32_t c, const float eye[3]) {
        culler.begin_cell(l.level, c, eye);
        horizon_given = horizon.begin_cell(l.level, c, eye);
    }
    void begin_empty(const RuntimeLevel& l, const float eye[3]) {
        culler.begin_frame(eye, nullptr, 0);
        horizon_given = horizon.begin_cell(l.level, l.cell_count(), eye);  // no cell: an empty horizon
    }
    template <class F>
    uint32_t for_each_drawn(const RuntimeLevel& l, uint32_t c, F&& visit) const {
        return l.level.for_each_drawn(c, &culler, horizon, visit);
    }
    int classify(const pvsbake::Box& box) const {
        const int path = int(culler.classify(&box.min[0]));
        return path != 0 ? path : horizon.is_hidden(&box.min[0]) ? 4 : 0;
    }
    size_t occluders_used() const { return culler.occluders_used(); }
};

struct LoaderLevel {
    pvsbake::Bake bake;
    const char* kind() const { return bake.cell_kind() == pvsbake::CellKind::kGrid ? "grid" : "octree"; }
};

struct LoaderCuller {
    pvsbake::OcclusionCuller culler;
    pvsbake::Horizon horizon{256};
    uint32_t horizon_given = 0;
    void begin_cell(const pvsbake::Bake& b, uint32_t c, const float eye[3]) {
        culler.begin_cell(b, c, eye);
        horizon_given = horizon.begin_cell(b, c, eye);
    }
    void begin_empty(const pvsbake::Bake& b, const float eye[3]) {
        culler.begin_frame(eye, nullptr, 0);
        horizon_given = horizon.begin_cell(b, b.cell_count(), eye);  // no cell: an empty horizon
    }
    template <class F>
    uint32_t for_each_drawn(const pvsbake::Bake& b, uint32_t c, F&& visit) const {
        return pvsbake::for_each_drawn(b, c, &culler, horizon, visit);
    }
    int classify(const pvsbake::Box& box) const {
        const int path = int(culler.classify(box));
        return path != 0 ? path : horizon.is_hidden(box) ? 4 : 0;
    }
    size_t occluders_used() const { return culler.occluders_used(); }
};

// The game loop over a level (pvsbake::Bake or RuntimeLevel) and its culler. Path values: 0 visible, 1 one
// shadow frustum, 2 the fused depth cube, 3 the exact union of the occluders' faces (both cullers number them
// so). The cullers keep their depth cube (32 pixels): with moving objects to test as well it pays.
template <class Level, class Culler>
int play(const Level& bake, Culler& culler, int frames, int movers_wanted, unsigned seed, bool quiet);

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s BAKE.h5|LEVEL.pvsr [--frames N] [--objects M] [--seed S] [--quiet]\n", argv[0]);
        return 2;
    }
    int frames = 240;
    int movers_wanted = 300;
    unsigned seed = 1;
    bool quiet = false;
    for (int i = 2; i < argc; ++i) {
        if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) frames = std::max(1, std::atoi(argv[++i]));
        if (std::strcmp(argv[i], "--objects") == 0 && i + 1 < argc)
            movers_wanted = std::max(0, std::atoi(argv[++i]));
        if (std::strcmp(argv[i], "--seed") == 0 && i + 1 < argc)
            seed = unsigned(std::strtoul(argv[++i], nullptr, 10));
        if (std::strcmp(argv[i], "--quiet") == 0) quiet = true;
    }

    // Level load: a runtime file (its magic) through the C99 runtime, anything else through the HDF5 loader.
    const auto t0 = std::chrono::steady_clock::now();
    std::ifstream file(argv[1], std::ios::binary | std::ios::ate);
    char magic[4] = {0, 0, 0, 0};
    if (file) {
        file.seekg(0);
        file.read(magic, 4);
    }
    if (file && std::memcmp(magic, "PVSR", 4) == 0) {
        RuntimeLevel level;
        file.seekg(0, std::ios::end);
        const size_t size = size_t(file.tellg());
        level.bytes.resize((size + 7) / 8);
        file.seekg(0);
        file.read(reinterpret_cast<char*>(level.bytes.data()), std::streamsize(size));
        std::string why;
        if (!file || level.level.open(level.bytes.data(), size, &why) != PVSR_OK) {
            std::fprintf(stderr, "%s: %s\n", argv[1], why.empty() ? "cannot read" : why.c_str());
            return 1;
        }
        const double load_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        std::printf("loaded %s in %.1f ms (runtime file): %u cells (%s), %u objects, %llu triangles, %s PVS (%s)\n",
                    argv[1], load_ms, level.cell_count(), level.kind(), level.object_count(),
                    (unsigned long long)level.total_triangles(), level.mode_label(), level.mode().c_str());
        RuntimeCuller culler;  // allocates once; every frame reuses it
        return play(level, culler, frames, movers_wanted, seed, quiet);
    }
    LoaderLevel level;
    const pvsbake::LoadResult loaded = level.bake.load(argv[1]);
    const double load_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!loaded) {
        std::fprintf(stderr, "%s (%s)\n", loaded.message.c_str(), pvsbake::status_name(loaded.status));
        return 1;
    }
    const pvsbake::Bake& bake = level.bake;
    std::printf("loaded %s in %.1f ms: %u cells (%s), %u objects, %llu triangles, %s PVS (%s)\n", argv[1],
                load_ms, bake.cell_count(), level.kind(), bake.object_count(),
                (unsigned long long)bake.total_triangles(), bake.mode_label(), bake.mode().c_str());
    LoaderCuller culler;  // allocates once; every frame reuses it
    return play(bake, culler, frames, movers_wanted, seed, quiet);
}

namespace {

template <class Level, class Culler>
int play(const Level& bake, Culler& culler, int frames, int movers_wanted, unsigned seed, bool quiet) {
    const uint32_t objects = bake.object_count();
    const uint64_t triangles = bake.total_triangles();
    // The camera path: 8 frames per segment between waypoints; 30 frames a second for the moving objects.
    const std::vector<Vec3> way =
        pvsbake::walk::waypoints(bake, uint32_t(frames / pvsbake::walk::kFramesPerSegment + 2));
    std::mt19937 rng(seed);
    std::vector<pvsbake::walk::Mover> movers =
        pvsbake::walk::spawn_movers(bake, uint32_t(movers_wanted), rng);
    uint64_t drawn_objects = 0, drawn_triangles = 0, pvs_triangles = 0, outside = 0;
    uint64_t moving_tested = 0, moving_culled = 0, culled_by_frusta = 0, culled_by_horizon = 0,
             occluders_used = 0, horizon_given = 0, frames_culling = 0;
    double cull_us = 0.0;
    for (int f = 0; f < frames && !way.empty(); ++f) {
        const Vec3 eye = pvsbake::walk::camera_eye(way, f);
        const float eye_m[3] = {eye.x, eye.y, eye.z};
        pvsbake::walk::step_movers(bake, movers, 1.0f / 30.0f, rng);

        // The per-frame work of a game: find the cell; in the eye space, where the bake promises what its
        // occluders hide, set the culler up with the cell's ranked occluders (elsewhere with none); walk what
        // to draw: the cell's PVS less what they hide from the eye.
        const int32_t cell = bake.find_cell(eye.x, eye.y, eye.z);
        const bool can_cull = cell >= 0 && bake.in_eye_space(eye.x, eye.y, eye.z);
        frames_culling += can_cull;
        const auto c0 = std::chrono::steady_clock::now();
        if (can_cull)
            culler.begin_cell(bake, uint32_t(cell), eye_m);
        else
            culler.begin_empty(bake, eye_m);
        uint32_t n = objects, pvs = objects;
        uint64_t tris = triangles, pvs_tris = triangles;
        if (cell >= 0) {
            n = 0;
            tris = 0;
            culler.for_each_drawn(bake, uint32_t(cell), [&](uint32_t o) {
                ++n;
                tris += bake.object_triangles(o);
            });
        } else {
            ++outside;
        }
        // Moving objects: their boxes against the same occluders.
        uint32_t culled = 0;
        for (const pvsbake::walk::Mover& m : movers) {
            const int path = culler.classify(pvsbake::walk::mover_box(m));
            culled += path != 0;
            culled_by_frusta += path == 1;
            culled_by_horizon += path == 4;
        }
        cull_us += std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - c0).count();
        if (cell >= 0) {  // the PVS, for the printout
            pvs = 0;
            pvs_tris = 0;
            bake.for_each_visible(uint32_t(cell), [&](uint32_t o) {
                ++pvs;
                pvs_tris += bake.object_triangles(o);
            });
        }
        drawn_objects += n;
        drawn_triangles += tris;
        pvs_triangles += pvs_tris;
        moving_tested += movers.size();
        moving_culled += culled;
        occluders_used += culler.occluders_used();
        horizon_given += culler.horizon_given;
        if (!quiet) {
            std::printf(
                "frame %4d  eye (%8.2f %8.2f %8.2f)  cell %7d  draws %5u of the PVS's %5u / %u objects, "
                "%8llu / "
                "%llu / %llu triangles; moving: culled %4u / %zu (%zu occluders)\n",
                f, eye.x, eye.y, eye.z, cell, n, pvs, objects, (unsigned long long)tris,
                (unsigned long long)pvs_tris, (unsigned long long)triangles, culled, movers.size(),
                culler.occluders_used());
        }
    }
    const double fo = double(drawn_objects) / std::max(1.0, double(frames) * objects);
    const double ft = double(drawn_triangles) / std::max(1.0, double(frames) * double(triangles));
    const double fp = double(pvs_triangles) / std::max(1.0, double(frames) * double(triangles));
    std::printf(
        "total: %d frames (%llu outside the view volume, drawn whole): drew %.1f%% of objects and %.1f%% of "
        "triangles (the PVS: %.1f%%)\n",
        frames, (unsigned long long)outside, 100.0 * fo, 100.0 * ft, 100.0 * fp);
    std::printf(
        "moving objects: %zu; the occluders culled %llu of %llu boxes tested (%.1f%%; %llu by single shadow "
        "frusta, %llu by the culler's depth cube or faces, %llu by the horizon alone) with %.1f occluders "
        "and "
        "%.1f horizon occluders a frame; the culling (the level's objects and the moving ones) at %.1f us a "
        "frame; %llu frames in the eye space culled, the others drew the whole PVS and every moving object\n",
        movers.size(), (unsigned long long)moving_culled, (unsigned long long)moving_tested,
        100.0 * double(moving_culled) / std::max(1.0, double(moving_tested)),
        (unsigned long long)culled_by_frusta,
        (unsigned long long)(moving_culled - culled_by_frusta - culled_by_horizon),
        (unsigned long long)culled_by_horizon, double(occluders_used) / std::max(1, frames),
        double(horizon_given) / std::max(1, frames), cull_us / std::max(1, frames),
        (unsigned long long)frames_culling);
    return 0;
}

}  // namespace
