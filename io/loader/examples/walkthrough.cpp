// pvsbake example: a game loop over a bake. Loads the bake at "level load", then every frame moves a
// camera along a smooth path through the world's cells (a Catmull-Rom spline through the centres of
// neighbouring cells, going straight where it can), looks up the camera's cell and walks its PVS, and prints
// how many objects and triangles it would draw against all of them. Outside the view volume a game draws
// everything.
//
//   pvsbake_walkthrough BAKE.h5 [--frames N] [--quiet]
//
// Links pvsbake::loader only (find_package(pvsbake) + target_link_libraries(game pvsbake::loader)).
#include <pvsbake/loader.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

struct Vec3 {
    float x, y, z;
};

Vec3 center_of(const pvsbake::Box& b) {
    return {0.5f * (b.min[0] + b.max[0]), 0.5f * (b.min[1] + b.max[1]), 0.5f * (b.min[2] + b.max[2])};
}

// Catmull-Rom between p1 and p2 at t in [0, 1].
Vec3 spline(Vec3 p0, Vec3 p1, Vec3 p2, Vec3 p3, float t) {
    auto c = [t](float a, float b, float c, float d) {
        return 0.5f * (2 * b + (-a + c) * t + (2 * a - 5 * b + 4 * c - d) * t * t +
                       (-a + 3 * b - 3 * c + d) * t * t * t);
    };
    return {c(p0.x, p1.x, p2.x, p3.x), c(p0.y, p1.y, p2.y, p3.y), c(p0.z, p1.z, p2.z, p3.z)};
}

// Waypoints: `count` cell centres, each in a face neighbour of the one before (the one straight ahead when
// it can, else turning), never back into a cell already visited while another way is open. Starts at the
// first cell whose centre lies in the view volume.
std::vector<Vec3> waypoints(const pvsbake::Bake& bake, uint32_t count) {
    std::vector<Vec3> path;
    std::vector<bool> visited(bake.cell_count(), false);
    int32_t cell = -1;
    Vec3 at{};
    for (uint32_t c = 0; c < bake.cell_count() && cell < 0; ++c) {
        at = center_of(bake.cell_bounds(c));
        if (bake.find_cell(at.x, at.y, at.z) == int32_t(c)) cell = int32_t(c);
    }
    int heading = 0;  // 0..5: +x, -x, +y, -y, +z, -z
    while (cell >= 0 && path.size() < count) {
        path.push_back(at);
        visited[size_t(cell)] = true;
        const pvsbake::Box box = bake.cell_bounds(uint32_t(cell));
        int32_t next = -1, fallback = -1;
        Vec3 next_at{}, fallback_at{};
        int next_heading = heading;
        for (int turn = 0; turn < 6 && next < 0; ++turn) {
            const int h = (heading + turn) % 6;
            const int axis = h / 2;
            const float step = (box.max[axis] - box.min[axis]) * (h % 2 ? -1.0f : 1.0f);
            Vec3 p = at;
            (axis == 0 ? p.x : axis == 1 ? p.y : p.z) += step;
            const int32_t c = bake.find_cell(p.x, p.y, p.z);
            if (c < 0 || c == cell) continue;
            const Vec3 centre = center_of(bake.cell_bounds(uint32_t(c)));
            const Vec3 q =
                bake.find_cell(centre.x, centre.y, centre.z) == c ? centre : p;  // stay in the volume
            if (!visited[size_t(c)]) {
                next = c;
                next_at = q;
                next_heading = h;
            } else if (fallback < 0) {
                fallback = c;
                fallback_at = q;
            }
        }
        heading = next_heading;
        cell = next >= 0 ? next : fallback;
        at = next >= 0 ? next_at : fallback_at;
    }
    return path;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s BAKE.h5 [--frames N] [--quiet]\n", argv[0]);
        return 2;
    }
    int frames = 240;
    bool quiet = false;
    for (int i = 2; i < argc; ++i) {
        if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) frames = std::max(1, std::atoi(argv[++i]));
        if (std::strcmp(argv[i], "--quiet") == 0) quiet = true;
    }

    // Level load.
    const auto t0 = std::chrono::steady_clock::now();
    pvsbake::Bake bake;
    const pvsbake::LoadResult loaded = bake.load(argv[1]);
    const double load_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!loaded) {
        std::fprintf(stderr, "%s (%s)\n", loaded.message.c_str(), pvsbake::status_name(loaded.status));
        return 1;
    }
    const uint32_t objects = bake.object_count();
    const uint64_t triangles = bake.total_triangles();
    std::printf("loaded %s in %.1f ms: %u cells (%s), %u objects, %llu triangles, %s PVS (%s)\n", argv[1],
                load_ms, bake.cell_count(), bake.cell_kind() == pvsbake::CellKind::kGrid ? "grid" : "octree",
                objects, (unsigned long long)triangles, bake.mode_label(), bake.mode().c_str());

    // The camera path: 8 frames per segment between waypoints.
    const int per_segment = 8;
    const std::vector<Vec3> way = waypoints(bake, uint32_t(frames / per_segment + 2));
    uint64_t drawn_objects = 0, drawn_triangles = 0, outside = 0;
    for (int f = 0; f < frames && !way.empty(); ++f) {
        const size_t seg = std::min(way.size() - 1, size_t(f / per_segment));
        const float t = float(f % per_segment) / float(per_segment);
        auto at = [&](long i) { return way[size_t(std::clamp<long>(i, 0, long(way.size()) - 1))]; };
        const Vec3 eye = spline(at(long(seg) - 1), at(long(seg)), at(long(seg) + 1), at(long(seg) + 2), t);

        // The per-frame work of a game: find the cell, walk its PVS.
        const int32_t cell = bake.find_cell(eye.x, eye.y, eye.z);
        uint32_t n = objects;
        uint64_t tris = triangles;
        // Ranked occluders (format 1.2) a game would test its moving objects against, best first.
        const uint32_t occluders = cell >= 0 ? bake.occluder_count(uint32_t(cell)) : 0;
        if (cell >= 0) {
            n = 0;
            tris = 0;
            bake.for_each_visible(uint32_t(cell), [&](uint32_t o) {
                ++n;
                tris += bake.object_triangles(o);
            });
        } else {
            ++outside;
        }
        drawn_objects += n;
        drawn_triangles += tris;
        if (!quiet) {
            std::printf(
                "frame %4d  eye (%8.2f %8.2f %8.2f)  cell %7d  draws %5u / %u objects, %8llu / %llu "
                "triangles, %u occluders\n",
                f, eye.x, eye.y, eye.z, cell, n, objects, (unsigned long long)tris,
                (unsigned long long)triangles, occluders);
        }
    }
    const double fo = double(drawn_objects) / std::max(1.0, double(frames) * objects);
    const double ft = double(drawn_triangles) / std::max(1.0, double(frames) * double(triangles));
    std::printf(
        "total: %d frames (%llu outside the view volume, drawn whole): drew %.1f%% of objects and %.1f%% of "
        "triangles\n",
        frames, (unsigned long long)outside, 100.0 * fo, 100.0 * ft);
    return 0;
}
