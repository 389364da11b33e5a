// pvsbake pvs: the conservative PVS with occluder fusion, by occluder shrinking (after P. Wonka, M. Wimmer,
// D. Schmalstieg, "Visibility Preprocessing with Occluder Fusion for Urban Walkthroughs", EGWR 2000; see
// ../shared/design/ALGORITHMS.md section 3).
//
// Why it is safe (the argument the code stands on):
// 1. Occluders are boxes of the proven solid shrunk by epsilon (pvs/occluder_synthesis.h): every point of a
//    box shrunk by epsilon has its whole epsilon-CUBE (the ball of radius epsilon in the Chebyshev metric,
//    |d|_inf = max_k |d_k|; the erosion is by whole voxels in that metric) inside the proven solid, where no
//    sight line goes.
//    The solid includes the inside of the union of closed box meshes (occluders/solid.h), so a wall
//    standing on a floor fuses with it without a seam.
// 2. If the segment from a sample point s to a point x meets a shrunk box at y = s + t (x - s), then for any
//    q with |q - s|_inf <= epsilon, the point q + t (x - q) of segment qx is within (1 - t) epsilon of y in
//    that metric, so inside the solid: segment qx is blocked too. Pointwise, so it holds for the union of
//    boxes: fusion for free. (In the Chebyshev metric a square patch of half-side e needs epsilon >= e, not
//    its half-diagonal e sqrt 2: half the samples of the Euclidean ball for the same epsilon.)
// 3. Eyes are points of the eye space (free voxels of the view volume, cells/view_volume.h; the lookup
//    region `view` is one voxel larger, and an eye in that rim, within a voxel of a surface, is not covered).
//    A cell's EYE REGION is the bounds of the eye voxels in it, clipped to the cell: convex, and it holds
//    every eye of the cell. Sight from an eye either ends inside the region (objects whose bounds meet it
//    are always listed) or leaves the region through a point q of its boundary. (Sampling the region, not
//    the cell, keeps samples out of floors and walls the cell box cuts through, where they would see the
//    backs of the level.) The boundary is cut into PATCHES (flat rectangles); a patch lies in the box of
//    half-extents spread_k around its sample s (its centre, rounded to float), spread_k the distance from
//    s_k to the patch's farther side on axis k (in double, exact; 0 along the face's axis), and
//    r = max_k spread_k is its Chebyshev radius, so the part of the sight line beyond q is blocked whenever
//    sx meets a box shrunk by some epsilon >= r.
//    The segment from the eye to q is unobstructed, so q is not inside the proven solid (cracks aside,
//    which the sight probe and the ray check of occluder synthesis handle): a patch all of whose voxels
//    (closed, so a patch on a voxel face meets both sides) are proven solid lets no sight line out and is
//    skipped. (An earlier version skipped patches far from the EYE space; that was wrong with
//    --play-height: an eye sees up through the top of its cell, above the eye space.) Faces of neighbouring
//    regions that coincide exactly are computed once, on the same samples, for both sides.
//    The region is convex, so a sight line leaving through q on a face goes outward: beyond q it stays in
//    the face's closed outer half-space. So a face lists, for the region it bounds, only objects whose
//    bounds reach its plane from the outer side (the rest cannot be seen through it).
// 4. From s, the depth cube (pvs/depth_cube.h) proves a box hidden only when every segment from s to the box
//    meets a shrunk occluder. So an object proven hidden from s at level k (boxes shrunk by epsilon_k >= r)
//    is hidden from every eye whose sight leaves the cell through the patch. A sample inside a shrunk box
//    needs no test: its epsilon-cube, which holds the patch, lies in the solid. Drawing fewer occluders only
//    leaves more pixels open, so the cube is drawn with only those meeting the box around s and the
//    objects still to prove (which holds every segment from s to them).
// 5. Adaptive refinement (ALGORITHMS.md section 3): a face is first tested as patches with r <= the
//    largest epsilon of the ladder; an object proven hidden from a patch is done for all of it; the objects
//    not yet proven go to the patch's four halves (r halves), down to r <= epsilon_0 (the floor), where an
//    object not proven hidden is listed. Each patch uses the smallest epsilon >= its r (fewer shrunk-away
//    walls). An object is left out of a cell's PVS only if every patch of the cell's boundary proved it.
//    So a face need not test what its cell already lists (through another face, or because its bounds
//    meet the region): the cell's row is the union of its faces' rows. The faces of a cell are solved one
//    after another (on a grid: in six phases, each with at most one face per cell), each skipping what the
//    cell listed before it; and a face's patches one after another, depth first, each skipping what the
//    patches before it listed.
//    Optionally (--panel-refine-levels) what is left at the floor goes down a few more halvings while some
//    panel is drawn: the boxes stay those of epsilon_0, still >= r, and the panels' inset halves with r.
// 6. Objects are tested hierarchically: a bounding volume hierarchy over the objects' bounds; a node proven
//    hidden proves every object under it (each point of those objects lies in the node's box). An object
//    whose whole box is not proven may still be, part by part (each of its triangles' boxes).
// 7. Objects a sight ray from a patch centre s reaches (Embree, against the real triangles) are listed at
//    once instead of refined: no patch holding s can prove them hidden, so refining them only costs time.
// 8. PANELS (occluders/panels.h) are flat rectangles wholly covered by opaque triangles: a segment that meets
//    one is stopped. A patch's sample s draws the panels whose plane is farther from s than the patch's box
//    reaches along their normal n (spread_n; so the whole box, which holds the patch, is on one side), only
//    on the cube face along the panel's normal, inset per pixel corner ray of face coordinates (u, v) by
//    spread_u + spread_n |u| on the u axis and spread_v + spread_n |v| on the v axis (pvs/depth_cube.h,
//    add_panel, with the proof). Why that is enough: put the plane at height 0, s at height h_s > spread_n,
//    x behind it at height -h_x < 0, and let y(q) be where segment q -> x crosses the plane, for q in the
//    box. With l_q = h_q / (h_q + h_x), y(q) - y(s) = (1 - l_q)(q - s)_par + (l_q - l_s)(x - s)_par,
//    |l_q - l_s| <= |h_q - h_s| / (h_s + h_x) and |x_u - s_u| / (h_s + h_x) = |u|, so
//    |y(q)_u - y(s)_u| <= |q_u - s_u| + |u| |h_q - h_s| <= spread_u + |u| spread_n (likewise on v). The
//    depth cube proves x hidden through a panel pixel only if y(s) lies in the rectangle inset so for the
//    ray s -> x (the inset test is concave in u and in v, so the corners decide for the whole pixel), so
//    y(q) lies in the covered one: every segment from the patch to x crosses an opaque triangle before x.
//    A patch is flat, so a panel parallel to it is inset by the patch's half-size alone, at every angle;
//    one across it by its half-size plus |u| times its half-size on one axis and by |u| times it on the
//    other. (The Euclidean ball around the patch gave r sqrt(1 + u^2) on both, r the half-diagonal.)
//    Unlike a box, a panel needs no solid behind it and no epsilon: a wall thinner than 2 epsilon + 2
//    voxels, or a hollow shell, still occludes by its faces. The bound holds with u replaced by any ray's
//    tangent relative to the panel's normal, (x - s)_k / (x - s)_normal, so at every sample the panels are
//    also drawn on the four SIDE faces of the cube (rays more than 45 degrees from the normal, tangents
//    > 1), over what the other faces left unproven, inset per ray by spread_k + spread_n |p_k| with p_k
//    those tangents (add_panel_sides: the tangent ranges are intervals, so the test stays separable).
// 9. OCCLUDERS PER BLOCK (pvs/occluder_synthesis.h, synthesize_block_occluders). Points 1 to 4 need the
//    occluders only to lie where no sight line from the eyes of THIS region goes: the segment from an eye e
//    through q to x, were it clear, would carry sight from e into the solid. So a region whose eyes all lie
//    in one block's sources may use that block's solid: what sight from those eyes alone never reaches (a
//    superset of the global solid; in a level open to the sky, also the space behind walls out of those
//    eyes' sight). ShrunkOccluders::set_for picks a region's set; a face shared by
//    regions of two blocks is solved once per side, each with its own set (argument 3 per side).
// 10. The SINGLE-OCCLUDER PASS (pvs/region_hiding.h, with its proof; --single-occluder-pass): before its
//    faces, a region leaves out every object one panel or one box (of the floor epsilon) hides from the
//    whole region, tested exactly on the 64 segments between the corners of the region and of the object's
//    bounds. It needs no shrinking: convexity of the occluder, not a sample's epsilon-cube, covers every
//    eye. No face of the region tests those objects (argument 5: a row is the union of what the faces list,
//    and an object hidden from every eye of the region need be listed by none).
// 11. OCTREE CHILDREN (conservative_box_rows with bounds): a child box lies in its parent, so the eye voxels
//    meeting it meet the parent, and its eye region (their bounds, clipped to the box) lies in the parent's.
//    Every eye of the child is an eye of the parent, so an object the parent's row leaves out (proven
//    hidden from every eye of the parent, by this same argument and with the set serving the parent's eyes)
//    is hidden from every eye of the child: the child neither lists nor tests it. The rule-listed objects
//    (bounds meeting the child's region, which lies in the parent's) are listed by both.
// What it rests on beyond this argument: the solid being truly closed to sight. The voxel sweep treats a
// voxel an opaque triangle touches as closed, so a line through a crack narrower than a voxel, or grazing
// past a surface's edge through a touched voxel, goes where the sweep says sight does not. The sight probe,
// the seal probe (global solid only: rays from the solid just behind touched voxels, where a crack
// subtends a large angle; what they find is swept through again, pvs/seal_probe.h) and the ray check of
// occluder synthesis (global and per block, from the eyes concerned; the global boxes also from eyes near
// each, where a crack lines up with more rays) look for such lines with Embree rays against the real
// triangles; they sample (ctf_inyard's octree once missed an object seen through a 5.7 mm gap in a floor;
// the seal probe alone now finds that gap). A block's shadow has such grazing boundaries all along it, so
// verification (pvs/verify.h) is the last word on every bake.
#pragma once

#include "core/cell_set.h"
#include "core/config.h"
#include "core/context.h"
#include "core/occluder.h"
#include "core/pvs_set.h"
#include "core/world.h"
#include "pvs/embree_scene.h"
#include "pvs/region_hiding.h"

#include <vector>

namespace pvs {

struct ConservativeFigures {
    uint64_t samples = 0;           // patch centres a depth cube was drawn from
    uint64_t samples_skipped = 0;   // patch centres inside a shrunk occluder (nothing passes the patch)
    uint64_t patches_in_solid = 0;  // patches wholly in the proven solid
    uint64_t object_tests = 0;      // box tests on a depth cube (hierarchy nodes, objects and parts)
    uint64_t rays = 0;              // sight rays from patch centres (objects seen need no refinement)
    uint64_t fine_samples = 0;      // floor samples that took a second look on the fine cube
    uint64_t panel_splits = 0;      // patches at the floor epsilon halved once more for the panels' sake
    uint64_t known_listed = 0;      // (face side, object) pairs not tested: the cell already listed them
    uint64_t region_hidden = 0;     // (cell, object) pairs the single-occluder pass proved hidden
    double region_seconds = 0.0;    // its time (grid; on boxes it is part of `seconds`)
    uint64_t patch_hidden = 0;      // (patch, object) pairs it proved hidden, of what a patch's cubes left
    uint64_t parent_hidden = 0;     // (octree box, object) pairs left out untested: its parent left them out
    std::vector<uint64_t> samples_per_level;  // samples at each epsilon of the ladder
    double seconds = 0.0;
};

// The conservative rows of arbitrary boxes (cells, or octree nodes being considered): rows has boxes.size()
// rows. Each box is first clipped to its eye region (the bounds of the `eyes` voxels in it; the whole box
// when `eyes` is empty). Lists pvs_always_visible objects and objects whose bounds meet the region, then
// every object some patch of the region's boundary cannot prove hidden. Parallel over boxes.
// With `bounds` (one per box, null for none): bounds[i] is this function's row for a box that holds box i
// (an octree node's parent). Its eye region holds box i's, so what that row leaves out is hidden from every
// eye of box i too: it is left out without a test (argument 11).
void conservative_box_rows(Context& ctx, const ConservativeConfig& config, const World& world,
                           const std::vector<Aabb>& boxes, const VoxelMask& eyes,
                           const ShrunkOccluders& occluders, const RayScene& scene, PvsSet& rows,
                           ConservativeFigures& figures, const RegionHiders* hiders = nullptr,
                           const std::vector<const uint64_t*>* bounds = nullptr);

// The conservative PVS of every cell. On a grid each face shared by two cells is computed once.
PvsSet bake_conservative_pvs(Context& ctx, const ConservativeConfig& config, const World& world,
                             const CellSet& cells, const ShrunkOccluders& occluders, const RayScene& scene,
                             ConservativeFigures& figures);

}  // namespace pvs
