// SPDX-License-Identifier: MIT
// pvsbake viewer: what pvsview shows, as plain data (no VTK here, so it is tested without a window).
//
// Conventions: glTF axes (right-handed, +Y up), metres, world space. Colours are 8-bit RGBA, alpha 255
// opaque. A cell index is an index into BakeData::cells.cells (-1: none picked). Objects are the World's
// objects in order, which are the bake's objects in order (pvs::check_bake_matches_world).
// Nothing here decides visibility: the viewer only shows what the bake file says.
#pragma once

#include "core/cell_set.h"
#include "core/math.h"
#include "core/world.h"
#include "io/bake_file.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace pvs::viewer {

using Rgba = std::array<uint8_t, 4>;

constexpr Rgba kBackground{26, 28, 34, 255};        // the clear colour of every view
constexpr Rgba kNeutralOpaque{190, 190, 185, 255};  // the world with no cell picked
constexpr Rgba kNeutralSeeThrough{120, 170, 230, 90};
constexpr Rgba kFadedOpaque{150, 150, 150, 40};  // an object the picked cell does not see, faded
constexpr Rgba kFadedSeeThrough{150, 150, 150, 25};
constexpr uint8_t kVisibleSeeThroughAlpha = 110;  // a see-through object the picked cell sees

// How an object is drawn.
enum class ObjectState : uint8_t {
    kNeutral = 0,  // no cell picked: shaded grey (see-through: translucent blue)
    kVisible = 1,  // in the picked cell's PVS: its own colour (object_color)
    kFaded = 2,    // not in the PVS, drawn faded
    kHidden = 3,   // not in the PVS, not drawn
};

// A distinct, saturated colour for object `object` (golden-ratio hues; never grey, never red, which
// marks misses). Deterministic: tests look for it at a pixel.
Rgba object_color(uint32_t object);

// Heat map for t in [0, 1]: dark blue (small PVS) through green and yellow to red (large PVS).
Rgba heat_color(double t);

// The state of every object for `cell` (-1: all kNeutral). hide_others: kHidden instead of kFaded.
std::vector<ObjectState> object_states(const BakeData& bake, int32_t cell, bool hide_others);

// The colour of every triangle of the world, from the states of their objects. A see-through triangle
// (triangle_opaque == 0) is translucent; a hidden object's triangles have alpha 0 (not drawn).
std::vector<Rgba> triangle_colors(const World& world, const std::vector<ObjectState>& states);

// PVS size (objects listed) of every cell.
std::vector<uint32_t> cell_pvs_counts(const BakeData& bake);

// The figures of one cell, for the overlay.
struct CellFigures {
    int32_t cell = -1;
    Aabb bounds;
    uint32_t objects_visible = 0;  // in the PVS
    uint32_t objects_total = 0;
    uint64_t triangles_visible = 0;  // of the objects in the PVS
    uint64_t triangles_total = 0;
    int64_t sampled_visible = -1;  // objects verification rays saw from the cell; -1: no verification
    double overestimation = -1.0;  // objects_visible / sampled_visible (as verify reports it); -1: unknown
    uint32_t misses = 0;           // verification misses recorded for this cell
    std::vector<uint32_t> listed;  // the PVS objects, ascending
    std::vector<RankedOccluder> ranked;  // the cell's ranked occluders, best first (format 1.2; else none)
};
CellFigures cell_figures(const BakeData& bake, int32_t cell);

// The overlay text: the cell, its bounds, counts, sampled set, overestimation, misses, and the first
// `max_names` object names (with their triangle counts).
std::string cell_overlay_text(const BakeData& bake, const CellFigures& figures, size_t max_names);

// The boxes of a cell's ranked occluders, best first (none for a cell out of range or an older bake).
std::vector<Aabb> ranked_occluder_boxes(const BakeData& bake, int32_t cell);

// The overlay of the whole bake (no cell picked): world, mode, cells, PVS sizes, misses, leak.
std::string bake_overlay_text(const BakeData& bake, const std::string& world_path);

// The help overlay: every key.
std::string help_text();

// The cell to pick for a point on a surface (from a click): the cell holding the point, else the first
// cell found stepping back toward the eye by `step_m` up to `max_steps` times (surfaces are the view
// volume's walls, so the point itself is often just outside it), else the cell whose bounds are nearest.
// -1 when the bake has no cells.
int32_t cell_for_surface_point(const CellSet& cells, glm::vec3 point, glm::vec3 toward_eye, float step_m,
                               int max_steps);

// A camera: eye, target (focal point), up.
struct CameraPose {
    glm::vec3 eye{0.0f};
    glm::vec3 target{0.0f};
    glm::vec3 up{0.0f, 1.0f, 0.0f};
};

// Parses "ex,ey,ez,tx,ty,tz,ux,uy,uz" (commas or spaces). nullopt when it is not nine finite numbers or
// the view direction is zero or parallel to up.
std::optional<CameraPose> parse_camera(const std::string& text);

// Parses "WxH" (each 16 to 8192). nullopt when malformed.
std::optional<std::array<int, 2>> parse_size(const std::string& text);

// The default camera looking at `box` from above (elevation_deg above the horizon, azimuth 30 degrees
// from +Z), as near as it can be with every corner of the box in view (vertical view angle
// view_angle_deg, aspect = width / height), plus a 5% margin.
CameraPose camera_for_box(const Aabb& box, double view_angle_deg, double aspect, double elevation_deg);
// The same for a set of points (a world's vertices): every point in view, looking at their bounds' centre.
CameraPose camera_for_points(const std::vector<glm::vec3>& points, double view_angle_deg, double aspect,
                             double elevation_deg);

// The box the default camera of a picked cell frames: the cell and the bounds of its PVS objects,
// clipped to the world bounds grown by the cell (a skybox in every PVS does not zoom out the view).
Aabb focus_box(const BakeData& bake, const World& world, int32_t cell);

// Where a world point lands in an image of width x height pixels seen by a perspective camera of vertical
// view angle view_angle_deg (VTK's camera model: pixel (0, 0) is the top-left). nullopt when behind the
// eye. Tests use it to find an object's pixel.
std::optional<glm::vec2> project_to_pixel(const CameraPose& camera, double view_angle_deg, int width,
                                          int height, glm::vec3 point);

// The boundary of a voxel mask as quads (4 corners each, outward): faces between a set voxel and an unset
// (or outside) one. The view volume's surface.
std::vector<glm::vec3> voxel_mask_surface(const VoxelMask& mask);

}  // namespace pvs::viewer
