// SPDX-License-Identifier: MIT
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
    const glm::dvec3 d = glm::max(
        glm::max(glm::dvec3(box.min) - glm::dvec3(p), glm::dvec3(p) - glm::dvec3(box.max)), glm::dvec3(0.0));
    return std::sqrt(glm::dot(d, d));
}

// Every object that reaches out of the rest, with the longest edge of that rest, in object order.
std::vector<std::pair<ObjectReach, double>> reaches(const World& world) {
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
    std::vector<std::pair<ObjectReach, double>> out;
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
        // A rest of view seeds and boxes alone (a level exported as one mesh) has no extent to stand apart
        // from: such an object is never called stray.
        const bool others = !before[i].is_empty() || !after[i + 1].is_empty();
        const glm::dvec3 e = glm::dvec3(rest.size());
        const double rest_edge = others ? std::max({e.x, e.y, e.z}) : std::numeric_limits<double>::infinity();
        if (r.distance_m > 0.0) out.emplace_back(r, rest_edge);
    }
    return out;
}

std::vector<ObjectReach> farthest_first(std::vector<ObjectReach> out, size_t count) {
    std::sort(out.begin(), out.end(), [](const ObjectReach& a, const ObjectReach& b) {
        return a.distance_m != b.distance_m ? a.distance_m > b.distance_m : a.object < b.object;
    });
    if (out.size() > count) out.resize(count);
    return out;
}

}  // namespace

std::vector<ObjectReach> farthest_objects(const World& world, size_t count) {
    std::vector<ObjectReach> out;
    for (const auto& [r, rest_edge] : reaches(world)) out.push_back(r);
    return farthest_first(std::move(out), count);
}

std::vector<ObjectReach> stray_objects(const World& world, size_t count) {
    std::vector<ObjectReach> out;
    for (const auto& [r, rest_edge] : reaches(world))
        if (r.distance_m >= std::max(rest_edge, kStrayMinReachM)) out.push_back(r);
    return farthest_first(std::move(out), count);
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
        out += fmt::format(
            "object '{}' has a vertex {} from the rest of the world (at {:.1f}, {:.1f}, {:.1f})",
            world.objects[r.object].name, format_distance(r.distance_m), r.vertex.x, r.vertex.y, r.vertex.z);
    }
    return out;
}

VoxelGrid view_voxel_grid(const ViewVolumeConfig& config, const World& world, double preferred_m,
                          int pad_voxels) {
    const glm::vec3 e = world.bounds.size();
    const bool automatic = !(config.voxel_size_m > 0.0);
    const auto grid_of = [&](double size) {
        return make_voxel_grid(world.bounds, size, pad_voxels > 0 ? pad_voxels : void_pad_voxels(size));
    };
    const auto count_of = [&](double size) {
        return voxel_grid_count(world.bounds, size, pad_voxels > 0 ? pad_voxels : void_pad_voxels(size));
    };
    if (!automatic) {
        // An explicit size: the grid's own limit only; the memory plan says whether it fits the machine.
        if (count_of(config.voxel_size_m) > double(kMaxVoxels)) {
            const std::string strays = describe_reaches(world, stray_objects(world, 3));
            throw bad_input(
                fmt::format("view volume: --voxel-size {} m over the world's bounds ({:.1f} x {:.1f} x "
                            "{:.1f} m) makes {:.3g} "
                            "voxels, more than a voxel grid can hold ({:.3g}){}{}. Use a larger --voxel-size",
                            config.voxel_size_m, e.x, e.y, e.z, count_of(config.voxel_size_m),
                            double(kMaxVoxels), strays.empty() ? "" : ": ", strays));
        }
        return grid_of(config.voxel_size_m);
    }
    // Automatic: the preferred size, coarser to stay within --max-voxels, but never coarser than
    // --max-voxel-size or the cells (docs/ALGORITHMS.md#world-extent).
    const uint64_t target = config.max_voxels > 0 ? std::min(config.max_voxels, kMaxVoxels) : kMaxVoxels;
    const double fit = default_voxel_size(world.bounds, preferred_m, target);
    const double cells =
        config.cell_edge_m > 0.0 ? config.cell_edge_m : std::numeric_limits<double>::infinity();
    const double limit = std::max(preferred_m, std::min(config.max_voxel_size_m, cells));
    if (fit <= limit) return grid_of(fit);
    const char* limit_name = limit < config.max_voxel_size_m ? "the cells'" : "--max-voxel-size";
    if (config.allow_coarse_voxels) return grid_of(fit);
    // Past the target: a world whose bounds an object stands apart from is almost always a broken file;
    // one that is just large keeps voxels of the limit, and the memory plan decides whether it fits.
    const std::vector<ObjectReach> strays = stray_objects(world, 3);
    if (!strays.empty()) {
        throw bad_input(fmt::format(
            "view volume: the world's bounds ({:.1f} x {:.1f} x {:.1f} m) need {:.3g} m voxels to stay "
            "within "
            "--max-voxels {}, coarser than {} {} m, because {}. Remove the stray geometry, or pass "
            "--allow-coarse-voxels to bake anyway",
            e.x, e.y, e.z, fit, target, limit_name, limit, describe_reaches(world, strays)));
    }
    if (count_of(limit) > double(kMaxVoxels)) {
        throw bad_input(
            fmt::format("view volume: the world's bounds ({:.1f} x {:.1f} x {:.1f} m) make {:.3g} voxels of "
                        "{} {} m, more "
                        "than a voxel grid can hold ({:.3g}); no object stands apart from the rest: the "
                        "world is just large. "
                        "Raise --max-voxel-size, or pass --allow-coarse-voxels to bake with coarser voxels",
                        e.x, e.y, e.z, count_of(limit), limit_name, limit, double(kMaxVoxels)));
    }
    return grid_of(limit);
}

}  // namespace pvs
