// A world written again with edits (samples/world_edit.h).
#include "samples/world_edit.h"

#include "core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <map>

namespace pvs {

namespace {

// An object's triangles as nodes, one per kind (opaque or not, two-sided or not), moved by `offset`, less
// the triangles whose centroid lies in one of `cuts`.
void add_object(SceneDesc& scene, const World& world, const WorldObject& obj, glm::vec3 offset,
                const std::vector<Aabb>& cuts) {
    std::map<int, SceneNode> by_kind;
    for (uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count; ++t) {
        std::array<glm::vec3, 3> p;
        for (int k = 0; k < 3; ++k) p[size_t(k)] = world.positions[world.triangles[t].v[k]] + offset;
        const glm::vec3 centroid = (p[0] + p[1] + p[2]) / 3.0f;
        if (std::any_of(cuts.begin(), cuts.end(), [&](const Aabb& c) { return c.contains(centroid); }))
            continue;
        const bool never = (obj.flags & kObjectNeverOccludes) != 0;
        const int kind = (world.triangle_opaque[t] || never ? 0 : 1) +
                         (t < world.triangle_double_sided.size() && world.triangle_double_sided[t] ? 2 : 0);
        SceneNode& n = by_kind[kind];
        for (const glm::vec3& q : p) {
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
        bool found = e.kind == WorldEdit::Kind::kCut || e.kind == WorldEdit::Kind::kAddBox;
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
    return scene;
}

}  // namespace pvs
