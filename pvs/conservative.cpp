// SPDX-License-Identifier: MIT
// The conservative solver: every cell's boundary cut into patches, refined where objects are not yet proven
// hidden; a depth cube of the shrunk occluders from each patch centre. Safety argument:
// docs/ALGORITHMS.md#conservative-pvs.
#include "pvs/conservative.h"

#include "cells/eyes.h"
#include "core/box_tree.h"
#include "occluders/panels.h"
#include "rays/ray_sampler.h"
#include "rays/surface_points.h"
#include "pvs/depth_cube.h"
#include "pvs/region_hiding.h"
#include "pvs/shaft_hiding.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <map>
#include <limits>
#include <optional>

namespace pvs {

namespace {

// Finer occludee boxes per object: its triangles in runs of kTrianglesPerPart, each run's bounds. An
// object whose one box is not proven hidden may still be, part by part (all parts hidden = hidden).
constexpr uint32_t kTrianglesPerPart = 1;

std::vector<std::vector<Aabb>> object_parts(const World& world) {
    std::vector<std::vector<Aabb>> parts(world.objects.size());
    for (size_t o = 0; o < world.objects.size(); ++o) {
        const WorldObject& obj = world.objects[o];
        for (uint32_t t0 = 0; t0 < obj.triangle_count; t0 += kTrianglesPerPart) {
            Aabb b;
            for (uint32_t t = t0; t < std::min(obj.triangle_count, t0 + kTrianglesPerPart); ++t) {
                for (uint32_t v : world.triangles[obj.first_triangle + t].v) b.extend(world.positions[v]);
            }
            parts[o].push_back(b);
        }
    }
    return parts;
}

// The object tree (core/box_tree.h) over the objects that can ever be left out (not pvs_always_visible).
// An object with empty bounds is never proven hidden (is_hidden() says visible), so it is listed: the safe
// side.
BoxTree object_tree(const World& world) {
    std::vector<Aabb> bounds(world.objects.size());
    std::vector<uint32_t> objects;
    for (uint32_t o = 0; o < world.objects.size(); ++o) {
        bounds[o] = world.objects[o].bounds;
        if (!(world.objects[o].flags & kObjectAlwaysVisible)) objects.push_back(o);
    }
    return BoxTree::build(bounds, &objects);
}

// Does the row list object o?
inline bool row_lists(const uint64_t* row, uint32_t o) {
    return (row[o >> 6] >> (o & 63)) & 1u;
}

// Are all voxels that meet the closed box (grown by a hair) set in the mask? False when the box reaches
// outside the mask's grid, or the mask is empty.
bool box_all_in_mask(const VoxelMask& mask, const Aabb& box) {
    if (mask.empty()) return false;
    constexpr float kHair = 1e-4f;
    glm::ivec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
        const float l = (box.min[a] - kHair - mask.origin[a]) / mask.voxel_size_m;
        const float h = (box.max[a] + kHair - mask.origin[a]) / mask.voxel_size_m;
        if (!(l >= 0.0f) || !(h < float(mask.dims[a]))) return false;
        lo[a] = int(std::floor(l));
        hi[a] = int(std::floor(h));
    }
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x)
                if (!mask.get(uint64_t(x) +
                              uint64_t(mask.dims.x) * (uint64_t(y) + uint64_t(mask.dims.y) * uint64_t(z))))
                    return false;
    return true;
}

struct Counts {
    uint64_t samples = 0, skipped = 0, in_solid = 0, tests = 0, rays = 0, fine_samples = 0, panel_splits = 0,
             known = 0, patch_hidden = 0;
    std::vector<uint64_t> per_level;
    Counts& operator+=(const Counts& o) {
        known += o.known;
        patch_hidden += o.patch_hidden;
        samples += o.samples;
        skipped += o.skipped;
        in_solid += o.in_solid;
        tests += o.tests;
        rays += o.rays;
        fine_samples += o.fine_samples;
        panel_splits += o.panel_splits;
        per_level.resize(std::max(per_level.size(), o.per_level.size()), 0);
        for (size_t k = 0; k < o.per_level.size(); ++k) per_level[k] += o.per_level[k];
        return *this;
    }
};

// Points on each object to aim sight rays at: the centroids of up to kRayTargets of its triangles, spread
// over its triangle list. first[o]..first[o + 1] index `points`.
constexpr uint32_t kRayTargets = 8;

struct RayTargets {
    std::vector<uint32_t> first;
    std::vector<glm::vec3> points;
};

RayTargets ray_targets(const World& world) {
    RayTargets out;
    for (const WorldObject& obj : world.objects) {
        out.first.push_back(uint32_t(out.points.size()));
        const uint32_t n = std::min(obj.triangle_count, kRayTargets);
        for (uint32_t k = 0; k < n; ++k) {
            const Triangle& t =
                world.triangles[obj.first_triangle + uint32_t(uint64_t(k) * obj.triangle_count / n)];
            out.points.push_back(
                (world.positions[t.v[0]] + world.positions[t.v[1]] + world.positions[t.v[2]]) / 3.0f);
        }
    }
    out.first.push_back(uint32_t(out.points.size()));
    return out;
}

// Trees over one occluder set (ShrunkOccluders::set): its boxes at each epsilon level, its panels and the
// bounds of its slanted panels; a sample finds those near it through them, not by testing every one, so its
// cost does not grow with the size of the world (docs/ALGORITHMS.md#object-bvh).
struct OccluderTrees {
    std::vector<BoxTree> boxes;  // per epsilon level
    BoxTree panels;
    std::vector<int8_t> panel_axis;  // per panel: panel_axis(), -1 when not flat along one axis
    BoxTree slanted;
    std::vector<std::array<uint32_t, 2>> corners;  // panel_corners() of its panels
    std::vector<Aabb> corner_boxes;                // each pair's line (a box flat along two axes)
    BoxTree corner_tree;                           // over them
};

// With `corners`, also its panels' corner pairs and their tree (drawn only with --corner-pairs).
OccluderTrees occluder_trees(const ShrunkOccluders& set, bool corners) {
    OccluderTrees trees;
    for (const std::vector<Aabb>& level : set.boxes) trees.boxes.push_back(BoxTree::build(level));
    trees.panels = BoxTree::build(set.panels);
    for (const Aabb& p : set.panels) trees.panel_axis.push_back(int8_t(panel_axis(p)));
    std::vector<Aabb> slanted(set.slanted.size());
    for (size_t i = 0; i < slanted.size(); ++i) slanted[i] = set.slanted[i].bounds;
    trees.slanted = BoxTree::build(slanted);
    if (!corners) return trees;
    trees.corners = panel_corners(set.panels);
    for (const auto& [i, j] : trees.corners)
        trees.corner_boxes.push_back(Aabb::of(glm::max(set.panels[i].min, set.panels[j].min),
                                              glm::min(set.panels[i].max, set.panels[j].max)));
    trees.corner_tree = BoxTree::build(trees.corner_boxes);
    return trees;
}

// What every thread shares: the world, its object tree, parts and ray targets, the occluders and their
// trees, the rays.
struct Shared {
    const World& world;
    const ShrunkOccluders& occ;
    const RayScene& scene;
    BoxTree tree;                          // over the objects (object_tree())
    std::vector<OccluderTrees> occ_trees;  // [set + 1]: the global set, then each block's
    std::vector<std::vector<Aabb>> parts;
    RayTargets targets;
    int cube_resolution;
    int fine_cube_resolution;  // 0: no second look at the floor
    int panel_refine_levels;   // halvings below the floor for what panels may still prove
    bool slanted_cubes;        // slanted panels are drawn on the cubes too
    bool corner_pairs;         // and corner pairs
    bool panel_bands;          // the panels' depth bands
};

// Per thread: the depth cube and scratch. solve_patch() refines one patch.
class PatchSolver {
public:
    explicit PatchSolver(const Shared& shared)
        : sh_(shared),
          cube_(shared.cube_resolution),
          fine_(std::max(shared.fine_cube_resolution, kMinCubeResolution)),
          open_mark_(shared.world.objects.size(), 0),
          last_seen_part_(shared.world.objects.size(), 0),
          open_under_(shared.tree.nodes.size(), 0) {
        counts_.per_level.assign(shared.occ.epsilon_m.size(), 0);
        cube_.set_panel_bands(shared.panel_bands);
        fine_.set_panel_bands(shared.panel_bands);
    }

    // The occluders of the next faces: those serving the eyes of the region whose face it is
    // (ShrunkOccluders::set_for; every set has the same epsilon ladder).
    // With `hider` (the single-occluder pass, pvs/region_hiding.h; of the same set), what a patch's cubes
    // leave open is also tried against one occluder at a time, exactly, before it is refined or listed.
    void use(int32_t set, const RegionHider* hider = nullptr) {
        occ_ = &sh_.occ.set(set);
        trees_ = &sh_.occ_trees[size_t(set + 1)];
        hider_ = hider;
    }

    // Sight leaves a convex region through a face outward (docs/ALGORITHMS.md#eye-region), so what it reaches
    // through the face lies on the face's outer side: for the side at the region's min along `axis` (side 0)
    // only objects reaching down to the face's plane matter, for side 1 only objects reaching up to it. A
    // face shared by two regions is solved for both sides at once, on the same depth cubes: Sides holds the
    // open objects and the row of each side (an empty list: that side is not wanted).
    struct Sides {
        std::array<std::vector<uint32_t>, 2> open;
        std::array<uint64_t*, 2> row{nullptr, nullptr};
        std::array<uint64_t*, 2> seen{nullptr, nullptr};  // or null: objects a sight ray saw, per side
        bool empty() const { return open[0].empty() && open[1].empty(); }
    };

    // The open objects of `candidates` on each wanted side of the face at `plane` along `axis`, less those
    // the region of that side already lists (`known_lo`, `known_hi`: its row so far, or null;
    // docs/ALGORITHMS.md#refinement). Objects in `hidden_lo`, `hidden_hi` (the single-occluder pass proved
    // them hidden from that side's region, pvs/region_hiding.h) are left out too.
    Sides sides_of(const std::vector<uint32_t>& candidates, int axis, float plane, uint64_t* row_lo,
                   uint64_t* row_hi, const uint64_t* known_lo = nullptr, const uint64_t* known_hi = nullptr,
                   const uint64_t* hidden_lo = nullptr, const uint64_t* hidden_hi = nullptr) {
        Sides out;
        out.row = {row_lo, row_hi};
        const auto in = [](const uint64_t* row, uint32_t o) { return row && row_lists(row, o); };
        for (uint32_t o : candidates) {
            const Aabb& b = sh_.world.objects[o].bounds;
            if (row_lo && b.min[axis] <= plane && !in(hidden_lo, o)) {
                if (in(known_lo, o)) {
                    ++counts_.known;
                } else {
                    out.open[0].push_back(o);
                }
            }
            if (row_hi && b.max[axis] >= plane && !in(hidden_hi, o)) {
                if (in(known_hi, o)) {
                    ++counts_.known;
                } else {
                    out.open[1].push_back(o);
                }
            }
        }
        return out;
    }

    // Lists in each side's row every object of its open list that some patch of the face `rect` (flat along
    // `axis`) cannot prove hidden. The face is first cut into n x n top patches so that halving them m times
    // ends at patches of half-side <= epsilon_0 (the Chebyshev radius, docs/ALGORITHMS.md#chebyshev) with as
    // few leaves as a plain grid would need (within 20% more), and with m as large as that allows and the
    // ladder has levels for.
    void solve_face(const Aabb& rect, int axis, const Sides& sides) {
        const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
        const glm::vec3 size = rect.size();
        const double eps0 = occ_->epsilon_m.front();
        const double side = std::max(size[ua], size[va]);
        const int need = std::max(1, int(std::ceil(side / (2.0 * eps0) - 1e-9)));
        int m = 0;
        for (int t = 1; t < int(occ_->epsilon_m.size()) && (1 << t) <= need; ++t) {
            const int n_leaf = ((need + (1 << t) - 1) >> t) << t;
            if (double(n_leaf) * n_leaf <= 1.2 * double(need) * need) m = t;
        }
        const int n = (need + (1 << m) - 1) >> m;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                Aabb p = rect;
                p.min[ua] = rect.min[ua] + size[ua] * float(i) / float(n);
                p.max[ua] = i + 1 == n ? rect.max[ua] : rect.min[ua] + size[ua] * float(i + 1) / float(n);
                p.min[va] = rect.min[va] + size[va] * float(j) / float(n);
                p.max[va] = j + 1 == n ? rect.max[va] : rect.min[va] + size[va] * float(j + 1) / float(n);
                solve_patch(p, axis, sides);
            }
    }

    // Lists in each side's row every object of its open list that some sub-patch of `rect` (flat along
    // `axis`) cannot prove hidden. `sides` is consumed.
    void solve_patch(const Aabb& rect, int axis, Sides sides) {
        // What an earlier patch of the face listed needs no proof here (docs/ALGORITHMS.md#refinement):
        // patches are solved one after another, depth first, so the row holds what the patches before this
        // one listed.
        for (int side = 0; side < 2; ++side) {
            const uint64_t* row = sides.row[size_t(side)];
            if (!row) continue;
            std::vector<uint32_t>& open = sides.open[size_t(side)];
            const size_t before = open.size();
            std::erase_if(open, [row](uint32_t o) { return row_lists(row, o); });
            counts_.known += before - open.size();
        }
        if (sides.empty()) return;
        // No sight line leaves through it (docs/ALGORITHMS.md#patches).
        if (box_all_in_mask(occ_->solid, rect)) {
            ++counts_.in_solid;
            return;
        }
        // The box around the sample s (the float centre) that holds the whole patch: its half-extent on
        // each axis is the distance from s to the farther side, in double; r, the largest, is the patch's
        // radius in the Chebyshev metric (docs/ALGORITHMS.md#chebyshev).
        const glm::vec3 s = rect.center();
        glm::dvec3 spread(0.0);
        for (int a = 0; a < 3; ++a)
            spread[a] = std::max(double(s[a]) - double(rect.min[a]), double(rect.max[a]) - double(s[a]));
        const double r = std::max({spread.x, spread.y, spread.z});
        const std::vector<double>& eps = occ_->epsilon_m;
        // The smallest epsilon >= r. r is exact: the differences of floats are exact in double (unless
        // their exponents differ by more than 29), so a face cut in patches of exactly epsilon_0 a side, as
        // voxel-aligned faces are, reaches the floor.
        size_t k = 0;
        while (k < eps.size() && eps[k] < r) ++k;
        if (k < eps.size()) {
            bool inside = false;
            trees_->boxes[k].walk([&](const Aabb& b) { return !inside && b.contains(s); },
                                  [&](uint32_t) { inside = true; });
            if (inside) {  // its epsilon-cube, which holds the patch, lies in the solid
                ++counts_.skipped;
                return;
            }
            ++counts_.samples;
            ++counts_.per_level[k];
            interest_.clear();
            for (const std::vector<uint32_t>& open : sides.open)
                for (uint32_t o : open) interest_.push_back(sh_.world.objects[o].bounds);
            cube_.clear_for(s, interest_);  // only the open objects' pixels are drawn, cleared and read
            // Only occluders meeting the box around s and the open objects (a segment from s to an open
            // object stays in it): drawing fewer is always safe, and these are nearly all that matter.
            Aabb reach = Aabb::of(s, s);
            for (const Aabb& b : interest_) reach.extend(b);
            // Found through the set's trees; boxes are put back in the set's order, so that add_occluders()
            // draws them in the same order as after a scan of every box.
            const auto meets_reach = [&reach](const Aabb& b) { return b.overlaps(reach); };
            found_.clear();
            trees_->boxes[k].walk(meets_reach, [&](uint32_t i) { found_.push_back(i); });
            std::sort(found_.begin(), found_.end());
            near_.clear();
            for (uint32_t i : found_) near_.push_back(occ_->boxes[k][i]);
            // Panels (docs/ALGORITHMS.md#panel-inset) whose plane the patch's box does not reach, inset per
            // ray for that box; drawn first, they are cheap and hide many boxes behind them, which
            // add_occluders() then skips.
            near_panels_.clear();
            panel_spread_ = spread * (1.0 + 1e-6);
            // (In the tree's order: a panel lowers a pixel to the least depth drawn there, whatever the
            // order.)
            trees_->panels.walk(meets_reach, [&](uint32_t i) {
                const Aabb& p = occ_->panels[i];
                const int a = trees_->panel_axis[i];
                if (a >= 0 && std::abs(double(p.min[a]) - double(s[a])) > panel_spread_[a])
                    near_panels_.push_back(p);
            });
            cube_.add_panels(near_panels_, panel_spread_);
            cube_.add_occluders(near_);
            for (int side = 0; side < 2; ++side)
                sides.open[size_t(side)] = unproven(cube_, sides.open[size_t(side)]);
            // The panels on the cube's side faces too (rays more than 45 degrees from a panel's normal;
            // docs/ALGORITHMS.md#panel-inset), drawn only over what is still unproven: a subset of the open
            // objects, so its pixels lie in the region clear_for() cleared. At every level, not only the
            // floor: what they prove on a large patch needs no smaller ones.
            if (!sides.empty() && !near_panels_.empty()) {
                open_hulls(s, sides);
                for (const Aabb& p : near_panels_)
                    if (meets_open_hulls(p)) cube_.add_panel_sides(p, panel_spread_);
                for (int side = 0; side < 2; ++side)
                    sides.open[size_t(side)] = unproven_each(cube_, sides.open[size_t(side)]);
            }
            // Corner pairs (docs/ALGORITHMS.md#corner-pairs) over what is still unproven: those whose line,
            // grown by the patch box's reach, meets the box around s and an open object's union (the pixels a
            // pair writes are rays that pass near its line; drawing fewer is always safe).
            if (sh_.corner_pairs && !sides.empty() && !trees_->corners.empty()) {
                open_hulls(s, sides);
                const float grow = float(2.0 * (panel_spread_.x + panel_spread_.y + panel_spread_.z));
                const Aabb grown_reach = Aabb::of(reach.min - grow, reach.max + grow);
                size_t drawn = 0;
                trees_->corner_tree.walk(
                    [&grown_reach](const Aabb& b) { return b.overlaps(grown_reach); },
                    [&](uint32_t c) {
                        const Aabb& line = trees_->corner_boxes[c];
                        if (!meets_open_hulls(Aabb::of(line.min - grow, line.max + grow))) return;
                        const auto& [i, j] = trees_->corners[c];
                        cube_.add_corner(occ_->panels[i], occ_->panels[j], panel_spread_);
                        ++drawn;
                    });
                if (drawn > 0)
                    for (int side = 0; side < 2; ++side)
                        sides.open[size_t(side)] = unproven_each(cube_, sides.open[size_t(side)]);
            }
            // Slanted panels (docs/ALGORITHMS.md#slanted-inset), on every face, over what is still unproven
            // (the same pixels' depths fuse with the boxes' and panels'): those meeting the box around s and
            // an object left open, as above; add_slanted_panel() leaves out those whose slab the patch's box
            // reaches.
            near_slanted_.clear();
            if (sh_.slanted_cubes && !sides.empty() && !occ_->slanted.empty()) {
                open_hulls(s, sides);
                Aabb all = hulls_[0];  // the union of the octants' unions, to skip most panels at once
                for (const Aabb& h : hulls_) all.extend(h);
                trees_->slanted.walk([&all](const Aabb& b) { return b.overlaps(all); },
                                     [&](uint32_t i) {
                                         if (slanted_may_hide(occ_->slanted[i], s))
                                             near_slanted_.push_back(i);
                                     });
                std::sort(near_slanted_.begin(), near_slanted_.end());
                cube_.add_slanted_panels(occ_->slanted, near_slanted_, panel_spread_);
                for (int side = 0; side < 2; ++side)
                    sides.open[size_t(side)] = unproven_each(cube_, sides.open[size_t(side)]);
            }
            // The single-occluder pass for the patch (a sight line leaving through it meets the occluder
            // beyond it; docs/ALGORITHMS.md#single-occluder).
            if (hider_)
                for (int side = 0; side < 2; ++side)
                    sides.open[size_t(side)] = hidden_by_one(rect, sides.open[size_t(side)]);
            if (k == 0) {  // the floor: whatever is not proven is listed
                // Below the floor (docs/ALGORITHMS.md#refinement): the boxes stay shrunk by epsilon_0, but
                // panels need no epsilon, so a patch half the size insets them by half as much. While the
                // panels are drawn here, what they left open goes down panel_refine_levels more halvings
                // (sight rays first, as above the floor); what is left after them is listed.
                if (!sides.empty() && (!near_panels_.empty() || !near_slanted_.empty()) &&
                    r > eps[0] / double(1 << sh_.panel_refine_levels)) {
                    for (int side = 0; side < 2; ++side)
                        sides.open[size_t(side)] = list_seen(
                            s, sides.open[size_t(side)], sides.row[size_t(side)], sides.seen[size_t(side)]);
                    if (sides.empty()) return;
                    ++counts_.panel_splits;
                    split(rect, axis, sides);
                    return;
                }
                if (sh_.fine_cube_resolution > 0 && !sides.empty()) second_look(s, sides);
                for (int side = 0; side < 2; ++side) {
                    for (uint32_t o : sides.open[size_t(side)])
                        sides.row[size_t(side)][o >> 6] |= uint64_t(1) << (o & 63);
                    sides.open[size_t(side)].clear();
                }
                return;
            }
            if (sides.empty()) return;
            for (int side = 0; side < 2; ++side)
                sides.open[size_t(side)] =
                    list_seen(s, sides.open[size_t(side)], sides.row[size_t(side)], sides.seen[size_t(side)]);
        }
        split(rect, axis, sides);
    }

    // Limits the cube to the pixels of the objects still open, and gathers their bounds by the octant of
    // their centre around s, each octant's union grown from s (hulls_). An occluder that lowers a pixel
    // below an open object's depth there has every ray of the pixel cross it first, so on a segment from s
    // into the object's bounds, which that union holds: an occluder meeting no union cannot help (drawing
    // fewer is always safe). Testing eight unions, not every open object, which may be thousands on open
    // levels.
    void open_hulls(glm::vec3 s, const Sides& sides) {
        interest_.clear();
        for (const std::vector<uint32_t>& open : sides.open)
            for (uint32_t o : open) interest_.push_back(sh_.world.objects[o].bounds);
        cube_.limit_to(interest_);
        hulls_.fill(Aabb::of(s, s));
        hull_used_.fill(false);
        for (const Aabb& b : interest_) {
            const glm::vec3 c = b.center();
            const int octant = (c.x > s.x ? 1 : 0) | (c.y > s.y ? 2 : 0) | (c.z > s.z ? 4 : 0);
            hulls_[size_t(octant)].extend(b);
            hull_used_[size_t(octant)] = true;
        }
    }
    bool meets_open_hulls(const Aabb& b) const {
        for (size_t o = 0; o < 8; ++o)
            if (hull_used_[o] && b.overlaps(hulls_[o])) return true;
        return false;
    }

    // Does the slanted panel meet an octant's union whose part beyond the panel's slab, seen from s, is not
    // empty? (What it hides lies beyond its slab; see open_hulls().)
    bool slanted_may_hide(const SlantedPanel& p, glm::vec3 s) const {
        const double side = glm::dot(p.normal, glm::dvec3(s)) - p.offset > 0.0 ? 1.0 : -1.0;
        const glm::dvec3 n = side * p.normal;
        for (size_t o = 0; o < 8; ++o) {
            if (!hull_used_[o] || !p.bounds.overlaps(hulls_[o])) continue;
            double lowest = 0.0;  // the least n.x over the union's corners
            for (int k = 0; k < 3; ++k)
                lowest += n[k] * double(n[k] >= 0.0 ? hulls_[o].min[k] : hulls_[o].max[k]);
            if (lowest < side * p.offset - p.thickness) return true;
        }
        return false;
    }

    const Counts& counts() const { return counts_; }

    // The objects of `open` no single occluder hides from all of `rect` (pvs/region_hiding.h).
    std::vector<uint32_t> hidden_by_one(const Aabb& rect, std::vector<uint32_t> open) {
        if (open.empty()) return open;
        hidden_.assign((sh_.world.objects.size() + 63) / 64, 0);
        const uint32_t n = hider_->hide(sh_.world, rect, open, hidden_.data());
        if (n == 0) return open;
        counts_.patch_hidden += n;
        std::erase_if(open, [this](uint32_t o) { return row_lists(hidden_.data(), o); });
        return open;
    }

    // Lists the objects of `open` a sight line from s reaches (a ray to a point of one of its triangles that
    // no opaque triangle stops) and returns the others (docs/ALGORITHMS.md#sight-rays). Such an object can
    // never be proven hidden from a patch holding s, so refining it would only cost time: the PVS is the
    // same, sooner. Only from free space (every voxel holding s free: untouched and not proven solid), or
    // rays would start behind walls and reach the backs of triangles through the sealed void.
    // Each object listed so is marked in `seen_row` too, when given.
    std::vector<uint32_t> list_seen(glm::vec3 s, const std::vector<uint32_t>& open, uint64_t* row,
                                    uint64_t* seen_row) {
        if (open.empty() || !box_all_in_mask(sh_.occ.free, Aabb::of(s, s))) return open;
        origins_.clear();
        dirs_.clear();
        tfar_.clear();
        for (uint32_t o : open)
            for (uint32_t p = sh_.targets.first[o]; p < sh_.targets.first[o + 1]; ++p) {
                const glm::vec3 d = sh_.targets.points[p] - s;
                const float len = glm::length(d);
                origins_.push_back(s);
                dirs_.push_back(len > 0.0f ? d / len : glm::vec3(1.0f, 0.0f, 0.0f));
                tfar_.push_back(len * (1.0f - 1e-4f));
            }
        blocked_.resize(origins_.size());
        if (!origins_.empty())
            sh_.scene.occluded_opaque(origins_.data(), dirs_.data(), tfar_.data(), uint32_t(origins_.size()),
                                      blocked_.data());
        counts_.rays += origins_.size();
        std::vector<uint32_t> out;
        size_t ray = 0;
        for (uint32_t o : open) {
            bool seen = false;
            for (uint32_t p = sh_.targets.first[o]; p < sh_.targets.first[o + 1]; ++p, ++ray)
                seen = seen || !blocked_[ray];
            if (seen) {
                row[o >> 6] |= uint64_t(1) << (o & 63);
                if (seen_row) seen_row[o >> 6] |= uint64_t(1) << (o & 63);
            } else {
                out.push_back(o);
            }
        }
        return out;
    }

private:
    // Solves the halves of a patch along its long in-plane sides (both for a square).
    void split(const Aabb& rect, int axis, const Sides& sides) {
        const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
        const glm::vec3 size = rect.size();
        const float longest = std::max(size[ua], size[va]);
        const bool split_u = size[ua] >= 0.5f * longest, split_v = size[va] >= 0.5f * longest;
        for (int iu = 0; iu < (split_u ? 2 : 1); ++iu)
            for (int iv = 0; iv < (split_v ? 2 : 1); ++iv) {
                Aabb child = rect;
                if (split_u) {
                    const float mid = 0.5f * (rect.min[ua] + rect.max[ua]);
                    (iu == 0 ? child.max[ua] : child.min[ua]) = mid;
                }
                if (split_v) {
                    const float mid = 0.5f * (rect.min[va] + rect.max[va]);
                    (iv == 0 ? child.max[va] : child.min[va]) = mid;
                }
                solve_patch(child, axis, sides);
            }
    }

    // At a floor sample, before listing what the cube could not prove: objects a sight ray from s reaches
    // are listed (no cube can prove them), and the rest get a second look on a finer cube (the same
    // occluders and panels, drawn only over their pixels). A pixel of the coarse cube is written only where
    // a box covers all of it and an object claims every pixel its bounds touch, so near every occluder edge
    // about two coarse pixels are lost; the fine cube loses the same count of pixels R_fine / R times
    // smaller. Both tests are conservative (docs/ALGORITHMS.md#depth-cube), so proving on either is enough.
    void second_look(glm::vec3 s, Sides& sides) {
        for (int side = 0; side < 2; ++side)
            sides.open[size_t(side)] =
                list_seen(s, sides.open[size_t(side)], sides.row[size_t(side)], sides.seen[size_t(side)]);
        if (sides.empty()) return;
        interest_.clear();
        for (const std::vector<uint32_t>& open : sides.open)
            for (uint32_t o : open) interest_.push_back(sh_.world.objects[o].bounds);
        fine_.clear_for(s, interest_);
        fine_.add_panels(near_panels_, panel_spread_);
        fine_.add_slanted_panels(occ_->slanted, near_slanted_, panel_spread_);
        fine_.add_occluders(near_);
        ++counts_.fine_samples;
        for (int side = 0; side < 2; ++side)
            sides.open[size_t(side)] = unproven(fine_, sides.open[size_t(side)]);
    }

    // Does the cube prove hidden every part of an object cut into several (its bounds alone were not)?
    // The part that was not hidden last time is tried first: the object's visible part, as a rule, from
    // the neighbouring samples too (the order changes the cost, not the answer).
    bool parts_hidden(const DepthCube& cube, uint32_t o) {
        const std::vector<Aabb>& parts = sh_.parts[o];
        if (parts.size() <= 1) return false;
        const uint32_t first = last_seen_part_[o];
        ++counts_.tests;
        if (!cube.is_hidden(parts[first])) return false;
        for (uint32_t p = 0; p < parts.size(); ++p) {
            if (p == first) continue;
            ++counts_.tests;
            if (!cube.is_hidden(parts[p])) {
                last_seen_part_[o] = p;
                return false;
            }
        }
        return true;
    }

    // The same as unproven(), one object at a time (no tree): for a few objects left after a first pass.
    std::vector<uint32_t> unproven_each(const DepthCube& cube, const std::vector<uint32_t>& open) {
        std::vector<uint32_t> out;
        for (uint32_t o : open) {
            ++counts_.tests;
            if (!cube.is_hidden(sh_.world.objects[o].bounds) && !parts_hidden(cube, o)) out.push_back(o);
        }
        return out;
    }

    // The objects of `open` the cube cannot prove hidden, in the order of `open`.
    std::vector<uint32_t> unproven(const DepthCube& cube, const std::vector<uint32_t>& open) {
        const std::vector<BoxTree::Node>& nodes = sh_.tree.nodes;
        // Mark the nodes with an open object under them: each open leaf's path up to the first node marked
        // already, so the cost follows the open objects, not the size of the tree.
        for (uint32_t o : open) {
            open_mark_[o] = 1;
            for (int32_t n = sh_.tree.leaf[o]; n >= 0 && !open_under_[size_t(n)]; n = nodes[size_t(n)].parent)
                open_under_[size_t(n)] = 1;
        }
        stack_.clear();
        if (!nodes.empty()) stack_.push_back(0);
        while (!stack_.empty()) {
            const int32_t n = stack_.back();
            stack_.pop_back();
            if (!open_under_[size_t(n)]) continue;
            const BoxTree::Node& node = nodes[size_t(n)];
            ++counts_.tests;
            if (cube.is_hidden(node.bounds)) continue;  // every open object under it stays proven
            if (node.item < 0) {
                stack_.push_back(node.right);
                stack_.push_back(node.left);
                continue;
            }
            if (!parts_hidden(cube, uint32_t(node.item)))
                open_mark_[size_t(node.item)] = 2;  // not proven from this sample
        }
        std::vector<uint32_t> out;
        for (uint32_t o : open) {
            // An object outside the tree (only pvs_always_visible ones are, and they are never open) is
            // listed.
            if (open_mark_[o] == 2 || sh_.tree.leaf[o] < 0) out.push_back(o);
            open_mark_[o] = 0;
            for (int32_t n = sh_.tree.leaf[o]; n >= 0 && open_under_[size_t(n)]; n = nodes[size_t(n)].parent)
                open_under_[size_t(n)] = 0;
        }
        return out;
    }

    const Shared& sh_;
    const ShrunkOccluders* occ_ = &sh_.occ;
    const OccluderTrees* trees_ = &sh_.occ_trees.front();
    const RegionHider* hider_ = nullptr;
    std::vector<uint64_t> hidden_;  // scratch: one bit per object
    DepthCube cube_;
    DepthCube fine_;                        // the second look at floor samples (1 pixel when off)
    std::vector<uint8_t> open_mark_;        // per object: 0 not open, 1 open, 2 open and not proven
    std::vector<uint32_t> last_seen_part_;  // per object: the part parts_hidden() last found not hidden
    std::vector<uint8_t> open_under_;       // per tree node: an open object lies under it (unproven())
    std::vector<int32_t> stack_;
    std::vector<Aabb> interest_;     // bounds of the open objects: the only pixels worth drawing
    std::vector<uint32_t> found_;    // scratch: indices found in a tree
    std::vector<Aabb> near_;         // the occluders drawn for the current sample
    std::vector<Aabb> near_panels_;  // the panels drawn for it
    std::array<Aabb, 8> hulls_;      // open_hulls()
    std::array<bool, 8> hull_used_{};
    std::vector<uint32_t> near_slanted_;  // and the slanted ones (indices into the set's)
    glm::dvec3 panel_spread_{0.0};        // and the half-extents of the box around s they are drawn for
    std::vector<glm::vec3> origins_, dirs_;
    std::vector<float> tfar_;
    std::vector<uint8_t> blocked_;
    Counts counts_;
};

// The objects that start open for a face or box: all but pvs_always_visible ones (listed anyway).
std::vector<uint32_t> leavable_objects(const World& world) {
    std::vector<uint32_t> out;
    for (uint32_t o = 0; o < world.objects.size(); ++o)
        if (!(world.objects[o].flags & kObjectAlwaysVisible)) out.push_back(o);
    return out;
}

// The share of the triangles of `all` objects that `some` of them hold (0 when they have none).
double triangle_share(const World& world, const std::vector<uint32_t>& all,
                      const std::vector<uint32_t>& some) {
    double total = 0.0, part = 0.0;
    for (uint32_t o : all) total += double(world.objects[o].triangle_count);
    for (uint32_t o : some) part += double(world.objects[o].triangle_count);
    return total > 0.0 ? part / total : 0.0;
}

}  // namespace

size_t leavable_count(const World& world) {
    return leavable_objects(world).size();
}

uint64_t shaft_candidates(const World& world, uint64_t regions) {
    return regions * uint64_t(leavable_objects(world).size());
}

std::vector<uint32_t> shaft_objects(const ConservativeConfig& config, const World& world, uint64_t regions) {
    if (config.shaft_budget <= 0) return {};
    const std::vector<uint32_t> leavable = leavable_objects(world);
    if (config.shaft_max_pairs == 0 || regions * uint64_t(leavable.size()) <= config.shaft_max_pairs)
        return leavable;
    const uint64_t keep = regions > 0 ? config.shaft_max_pairs / regions : uint64_t(leavable.size());
    // The heaviest first (a stable order: ties by index), then back in index order.
    std::vector<uint32_t> chosen = leavable;
    std::stable_sort(chosen.begin(), chosen.end(), [&](uint32_t a, uint32_t b) {
        return world.objects[a].triangle_count > world.objects[b].triangle_count;
    });
    chosen.resize(size_t(std::min<uint64_t>(keep, chosen.size())));
    std::sort(chosen.begin(), chosen.end());
    if (chosen.empty() || !(triangle_share(world, leavable, chosen) >= config.shaft_min_share)) return {};
    return chosen;
}

double shaft_objects_digest(const World& world, const std::vector<uint32_t>& chosen) {
    if (chosen.size() == leavable_objects(world).size()) return 0.0;
    std::vector<const std::string*> names;
    for (uint32_t o : chosen) names.push_back(&world.objects[o].name);
    std::sort(names.begin(), names.end(), [](const std::string* a, const std::string* b) { return *a < *b; });
    uint64_t h = 1469598103934665603ull;  // FNV-1a, 64 bits; each name ends with a 0 byte
    for (const std::string* n : names) {
        for (const char ch : *n) h = (h ^ uint8_t(ch)) * 1099511628211ull;
        h *= 1099511628211ull;
    }
    return double((h >> 12) | 1u);  // 52 bits, exact in a double, never 0
}

bool shaft_pass_runs(const ConservativeConfig& config, const World& world, uint64_t regions) {
    return !shaft_objects(config, world, regions).empty();
}

int shaft_pair_budget(const ConservativeConfig& config, const World& world, uint64_t regions) {
    constexpr int kShaftMostBudget = 4096;  // --shaft-budget's own limit
    const size_t tried = shaft_objects(config, world, regions).size();
    if (tried == 0 || config.shaft_small_spend <= 0.0) return config.shaft_budget;
    const double candidates = double(regions) * double(tried);
    if (candidates <= 0.0) return config.shaft_budget;
    // Doubled while the whole pass's piece pairs stay within the spend, at most six times: powers of two, so
    // that a re-bake after a small edit mostly keeps the budget its old rows were made with.
    int budget = config.shaft_budget;
    for (int k = 0; k < 6 && budget * 2 <= kShaftMostBudget &&
                    candidates * 2.0 * double(budget) <= config.shaft_small_spend;
         ++k)
        budget *= 2;
    return budget;
}

uint64_t octree_shaft_regions(const std::vector<Aabb>& boxes, double min_cell_m) {
    uint64_t regions = 0;
    for (const Aabb& b : boxes) {
        const glm::vec3 size = b.size();
        const double edge = std::max({double(size.x), double(size.y), double(size.z)});
        uint64_t split = 1;  // cells along an edge
        while (min_cell_m > 0.0 && double(split) * min_cell_m < edge * (1.0 - 1e-6) && split < (1u << 20))
            split *= 2;
        regions += split * split * split;
    }
    return regions;
}

uint64_t grid_shaft_regions(const ConservativeConfig&, const CellSet& cells) { return cells.size(); }

namespace {

// A grid cell's position in the grid.
glm::ivec3 grid_position(const CellSet& cells, uint32_t c) {
    glm::ivec3 g;
    for (int a = 0; a < 3; ++a) {
        const double at =
            (double(cells.cells[c].bounds.center()[a]) - double(cells.origin[a])) / double(cells.cell_size_m);
        g[a] = std::clamp(int(std::floor(at)), 0, cells.dims[a] - 1);
    }
    return g;
}

}  // namespace

std::vector<std::vector<uint32_t>> grid_shaft_blocks(const CellSet& cells, int k) {
    k = std::max(k, 1);
    const glm::ivec3 nb = (cells.dims + glm::ivec3(k - 1)) / k;
    std::vector<int64_t> first(size_t(nb.x) * size_t(nb.y) * size_t(nb.z), -1);
    std::vector<std::vector<uint32_t>> blocks;
    for (uint32_t c = 0; c < cells.size(); ++c) {
        const glm::ivec3 g = grid_position(cells, c) / k;
        int64_t& b = first[size_t(g.x) + size_t(nb.x) * (size_t(g.y) + size_t(nb.y) * size_t(g.z))];
        if (b < 0) {
            b = int64_t(blocks.size());
            blocks.emplace_back();
        }
        blocks[size_t(b)].push_back(c);
    }
    return blocks;
}

namespace {

// The pass cap's note (docs/ALGORITHMS.md#shaft-cap): the objects the pass tries over `regions` (`chosen`)
// and what the cap leaves untried; and the figures of the choice.
void note_shaft_objects(Context& ctx, const ConservativeConfig& config, const World& world, uint64_t regions,
                        const std::vector<uint32_t>& leavable, const std::vector<uint32_t>& chosen,
                        ConservativeFigures& figures, ShaftFigures& shaft) {
    if (config.shaft_budget <= 0 || chosen.size() == leavable.size()) {
        if (!chosen.empty() && figures.shaft_objects == 0) {
            figures.shaft_objects = chosen.size();
            figures.shaft_objects_triangle_share = 1.0;
        }
        return;
    }
    shaft.skipped_candidates += regions * uint64_t(leavable.size() - chosen.size());
    if (chosen.empty()) {
        ctx.info(fmt::format(
            "shaft pass: not run: {} regions x {} objects = {} candidate pairs, over --shaft-max-pairs {}, "
            "and the objects with the most triangles that fit hold less than --shaft-min-share {} of them "
            "(raise either to run the pass, at about a thread-millisecond a pair it tries)",
            regions, leavable.size(), regions * leavable.size(), config.shaft_max_pairs,
            config.shaft_min_share));
        return;
    }
    const double share = triangle_share(world, leavable, chosen);
    ctx.info(
        fmt::format("shaft pass: on the {} of {} objects with the most triangles ({:.1f}% of their "
                    "triangles): {} regions x {} objects = {} candidate pairs, over --shaft-max-pairs {} "
                    "(raise it to try more, at about a thread-millisecond a pair the pass tries)",
                    chosen.size(), leavable.size(), 100.0 * share, regions, leavable.size(),
                    regions * leavable.size(), config.shaft_max_pairs));
    if (figures.shaft_objects == 0 || chosen.size() < figures.shaft_objects) {
        figures.shaft_objects = chosen.size();
        figures.shaft_objects_triangle_share = share;
        figures.shaft_objects_digest = shaft_objects_digest(world, chosen);
    }
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// One proof of the shaft pass (pvs/shaft_hiding.h): is object o hidden from every eye of `region`? Counts
// the try in `level` (its level of the hierarchy, docs/ALGORITHMS.md#shaft-hierarchy) and its time by how
// it ended; the caller counts the cells it settles.
bool shaft_prove(const ShaftProver& prover, const World& world, const VoxelMask& eyes,
                 const ShaftRegion& region, uint32_t o, int budget, ShaftLevel& level, ShaftFigures& figures) {
    const ShaftFigures before = figures;
    const auto start = std::chrono::steady_clock::now();
    const bool hidden = prover.hides(world, eyes, region, o, budget, figures);
    const double s = seconds_since(start);
    if (hidden)
        figures.seconds_hidden += s;
    else if (figures.certain > before.certain)
        figures.seconds_certain += s;
    else if (figures.out_of_budget > before.out_of_budget)
        figures.seconds_out_of_budget += s;
    else
        figures.seconds_stuck += s;
    ++level.tried;
    level.seconds += s;
    level.proven += hidden ? 1 : 0;
    return hidden;
}

// Tries object o once more against a cell's or box's region; proven hidden, it leaves `row`.
bool shaft_try(const ShaftProver& prover, const World& world, const VoxelMask& eyes,
               const ShaftRegion& region, uint32_t o, int budget, uint64_t* row, ShaftFigures& figures) {
    const bool hidden = shaft_prove(prover, world, eyes, region, o, budget, figures.levels[0], figures);
    if (hidden) {
        row[o >> 6] &= ~(uint64_t(1) << (o & 63));
        ++figures.levels[0].settled;
    }
    return hidden;
}

// The shaft pass over one region's row (pvs/shaft_hiding.h, docs/ALGORITHMS.md#shaft-pass): every object
// of `candidates` the row lists whose bounds do not meet the region and that no sight ray saw (`seen`, or
// null) is tried once more against the whole region; proven hidden from every eye of it, it leaves the row.
void shaft_row(const ShaftProver& prover, const World& world, const VoxelMask& eyes, const Aabb& region,
               const std::vector<uint32_t>& candidates, int budget, uint64_t* row, const uint64_t* seen,
               ShaftFigures& figures) {
    const ShaftRegion shaft = shaft_region(eyes, region);
    for (uint32_t o : candidates) {
        if (!row_lists(row, o) || world.objects[o].bounds.overlaps(region)) continue;
        if (seen && row_lists(seen, o)) {
            ++figures.levels[0].seen;
            continue;
        }
        shaft_try(prover, world, eyes, shaft, o, budget, row, figures);
    }
}

// The hierarchy of one block of grid cells for the shaft pass (docs/ALGORITHMS.md#shaft-hierarchy): the
// root holds the block's cells with an eye region; a node's box of grid positions is halved along every
// axis longer than one position, and each half holding cells is a child; a node of one cell is a leaf.
// Built and walked in a fixed order, so what it proves depends only on the rows it starts from.
class ShaftHierarchy {
public:
    struct Node {
        Aabb box;                        // the bounds of its cells' eye regions
        int level = 0;                   // 0 for one cell; else ceil(log2(its longest side in positions))
        uint32_t first = 0, count = 0;   // its cells: cells_[first, first + count)
        std::vector<uint32_t> children;  // indexes into nodes_
    };

    // `block`: the block's cells; those with an empty region are left out.
    void build(const CellSet& cells, const std::vector<Aabb>& regions, const std::vector<uint32_t>& block) {
        nodes_.clear();
        cells_.clear();
        leaves_.clear();
        shafts_.clear();
        members_.clear();
        glm::ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
        for (uint32_t c : block) {
            if (regions[c].is_empty()) continue;
            const glm::ivec3 g = grid_position(cells, c);
            members_.push_back({g, c});
            lo = glm::min(lo, g);
            hi = glm::max(hi, g + 1);
        }
        if (members_.empty()) return;
        add(regions, 0, uint32_t(members_.size()), lo, hi);
        for (const auto& m : members_) cells_.push_back(m.cell);
        leaves_.assign(cells_.size(), 0);
        for (uint32_t n = 0; n < nodes_.size(); ++n)
            if (nodes_[n].children.empty()) leaves_[nodes_[n].first] = n;
        shafts_.resize(nodes_.size());
    }
    const std::vector<Node>& nodes() const { return nodes_; }
    // The cell of position i (of the root's cells), and its leaf.
    uint32_t cell(uint32_t i) const { return cells_[i]; }
    uint32_t leaf(uint32_t i) const { return leaves_[i]; }
    // The node's region for the prover, built at its first use.
    const ShaftRegion& shaft(const VoxelMask& eyes, uint32_t n) {
        if (!shafts_[n]) shafts_[n].emplace(shaft_region(eyes, nodes_[n].box));
        return *shafts_[n];
    }

private:
    struct Member {
        glm::ivec3 g;
        uint32_t cell;
    };
    // Adds the node of members_[first, first + count), within grid positions [lo, hi), and its subtree.
    uint32_t add(const std::vector<Aabb>& regions, uint32_t first, uint32_t count, glm::ivec3 lo,
                 glm::ivec3 hi) {
        const uint32_t n = uint32_t(nodes_.size());
        nodes_.emplace_back();
        Aabb box;
        for (uint32_t i = first; i < first + count; ++i) box.extend(regions[members_[i].cell]);
        nodes_[n].box = box;
        nodes_[n].first = first;
        nodes_[n].count = count;
        if (count == 1) return n;
        const glm::ivec3 extent = hi - lo;
        const int longest = std::max({extent.x, extent.y, extent.z});
        int level = 0;
        while ((1 << level) < longest) ++level;
        nodes_[n].level = std::max(level, 1);
        const glm::ivec3 mid = lo + (extent + 1) / 2;
        const auto octant = [&](const Member& m) {
            int k = 0;
            for (int a = 0; a < 3; ++a)
                if (extent[a] > 1 && m.g[a] >= mid[a]) k |= 1 << a;
            return k;
        };
        // Cells by octant, in cell order within each (a fixed order).
        std::stable_sort(members_.begin() + first, members_.begin() + first + count,
                         [&](const Member& a, const Member& b) {
                             return octant(a) != octant(b) ? octant(a) < octant(b) : a.cell < b.cell;
                         });
        std::vector<uint32_t> children;
        for (uint32_t i = first; i < first + count;) {
            const int k = octant(members_[i]);
            uint32_t j = i;
            while (j < first + count && octant(members_[j]) == k) ++j;
            glm::ivec3 clo = lo, chi = hi;
            for (int a = 0; a < 3; ++a)
                if (extent[a] > 1) (k >> a & 1 ? clo[a] : chi[a]) = mid[a];
            children.push_back(add(regions, i, j - i, clo, chi));
            i = j;
        }
        nodes_[n].children = std::move(children);
        return n;
    }

    std::vector<Node> nodes_;
    std::vector<Member> members_;
    std::vector<uint32_t> cells_;   // the cells, by node (members_' order)
    std::vector<uint32_t> leaves_;  // the leaf of each of them
    std::vector<std::optional<ShaftRegion>> shafts_;
};

// The probe before the shaft pass's proofs (docs/ALGORITHMS.md#shaft-probe): eye points of a cell aim one
// ray each at a random point of every object the pass would try for it; an object its own ray touches is
// seen from an eye of the cell, so no proof of it can hold. The eyes are seeded by the region's box, each
// ray by that box, the eye and the object, so what the probe finds for a pair depends on that pair alone,
// not on threads, processes or the other objects.
constexpr uint64_t kProbeEyeStream = uint64_t(0x50524f) << 40;    // ^ the region's key
constexpr uint64_t kProbePointStream = uint64_t(0x505054) << 40;  // ^ mix64(key ^ object) ^ eye
constexpr uint64_t kProbeSeed = 0x7368616674ULL;
constexpr float kProbeMinDistanceM = 1e-4f;  // closer targets give no direction

struct ShaftProbe {
    std::vector<glm::vec3> eyes, directions;
    std::vector<uint32_t> targets, aimed;
    std::vector<RayTouch> touches;
    std::vector<uint8_t> seen;  // per target
};

// Marks in `seen` what the probe's rays from `region` (a cell's or box's eye region) find among the objects
// the pass would try for it: those of `candidates` that `row` lists, `seen` does not, and whose bounds miss
// the region.
void probe_region(const RayScene& scene, const World& world, const std::vector<double>& cum_area,
                  const VoxelMask& eyes, const Aabb& region, const std::vector<uint32_t>& candidates,
                  const uint64_t* row, int rays, ShaftProbe& p, uint64_t* seen, ShaftFigures& figures) {
    if (rays <= 0) return;
    p.targets.clear();
    for (uint32_t o : candidates)
        if (row_lists(row, o) && !row_lists(seen, o) && !world.objects[o].bounds.overlaps(region))
            p.targets.push_back(o);
    if (p.targets.empty()) return;
    // The region's key: its corners' bits, so that a region gets the same rays whatever its index.
    uint64_t c = 0;
    for (const glm::vec3 corner : {region.min, region.max})
        for (int a = 0; a < 3; ++a) c = mix64(c ^ std::bit_cast<uint32_t>(corner[a]));
    p.eyes.clear();
    sample_eye_points_in(eyes, region, kProbeEyeStream ^ c, uint32_t(rays), kProbeSeed, p.eyes);
    for (uint32_t e = 0; e < p.eyes.size() && !p.targets.empty(); ++e) {
        p.directions.clear();
        p.aimed.clear();
        for (uint32_t i = 0; i < p.targets.size(); ++i) {
            const uint32_t o = p.targets[i];
            Rng rng(kProbeSeed, kProbePointStream ^ mix64(c ^ o) ^ e);
            const glm::vec3 d = random_point_on(world, cum_area, o, rng) - p.eyes[e];
            const float len = glm::length(d);
            if (len < kProbeMinDistanceM) continue;
            p.directions.push_back(d / len);
            p.aimed.push_back(i);
        }
        p.touches.clear();
        scene.trace(p.eyes[e], p.directions.data(), uint32_t(p.directions.size()), p.touches);
        figures.probe_rays += p.directions.size();
        p.seen.assign(p.targets.size(), 0);
        bool any = false;
        for (const RayTouch& t : p.touches) {
            const uint32_t i = p.aimed[t.ray];
            if (t.object != p.targets[i] || p.seen[i]) continue;
            p.seen[i] = 1;
            seen[t.object >> 6] |= uint64_t(1) << (t.object & 63);
            ++figures.probe_seen;
            any = true;
        }
        if (!any) continue;
        uint32_t kept = 0;
        for (uint32_t i = 0; i < p.targets.size(); ++i)
            if (!p.seen[i]) p.targets[kept++] = p.targets[i];
        p.targets.resize(kept);
    }
}

PatchSolver::Sides with_seen(PatchSolver::Sides sides, uint64_t* seen_lo, uint64_t* seen_hi) {
    sides.seen = {seen_lo, seen_hi};
    return sides;
}

void add_counts(ConservativeFigures& figures, const Counts& n, std::chrono::steady_clock::time_point start) {
    figures.samples += n.samples;
    figures.samples_skipped += n.skipped;
    figures.patches_in_solid += n.in_solid;
    figures.object_tests += n.tests;
    figures.rays += n.rays;
    figures.fine_samples += n.fine_samples;
    figures.panel_splits += n.panel_splits;
    figures.known_listed += n.known;
    figures.patch_hidden += n.patch_hidden;
    figures.samples_per_level.resize(std::max(figures.samples_per_level.size(), n.per_level.size()), 0);
    for (size_t k = 0; k < n.per_level.size(); ++k) figures.samples_per_level[k] += n.per_level[k];
    figures.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Shared make_shared(const ConservativeConfig& config, const World& world, const ShrunkOccluders& occluders,
                   const RayScene& scene) {
    std::vector<OccluderTrees> trees;
    trees.push_back(occluder_trees(occluders, config.corner_pairs));
    for (const ShrunkOccluders& block : occluders.block_sets)
        trees.push_back(occluder_trees(block, config.corner_pairs));
    return Shared{world,
                  occluders,
                  scene,
                  object_tree(world),
                  std::move(trees),
                  object_parts(world),
                  ray_targets(world),
                  config.cube_resolution,
                  config.fine_cube_resolution,
                  config.panel_refine_levels,
                  config.slanted_cubes,
                  config.corner_pairs,
                  config.panel_bands};
}

// One face of a box: the side at box.min[axis] (side 0) or box.max[axis] (side 1), flat along `axis`.
Aabb box_face(const Aabb& box, int axis, int side) {
    Aabb f = box;
    f.min[axis] = f.max[axis] = side ? box.max[axis] : box.min[axis];
    return f;
}

}  // namespace

void conservative_box_rows(Context& ctx, const ConservativeConfig& config, const World& world,
                           const std::vector<Aabb>& boxes, const VoxelMask& eyes,
                           const ShrunkOccluders& occluders, const RayScene& scene, PvsSet& pvs,
                           ConservativeFigures& figures, const RegionHiders* hiders,
                           const std::vector<const uint64_t*>* bounds, const ShaftProvers* provers,
                           RowJournal* journal, const std::vector<uint64_t>* keys, WorkShare* shared_work) {
    const auto start = std::chrono::steady_clock::now();
    if (!keys) journal = nullptr;
    const Shared shared = make_shared(config, world, occluders, scene);
    const std::vector<uint32_t> leavable = leavable_objects(world);
    std::optional<RegionHiders> own_hiders;
    if (config.single_occluder_pass && !hiders) hiders = &own_hiders.emplace(ctx, occluders);
    if (!config.single_occluder_pass) hiders = nullptr;
    // The objects the shaft pass tries (docs/ALGORITHMS.md#shaft-cap), as a row.
    const std::vector<uint32_t> chosen = shaft_objects(config, world, boxes.size());
    const bool shaft_runs = !chosen.empty();
    std::vector<uint64_t> chosen_row(pvs.words_per_row, 0);
    for (uint32_t o : chosen) chosen_row[o >> 6] |= uint64_t(1) << (o & 63);
    if (shaft_runs) figures.shaft_pair_budget = std::max(figures.shaft_pair_budget, config.shaft_budget);
    std::optional<ShaftProvers> own_provers;
    if (shaft_runs && !provers)
        provers = &own_provers.emplace(ctx, occluders, config.shaft_fusion, config.shaft_caps,
                                       config.shaft_cups, config.shaft_flood);
    if (!shaft_runs) provers = nullptr;
    const std::vector<double> cum_area = shaft_runs ? cumulative_areas(world) : std::vector<double>();
    Counts total;
    ShaftFigures shaft;
    note_shaft_objects(ctx, config, world, boxes.size(), leavable, chosen, figures, shaft);
    uint64_t region_hidden = 0, skipped = 0;
    WorkShare alone;
    WorkShare& share = shared_work ? *shared_work : alone;
    share.begin(boxes.size());
#pragma omp parallel reduction(+ : region_hidden, skipped)
    {
        PatchSolver solver(shared);
        std::vector<uint32_t> open, candidates, shaft_tried;
        std::vector<uint64_t> hidden(pvs.words_per_row), seen(pvs.words_per_row);
        ShaftFigures local_shaft;
        ShaftProbe probe;
        for_each_dealt(share, ctx, 1, [&](uint64_t ci) {
            const Aabb box = eye_region(eyes, boxes[size_t(ci)]);
            uint64_t* row = pvs.row(uint32_t(ci));
            if (journal && journal->find("box", (*keys)[size_t(ci)], row, pvs.words_per_row)) return;
            open.clear();
            for (uint32_t o = 0; o < world.objects.size(); ++o) {
                if ((world.objects[o].flags & kObjectAlwaysVisible) ||
                    world.objects[o].bounds.overlaps(box)) {
                    row[o >> 6] |= uint64_t(1) << (o & 63);
                }
            }
            if (!box.is_empty()) {
                const int32_t set = occluders.set_for(box);
                solver.use(set, hiders ? &hiders->of(set) : nullptr);
                // Only what the box's bound lists (docs/ALGORITHMS.md#octree-parent-bound).
                const uint64_t* bound = bounds ? (*bounds)[size_t(ci)] : nullptr;
                candidates.clear();
                for (uint32_t o : leavable)
                    if (!bound || row_lists(bound, o)) candidates.push_back(o);
                skipped += leavable.size() - candidates.size();
                std::fill(hidden.begin(), hidden.end(), 0);
                if (hiders) region_hidden += hiders->of(set).hide(world, box, candidates, hidden.data());
                for (uint32_t o : candidates)
                    if (!world.objects[o].bounds.overlaps(box) && !row_lists(hidden.data(), o))
                        open.push_back(o);
                // One face after another into the cell's own row: solve_patch() skips what the faces (and
                // patches) before it listed (docs/ALGORITHMS.md#refinement).
                std::fill(seen.begin(), seen.end(), 0);
                for (int axis = 0; axis < 3; ++axis)
                    for (int side = 0; side < 2; ++side)
                        solver.solve_face(
                            box_face(box, axis, side), axis,
                            with_seen(solver.sides_of(open, axis, side ? box.max[axis] : box.min[axis],
                                                      side ? nullptr : row, side ? row : nullptr),
                                      side ? nullptr : seen.data(), side ? seen.data() : nullptr));
                if (provers) {
                    const auto shaft_start = std::chrono::steady_clock::now();
                    shaft_tried.clear();
                    for (uint32_t o : candidates)
                        if (row_lists(chosen_row.data(), o)) shaft_tried.push_back(o);
                    // The probe (docs/ALGORITHMS.md#shaft-probe).
                    probe_region(scene, world, cum_area, eyes, box, shaft_tried, row, config.shaft_probe_rays,
                                 probe, seen.data(), local_shaft);
                    shaft_row(provers->of(set), world, eyes, box, shaft_tried, config.shaft_budget, row,
                              seen.data(), local_shaft);
                    local_shaft.seconds +=
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - shaft_start).count();
                }
            }
            if (journal) journal->record("box", (*keys)[size_t(ci)], row, pvs.words_per_row);
        });
#pragma omp critical
        {
            total += solver.counts();
            shaft += local_shaft;
        }
    }
    share.unite(pvs.words.data(), pvs.words.size());  // each row was written by the process it was dealt to
    figures.shaft += shaft;
    figures.region_hidden += region_hidden;
    figures.parent_hidden += skipped;
    add_counts(figures, total, start);
}

// A grid: each face shared by two cells is computed once, for both sides (PatchSolver::Sides). A face
// side's row lists every object on that side that some patch of the face cannot prove hidden; a cell's row
// is the union of its six faces' outward rows, the objects whose bounds meet its region, and
// add_always_listed().
// The faces are solved in six PHASES, by axis and by the parity of the face's plane in the grid (a cell's min
// face lies on plane i, its max face on plane i + 1): so each cell has at most one face in a phase. A face
// side skips the objects its cell already lists when the phase starts (docs/ALGORITHMS.md#refinement: they
// are in the row anyway), and its row joins the cell's at the end of the phase. So the later faces of a cell
// test only what the earlier ones proved hidden, and the result depends on the phases, not on the threads.
static void conservative_grid_rows(Context& ctx, const ConservativeConfig& config, const World& world,
                                   const CellSet& cells, const ShrunkOccluders& occluders,
                                   const RayScene& scene, PvsSet& pvs, ConservativeFigures& figures,
                                   RowJournal* journal, WorkShare& share, const ReusePlan* reuse) {
    const auto start = std::chrono::steady_clock::now();
    const uint32_t n_objects = uint32_t(world.objects.size());
    // Faces of each cell's eye region (eye_region()); neighbours whose regions fill both cells share the
    // face between them, found by its exact corners. In cell order, so the result is deterministic.
    struct Face {
        int axis;
        Aabb rect;                                 // flat along `axis`
        std::array<bool, 2> wanted{false, false};  // side 0: a region's min face (sight goes to -axis)
        std::array<int32_t, 2> set{-1, -1};        // each side's occluders (ShrunkOccluders::set_for)
        std::array<int32_t, 2> cell{-1, -1};       // each side's cell
        int phase = 0;                             // 2 * axis + the parity of its plane's grid index
    };
    constexpr int kPhases = 6;
    std::vector<Face> faces;
    std::map<std::array<float, 6>, uint32_t> face_of;
    std::vector<Aabb> regions(cells.size());
    for (uint32_t c = 0; c < cells.size(); ++c) {
        regions[c] = eye_region(cells.eyes, cells.cells[c].bounds);
        if (regions[c].is_empty()) continue;
        for (int axis = 0; axis < 3; ++axis) {
            const double at = (double(cells.cells[c].bounds.center()[axis]) - double(cells.origin[axis])) /
                              cells.cell_size_m;
            const int64_t index = cells.cell_size_m > 0.0f ? int64_t(std::floor(at)) : 0;
            for (int side = 0; side < 2; ++side) {
                const Aabb rect = box_face(regions[c], axis, side);
                std::array<float, 6> key{rect.min.x, rect.min.y, rect.min.z,
                                         rect.max.x, rect.max.y, rect.max.z};
                auto [it, fresh] = face_of.emplace(key, uint32_t(faces.size()));
                if (fresh) faces.push_back(Face{axis, rect});
                Face& f = faces[it->second];
                f.wanted[size_t(side)] = true;
                f.set[size_t(side)] = occluders.set_for(regions[c]);
                f.cell[size_t(side)] = int32_t(c);
                // A cell's min face (side 0) is on plane `index`, its max face on `index + 1`; a shared
                // face gets the same parity from both cells.
                f.phase = 2 * axis + int((index + side) & 1);
            }
        }
    }
    // Rows start with the objects whose bounds meet the region (always listed): no face tests them.
    for (uint32_t c = 0; c < cells.size(); ++c) {
        uint64_t* row = pvs.row(c);
        for (uint32_t o = 0; o < n_objects; ++o)
            if (world.objects[o].bounds.overlaps(regions[c])) row[o >> 6] |= uint64_t(1) << (o & 63);
        // Reusing an old bake (docs/ALGORITHMS.md#reuse): the settled pairs it lists are known listed.
        if (reuse)
            for (uint32_t w = 0; w < pvs.words_per_row; ++w) row[w] |= reuse->listed.row(c)[w];
    }
    // The objects a pass tests for cell c: the leavable ones, less the pairs a reuse settled.
    const auto unsettled = [&](uint32_t c, const std::vector<uint32_t>& all,
                               std::vector<uint32_t>& out) -> const std::vector<uint32_t>& {
        if (!reuse) return all;
        out.clear();
        for (uint32_t o : all)
            if (!reuse->settled.test(c, o)) out.push_back(o);
        return out;
    };
    std::array<std::vector<uint32_t>, kPhases> phase_faces;
    for (uint32_t f = 0; f < faces.size(); ++f) phase_faces[size_t(faces[f].phase)].push_back(f);
    const Shared shared = make_shared(config, world, occluders, scene);
    const std::vector<uint32_t> leavable = leavable_objects(world);
    // The blocks the shaft pass proves over (docs/ALGORITHMS.md#shaft-hierarchy); the cap counts cells.
    const std::vector<std::vector<uint32_t>> blocks = config.shaft_budget > 0
                                                          ? grid_shaft_blocks(cells, config.shaft_block)
                                                          : std::vector<std::vector<uint32_t>>{};
    // The objects the shaft pass tries (docs/ALGORITHMS.md#shaft-cap).
    const std::vector<uint32_t> chosen = shaft_objects(config, world, grid_shaft_regions(config, cells));
    const bool shaft_runs = !chosen.empty();
    if (shaft_runs) figures.shaft_pair_budget = std::max(figures.shaft_pair_budget, config.shaft_budget);
    // The blocks' proofs before the faces (docs/ALGORITHMS.md#shaft-early).
    const bool early = shaft_runs && config.shaft_early && config.shaft_block > 1;
    // The single-occluder pass: what one occluder hides from a cell's whole region, no face of it tests.
    PvsSet hidden =
        PvsSet::make(config.single_occluder_pass || early ? uint32_t(cells.size()) : 0, n_objects);
    std::optional<RegionHiders> hiders;
    if (config.single_occluder_pass) {
        const auto pass_start = std::chrono::steady_clock::now();
        hiders.emplace(ctx, occluders);
        uint64_t n_hidden = 0;
        ctx.progress_begin("single-occluder pass", cells.size(), "cells");
        share.begin(cells.size());
#pragma omp parallel reduction(+ : n_hidden)
        {
            std::vector<uint32_t> scratch;
            for_each_dealt(share, ctx, 16, [&](uint64_t c) {
                uint64_t* row = hidden.row(uint32_t(c));
                if (!regions[size_t(c)].is_empty() &&
                    !(journal && journal->find("hidden", c, row, hidden.words_per_row))) {
                    n_hidden +=
                        hiders->of(occluders.set_for(regions[size_t(c)]))
                            .hide(world, regions[size_t(c)], unsettled(uint32_t(c), leavable, scratch), row);
                    if (journal) journal->record("hidden", c, row, hidden.words_per_row);
                }
            });
        }
        share.unite(hidden.words.data(), hidden.words.size());
        ctx.progress_end();
        if (journal) journal->flush();
        figures.region_hidden += n_hidden;
        figures.region_seconds +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - pass_start).count();
    }
    std::optional<ShaftProvers> provers;
    std::vector<double> cum_area;
    if (shaft_runs) {
        provers.emplace(ctx, occluders, config.shaft_fusion, config.shaft_caps, config.shaft_cups,
                        config.shaft_flood);
        cum_area = cumulative_areas(world);
    }
    // Each block's root proofs: root_failed row b lists the objects its root could not prove (the pass after
    // the faces does not try them again there).
    PvsSet root_failed = PvsSet::make(early ? uint32_t(blocks.size()) : 0, n_objects);
    if (early) {
        const auto pass_start = std::chrono::steady_clock::now();
        ShaftFigures shaft;
        ctx.progress_begin("shaft pass, blocks first", blocks.size(), "blocks");
        share.begin(blocks.size());
#pragma omp parallel
        {
            ShaftFigures local;
            ShaftHierarchy tree;
            ShaftProbe probe;
            std::vector<uint32_t> targets;
            std::vector<uint64_t> node_seen(hidden.words_per_row), replayed,
                all(hidden.words_per_row, ~uint64_t(0));
            for_each_dealt(share, ctx, 1, [&](uint64_t b) {
                const std::vector<uint32_t>& block = blocks[size_t(b)];
                // A block is taken from the journal when it holds every one of its cells' rows and its
                // root's failures.
                if (journal) {
                    replayed.resize((block.size() + 1) * hidden.words_per_row);
                    bool found = journal->find("early_failed", b, replayed.data(), hidden.words_per_row);
                    for (size_t i = 0; i < block.size() && found; ++i)
                        found =
                            journal->find("early", block[i], replayed.data() + (i + 1) * hidden.words_per_row,
                                          hidden.words_per_row);
                    if (found) {
                        std::copy_n(replayed.data(), hidden.words_per_row, root_failed.row(uint32_t(b)));
                        for (size_t i = 0; i < block.size(); ++i)
                            std::copy_n(replayed.data() + (i + 1) * hidden.words_per_row,
                                        hidden.words_per_row, hidden.row(block[i]));
                        return;
                    }
                }
                tree.build(cells, regions, block);
                if (!tree.nodes().empty() && tree.nodes()[0].count >= 2) {
                    const ShaftHierarchy::Node& root = tree.nodes()[0];
                    // The objects a cell of the block would still test (not hidden there, not settled by
                    // a reuse: a plan settles a block's cells alike) and whose bounds miss the root's box.
                    targets.clear();
                    for (uint32_t o : chosen) {
                        if (world.objects[o].bounds.overlaps(root.box)) continue;
                        bool open = false;
                        for (uint32_t i = 0; i < root.count && !open; ++i) {
                            const uint32_t c = tree.cell(i);
                            open = !row_lists(hidden.row(c), o) && !(reuse && reuse->settled.test(c, o));
                        }
                        if (open) targets.push_back(o);
                    }
                    // What a ray from an eye of the block reaches, no proof over the block can hide.
                    // Its rays count with the probe's; what they reach counts as `early.seen` below, not as
                    // the cells' `probe_seen`.
                    std::fill(node_seen.begin(), node_seen.end(), uint64_t(0));
                    ShaftFigures probed;
                    probe_region(scene, world, cum_area, cells.eyes, root.box, targets, all.data(),
                                 config.shaft_probe_rays, probe, node_seen.data(), probed);
                    local.probe_rays += probed.probe_rays;
                    const ShaftProver& prover = provers->of(occluders.set_for(root.box));
                    uint64_t* failed = root_failed.row(uint32_t(b));
                    for (uint32_t o : targets) {
                        if (row_lists(node_seen.data(), o)) {
                            ++local.early.seen;
                            continue;
                        }
                        if (!shaft_prove(prover, world, cells.eyes, tree.shaft(cells.eyes, 0), o,
                                         config.shaft_budget, local.early, local)) {
                            failed[o >> 6] |= uint64_t(1) << (o & 63);
                            continue;
                        }
                        for (uint32_t i = 0; i < root.count; ++i) {
                            uint64_t* row = hidden.row(tree.cell(i));
                            if (row_lists(row, o)) continue;
                            row[o >> 6] |= uint64_t(1) << (o & 63);
                            ++local.early.settled;
                        }
                    }
                }
                if (journal) {
                    journal->record("early_failed", b, root_failed.row(uint32_t(b)), hidden.words_per_row);
                    for (uint32_t c : block) journal->record("early", c, hidden.row(c), hidden.words_per_row);
                }
            });
#pragma omp critical
            shaft += local;
        }
        share.unite(hidden.words.data(), hidden.words.size());
        share.unite(root_failed.words.data(), root_failed.words.size());
        ctx.progress_end();
        if (journal) journal->flush();
        ctx.info(
            fmt::format("shaft pass, blocks first: {} of {} objects tried proven hidden from whole blocks "
                        "({} (cell, object) pairs the faces skip), {} reached by a block's rays; {:.1f} s",
                        shaft.early.proven, shaft.early.tried, shaft.early.settled, shaft.early.seen,
                        seconds_since(pass_start)));
        figures.shaft += shaft;
    }
    const auto hider = [&](int32_t set) { return hiders ? &hiders->of(set) : nullptr; };
    // What no face tests because it is known hidden: what the single-occluder pass proved, and with a
    // reuse the settled pairs it does not list.
    PvsSet excluded;
    if (reuse) {
        excluded = PvsSet::make(uint32_t(cells.size()), n_objects);
        for (uint32_t c = 0; c < cells.size(); ++c)
            for (uint32_t w = 0; w < excluded.words_per_row; ++w)
                excluded.row(c)[w] = (reuse->settled.row(c)[w] & ~reuse->listed.row(c)[w]) |
                                     (hidden.cell_count > 0 ? hidden.row(c)[w] : 0);
    }
    const auto hidden_row = [&](int32_t cell) -> const uint64_t* {
        if (cell < 0) return nullptr;
        if (reuse) return excluded.row(uint32_t(cell));
        return hidden.cell_count > 0 ? hidden.row(uint32_t(cell)) : nullptr;
    };
    PvsSet face_rows = PvsSet::make(uint32_t(2 * faces.size()), n_objects);  // face * 2 + side
    // What sight rays saw, per cell, for the shaft pass: a cell has at most one face in a phase, so each row
    // is written by one thread at a time.
    PvsSet seen = PvsSet::make(shaft_runs ? uint32_t(cells.size()) : 0, n_objects);
    const auto seen_row = [&](int32_t cell) -> uint64_t* {
        return shaft_runs && cell >= 0 ? seen.row(uint32_t(cell)) : nullptr;
    };
    // Resuming (docs/ALGORITHMS.md#resume): a face's rows depend only on the cells' rows as its phase
    // started, so a face whose every wanted side the journal holds is taken from it. The seen rows recorded
    // are the cell's whole row after the face (no other face of the cell runs in the phase); their union
    // is the row an uninterrupted run has.
    const auto replay_face = [&](uint32_t fi) {
        const Face& f = faces[fi];
        for (int side = 0; side < 2; ++side) {
            if (!f.wanted[size_t(side)]) continue;
            const uint64_t key = 2 * uint64_t(fi) + uint64_t(side);
            if (!journal->find("face", key, face_rows.row(uint32_t(key)), face_rows.words_per_row))
                return false;
        }
        if (shaft_runs) {
            std::vector<uint64_t> snapshot(seen.words_per_row);
            for (int side = 0; side < 2; ++side) {
                if (!f.wanted[size_t(side)]) continue;
                if (!journal->find("face_seen", 2 * uint64_t(fi) + uint64_t(side), snapshot.data(),
                                   seen.words_per_row))
                    return false;
                uint64_t* row = seen_row(f.cell[size_t(side)]);
                for (uint32_t w = 0; w < seen.words_per_row; ++w) row[w] |= snapshot[w];
            }
        }
        return true;
    };
    const auto record_face = [&](uint32_t fi) {
        const Face& f = faces[fi];
        for (int side = 0; side < 2; ++side) {
            if (!f.wanted[size_t(side)]) continue;
            const uint64_t key = 2 * uint64_t(fi) + uint64_t(side);
            journal->record("face", key, face_rows.row(uint32_t(key)), face_rows.words_per_row);
            if (shaft_runs)
                journal->record("face_seen", key, seen_row(f.cell[size_t(side)]), seen.words_per_row);
        }
    };
    Counts total;
    ctx.progress_begin("conservative PVS", faces.size(), "faces");
    share.begin(phase_faces[0].size());
#pragma omp parallel
    {
        PatchSolver solver(shared);
        for (size_t p = 0; p < phase_faces.size(); ++p) {
            const std::vector<uint32_t>& phase = phase_faces[p];
            for_each_dealt(share, ctx, 4, [&](uint64_t k) {
                const uint32_t fi = phase[size_t(k)];
                const Face& f = faces[fi];
                uint64_t* row_lo = f.wanted[0] ? face_rows.row(2 * fi) : nullptr;
                uint64_t* row_hi = f.wanted[1] ? face_rows.row(2 * fi + 1) : nullptr;
                if (journal && replay_face(fi)) return;
                // The cells' rows as the phase started: only the merge below writes them.
                const uint64_t* known_lo = f.wanted[0] ? pvs.row(uint32_t(f.cell[0])) : nullptr;
                const uint64_t* known_hi = f.wanted[1] ? pvs.row(uint32_t(f.cell[1])) : nullptr;
                const float plane = f.rect.min[f.axis];
                if (row_lo && row_hi && f.set[0] != f.set[1]) {
                    // The regions on the two sides take their occluders from different blocks: once per side.
                    solver.use(f.set[0], hider(f.set[0]));
                    solver.solve_face(
                        f.rect, f.axis,
                        with_seen(solver.sides_of(leavable, f.axis, plane, row_lo, nullptr, known_lo, nullptr,
                                                  hidden_row(f.cell[0]), nullptr),
                                  seen_row(f.cell[0]), nullptr));
                    solver.use(f.set[1], hider(f.set[1]));
                    solver.solve_face(
                        f.rect, f.axis,
                        with_seen(solver.sides_of(leavable, f.axis, plane, nullptr, row_hi, nullptr, known_hi,
                                                  nullptr, hidden_row(f.cell[1])),
                                  nullptr, seen_row(f.cell[1])));
                } else {
                    solver.use(row_lo ? f.set[0] : f.set[1], hider(row_lo ? f.set[0] : f.set[1]));
                    solver.solve_face(
                        f.rect, f.axis,
                        with_seen(solver.sides_of(leavable, f.axis, plane, row_lo, row_hi, known_lo, known_hi,
                                                  row_lo ? hidden_row(f.cell[0]) : nullptr,
                                                  row_hi ? hidden_row(f.cell[1]) : nullptr),
                                  row_lo ? seen_row(f.cell[0]) : nullptr,
                                  row_hi ? seen_row(f.cell[1]) : nullptr));
                }
                if (journal) record_face(fi);
            });
#pragma omp barrier
            // Every face of the phase is done. One thread merges, a few words per face (a face dealt to
            // another process has a zero row here, and unite() brings its rows); the barrier after it starts
            // the next phase on the merged rows.
#pragma omp single
            {
                for (const uint32_t fi : phase) {
                    for (int side = 0; side < 2; ++side) {
                        if (!faces[fi].wanted[size_t(side)]) continue;
                        uint64_t* row = pvs.row(uint32_t(faces[fi].cell[size_t(side)]));
                        const uint64_t* fr = face_rows.row(2 * fi + uint32_t(side));
                        for (uint32_t w = 0; w < pvs.words_per_row; ++w) row[w] |= fr[w];
                    }
                }
                share.unite(pvs.words.data(), pvs.words.size());
                if (journal) journal->flush();  // a phase is a stage's end (docs/ALGORITHMS.md#resume)
                if (p + 1 < phase_faces.size()) share.begin(phase_faces[p + 1].size());
            }
        }
#pragma omp critical
        total += solver.counts();
    }
    ctx.progress_end();
    // The shaft pass (docs/ALGORITHMS.md#shaft-pass), on the cells' finished rows, when the cap allows it
    // (docs/ALGORITHMS.md#shaft-cap), over blocks of cells (docs/ALGORITHMS.md#shaft-hierarchy).
    {
        ShaftFigures shaft;
        note_shaft_objects(ctx, config, world, grid_shaft_regions(config, cells), leavable, chosen, figures,
                           shaft);
        figures.shaft += shaft;
    }
    if (shaft_runs) {
        const auto pass_start = std::chrono::steady_clock::now();
        ShaftFigures shaft;
        ctx.progress_begin("shaft pass", blocks.size(), "blocks");
        // The seen rows of faces other processes solved; then each row of the pass comes from the process
        // its block was dealt to (the others zero theirs).
        share.unite(seen.words.data(), seen.words.size());
        std::vector<uint8_t> mine(share.processes() > 1 ? cells.size() : 0, 0);
        share.begin(blocks.size());
#pragma omp parallel
        {
            ShaftFigures local;
            std::vector<uint32_t> candidates, stack;
            std::vector<uint64_t> replayed;
            ShaftHierarchy tree;
            ShaftProbe probe;
            std::vector<uint8_t> failed;
            const std::vector<uint32_t> none;
            for_each_dealt(share, ctx, 1, [&](uint64_t b) {
                const std::vector<uint32_t>& block = blocks[size_t(b)];
                for (uint32_t c : block)
                    if (!mine.empty()) mine[c] = 1;
                // A block is taken from the journal when it holds every one of its rows.
                if (journal) {
                    replayed.resize(block.size() * pvs.words_per_row);
                    bool all = true;
                    for (size_t i = 0; i < block.size() && all; ++i)
                        all = journal->find("shaft", block[i], replayed.data() + i * pvs.words_per_row,
                                            pvs.words_per_row);
                    if (all) {
                        for (size_t i = 0; i < block.size(); ++i)
                            std::copy_n(replayed.data() + i * pvs.words_per_row, pvs.words_per_row,
                                        pvs.row(block[i]));
                        return;
                    }
                }
                // The hierarchy (docs/ALGORITHMS.md#shaft-hierarchy): per object, a node's proof settles
                // every cell of it; what a node cannot prove, or a cell of it saw, goes to its children.
                tree.build(cells, regions, block);
                // The objects no cell of the block has settled by a reuse (docs/ALGORITHMS.md#reuse: a
                // plan settles a block's cells alike).
                const std::vector<uint32_t>* tried = &chosen;
                if (reuse) {
                    candidates.clear();
                    for (uint32_t o : chosen) {
                        bool open = true;
                        for (uint32_t c : block) open = open && !reuse->settled.test(c, o);
                        if (open) candidates.push_back(o);
                    }
                    tried = &candidates;
                }
                // The probe (docs/ALGORITHMS.md#shaft-probe): what rays from a cell reach needs no proof.
                for (uint32_t c : block)
                    if (!regions[c].is_empty())
                        probe_region(scene, world, cum_area, cells.eyes, regions[c], *tried, pvs.row(c),
                                     config.shaft_probe_rays, probe, seen.row(c), local);
                // A block without a cell with eyes has nothing to try.
                if (tree.nodes().empty()) tried = &none;
                for (uint32_t o : *tried) {
                    const Aabb& bounds = world.objects[o].bounds;
                    const auto lists = [&](uint32_t i) {
                        const uint32_t c = tree.cell(i);
                        return row_lists(pvs.row(c), o) && !bounds.overlaps(regions[c]);
                    };
                    // One proof over node n (a leaf: its cell's), with the counts of its level; proven, o
                    // leaves the row of every cell of n that lists it.
                    const auto prove = [&](uint32_t n) {
                        const ShaftHierarchy::Node& node = tree.nodes()[n];
                        ShaftLevel& level = local.levels[size_t(std::min(node.level, kShaftLevels - 1))];
                        if (!shaft_prove(provers->of(occluders.set_for(node.box)), world, cells.eyes,
                                         tree.shaft(cells.eyes, n), o, config.shaft_budget, level, local))
                            return false;
                        for (uint32_t i = node.first; i < node.first + node.count; ++i) {
                            if (!lists(i)) continue;
                            uint64_t* row = pvs.row(tree.cell(i));
                            row[o >> 6] &= ~(uint64_t(1) << (o & 63));
                            ++level.settled;
                        }
                        return true;
                    };
                    // A cell's own proof, tried at most once: failed[i] once it could not prove o.
                    failed.assign(tree.nodes()[0].count, 0);
                    const auto prove_cell = [&](uint32_t i) {
                        if (!lists(i) || failed[i]) return !failed[i];
                        failed[i] = prove(tree.leaf(i)) ? 0 : 1;
                        return !failed[i];
                    };
                    // Whether a node gives o up for its cells when both its witnesses fail.
                    const auto give_up_here = [&](const ShaftHierarchy::Node& node) {
                        return config.shaft_give_up > 0 && node.level >= config.shaft_give_up;
                    };
                    stack.assign(1, 0);
                    while (!stack.empty()) {
                        const uint32_t n = stack.back();
                        stack.pop_back();
                        const ShaftHierarchy::Node& node = tree.nodes()[n];
                        // The node's listing cells: those that list o and whose regions it does not meet.
                        uint32_t listing = 0, parts = 0, first = 0, last = 0;
                        bool saw = false;
                        const uint32_t* parts_of = node.children.empty() ? &n : node.children.data();
                        const size_t n_parts = node.children.empty() ? 1 : node.children.size();
                        for (size_t k = 0; k < n_parts; ++k) {
                            const ShaftHierarchy::Node& child = tree.nodes()[parts_of[k]];
                            bool any = false;
                            for (uint32_t i = child.first; i < child.first + child.count; ++i) {
                                if (!lists(i)) continue;
                                if (!listing) first = i;
                                last = i;
                                any = true;
                                ++listing;
                                saw = saw || row_lists(seen.row(tree.cell(i)), o);
                            }
                            parts += any ? 1 : 0;
                        }
                        if (listing == 0) continue;
                        if (node.children.empty()) {
                            if (saw)
                                ++local.levels[0].seen;
                            else
                                prove_cell(node.first);
                            continue;
                        }
                        // A sight ray or the probe saw o from a cell of the node: no proof over it can hold.
                        // Else the node tries o when its listing cells lie in two children or more, o does
                        // not meet its box, and the first and last of those cells prove it hidden on their
                        // own (a cell that cannot would most likely fail the node's proof too: the witnesses,
                        // docs/ALGORITHMS.md#shaft-hierarchy); what it cannot prove goes to the children.
                        ShaftLevel& level = local.levels[size_t(std::min(node.level, kShaftLevels - 1))];
                        if (saw) {
                            ++level.seen;
                        } else if (parts >= 2 && !bounds.overlaps(node.box)) {
                            const bool first_hidden = prove_cell(first);
                            const bool last_hidden = (first_hidden || give_up_here(node)) && prove_cell(last);
                            if (first_hidden && last_hidden) {
                                uint32_t left = 0;
                                for (uint32_t i = node.first; i < node.first + node.count; ++i)
                                    left += lists(i);
                                // A root the blocks' first proofs could not prove fails again here.
                                const bool known_failed =
                                    n == 0 && early && row_lists(root_failed.row(uint32_t(b)), o);
                                if (left == 0 || (left >= 2 && !known_failed && prove(n))) continue;
                            } else if (!first_hidden && failed[last] && give_up_here(node)) {
                                // Both witnesses failed: the node's other cells keep o listed untried
                                // (docs/ALGORITHMS.md#shaft-give-up).
                                for (uint32_t i = node.first; i < node.first + node.count; ++i)
                                    if (lists(i) && !failed[i]) {
                                        failed[i] = 1;
                                        ++level.given_up;
                                    }
                                continue;
                            }
                        }
                        for (auto ch = node.children.rbegin(); ch != node.children.rend(); ++ch)
                            stack.push_back(*ch);
                    }
                }
                if (journal)
                    for (uint32_t c : block) journal->record("shaft", c, pvs.row(c), pvs.words_per_row);
            });
#pragma omp critical
            shaft += local;
        }
        for (size_t c = 0; c < mine.size(); ++c)
            if (!mine[c]) std::fill_n(pvs.row(uint32_t(c)), pvs.words_per_row, uint64_t(0));
        share.unite(pvs.words.data(), pvs.words.size());
        ctx.progress_end();
        if (journal) journal->flush();
        shaft.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - pass_start).count();
        figures.shaft += shaft;
    }
    add_counts(figures, total, start);
}

PvsSet bake_conservative_pvs(Context& ctx, const ConservativeConfig& config, const World& world,
                             const CellSet& cells, const ShrunkOccluders& occluders, const RayScene& scene,
                             ConservativeFigures& figures, RowJournal* journal, WorkShare* shared_work,
                             const ReusePlan* reuse) {
    ScopedTimer timer(ctx, "conservative_pvs");
    ctx.info(fmt::format(
        "conservative PVS: {} cells, epsilon {} m to {} m ({} levels), {} shrunk occluders "
        "at the floor, cube {} px",
        cells.size(), occluders.epsilon_m.empty() ? 0.0 : occluders.epsilon_m.front(),
        occluders.epsilon_m.empty() ? 0.0 : occluders.epsilon_m.back(), occluders.epsilon_m.size(),
        occluders.boxes.empty() ? 0 : occluders.boxes[0].size(), config.cube_resolution));
    PvsSet pvs = PvsSet::make(uint32_t(cells.size()), uint32_t(world.objects.size()));
    if (cells.kind == CellSet::Kind::kGrid) {
        WorkShare alone;
        // A small bake's pass takes more piece pairs per pair (docs/ALGORITHMS.md#shaft-small).
        ConservativeConfig grid = config;
        grid.shaft_budget = shaft_pair_budget(config, world, grid_shaft_regions(config, cells));
        conservative_grid_rows(ctx, grid, world, cells, occluders, scene, pvs, figures, journal,
                               shared_work ? *shared_work : alone, reuse);
    } else {
        std::vector<Aabb> boxes;
        for (const Cell& c : cells.cells) boxes.push_back(c.bounds);
        ctx.progress_begin("conservative PVS", cells.size(), "cells");
        ConservativeConfig box = config;
        box.shaft_budget = shaft_pair_budget(config, world, boxes.size());
        conservative_box_rows(ctx, box, world, boxes, cells.eyes, occluders, scene, pvs, figures);
        ctx.progress_end();
    }
    add_always_listed(world, cells, pvs);
    if (figures.shaft.pairs > 0) {
        ctx.info(fmt::format(
            "shaft pass: {:.3f} M of {:.3f} M (cell, object) pairs proven hidden ({:.3f} M given up at once, "
            "{:.3f} M out of budget, {:.3f} M on pieces that meet, {:.3f} M halved too often, {:.3f} M too "
            "small to halve), {:.2f} M piece pairs, {:.1f} s; thread seconds on pairs proven / given up at "
            "once / out of budget / stuck: {:.1f} / {:.1f} / {:.1f} / {:.1f}",
            double(figures.shaft.hidden) * 1e-6, double(figures.shaft.pairs) * 1e-6,
            double(figures.shaft.certain) * 1e-6, double(figures.shaft.out_of_budget) * 1e-6,
            double(figures.shaft.stuck_meet) * 1e-6, double(figures.shaft.stuck_depth) * 1e-6,
            double(figures.shaft.stuck - figures.shaft.stuck_meet - figures.shaft.stuck_depth) * 1e-6,
            double(figures.shaft.tests) * 1e-6, figures.shaft.seconds, figures.shaft.seconds_hidden,
            figures.shaft.seconds_certain, figures.shaft.seconds_out_of_budget, figures.shaft.seconds_stuck));
        for (int l = kShaftLevels - 1; l >= 0; --l) {
            const ShaftLevel& level = figures.shaft.levels[size_t(l)];
            if (level.tried == 0 && level.seen == 0) continue;
            ctx.info(fmt::format(
                "shaft pass, {}: {} proofs tried, {} proven ({} (cell, object) pairs left out), "
                "{} not tried for a sight ray's hit, {} (cell, object) pairs given up where both "
                "witnesses failed, {:.1f} thread seconds",
                l == 0 ? std::string("cells") : fmt::format("nodes of up to {0}x{0}x{0} cells", 1 << l),
                level.tried, level.proven, level.settled, level.seen, level.given_up, level.seconds));
        }
    }
    ctx.info(fmt::format(
        "conservative PVS: one occluder hides {:.2f} M (cell, object) pairs from the whole region ({:.1f} s) "
        "and {:.2f} M (patch, object) pairs from a patch; {} samples (per epsilon level {}; {} floor patches "
        "halved for panels; {} second "
        "looks at {} px), {} inside occluders and {} patches in solid skipped, {:.1f} M box tests, {:.1f} M "
        "sight rays, {:.1f} M (face side, object) pairs already listed by the cell, {:.1f} s ({:.0f} "
        "cells/s)",
        double(figures.region_hidden) * 1e-6, figures.region_seconds, double(figures.patch_hidden) * 1e-6,
        figures.samples, fmt::join(figures.samples_per_level, "/"), figures.panel_splits,
        figures.fine_samples, config.fine_cube_resolution, figures.samples_skipped, figures.patches_in_solid,
        double(figures.object_tests) * 1e-6, double(figures.rays) * 1e-6, double(figures.known_listed) * 1e-6,
        figures.seconds, double(cells.size()) / std::max(1e-9, figures.seconds)));
    return pvs;
}

}  // namespace pvs
