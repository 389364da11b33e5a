// SPDX-License-Identifier: MIT
// pvsbake solver: the shaft pass. An object the depth cubes left listed is proven hidden from a cell's whole
// eye region, exactly, when the region and the object can be cut into pieces such that, for every pair of
// pieces, ONE plane holds an occluder cover of all the segments between them: no shrinking, no inset, no
// pixels; the occluders of one plane fuse (the panels of a wall and the slice of the proven solid).
//
// Contract: plane_covers() is true only if every segment from the box `region` to the box `target` crosses
// the plane (axis, c) at a point that lies, with its whole square of half-side kHideToleranceM in the plane,
// in the union of the panels of that plane and of the interior of the proven solid's slice (both boxes lie
// strictly on opposite sides of the plane), or, with fusion, in the umbra of an occluder of another plane:
// the segments from every point of `region` to it meet that occluder (a front umbra), or those from it to
// every point of `target` do (a back umbra; the occluder misses `target`). A segment crossing a panel meets
// an opaque triangle; one reaching the interior of the proven solid is stopped by S; one through an umbra
// meets its occluder before its end. hides() is true only if every piece pair of a cover of the region's
// eyes and of the object's triangles passes plane_covers(), slanted_hides(), a convex cap (cap_hides) or a
// cup: a box holding one piece and not the other, each of whose faces covers, as plane_covers() does, the
// crossings inside its window of the segments that leave the box through it; or the flood: the occluders
// separate the two pieces in the hull of their boxes (pvs/shaft_flood.h). So what it proves is hidden
// from every eye of the region. The argument: docs/ALGORITHMS.md#shaft-pass, #cross-plane-fusion,
// #convex-caps, #cups and #shaft-flood.
#pragma once

#include "core/cell_set.h"
#include "core/context.h"
#include "core/occluder.h"
#include "core/world.h"
#include "pvs/convex_cap.h"
#include "pvs/shaft_flood.h"
#include "rays/ray_scene.h"

#include <array>
#include <memory>
#include <vector>

namespace pvs {

// One level of the hierarchy of cells the shaft pass proves over (docs/ALGORITHMS.md#shaft-hierarchy):
// level 0 is a cell alone, level L a node of at most 2^L x 2^L x 2^L grid positions.
struct ShaftLevel {
    uint64_t tried = 0;    // (node, object) proofs tried
    uint64_t proven = 0;   // of them, proven hidden from the whole node
    uint64_t settled = 0;  // (cell, object) pairs those proofs left out of rows
    uint64_t seen = 0;     // (node, object) pairs not tried: a sight ray from a cell of the node saw it
    uint64_t given_up = 0;  // (cell, object) pairs left listed untried: both witnesses of the node failed
    double seconds = 0.0;  // thread seconds of its tries

    ShaftLevel& operator+=(const ShaftLevel& o) {
        tried += o.tried;
        proven += o.proven;
        settled += o.settled;
        seen += o.seen;
        given_up += o.given_up;
        seconds += o.seconds;
        return *this;
    }
};
constexpr int kShaftLevels = 5;  // cells, and nodes of up to 16 x 16 x 16 of them

struct ShaftFigures {
    uint64_t pairs = 0;          // (region, object) pairs tried
    uint64_t hidden = 0;         // of them, proven hidden
    uint64_t tests = 0;          // piece pairs tested
    uint64_t certain = 0;        // pairs given up at once: a line from an eye to the object meets no occluder
    uint64_t out_of_budget = 0;  // pairs given up when the budget of piece pairs ran out
    uint64_t stuck = 0;  // pairs given up on pieces that meet, cannot be halved or were halved too often
    uint64_t stuck_meet = 0;   // of them, on pieces that meet
    uint64_t stuck_depth = 0;  // on pieces halved kBaseHalvings + log2(budget) times
    uint64_t umbrae = 0;  // umbrae of occluders in other planes computed (cross-plane fusion)
    uint64_t capped = 0;  // piece pairs a convex cap covered (pvs/convex_cap.h)
    uint64_t cupped = 0;  // piece pairs a cup covered (docs/ALGORITHMS.md#cups)
    FloodFigures flood;   // separation in the shaft (docs/ALGORITHMS.md#shaft-flood)
    uint64_t skipped_candidates = 0;  // regions x objects of the passes not run for the pair cap
    uint64_t probe_rays = 0;  // rays of the probe before the proofs (docs/ALGORITHMS.md#shaft-probe)
    uint64_t probe_seen = 0;  // (cell, object) pairs they settled as visible
    double seconds = 0.0;
    // Where the time went, by how each pair ended (shaft_row() times each pair).
    double seconds_hidden = 0.0, seconds_certain = 0.0, seconds_out_of_budget = 0.0, seconds_stuck = 0.0;
    std::array<ShaftLevel, kShaftLevels> levels{};  // by level of the hierarchy (grids; octrees: level 0)
    ShaftLevel early;  // the blocks' proofs before the faces (docs/ALGORITHMS.md#shaft-early)

    ShaftFigures& operator+=(const ShaftFigures& o) {
        for (size_t l = 0; l < levels.size(); ++l) levels[l] += o.levels[l];
        early += o.early;
        pairs += o.pairs;
        hidden += o.hidden;
        tests += o.tests;
        certain += o.certain;
        out_of_budget += o.out_of_budget;
        stuck += o.stuck;
        stuck_meet += o.stuck_meet;
        stuck_depth += o.stuck_depth;
        umbrae += o.umbrae;
        capped += o.capped;
        cupped += o.cupped;
        flood += o.flood;
        skipped_candidates += o.skipped_candidates;
        probe_rays += o.probe_rays;
        probe_seen += o.probe_seen;
        seconds += o.seconds;
        seconds_hidden += o.seconds_hidden;
        seconds_certain += o.seconds_certain;
        seconds_out_of_budget += o.seconds_out_of_budget;
        seconds_stuck += o.seconds_stuck;
        return *this;
    }
};

// A region with its eye voxels (those meeting it with volume) as summed counts over their index box, built
// once for all the objects tried against it.
struct ShaftRegion {
    Aabb box;
    glm::ivec3 base{0}, n{0};   // the index box of the voxels meeting `box`: [base, base + n)
    std::vector<uint32_t> sum;  // (n + 1)^3 summed counts; empty without eye voxels (every point is an eye)
    // The eye voxels with local indices in [lo, hi).
    uint32_t count(glm::ivec3 lo, glm::ivec3 hi) const {
        if (lo.x >= hi.x || lo.y >= hi.y || lo.z >= hi.z) return 0;
        const auto at = [&](int x, int y, int z) {
            return int64_t(sum[size_t(x) + size_t(n.x + 1) * (size_t(y) + size_t(n.y + 1) * size_t(z))]);
        };
        return uint32_t(at(hi.x, hi.y, hi.z) - at(lo.x, hi.y, hi.z) - at(hi.x, lo.y, hi.z) -
                        at(hi.x, hi.y, lo.z) + at(lo.x, lo.y, hi.z) + at(lo.x, hi.y, lo.z) +
                        at(hi.x, lo.y, lo.z) - at(lo.x, lo.y, lo.z));
    }
};
ShaftRegion shaft_region(const VoxelMask& eyes, const Aabb& region);

// The umbra on the plane x[axis] = c of the convex set conv(corners[0 .. n)) seen from the box with corners
// `eyes`: the points y of the plane such that the segment from EVERY eye corner to y meets the set, which
// by convexity is every segment from the box (docs/ALGORITHMS.md#cross-plane-fusion). `side` is +1 when the
// eyes lie above the plane along the axis, -1 below; every corner must lie on that side or on the plane and
// strictly nearer to it than every eye corner (else false). Writes the umbra, convex and counter-clockwise
// in the plane's coordinates (axis + 1, axis + 2); false when it has no area.
bool umbra_on_plane(const std::array<glm::dvec3, 8>& eyes, const glm::dvec3* corners, size_t n, int axis,
                    double c, int side, std::vector<glm::dvec2>& out);

// The occluders of one set (ShrunkOccluders: its panels, slanted panels and proven solid), indexed by plane.
// With `fusion`, a plane's cover also takes in the umbrae of occluders in other planes, seen from either
// piece (docs/ALGORITHMS.md#cross-plane-fusion). With `caps`, a piece pair is also covered by the convex cap
// of a panel the line meets and its neighbours across edges (pvs/convex_cap.h). With `cups`, a piece pair is
// also covered by a cup (docs/ALGORITHMS.md#cups). With `flood`, a piece pair is also covered when the axis
// panels and the proven solid separate the two pieces in the hull of their boxes (pvs/shaft_flood.h).
class ShaftProver {
public:
    ShaftProver(Context& ctx, const ShrunkOccluders& set, bool fusion = true, bool caps = true,
                bool cups = true, bool flood = true);
    ~ShaftProver();
    ShaftProver(const ShaftProver&) = delete;
    ShaftProver& operator=(const ShaftProver&) = delete;

    // Is every segment from an eye in `region` (a point of a voxel of `eyes` in it, shaft_region(); every
    // point of the region when `eyes` is empty) to a point of object `object`'s triangles stopped by an
    // occluder? Tests at most `budget` piece pairs. Thread-safe.
    bool hides(const World& world, const VoxelMask& eyes, const ShaftRegion& region, uint32_t object,
               int budget, ShaftFigures& figures) const;

    // Where a plane's cover fell short: the bounds of the crossing and of the part left open, in the plane's
    // coordinates (axis + 1, axis + 2).
    struct PlaneMiss {
        int axis = -1;
        float c = 0.0f;
        glm::dvec2 lo{0.0}, hi{0.0}, open_lo{0.0}, open_hi{0.0};
    };
    // Does every segment from `region` to `target` cross the plane x[axis] = c inside the panels of that
    // plane and the proven solid's slice (see the contract above), or, with fusion, at a point from which
    // an occluder of another plane stops it on the way to either end? When not, and the boxes lie on
    // opposite sides of the plane, `miss` (if given) says where. `umbrae` (if given) counts the umbrae
    // computed.
    bool plane_covers(const Aabb& region, const Aabb& target, int axis, float c, PlaneMiss* miss = nullptr,
                      uint64_t* umbrae = nullptr) const;

private:
    struct Plane {
        float c;
        uint32_t first, count;  // into rects_
        glm::dvec2 lo, hi;      // the bounds of its panels
    };
    struct Rect {
        double u0, u1, v0, v1;
    };
    struct Pair;
    struct Scratch;
    // Does one plane that the line from -> to crosses an occluder in cover the pair? `line_blocked`: the line
    // meets an occluder at all.
    // `miss`: of the planes tried, the one whose open part is narrowest across, relative to its crossing.
    bool try_pair(const Pair& pair, glm::vec3 from, glm::vec3 to, bool& line_blocked, PlaneMiss& miss,
                  Scratch& sc, ShaftFigures& figures) const;
    // Does the convex cap of a panel or slanted panel the line met (index into panels_, then slanted_) and
    // its neighbours, seen from one of the pieces, cover the pair?
    bool cap_covers(uint32_t polygon, const Aabb& region, const Aabb& target) const;
    struct PlaneScratch;
    // A rectangle of a plane in its coordinates (axis + 1, axis + 2): the face of a cup.
    struct Window {
        glm::dvec2 lo, hi;
    };
    // plane_covers() with or without the umbrae of other planes' occluders. With a window, only the
    // crossings inside it need a cover (true when none lies there), and the target may reach the plane from
    // its side while the region lies kCupMarginTolerances tolerances from it (docs/ALGORITHMS.md#cups).
    bool cover(const Aabb& region, const Aabb& target, int axis, float c, bool fuse, PlaneMiss* miss,
               uint64_t* umbrae = nullptr, const Window* window = nullptr) const;
    // Is every segment between the pieces stopped by the faces of a cup, a box holding one piece and not the
    // other whose faces the segments leave it by are covered (docs/ALGORITHMS.md#cups)?
    bool cup_covers(const Pair& pair, Scratch& sc, ShaftFigures& figures) const;
    // Adds to the scratch the umbrae on the plane (axis, c) of the occluders that the lines from the centre
    // of each box through the plane's point y (in the plane's coordinates) meet, each occluder once.
    void add_umbrae(const Aabb& region, const Aabb& target, int axis, double c, glm::dvec2 y,
                    PlaneScratch& ps) const;
    bool meets_occluder(glm::vec3 from, glm::vec3 to, Scratch& sc) const;
    // Adds to the scratch's umbrae the cross-sections with the plane (axis, c) of the convex caps of
    // polygon `polygon` (index into panels_, then slanted_) that guard the region or the target piece.
    void add_cap_slices(uint32_t polygon, const Aabb& region, const Aabb& target, int axis, double c,
                        PlaneScratch& ps) const;

    std::vector<Plane> planes_[3];  // per axis, by c
    // Per axis and voxel layer across it, the bounds of the layer's solid voxels in the plane's coordinates
    // (empty when none): a crossing outside them and the plane's panels is not covered.
    std::vector<glm::dvec2> layer_lo_[3], layer_hi_[3];
    std::vector<Rect> rects_;  // the panels of each plane, in its (axis + 1, axis + 2) coordinates
    std::vector<Aabb> panels_;
    std::vector<int> panel_axis_;
    std::vector<SlantedPanel> slanted_;
    const VoxelMask& solid_;
    std::unique_ptr<RayScene> scene_;  // panels_, then slanted_, every triangle see-through
    bool fusion_ = false;
    std::vector<Aabb> boxes_;  // the boxes of the floor epsilon (inside the proven solid), for their umbrae
    std::unique_ptr<RayScene> umbra_scene_;  // boxes_, panels_, then slanted_, every triangle see-through
    std::vector<CapPolygon> cap_polygons_;   // panels_, then slanted_ (none for a slab with thickness)
    std::vector<ConvexCap> caps_;            // build_caps(cap_polygons_); empty without caps
    bool cups_ = false;
    std::unique_ptr<ShaftFlood> flood_;  // null without the flood
};

// A ShaftProver for every set of a ShrunkOccluders (the global one and each block's), built once.
class ShaftProvers {
public:
    ShaftProvers(Context& ctx, const ShrunkOccluders& occluders, bool fusion = true, bool caps = true,
                 bool cups = true, bool flood = true);
    const ShaftProver& of(int32_t i) const { return *provers_[size_t(i + 1)]; }

private:
    std::vector<std::unique_ptr<ShaftProver>> provers_;
};

}  // namespace pvs
