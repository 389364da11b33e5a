// The voxels a world's extent gets, and how far each object reaches from the rest (cells/world_extent.h).
#include "cells/world_extent.h"

#include "core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pvs {

namespace {

double distance_to_box(const Aabb& box, glm::vec3 p) {
    const glm::dvec3 d = glm::max(glm::max(glm::dvec3(box.min) - glm::dvec3(p), glm::dvec3(p) - glm::dvec3(box.max)),
                                  glm::dvec3(0.0));
    return std::sqrt(glm::dot(d, d));
}

}  // namespace

std::vector<ObjectReach> farthest_objects(const World& world, size_t count) {
    const size_t n = world.objects.size();
    // What every object is measured against besides the other objects: the view seeds and boxes.
    Aabb markers;
    for (const glm::vec3& s : world.view_seeds) markers.extend(s);
    for (const Aabb& b : world.view_volume_boxes)
        if (!b.is_empty()) markers.extend(b);
    // The bounds of every object but i: a prefix and a suffix union, O(n).
    std::vector<Aabb> before(n + 1), after(n + 1);
    for (size_t i = 0; i < n; ++i) {
        before[i + 1] = before[i];
        if (world.objects[i].triangle_count) before[i + 1].extend(world.objects[i].bounds);
    }
    for (size_t i = n; i-- > 0;) {
        after[i] = after[i + 1];
        if (world.objects[i].triangle_count) after[i].extend(world.objects[i].bounds);
    }
    std::vector<ObjectReach> out;
    for (size_t i = 0; i < n; ++i) {
        Aabb rest = markers;
        if (!before[i].is_empty()) rest.extend(before[i]);
        if (!after[i + 1].is_empty()) rest.extend(after[i + 1]);
        const WorldObject& o = world.objects[i];
        if (rest.is_empty() || o.triangle_count == 0) continue;
        ObjectReach r{uint32_t(i), 0.0, {}};
        for (uint32_t t = o.first_triangle; t < o.first_triangle + o.triangle_count; ++t)
            for (uint32_t v : world.triangles[t].v) {
                const double d = distance_to_box(rest, world.positions[v]);
                if (d > r.distance_m) r = {uint32_t(i), d, world.positions[v]};
            }
        if (r.distance_m > 0.0) out.push_back(r);
    }
    std::sort(out.begin(), out.end(), [](const ObjectReach& a, const ObjectReach& b) {
        return a.distance_m != b.distance_m ? a.distance_m > b.distance_m : a.object < b.object;
    });
    // Only those that stand out: within a tenth of the farthest reach.
    const double floor_m = out.empty() ? 0.0 : 0.1 * out.front().distance_m;
    std::erase_if(out, [&](const ObjectReach& r) { return r.distance_m < floor_m; });
    if (out.size() > count) out.resize(count);
    return out;
}

std::string format_distance(double metres) {
    if (metres >= 1000.0) return fmt::format("{:.1f} km", metres * 1e-3);
    if (metres >= 10.0) return fmt::format("{:.0f} m", metres);
    return fmt::format("{:.2f} m", metres);
}

std::string describe_reaches(const World& world, const std::vector<ObjectReach>& reaches) {
    std::string out;
    for (const ObjectReach& r : reaches) {
        if (!out.empty()) out += "; ";
        out += fmt::format("object '{}' has a vertex {} from the rest of the world (at {:.1f}, {:.1f}, {:.1f})",
                           world.objects[r.object].name, format_distance(r.distance_m), r.vertex.x, r.vertex.y,
                           r.vertex.z);
    }
    return out;
}

VoxelGrid view_voxel_grid(const ViewVolumeConfig& config, const World& world, double preferred_m, int pad_voxels) {
    const glm::vec3 e = world.bounds.size();
    const auto outliers = [&] {
        const std::string far = describe_reaches(world, farthest_objects(world, 3));
        return far.empty() ? std::string("no object reaches far from the rest: the world is just large")
                           : far;
    };
    const bool automatic = !(config.voxel_size_m > 0.0);
    const uint64_t cap = std::min(config.max_voxels, kMaxVoxels);  // make_voxel_grid()'s own limit
    const double size = automatic ? default_voxel_size(world.bounds, preferred_m, cap) : config.voxel_size_m;
    const int pad = pad_voxels > 0 ? pad_voxels : void_pad_voxels(size);
    const double count = voxel_grid_count(world.bounds, size, pad);
    if (!automatic && count > double(cap)) {
        throw bad_input(fmt::format(
            "view volume: --voxel-size {} m over the world's bounds ({:.1f} x {:.1f} x {:.1f} m) makes {:.3g} "
            "voxels, over --max-voxels {}: {}. Use a larger --voxel-size, or raise --max-voxels (the memory "
            "plan then says what they cost)",
            size, e.x, e.y, e.z, count, cap, outliers()));
    }
    const double cells = config.cell_edge_m > 0.0 ? config.cell_edge_m : std::numeric_limits<double>::infinity();
    const double limit = std::min(config.max_voxel_size_m, cells);
    if (automatic && size > preferred_m && size > limit && !config.allow_coarse_voxels) {
        const double wanted = voxel_grid_count(world.bounds, preferred_m, void_pad_voxels(preferred_m));
        throw bad_input(fmt::format(
            "view volume: the world's bounds ({:.1f} x {:.1f} x {:.1f} m) need {:.3g} m voxels to stay within "
            "--max-voxels {}, coarser than {} {} m: {}. Remove the stray geometry, or raise --max-voxels "
            "({} m voxels need {:.3g}), or pass --allow-coarse-voxels to bake anyway",
            e.x, e.y, e.z, size, cap, limit < config.max_voxel_size_m ? "the cells'" : "--max-voxel-size",
            limit, outliers(), preferred_m, wanted));
    }
    return make_voxel_grid(world.bounds, size, pad);
}

}  // namespace pvs
