// SPDX-License-Identifier: MIT
// Ranking by sight: the candidates' ray scene and the first-hit counts (occluders/sight_ranking.h).
#include "occluders/sight_ranking.h"

#include "rays/surface_points.h"

#include <algorithm>

namespace pvs {

namespace {

void add_candidate(World& w, const Aabb& b) {
    WorldObject o;
    o.name = "occluder" + std::to_string(w.objects.size());
    o.bounds = b;
    o.first_triangle = uint32_t(w.triangles.size());
    o.flags = kObjectHasOpaque;
    const uint32_t base = uint32_t(w.positions.size());
    for (int c = 0; c < 8; ++c)
        w.positions.push_back(
            glm::vec3(c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y, c & 4 ? b.max.z : b.min.z));
    // The six faces as two triangles each; a face of a panel's flat axis collapses to a point or a line
    // and is left out, so a panel is its rectangle (twice, from both sides: one rectangle once).
    static const uint32_t kFaces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                          {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
    const glm::vec3 size = b.size();
    for (int f = 0; f < 6; ++f) {
        const int axis = f / 2;  // the face's normal axis
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        if (!(size[u] > 0.0f) || !(size[v] > 0.0f)) continue;
        if (size[axis] == 0.0f && f % 2 == 1) continue;  // a panel: one rectangle
        const uint32_t* q = kFaces[f];
        w.triangles.push_back(Triangle{{base + q[0], base + q[1], base + q[2]}});
        w.triangles.push_back(Triangle{{base + q[0], base + q[2], base + q[3]}});
    }
    o.triangle_count = uint32_t(w.triangles.size()) - o.first_triangle;
    w.triangle_opaque.resize(w.triangles.size(), 1);
    w.triangle_double_sided.resize(w.triangles.size(), 1);
    w.bounds.extend(b);
    w.objects.push_back(o);
}

void add_polygon(World& w, const OccluderPolygon& p) {
    WorldObject o;
    o.name = "occluder" + std::to_string(w.objects.size());
    o.bounds = p.bounds;
    o.first_triangle = uint32_t(w.triangles.size());
    o.flags = kObjectHasOpaque;
    const uint32_t base = uint32_t(w.positions.size());
    for (const glm::vec3& c : p.corners) w.positions.push_back(c);
    for (uint32_t i = 1; i + 1 < p.corners.size(); ++i)
        w.triangles.push_back(Triangle{{base, base + i, base + i + 1}});
    o.triangle_count = uint32_t(w.triangles.size()) - o.first_triangle;
    w.triangle_opaque.resize(w.triangles.size(), 1);
    w.triangle_double_sided.resize(w.triangles.size(), 1);
    w.bounds.extend(p.bounds);
    w.objects.push_back(o);
}

}  // namespace

OccluderSightScene::OccluderSightScene(Context& ctx, const std::vector<Aabb>& candidates,
                                       const std::vector<OccluderPolygon>& polygons) {
    for (const Aabb& b : candidates) add_candidate(world_, b);
    for (const OccluderPolygon& p : polygons) add_polygon(world_, p);
    scene_ = std::make_unique<RayScene>(ctx, world_, BuildQuality::kMedium);
}

void OccluderSightScene::first_hits(const glm::vec3* eyes, const glm::vec3* points, uint32_t count,
                                    uint32_t* first) const {
    std::vector<glm::vec3> dirs(count);
    std::vector<float> ends(count);
    for (uint32_t i = 0; i < count; ++i) {
        const glm::vec3 d = points[i] - eyes[i];
        const float len = glm::length(d);
        dirs[i] = len > 0.0f ? d / len : glm::vec3(1, 0, 0);
        ends[i] = len - kSightEndMargin_m;
        first[i] = UINT32_MAX;
    }
    std::vector<RayTouch> touches;
    scene_->trace_from(eyes, dirs.data(), count, touches);
    std::vector<float> nearest(count, INFINITY);
    for (const RayTouch& t : touches) {
        if (!t.stops || !(t.t < ends[t.ray]) || !(t.t < nearest[t.ray])) continue;
        nearest[t.ray] = t.t;
        first[t.ray] = t.object;
    }
}

void count_first_hits(const OccluderSightScene& scene, const World& world,
                      const std::vector<double>& cum_area, const uint64_t* pvs_row,
                      const std::vector<glm::vec3>& eyes, uint32_t lines, Rng& rng,
                      std::vector<uint32_t>& out) {
    out.assign(scene.world().objects.size(), 0);
    std::vector<uint32_t> objects;
    std::vector<double> cum;
    double total = 0.0;
    for (uint32_t o = 0; o < world.objects.size(); ++o) {
        if (!((pvs_row[o >> 6] >> (o & 63)) & 1u) || world.objects[o].triangle_count == 0) continue;
        objects.push_back(o);
        total += double(world.objects[o].triangle_count);
        cum.push_back(total);
    }
    if (objects.empty() || eyes.empty() || lines == 0) return;
    std::vector<glm::vec3> from(lines), to(lines);
    for (uint32_t i = 0; i < lines; ++i) {
        from[i] = eyes[i % eyes.size()];
        const double pick = double(rng.uniform()) * total;
        const size_t k = std::min(size_t(std::upper_bound(cum.begin(), cum.end(), pick) - cum.begin()),
                                  objects.size() - 1);
        to[i] = random_point_on(world, cum_area, objects[k], rng);
    }
    std::vector<uint32_t> first(lines);
    scene.first_hits(from.data(), to.data(), lines, first.data());
    for (uint32_t f : first)
        if (f != UINT32_MAX) ++out[f];
}

}  // namespace pvs
