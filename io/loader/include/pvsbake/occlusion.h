// SPDX-License-Identifier: MIT
// pvsbake runtime loader: run-time culling of MOVING objects (characters, vehicles, props: what no PVS can
// list) against a few occluder boxes, such as the ranked occluders a bake stores per cell
// (docs/ALGORITHMS.md#ranking; why the culler is conservative: docs/ALGORITHMS.md#runtime-culler). Every
// frame: begin_frame(eye, occluders), then is_hidden(box) / classify(box) for each moving object's bounding
// box. Part of pvsbake::loader: no exceptions leave it, no global state, no allocation after construction (an
// OcclusionCuller whose buffers could not be allocated culls nothing: ok() false).
//
// After: T. Hudson, D. Manocha, J. Cohen, M. Lin, K. Hoff, H. Zhang. Accelerated Occlusion Culling using
// Shadow Frusta. SoCG 1997 (one occluder: is the box inside its shadow frustum?); fusing occluders on a
// small conservative depth buffer as H. Zhang, D. Manocha, T. Hudson, K. Hoff. Visibility Culling using
// Hierarchical Occlusion Maps. SIGGRAPH 1997 (a box is hidden when every pixel it touches is covered
// nearer than it), with the coverage and depth rules of pvs/depth_cube.h (the baker's from-point test of
// P. Wonka, M. Wimmer, D. Schmalstieg. Visibility Preprocessing with Occluder Fusion for Urban
// Walkthroughs, EGWR 2000), written here in float with explicit margins, as a cube map so that every
// direction around the eye is covered (the culler needs no view frustum).
//
// Conventions (read these before touching the code; Masked Occlusion Culling style):
// - Axes: glTF world axes (right-handed, +Y up), metres. Boxes are pvsbake::Box (loader.h): closed,
//   axis-aligned; min > max on some axis is an empty box. Everything is relative to the eye: Δ = p - eye.
// - Occluders are SOLID boxes: a box counts as blocking sight exactly inside its own volume (as the
//   bake's occluders are boxes inside the opaque solid: no sight line from the view volume enters them).
//   An occluder that contains or touches the eye (within its margin) is skipped: it hides nothing.
// - PANELS: an occluder flat along exactly one axis (min == max there) is a RECTANGLE, a face of the opaque
//   surface such as a bake's panels (every segment that meets one meets an opaque triangle). It blocks the
//   segments that cross its plane inside it. It is used with its rectangle shrunk by its margin, and skipped
//   when the eye lies within that margin of its plane (seen edge-on it hides nothing). Its shadow frustum is
//   the half-space behind its plane within the planes through the eye and its edges; on the depth cube a
//   corner ray passes it when it crosses the plane inside the shrunk rectangle (entry = exit there). A box
//   flat along two or three axes hides nothing (docs/ALGORITHMS.md#runtime-panels).
// - "Hidden" (the one conservative answer): is_hidden(Q) is true only if every segment from the eye to any
//   point x of Q enters some occluder strictly before x, or (path 3 only) passes within 1e-9 of the scale
//   of the coordinates of it (below their float precision). Anything not proven is visible: empty or
//   non-finite boxes, a box within kNearPlane_m of the eye (which covers "contains the eye"), and every box
//   when the eye is not finite or there are no usable occluders. Wrong answers can only be "visible".
// - Path 1, shadow frusta (one occluder at a time, Hudson et al.): the shadow of a convex occluder B from
//   the eye, S(B) = { x : the segment eye-x meets B }, is convex; for a box B it is the intersection of the
//   half-spaces behind B's front faces (those facing the eye) and of the planes through the eye and B's
//   silhouette edges (4 or 6). Q is hidden by B when Q lies in S(B). Computed in double on the float
//   inputs with margins: B is shrunk and Q grown by delta = kMargin_m + kMarginRel * (largest |coordinate|
//   of the eye and the box), per box, far above double rounding (docs/ALGORITHMS.md#runtime-frusta).
// - Path 2, the depth cube (fusion: several occluders together): six faces, in this order 0 = +X, 1 = -X,
//   2 = +Y, 3 = -Y, 4 = +Z, 5 = -Z; face f has axis a = f / 2, sign s = +1 for even f, and side axes
//   ua = (a + 1) % 3, va = (a + 2) % 3. Depth on face f: d = s * Δ[a] (along the face normal, not the
//   Euclidean distance; larger = farther; along any ray it grows with distance). Face coordinates
//   u = Δ[ua] / d, v = Δ[va] / d, no mirroring. Cones are CLOSED (a direction on a cube edge belongs to
//   every tied face, and each face is checked on its own, so no tie breaking is needed).
//   Pixels: R per face edge; pixel (i, j) is the closed square [g(i), g(i + 1)] x [g(j), g(j + 1)] with
//   g(k) = float(-1 + 2k / R), one table shared by writing and testing (neighbours share edges; g(R / 2) = 0
//   exactly). An empty pixel holds +infinity. Near plane: d = kNearPlane_m.
// - Occluder pixel rule (writing less is always safe): occluder B writes pixel P of face f only when each
//   of P's four corner rays, over depths [kNearPlane_m, inf), passes through B with room to spare
//   (exit >= entry * (1 + kDepthSlack)); it writes the FARTHEST of the four entry depths times
//   (1 + kDepthSlack), and a pixel keeps the nearest of what is written (min). Every ray through the pixel
//   then meets B no farther than that (docs/ALGORITHMS.md#depth-cube).
// - Occludee rule (touching more is always safe): on each face, L_f = the smallest depth of Q's part inside
//   the face's cone (max(d_min, dist(0, Δu range), dist(0, Δv range), near)); the touched pixels are those
//   whose closed square meets the bounding rectangle of the projection of Q ∩ {L_f <= d <= d_max}, widened
//   by kRectPad (relative). The conservative comparison: hidden only if on every face, at every touched
//   pixel, stored depth < L_f * (1 - kDepthSlack), STRICTLY nearer; +infinity (empty) is never nearer.
// - Float: the depth cube is float. kDepthSlack and kRectPad exceed the float rounding of a corner depth
//   or an occludee bound (under 1e-6 relative) tenfold, so the rules hold as if computed exactly
//   (docs/ALGORITHMS.md#runtime-depth-cube).
// - Costs: begin_frame() is O(occluders * pixels they cover) (the cube's written parts are cleared, not
//   the whole cube); is_hidden() is O(occluders) for the frusta, then O(pixels the box touches), then
//   O(faces) to find a point of the box no face hides, and only failing that the fragments of path 3.
// - Path 3, the faces (exact fusion: occluders meeting at junctions): the faces of the used occluders toward
//   the eye (a panel's rectangle, a box's front faces), each grown by 1e-9 of its scale in its plane so that
//   faces that meet overlap; the box is cut into fragments (a sub-box with a convex polygon of directions,
//   projected along an axis on which the box lies ahead of the eye) until every fragment lies beyond a face
//   within its directions (hidden) or one passes every face (visible). Limits on faces, fragments and
//   vertices; past one the answer is visible (docs/ALGORITHMS.md#runtime-faces).
#pragma once

#include <pvsbake/loader.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace pvsbake {

class OcclusionCuller {
public:
    // Which test proved a box hidden (tests and figures). Values are stable (the C API uses them).
    enum class Path : int32_t {
        kVisible = 0,        // not proven hidden: draw it
        kShadowFrustum = 1,  // inside the shadow frustum of one occluder
        kDepthBuffer = 2,    // hidden by the depth cube, not by any single frustum (occluders fused)
        kFaces = 3,          // hidden by the exact union of the occluders' faces only
    };

    static constexpr int kDefaultResolution = 32;  // pixels per cube face edge
    static constexpr int kMinResolution = 2;       // even sizes only: g(R / 2) = 0 is a pixel edge
    static constexpr int kMaxResolution = 256;
    static constexpr size_t kMaxOccluders = 64;  // more are ignored (pass the best first)
    static constexpr size_t kMaxPolygons = 32;   // polygon occluders of a frame; more are refused
    static constexpr uint32_t kMaxPolygonCorners = 8;
    static constexpr float kNearPlane_m = 1e-3f;
    static constexpr float kDepthSlack = 1e-5f;
    static constexpr float kRectPad = 1e-5f;
    static constexpr double kMargin_m = 1e-5;
    static constexpr double kMarginRel = 1e-6;

    // resolution: pixels per cube face edge, rounded up to even and clamped to [kMinResolution,
    // kMaxResolution]; 0 turns the depth cube off (shadow frusta only). Allocates the buffers
    // (6 * resolution^2 floats); if that fails, ok() is false and nothing is ever culled.
    explicit OcclusionCuller(int resolution = kDefaultResolution) noexcept;
    ~OcclusionCuller();
    OcclusionCuller(OcclusionCuller&&) noexcept;
    OcclusionCuller& operator=(OcclusionCuller&&) noexcept;
    OcclusionCuller(const OcclusionCuller&) =
        delete;  // a copy would allocate (and could throw): make another
    OcclusionCuller& operator=(const OcclusionCuller&) = delete;

    // Prepares one frame: the eye (metres) and the occluder boxes (solid). Boxes are read at `stride_bytes`
    // apart (default: a plain array of Box), so an array of structs holding a Box can be passed as
    // (&array[0].box, n, sizeof array[0]). At most kMaxOccluders are used, the first ones. Empty, non-finite
    // and eye-touching boxes are skipped; the rest go in nearest first, and a box the ones before it already
    // hide is skipped too (it could add nothing: its shadow lies in theirs). A non-finite eye makes every box
    // visible this frame.
    void begin_frame(const float eye[3], const Box* occluders, size_t count,
                     size_t stride_bytes = sizeof(Box)) noexcept;
    void begin_frame(const float eye[3], const std::vector<Box>& occluders) noexcept {
        begin_frame(eye, occluders.data(), occluders.size());
    }

    // Prepares one frame with cell c's best min(its count, max_occluders, kMaxOccluders) ranked occluders
    // (Bake::occluder_boxes); returns how many were given. Allocates nothing. Then for_each_drawn() gives
    // what to draw of the cell's PVS.
    uint32_t begin_cell(const Bake& bake, uint32_t c, const float eye[3],
                        size_t max_occluders = kMaxOccluders) noexcept;

    // Adds a convex POLYGON occluder to this frame, after begin_frame(): a slanted panel of the opaque
    // surface (Bake::occluder_polygon). plane = normal x, y, z, offset, thickness: the opaque surface lies in
    // the slab |normal . x - offset| <= thickness; corners = `count` points of 3 floats, convex and
    // counter-clockwise seen from the side the normal points to, 3 <= count <= kMaxPolygonCorners. Its
    // promise: every segment that crosses the slab from one side to the other, entering and leaving it inside
    // the prism over the corners (along the normal), meets the opaque surface. Only the faces test uses
    // polygons (docs/ALGORITHMS.md#runtime-polygons). False when refused: the eye within the slab's margin, a
    // polygon that is not convex and counter-clockwise, a value that is not finite, or kMaxPolygons added.
    bool add_polygon(const float plane[5], const float* corners, uint32_t count) noexcept;
    size_t polygons_used() const noexcept;

    // True only if the box is certainly hidden from this frame's eye (see the conventions above).
    // Thread-safe between begin_frame() calls (const, no scratch).
    bool is_hidden(const Box& box) const noexcept { return classify(box) != Path::kVisible; }
    // The same answer with the test that proved it: shadow frusta first, then the depth cube, then the faces.
    Path classify(const Box& box) const noexcept;
    // The depth cube's answer alone, the shadow frusta's alone, or the faces' alone (tests, figures).
    bool hidden_by_depth_cube(const Box& box) const noexcept;
    bool hidden_by_shadow_frusta(const Box& box) const noexcept;
    bool hidden_by_faces(const Box& box) const noexcept;

    bool ok() const noexcept;
    int resolution() const noexcept;
    // Occluders this frame uses (after skipping those that touch the eye and those the nearer ones already
    // hide), the redundant ones skipped, and the cube pixels the used ones cover.
    size_t occluders_used() const noexcept;
    size_t occluders_redundant() const noexcept;
    size_t covered_pixels() const noexcept;

private:
    struct State;  // the C99 runtime's culler (runtime/pvsr.c) and its memory
    std::unique_ptr<State> state_;
};

// Whether object o of the bake is culled by `hidden` (a test of a box from this frame's eye): its bounds are
// hidden or, where it has parts (format 1.9), every part is; objects flagged always visible never are.
template <class Hidden>
bool culled_by(const Bake& bake, uint32_t o, Hidden&& hidden) noexcept {
    constexpr uint32_t kAlwaysVisible = 4;  // object_flags bit 2
    if ((bake.object_flags(o) & kAlwaysVisible) != 0) return false;
    if (hidden(bake.object_bounds(o))) return true;  // an empty box is never hidden
    const uint32_t parts = bake.object_part_count(o);
    for (uint32_t k = 0; k < parts; ++k)
        if (!hidden(bake.object_part(o, k))) return false;
    return parts > 0;
}

// Whether the culler culls object o of the bake from this frame's eye: the test for_each_drawn makes.
inline bool is_culled(const Bake& bake, const OcclusionCuller& culler, uint32_t o) noexcept {
    return culled_by(bake, o, [&](const Box& b) { return culler.is_hidden(b); });
}

// What a game draws of cell c from this frame's eye: its PVS less what the culler (set up by begin_cell, or
// begin_frame with any occluders) proves hidden by the object's bounds or every one of its parts; objects
// flagged always visible, and those without bounds, are never culled. Calls visit(object) in increasing
// order; returns how many. Allocates nothing; the culler is only read, so threads may walk cells with one
// culler between frames.
template <class F>
uint32_t for_each_drawn(const Bake& bake, uint32_t c, const OcclusionCuller& culler, F&& visit) {
    uint32_t drawn = 0;
    bake.for_each_visible(c, [&](uint32_t o) {
        if (!is_culled(bake, culler, o)) {
            visit(o);
            ++drawn;
        }
    });
    return drawn;
}

// The occlusion horizon of a frame built from the cell's list of horizon occluders (format 1.8): the C99
// runtime's own code (runtime/pvsr.h, pvsr_horizon; docs/ALGORITHMS.md#horizon-lists), compiled into this
// library in a namespace of its own, so its answers are the runtime's. Its memory is allocated once, here.
class Horizon {
public:
    // columns a side (a power of two, 4 to 8192) and the pieces a frame may hold (past them occluders are
    // dropped: fewer culls). ok() is false when the memory could not be allocated: then it hides nothing.
    explicit Horizon(int columns = 256, size_t max_pieces = 65536) noexcept;
    ~Horizon();
    Horizon(Horizon&&) noexcept;
    Horizon& operator=(Horizon&&) noexcept;
    Horizon(const Horizon&) = delete;
    Horizon& operator=(const Horizon&) = delete;

    bool ok() const noexcept;
    // A frame at the eye with cell c's list (in the file's order); returns how many occluders were given.
    // Allocates nothing.
    uint32_t begin_cell(const Bake& bake, uint32_t c, const float eye[3]) noexcept;
    // True only if the box is certainly hidden from this frame's eye by the horizon. Only reads the horizon.
    bool is_hidden(const Box& box) const noexcept;

private:
    struct State;
    std::unique_ptr<State> state_;
};

// What a game draws of cell c, culled by the culler (when given) and the horizon: its PVS less the objects
// whose bounds, or every one of whose parts, either proves hidden (objects flagged always visible, and those
// without bounds, never). Where the bake kept the cell's tests (format 1.10, Bake::horizon_tests), the
// horizon tests only those objects; the culler tests every one (docs/ALGORITHMS.md#horizon-tests).
template <class F>
uint32_t for_each_drawn(const Bake& bake, uint32_t c, const OcclusionCuller* culler, const Horizon& horizon,
                        F&& visit) {
    uint32_t drawn = 0;
    const uint32_t *test = nullptr, *tests_end = nullptr;
    const bool testing = bake.horizon_tests(c, test, tests_end);
    bake.for_each_visible(c, [&](uint32_t o) {
        bool tested = true;
        if (testing) {  // the PVS and the tests ascend: one pass over each
            while (test != tests_end && *test < o) ++test;
            tested = test != tests_end && *test == o;
        }
        const bool culled = culled_by(bake, o, [&](const Box& b) {
            return (culler != nullptr && culler->is_hidden(b)) || (tested && horizon.is_hidden(b));
        });
        if (!culled) {
            visit(o);
            ++drawn;
        }
    });
    return drawn;
}

}  // namespace pvsbake
