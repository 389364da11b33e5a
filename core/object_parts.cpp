// SPDX-License-Identifier: MIT
// Part boxes of objects (core/object_parts.h).
#include "core/object_parts.h"

#include "core/convex_clip.h"

#include <algorithm>

namespace pvs {

namespace {

using Polygon = std::vector<glm::dvec3>;

double grown_volume(const Aabb& b) {
    double v = 1.0;
    for (int a = 0; a < 3; ++a) v *= double(b.max[a]) - double(b.min[a]) + 2.0 * kPartSlackM;
    return v;
}

// What a part costs a test: the area of its box grown by the slack (a box's projection grows with it).
double part_cost(const Aabb& b) {
    if (b.is_empty()) return 0.0;
    double s[3];
    for (int a = 0; a < 3; ++a) s[a] = double(b.max[a]) - double(b.min[a]) + 2.0 * kPartSlackM;
    return s[0] * s[1] + s[1] * s[2] + s[2] * s[0];
}

// The bounds of the polygons' corners, each rounded outward to floats, met with the object's bounds (every
// corner lies in them, up to the rounding of a cut).
Aabb polygons_bounds(const std::vector<Polygon>& polygons, const Aabb& bounds) {
    Aabb box;
    for (const Polygon& p : polygons)
        for (const glm::dvec3& v : p)
            for (int a = 0; a < 3; ++a) {
                box.min[a] = std::min(box.min[a], float_at_most(v[a]));
                box.max[a] = std::max(box.max[a], float_at_least(v[a]));
            }
    if (box.is_empty()) return box;
    box.min = glm::max(box.min, bounds.min);
    box.max = glm::min(box.max, bounds.max);
    return box;
}

// The polygons cut by x[axis] = at into the parts at or below it and at or above it; a part with fewer than
// three corners is dropped (its points lie on the plane, in the other side's part).
void cut(const std::vector<Polygon>& polygons, int axis, double at, std::vector<Polygon>& below,
         std::vector<Polygon>& above) {
    below.clear();
    above.clear();
    Polygon part;
    for (const Polygon& p : polygons) {
        clip(p, axis, at, true, part);
        if (part.size() >= 3) below.push_back(part);
        clip(p, axis, at, false, part);
        if (part.size() >= 3) above.push_back(part);
    }
}

struct Leaf {
    std::vector<Polygon> polygons;
    Aabb box;
    double cost = 0.0;
    // The best cut, once searched: its gain (the cost it saves; 0: none) and its plane.
    bool searched = false;
    double gain = 0.0;
    int axis = 0;
    double at = 0.0;
};

// The cut of the leaf that saves the most cost, among the planes at each 1 / kPartCutsPerAxis of its box on
// each axis.
void search_cut(Leaf& leaf, const Aabb& bounds, std::vector<Polygon>& below, std::vector<Polygon>& above) {
    leaf.searched = true;
    leaf.gain = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double lo = double(leaf.box.min[a]), hi = double(leaf.box.max[a]);
        if (!(hi > lo)) continue;
        for (int k = 1; k < kPartCutsPerAxis; ++k) {
            const double at = lo + (hi - lo) * k / kPartCutsPerAxis;
            cut(leaf.polygons, a, at, below, above);
            const double gain = leaf.cost - part_cost(polygons_bounds(below, bounds)) -
                                part_cost(polygons_bounds(above, bounds));
            if (gain > leaf.gain) {
                leaf.gain = gain;
                leaf.axis = a;
                leaf.at = at;
            }
        }
    }
}

}  // namespace

std::vector<Aabb> object_part_boxes(const World& world, uint32_t object, uint32_t max_parts) {
    const WorldObject& obj = world.objects[object];
    std::vector<Leaf> leaves(1);
    for (uint32_t k = 0; k < obj.triangle_count; ++k) {
        const Triangle& t = world.triangles[obj.first_triangle + k];
        leaves[0].polygons.push_back({glm::dvec3(world.positions[t.v[0]]),
                                      glm::dvec3(world.positions[t.v[1]]),
                                      glm::dvec3(world.positions[t.v[2]])});
    }
    leaves[0].box = polygons_bounds(leaves[0].polygons, obj.bounds);
    leaves[0].cost = part_cost(leaves[0].box);
    if (leaves[0].box.is_empty()) return {};
    std::vector<Polygon> below, above;
    for (uint32_t round = 0; leaves.size() < std::max(max_parts, 1u) && round < 4 * kMaxObjectParts;
         ++round) {
        size_t best = leaves.size();
        for (size_t i = 0; i < leaves.size(); ++i) {
            if (!leaves[i].searched) search_cut(leaves[i], obj.bounds, below, above);
            if (leaves[i].gain > 0.0 && (best == leaves.size() || leaves[i].gain > leaves[best].gain))
                best = i;
        }
        if (best == leaves.size()) break;  // no cut makes the parts cheaper
        cut(leaves[best].polygons, leaves[best].axis, leaves[best].at, below, above);
        Leaf lo, hi;
        lo.polygons = std::move(below);
        hi.polygons = std::move(above);
        below.clear();
        above.clear();
        for (Leaf* l : {&lo, &hi}) {
            l->box = polygons_bounds(l->polygons, obj.bounds);
            l->cost = part_cost(l->box);
        }
        leaves[best] = std::move(lo);
        if (!hi.polygons.empty()) leaves.push_back(std::move(hi));
    }
    std::vector<Aabb> boxes;
    for (const Leaf& l : leaves)
        if (!l.box.is_empty()) boxes.push_back(l.box);
    return boxes;
}

ObjectParts object_parts(const World& world, uint32_t max_parts) {
    ObjectParts out;
    if (max_parts < 2) return out;
    max_parts = std::min(max_parts, kMaxObjectParts);
    out.offsets.reserve(world.objects.size() + 1);
    out.offsets.push_back(0);
    for (uint32_t o = 0; o < uint32_t(world.objects.size()); ++o) {
        const WorldObject& obj = world.objects[o];
        if ((obj.flags & kObjectAlwaysVisible) == 0 && !obj.bounds.is_empty()) {
            const std::vector<Aabb> parts = object_part_boxes(world, o, max_parts);
            double volume = 0.0;
            for (const Aabb& p : parts) volume += grown_volume(p);
            if (parts.size() >= 2 && volume < kPartVolumeShare * grown_volume(obj.bounds))
                out.boxes.insert(out.boxes.end(), parts.begin(), parts.end());
        }
        out.offsets.push_back(uint32_t(out.boxes.size()));
    }
    return out;
}

}  // namespace pvs
