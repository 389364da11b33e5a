// SPDX-License-Identifier: MIT
// pvsbake example helpers: the camera path of the game-loop example (pvsbake_walkthrough) and the moving
// objects it culls. Shared with bench/bench_runtime_cull.cpp, which follows the same path and moves the
// same objects to check the culler against rays. A level is any type with cell_count(), cell_bounds(c)
// giving a pvsbake::Box and find_cell(x, y, z): pvsbake::Bake, or the example's view of a runtime file.
//
// Conventions: glTF axes (right-handed, +Y up), metres, seconds.
#pragma once

#include <pvsbake/loader.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace pvsbake::walk {

struct Vec3 {
    float x, y, z;
};

inline Vec3 center_of(const Box& b) {
    return {0.5f * (b.min[0] + b.max[0]), 0.5f * (b.min[1] + b.max[1]), 0.5f * (b.min[2] + b.max[2])};
}

// Catmull-Rom between p1 and p2 at t in [0, 1].
inline Vec3 spline(Vec3 p0, Vec3 p1, Vec3 p2, Vec3 p3, float t) {
    auto c = [t](float a, float b, float c, float d) {
        return 0.5f * (2 * b + (-a + c) * t + (2 * a - 5 * b + 4 * c - d) * t * t +
                       (-a + 3 * b - 3 * c + d) * t * t * t);
    };
    return {c(p0.x, p1.x, p2.x, p3.x), c(p0.y, p1.y, p2.y, p3.y), c(p0.z, p1.z, p2.z, p3.z)};
}

// Waypoints: `count` cell centres, each in a face neighbour of the one before (the one straight ahead when
// it can, else turning), never back into a cell already visited while another way is open. Starts at the
// first cell whose centre lies in the view volume.
template <class Level>
inline std::vector<Vec3> waypoints(const Level& bake, uint32_t count) {
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
        const Box box = bake.cell_bounds(uint32_t(cell));
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

// Frames per segment between waypoints, and the eye at frame f.
constexpr int kFramesPerSegment = 8;
inline Vec3 camera_eye(const std::vector<Vec3>& way, int f) {
    const size_t seg = std::min(way.size() - 1, size_t(f / kFramesPerSegment));
    const float t = float(f % kFramesPerSegment) / float(kFramesPerSegment);
    auto at = [&](long i) { return way[size_t(std::clamp<long>(i, 0, long(way.size()) - 1))]; };
    return spline(at(long(seg) - 1), at(long(seg)), at(long(seg) + 1), at(long(seg) + 2), t);
}

// ---- Moving objects: people (0.6 x 1.8 x 0.6 m, 1.4 m/s) and, one in five, vehicles (2 x 1.6 x 4.5 m,
// 6 m/s), walking straight through the view volume and turning at random where the next step would leave
// it (its centre: the box may reach into walls, which only makes culling harder).
struct Mover {
    Vec3 at;         // box centre
    Vec3 velocity;   // metres per second, horizontal
    Vec3 half_size;  // metres
};

inline Box mover_box(const Mover& m) {
    return Box{{m.at.x - m.half_size.x, m.at.y - m.half_size.y, m.at.z - m.half_size.z},
               {m.at.x + m.half_size.x, m.at.y + m.half_size.y, m.at.z + m.half_size.z}};
}

inline Vec3 random_heading(std::mt19937& rng, float speed) {
    const float a = std::uniform_real_distribution<float>(0.0f, 6.2831853f)(rng);
    return {speed * std::cos(a), 0.0f, speed * std::sin(a)};
}

// `count` movers at random points of random cells (points in the view volume), from a fixed seed.
template <class Level>
inline std::vector<Mover> spawn_movers(const Level& bake, uint32_t count, std::mt19937& rng) {
    std::vector<Mover> movers;
    if (bake.cell_count() == 0) return movers;
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (uint32_t tries = 0; movers.size() < count && tries < 100 * count; ++tries) {
        const Box c = bake.cell_bounds(uint32_t(rng() % bake.cell_count()));
        const Vec3 p{c.min[0] + u(rng) * (c.max[0] - c.min[0]), c.min[1] + u(rng) * (c.max[1] - c.min[1]),
                     c.min[2] + u(rng) * (c.max[2] - c.min[2])};
        if (bake.find_cell(p.x, p.y, p.z) < 0) continue;
        const bool vehicle = movers.size() % 5 == 4;
        const Vec3 half = vehicle ? Vec3{1.0f, 0.8f, 2.25f} : Vec3{0.3f, 0.9f, 0.3f};
        movers.push_back({p, random_heading(rng, vehicle ? 6.0f : 1.4f), half});
    }
    return movers;
}

// One time step of dt_s seconds.
template <class Level>
inline void step_movers(const Level& bake, std::vector<Mover>& movers, float dt_s, std::mt19937& rng) {
    for (Mover& m : movers) {
        const Vec3 next{m.at.x + m.velocity.x * dt_s, m.at.y, m.at.z + m.velocity.z * dt_s};
        if (bake.find_cell(next.x, next.y, next.z) >= 0) {
            m.at = next;
        } else {
            const float speed = std::sqrt(m.velocity.x * m.velocity.x + m.velocity.z * m.velocity.z);
            m.velocity = random_heading(rng, speed);
        }
    }
}

}  // namespace pvsbake::walk
