// SPDX-License-Identifier: MIT
// A world written again with edits (samples/world_edit.h).
#include "samples/world_edit.h"

#include "core/convex_clip.h"
#include "core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <map>

namespace pvs {

namespace {

using Polygon = std::vector<glm::dvec3>;

// The convex polygon less the box: the convex pieces outside each of the box's six planes in turn, the
// rest going on to the next plane; what is left after the sixth lies in the box and goes.
std::vector<Polygon> cut_polygon(const Polygon& poly, const Aabb& box) {
    glm::dvec3 lo = poly[0], hi = poly[0];
    for (const glm::dvec3& q : poly) {
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
    }
    if (!Aabb::of(glm::vec3(lo), glm::vec3(hi)).overlaps(box)) return {poly};
    std::vector<Polygon> pieces;
    Polygon rest = poly, part;
    for (int axis = 0; axis < 3; ++axis) {
        for (const bool below : {true, false}) {
            const double at = below ? double(box.min[axis]) : double(box.max[axis]);
            // Wholly beyond the plane (on it counts as beyond, once): it stays whole.
            if (std::all_of(rest.begin(), rest.end(),
                            [&](const glm::dvec3& q) { return below ? q[axis] <= at : q[axis] >= at; })) {
                pieces.push_back(rest);
                return pieces;
            }
            clip(rest, axis, at, below, part);  // the piece beyond this plane stays
            if (part.size() >= 3) pieces.push_back(part);
            clip(rest, axis, at, !below, part);  // the rest goes on
            rest.swap(part);
            if (rest.size() < 3) return pieces;
        }
    }
    return pieces;
}

// An object's triangles as nodes, one per kind (opaque or not, two-sided or not), moved by `offset`, less
// what lies in `cuts` (triangles are clipped; the pieces keep the triangle's facing).
void add_object(SceneDesc& scene, const World& world, const WorldObject& obj, glm::vec3 offset,
                const std::vector<Aabb>& cuts) {
    std::map<int, SceneNode> by_kind;
    for (uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count; ++t) {
        Polygon tri(3);
        for (int k = 0; k < 3; ++k)
            tri[size_t(k)] = glm::dvec3(world.positions[world.triangles[t].v[k]] + offset);
        std::vector<Polygon> pieces{tri};
        for (const Aabb& c : cuts) {
            std::vector<Polygon> next;
            for (const Polygon& piece : pieces)
                for (Polygon& q : cut_polygon(piece, c)) next.push_back(std::move(q));
            pieces = std::move(next);
        }
        std::vector<glm::vec3> corners;  // the pieces as a fan each, slivers of no area left out
        for (const Polygon& piece : pieces)
            for (size_t i = 1; i + 1 < piece.size(); ++i) {
                const glm::dvec3 e = glm::cross(piece[i] - piece[0], piece[i + 1] - piece[0]);
                if (glm::dot(e, e) <= 1e-14) continue;
                for (const glm::dvec3& q : {piece[0], piece[i], piece[i + 1]}) corners.emplace_back(q);
            }
        if (corners.empty()) continue;
        const bool never = (obj.flags & kObjectNeverOccludes) != 0;
        const int kind = (world.triangle_opaque[t] || never ? 0 : 1) +
                         (t < world.triangle_double_sided.size() && world.triangle_double_sided[t] ? 2 : 0);
        SceneNode& n = by_kind[kind];
        for (const glm::vec3& q : corners) {
            n.indices.push_back(uint32_t(n.positions.size()));
            n.positions.push_back(q);
        }
        n.material = kind;
        n.occluder = !never;
        n.always_visible = (obj.flags & kObjectAlwaysVisible) != 0;
    }
    for (auto& [kind, node] : by_kind) {
        node.name = by_kind.size() == 1 ? obj.name : fmt::format("{}#{}", obj.name, kind);
        scene.nodes.push_back(std::move(node));
    }
}

}  // namespace

SceneDesc edited_world(const World& world, const std::vector<WorldEdit>& edits) {
    using Alpha = SceneMaterial::Alpha;
    SceneDesc scene;
    scene.materials = {{"opaque", {0.7f, 0.7f, 0.7f, 1.0f}, Alpha::kOpaque, false},
                       {"see_through", {0.6f, 0.8f, 0.9f, 0.4f}, Alpha::kBlend, false},
                       {"opaque_two_sided", {0.7f, 0.7f, 0.7f, 1.0f}, Alpha::kOpaque, true},
                       {"see_through_two_sided", {0.6f, 0.8f, 0.9f, 0.4f}, Alpha::kBlend, true}};
    std::vector<glm::vec3> offset(world.objects.size(), glm::vec3(0.0f));
    std::vector<bool> removed(world.objects.size(), false);
    std::vector<Aabb> cuts;
    std::vector<SceneNode> added;
    for (const WorldEdit& e : edits) {
        bool found = e.kind == WorldEdit::Kind::kCut || e.kind == WorldEdit::Kind::kAddBox ||
                     e.kind == WorldEdit::Kind::kTile;
        for (size_t o = 0; o < world.objects.size(); ++o) {
            const WorldObject& obj = world.objects[o];
            if (e.kind == WorldEdit::Kind::kMove && obj.name == e.name) {
                offset[o] += e.offset;
                found = true;
            } else if (e.kind == WorldEdit::Kind::kRemove && obj.name == e.name) {
                removed[o] = found = true;
            } else if (e.kind == WorldEdit::Kind::kRemoveIn && e.box.contains(obj.bounds.min) &&
                       e.box.contains(obj.bounds.max)) {
                removed[o] = found = true;
            }
        }
        // An object added by an earlier edit is moved or removed too.
        for (auto it = added.begin(); it != added.end();) {
            if (it->name == e.name && e.kind == WorldEdit::Kind::kMove) {
                for (glm::vec3& q : it->positions) q += e.offset;
                found = true;
            } else if (it->name == e.name && e.kind == WorldEdit::Kind::kRemove) {
                it = added.erase(it);
                found = true;
                continue;
            }
            ++it;
        }
        if (e.kind == WorldEdit::Kind::kCut) cuts.push_back(e.box);
        if (e.kind == WorldEdit::Kind::kAddBox) added.push_back(make_box_node(e.name, e.box, 0));
        if (e.kind == WorldEdit::Kind::kTile &&
            (e.copies.x < 1 || e.copies.y < 1 || e.copies.x * e.copies.y > 4096))
            throw bad_input(fmt::format("tiling {} x {} copies: each count is 1 or more, 4096 copies at most",
                                        e.copies.x, e.copies.y));
        if (!found) {
            throw bad_input(e.kind == WorldEdit::Kind::kRemoveIn
                                ? "--remove-in: no object lies wholly in the box"
                                : fmt::format("no object is named '{}'", e.name));
        }
    }
    for (size_t o = 0; o < world.objects.size(); ++o)
        if (!removed[o]) add_object(scene, world, world.objects[o], offset[o], cuts);
    for (SceneNode& n : added) scene.nodes.push_back(std::move(n));
    for (size_t i = 0; i < world.view_seeds.size(); ++i) {
        SceneNode seed;
        seed.name = fmt::format("view_seed_{}", i);
        seed.translation = world.view_seeds[i];
        seed.view_seed = true;
        scene.nodes.push_back(std::move(seed));
    }
    for (size_t i = 0; i < world.view_volume_boxes.size(); ++i) {
        SceneNode box = make_box_node(fmt::format("view_volume_{}", i), world.view_volume_boxes[i]);
        box.view_volume = true;
        scene.nodes.push_back(std::move(box));
    }
    for (const WorldEdit& e : edits) {
        if (e.kind != WorldEdit::Kind::kTile || e.copies == glm::ivec2(1)) continue;
        std::vector<SceneNode> tiled;
        tiled.reserve(scene.nodes.size() * size_t(e.copies.x * e.copies.y));
        for (int i = 0; i < e.copies.x; ++i) {
            for (int j = 0; j < e.copies.y; ++j) {
                const glm::vec3 step(float(i) * e.offset.x, 0.0f, float(j) * e.offset.z);
                for (const SceneNode& n : scene.nodes) {
                    SceneNode c = n;
                    c.name = fmt::format("{}@{},{}", n.name, i, j);
                    if (n.positions.empty()) {
                        c.translation += step;
                    } else {
                        for (glm::vec3& q : c.positions) q += step;
                    }
                    tiled.push_back(std::move(c));
                }
            }
        }
        scene.nodes = std::move(tiled);
    }
    return scene;
}

Enclosure enclosure(const Aabb& bounds, float thickness) {
    const float t = thickness, lo = bounds.min.y - t, hi = bounds.max.y;
    Enclosure e;
    e.outer = bounds;
    e.outer.min -= glm::vec3(2.0f * t, t, 2.0f * t);
    e.outer.max += glm::vec3(2.0f * t, 0.0f, 2.0f * t);
    const glm::vec3 a = e.outer.min, b = e.outer.max;
    const auto wall = [&](const char* name, glm::vec3 from, glm::vec3 to) {
        e.walls.push_back({WorldEdit::Kind::kAddBox, name, Aabb::of(from, to), {}});
    };
    wall("enclosure_west", {a.x, lo, a.z}, {a.x + t, hi, b.z});
    wall("enclosure_east", {b.x - t, lo, a.z}, {b.x, hi, b.z});
    wall("enclosure_south", {a.x, lo, a.z}, {b.x, hi, a.z + t});
    wall("enclosure_north", {a.x, lo, b.z - t}, {b.x, hi, b.z});
    return e;
}

}  // namespace pvs
