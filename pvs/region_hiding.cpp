// SPDX-License-Identifier: MIT
// Objects one occluder hides from a whole region: the 64 corner segments, candidates by Embree.
#include "pvs/region_hiding.h"

#include "occluders/panels.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace pvs {

namespace {

// Does the segment q -> x meet the closed box [lo, hi]? (Slabs, in double.)
bool segment_meets(const glm::dvec3& q, const glm::dvec3& x, const glm::dvec3& lo, const glm::dvec3& hi) {
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; ++k) {
        const double d = x[k] - q[k];
        if (d == 0.0) {
            if (q[k] < lo[k] || q[k] > hi[k]) return false;
            continue;
        }
        double a = (lo[k] - q[k]) / d, b = (hi[k] - q[k]) / d;
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
        if (t0 > t1) return false;
    }
    return true;
}

}  // namespace

std::array<glm::dvec3, 8> box_corners(const Aabb& b, double grow) {
    const glm::dvec3 lo = glm::dvec3(b.min) - grow, hi = glm::dvec3(b.max) + grow;
    std::array<glm::dvec3, 8> c;
    for (int i = 0; i < 8; ++i)
        c[size_t(i)] = glm::dvec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    return c;
}

World box_world(const std::vector<Aabb>& boxes, const std::vector<Aabb>& flat, bool opaque,
                const std::vector<SlantedPanel>& slanted) {
    static constexpr std::array<std::array<uint32_t, 3>, 12> kFaces{{{0, 2, 1},
                                                                     {1, 2, 3},
                                                                     {4, 5, 6},
                                                                     {5, 7, 6},
                                                                     {0, 1, 4},
                                                                     {1, 5, 4},
                                                                     {2, 6, 3},
                                                                     {3, 6, 7},
                                                                     {0, 4, 2},
                                                                     {2, 4, 6},
                                                                     {1, 3, 5},
                                                                     {3, 7, 5}}};
    World w;
    auto add = [&](const Aabb& b) {
        WorldObject o;
        o.name = "box" + std::to_string(w.objects.size());
        o.bounds = b;
        o.first_triangle = uint32_t(w.triangles.size());
        if (!b.is_empty()) {
            const uint32_t v0 = uint32_t(w.positions.size());
            for (int i = 0; i < 8; ++i)
                w.positions.emplace_back(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y,
                                         i & 4 ? b.max.z : b.min.z);
            for (const auto& f : kFaces) {
                w.triangles.push_back(Triangle{{v0 + f[0], v0 + f[1], v0 + f[2]}});
                w.triangle_opaque.push_back(opaque ? 1 : 0);
                w.triangle_double_sided.push_back(1);
            }
            o.triangle_count = 12;
            o.flags = opaque ? kObjectHasOpaque : kObjectHasSeeThrough;
            w.bounds.extend(b);
        }
        w.objects.push_back(o);  // empty boxes too: object i is box i
    };
    for (const Aabb& b : boxes) add(b);
    for (const Aabb& b : flat) add(b);
    for (const SlantedPanel& p : slanted) {
        WorldObject o;
        o.name = "slanted" + std::to_string(w.objects.size());
        o.bounds = p.bounds;
        o.first_triangle = uint32_t(w.triangles.size());
        const uint32_t v0 = uint32_t(w.positions.size());
        for (const glm::dvec3& c : p.corners) w.positions.emplace_back(c);
        for (uint32_t i = 1; i + 1 < uint32_t(p.corners.size()); ++i) {
            w.triangles.push_back(Triangle{{v0, v0 + i, v0 + i + 1}});
            w.triangle_opaque.push_back(opaque ? 1 : 0);
            w.triangle_double_sided.push_back(1);
        }
        o.triangle_count = uint32_t(w.triangles.size()) - o.first_triangle;
        o.flags = opaque ? kObjectHasOpaque : kObjectHasSeeThrough;
        w.bounds.extend(p.bounds);
        w.objects.push_back(o);
    }
    return w;
}

bool panel_hides(const Aabb& region, const Aabb& object, const Aabb& panel, int axis) {
    const int a = axis, u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double c = panel.min[a], tol = kHideToleranceM;
    const bool region_below = double(region.max[a])<c - tol&& double(object.min[a])> c + tol;
    const bool region_above = double(region.min[a]) > c + tol && double(object.max[a]) < c - tol;
    if (!region_below && !region_above) return false;
    const double u0 = double(panel.min[u]) + tol, u1 = double(panel.max[u]) - tol;
    const double v0 = double(panel.min[v]) + tol, v1 = double(panel.max[v]) - tol;
    if (!(u0 <= u1 && v0 <= v1)) return false;
    const std::array<glm::dvec3, 8> rc = box_corners(region), oc = box_corners(object);
    for (const glm::dvec3& q : rc)
        for (const glm::dvec3& x : oc) {
            const double t = (c - q[a]) / (x[a] - q[a]);  // in (0, 1): q and x are on opposite sides
            const double yu = q[u] + t * (x[u] - q[u]), yv = q[v] + t * (x[v] - q[v]);
            if (!(yu >= u0 && yu <= u1 && yv >= v0 && yv <= v1)) return false;
        }
    return true;
}

bool box_hides(const Aabb& region, const Aabb& object, const Aabb& box) {
    const glm::dvec3 lo = glm::dvec3(box.min) + kHideToleranceM, hi = glm::dvec3(box.max) - kHideToleranceM;
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) return false;
    const std::array<glm::dvec3, 8> rc = box_corners(region), oc = box_corners(object);
    for (const glm::dvec3& q : rc)
        for (const glm::dvec3& x : oc)
            if (!segment_meets(q, x, lo, hi)) return false;
    return true;
}

bool slanted_hides(const Aabb& region, const Aabb& object, const SlantedPanel& panel) {
    const size_t n = panel.corners.size();
    if (n < 3) return false;
    const glm::dvec3 normal = panel.normal;
    const double tol = kHideToleranceM;
    const std::array<glm::dvec3, 8> rc = box_corners(region), oc = box_corners(object);
    auto support = [&](const std::array<glm::dvec3, 8>& c) {
        double lo = INFINITY, hi = -INFINITY;
        for (const glm::dvec3& p : c) {
            const double h = glm::dot(normal, p);
            lo = std::min(lo, h);
            hi = std::max(hi, h);
        }
        return std::pair{lo, hi};
    };
    const auto [r_lo, r_hi] = support(rc);
    const auto [o_lo, o_hi] = support(oc);
    const double below = panel.offset - panel.thickness - tol, above = panel.offset + panel.thickness + tol;
    if (!((r_hi < below && o_lo > above) || (o_hi < below && r_lo > above))) return false;
    // The polygon's edges as inward half-planes m.x >= k + tol (m in the plane, square to the edge). Their
    // intersection lies in the polygon even if rounding left it a hair short of convex.
    if (panel.edge_normal.size() != n || panel.edge_offset.size() != n) return false;
    const std::vector<glm::dvec3>& m = panel.edge_normal;
    const std::vector<double>& k = panel.edge_offset;
    const double faces[2] = {panel.offset - panel.thickness, panel.offset + panel.thickness};
    for (const glm::dvec3& q : rc)
        for (const glm::dvec3& x : oc) {
            const double hq = glm::dot(normal, q), hx = glm::dot(normal, x);
            for (double face : faces) {
                const double t = (face - hq) / (hx - hq);  // in (0, 1): q and x lie beyond the slab's faces
                const glm::dvec3 y = q + t * (x - q);
                for (size_t i = 0; i < n; ++i)
                    if (!(glm::dot(m[i], y) >= k[i] + tol)) return false;
            }
        }
    return true;
}

RegionHider::RegionHider(Context& ctx, const ShrunkOccluders& set)
    : boxes_(set.boxes.empty() ? std::vector<Aabb>{} : set.boxes.front()),
      panels_(set.panels),
      slanted_(set.slanted) {
    for (const Aabb& p : panels_) panel_axis_.push_back(panel_axis(p));
    // Embree's own log lines would repeat per set: a quiet context for the scene, one line here.
    Context quiet(Context::Options{LogLevel::kWarning, true, nullptr});
    scene_ = std::make_unique<RayScene>(quiet, box_world(boxes_, panels_, false, slanted_),
                                        BuildQuality::kMedium, 1);
    ctx.debug(fmt::format("single-occluder pass: {} boxes, {} panels and {} slanted panels as candidates",
                          boxes_.size(), panels_.size(), slanted_.size()));
}

RegionHider::~RegionHider() = default;

RegionHiders::RegionHiders(Context& ctx, const ShrunkOccluders& occluders) {
    hiders_.push_back(std::make_unique<RegionHider>(ctx, occluders));
    for (const ShrunkOccluders& set : occluders.block_sets)
        hiders_.push_back(std::make_unique<RegionHider>(ctx, set));
}

bool RegionHider::occluder_hides(const Aabb& region, const Aabb& object, uint32_t k) const {
    const uint32_t n_boxes = uint32_t(boxes_.size()), n_flat = n_boxes + uint32_t(panels_.size());
    if (k < n_boxes) return box_hides(region, object, boxes_[k]);
    if (k < n_flat)
        return panel_axis_[k - n_boxes] >= 0 &&
               panel_hides(region, object, panels_[k - n_boxes], panel_axis_[k - n_boxes]);
    return slanted_hides(region, object, slanted_[k - n_flat]);
}

namespace {

// The objects tried: every one of `objects` with bounds apart from the region, with the direction and
// distance from the region's centre to the centre of its bounds.
struct Tried {
    std::vector<uint32_t> objects;
    std::vector<glm::vec3> dirs;
    std::vector<float> tfar;
};

Tried objects_to_try(const World& world, const Aabb& region, const std::vector<uint32_t>& objects) {
    Tried tried;
    const glm::vec3 from = region.center();
    for (uint32_t o : objects) {
        const Aabb& b = world.objects[o].bounds;
        if (b.is_empty() || b.overlaps(region)) continue;
        const glm::vec3 d = b.center() - from;
        const float len = glm::length(d);
        if (!(len > 0.0f)) continue;
        tried.objects.push_back(o);
        tried.dirs.push_back(d / len);
        tried.tfar.push_back(len);
    }
    return tried;
}

}  // namespace

// One ray per object, from the region's centre to the centre of the object's bounds: an occluder hiding
// the object from the whole region meets every segment between them, so this one too. The ray stops at
// the first occluder touched that hides the object.
uint32_t RegionHider::hide(const World& world, const Aabb& region, const std::vector<uint32_t>& objects,
                           uint64_t* hidden) const {
    if (region.is_empty() || (boxes_.empty() && panels_.empty() && slanted_.empty())) return 0;
    const Tried tried = objects_to_try(world, region, objects);
    if (tried.objects.empty()) return 0;
    struct Test {
        const RegionHider* hider;
        const World* world;
        const Aabb* region;
        const Tried* tried;
        std::vector<uint32_t> last;  // per ray, the occluder last refused (a box is touched twice)
    } test{this, &world, &region, &tried, std::vector<uint32_t>(tried.objects.size(), UINT32_MAX)};
    const RayScene::TouchTest accept = [](void* user, uint32_t ray, uint32_t k) {
        auto* t = static_cast<Test*>(user);
        if (t->last[ray] == k) return false;
        t->last[ray] = k;
        return t->hider->occluder_hides(*t->region, t->world->objects[t->tried->objects[ray]].bounds, k);
    };
    std::vector<uint8_t> found(tried.objects.size(), 0);
    scene_->touches_any(region.center(), tried.dirs.data(), tried.tfar.data(), uint32_t(tried.objects.size()),
                        accept, &test, found.data());
    uint32_t n = 0;
    for (size_t r = 0; r < found.size(); ++r) {
        if (!found[r]) continue;
        const uint32_t o = tried.objects[r];
        hidden[o >> 6] |= uint64_t(1) << (o & 63);
        ++n;
    }
    return n;
}

uint32_t RegionHider::hide_reference(const World& world, const Aabb& region,
                                     const std::vector<uint32_t>& objects, uint64_t* hidden) const {
    if (region.is_empty() || (boxes_.empty() && panels_.empty() && slanted_.empty())) return 0;
    const Tried tried = objects_to_try(world, region, objects);
    uint32_t n = 0;
    std::vector<RayTouch> touches;
    for (size_t r = 0; r < tried.objects.size(); ++r) {
        touches.clear();
        scene_->trace_reference(region.center(), &tried.dirs[r], 1, touches);
        const uint32_t o = tried.objects[r];
        bool is_hidden = false;
        for (const RayTouch& t : touches)
            if (t.t <= tried.tfar[r] && occluder_hides(region, world.objects[o].bounds, t.object))
                is_hidden = true;
        if (is_hidden) {
            hidden[o >> 6] |= uint64_t(1) << (o & 63);
            ++n;
        }
    }
    return n;
}

}  // namespace pvs
