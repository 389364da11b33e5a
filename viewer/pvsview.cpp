// SPDX-License-Identifier: MIT
// pvsbake viewer: pvsview on VTK. See pvsview.h. What is shown is decided in view_model.h (plain data);
// this file only turns it into VTK actors, handles keys and clicks, and writes screenshots.
#include "viewer/pvsview.h"

#include "core/context.h"
#include "core/error.h"
#include "driver/bake.h"
#include "io/atomic_file.h"
#include "io/bake_file.h"
#include "io/file_hash.h"
#include "io/gltf_loader.h"
#include "viewer/view_model.h"

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellPicker.h>
#include <vtkFloatArray.h>
#include <vtkInteractorStyleTrackballCamera.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPNGWriter.h>
#include <vtkPlane.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkSmartPointer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace pvs::viewer {

namespace {

constexpr double kViewAngleDeg = 30.0;  // VTK's default vertical view angle; project_to_pixel uses it too
constexpr size_t kOverlayNames = 12;    // object names listed in the overlay
constexpr double kCutAboveCellM = 1.0;  // the cut (key k) clips the world this far above the picked cell
constexpr Rgba kMissColor = {255, 30, 30, 255};  // a verification miss
// A miss through an opening narrower than the gap tolerance (outside the promise).
constexpr Rgba kNarrowMissColor = {255, 170, 0, 255};
constexpr size_t kMaxOutlineCells = 4000;  // more cells than this start as a slice (key x, --outlines)

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Options {
    std::string world_path;
    std::string bake_path;
    std::string screenshot_path;
    int32_t cell = -1;
    std::vector<float> at;  // 3 values when given
    std::string camera;
    std::string size = "1280x720";
    bool hide_others = false;
    bool no_cells = false;
    bool slice = false;
    bool outlines = false;
    bool occluders = false;
    bool view_volume = false;
    bool no_misses = false;
    bool help_overlay = false;
    bool no_text = false;
    bool cut = false;
    std::string keys;        // headless: keys pressed before the screenshot
    std::vector<int> click;  // headless: a click at (x, y) pixels from the top-left
    bool quiet = false;
};

void add_box_edges(vtkPoints* points, vtkCellArray* lines, const Aabb& b) {
    const vtkIdType base = points->GetNumberOfPoints();
    for (int i = 0; i < 8; ++i) {
        points->InsertNextPoint(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y,
                                i & 4 ? b.max.z : b.min.z);
    }
    static const int kEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                      {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    for (const auto& e : kEdges) {
        const vtkIdType ids[2] = {base + e[0], base + e[1]};
        lines->InsertNextCell(2, ids);
    }
}

void add_box_faces(vtkPoints* points, vtkCellArray* polys, const Aabb& b) {
    const vtkIdType base = points->GetNumberOfPoints();
    for (int i = 0; i < 8; ++i) {
        points->InsertNextPoint(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y,
                                i & 4 ? b.max.z : b.min.z);
    }
    static const int kFaces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : kFaces) {
        const vtkIdType ids[4] = {base + f[0], base + f[1], base + f[2], base + f[3]};
        polys->InsertNextCell(4, ids);
    }
}

vtkSmartPointer<vtkActor> make_actor(vtkPolyData* data) {
    vtkNew<vtkPolyDataMapper> mapper;
    mapper->SetInputData(data);
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    return actor;
}

void set_color(vtkActor* actor, Rgba c, double opacity) {
    actor->GetProperty()->SetColor(c[0] / 255.0, c[1] / 255.0, c[2] / 255.0);
    actor->GetProperty()->SetOpacity(opacity);
}

// An unlit, unpickable actor of lines in one colour, added to `renderer`.
vtkSmartPointer<vtkActor> make_line_actor(vtkPolyData* data, Rgba c, float width_px, vtkRenderer* renderer) {
    auto actor = make_actor(data);
    set_color(actor, c, 1.0);
    actor->GetProperty()->SetLineWidth(width_px);
    actor->GetProperty()->SetLighting(false);
    actor->PickableOff();
    renderer->AddActor(actor);
    return actor;
}

class Viewer;

// Trackball camera, plus our keys and click-to-pick (a click is a press and release within 3 pixels).
class PickStyle : public vtkInteractorStyleTrackballCamera {
public:
    static PickStyle* New();
    vtkTypeMacro(PickStyle, vtkInteractorStyleTrackballCamera);
    Viewer* viewer = nullptr;
    std::FILE* log = nullptr;  // where pick timings go (nullptr: nowhere)

    void OnLeftButtonDown() override {
        GetInteractor()->GetEventPosition(press_);
        vtkInteractorStyleTrackballCamera::OnLeftButtonDown();
    }
    void OnLeftButtonUp() override;
    void OnKeyPress() override;
    void OnChar() override;

private:
    int press_[2] = {0, 0};
};
vtkStandardNewMacro(PickStyle);

class Viewer {
public:
    Viewer(Options options, World world, BakeData bake)
        : options_(std::move(options)), world_(std::move(world)), bake_(std::move(bake)) {
        gap_tolerance_ = gap_tolerance_of(bake_);
        hide_others_ = options_.hide_others;
        show_cells_ = !options_.no_cells;
        // Outlines of tens of thousands of cells are a fog: big bakes start with the slice.
        slice_ = options_.slice || (!options_.outlines && bake_.cells.size() > kMaxOutlineCells);
        show_occluders_ = options_.occluders;
        show_view_volume_ = options_.view_volume;
        show_misses_ = !options_.no_misses;
        show_help_ = options_.help_overlay;
        show_text_ = !options_.no_text;
        cut_ = options_.cut;
        pvs_counts_ = cell_pvs_counts(bake_);
        build();
    }

    vtkRenderWindow* window() { return window_; }
    int32_t cell() const { return cell_; }

    void set_size(int w, int h) { window_->SetSize(w, h); }

    void set_cell(int32_t cell) {
        cell_ = cell >= 0 && size_t(cell) < bake_.cells.size() ? cell : -1;
        update_world();
        update_picked();
        update_misses();
        update_cut();
        update_cells();
        update_text();
    }
    void step_cell(int delta) {
        const int32_t n = int32_t(bake_.cells.size());
        if (n == 0) return;
        const int32_t from = cell_ < 0 ? (delta > 0 ? -1 : 0) : cell_;
        set_cell(((from + delta) % n + n) % n);
    }

    void reset_camera() {
        int* sz = window_->GetSize();
        const double aspect = sz[1] > 0 ? double(sz[0]) / double(sz[1]) : 1.0;
        if (cell_ >= 0) {
            set_camera(camera_for_box(focus_box(bake_, world_, cell_), kViewAngleDeg, aspect, 55.0));
        } else {
            set_camera(camera_for_points(world_.positions, kViewAngleDeg, aspect, 35.0));
        }
    }
    void set_camera(const CameraPose& p) {
        vtkCamera* cam = renderer_->GetActiveCamera();
        cam->SetViewAngle(kViewAngleDeg);
        cam->SetPosition(p.eye.x, p.eye.y, p.eye.z);
        cam->SetFocalPoint(p.target.x, p.target.y, p.target.z);
        cam->SetViewUp(p.up.x, p.up.y, p.up.z);
        cam->OrthogonalizeViewUp();
        renderer_->ResetCameraClippingRange();
    }

    void toggle(char key) {
        switch (key) {
            case 'c':
                show_cells_ = !show_cells_;
                break;
            case 'x':
                slice_ = !slice_;
                break;
            case 'o':
                show_occluders_ = !show_occluders_;
                break;
            case 'v':
                show_view_volume_ = !show_view_volume_;
                break;
            case 'm':
                show_misses_ = !show_misses_;
                break;
            case 'f':
                hide_others_ = !hide_others_;
                update_world();
                break;
            case 'h':
                show_help_ = !show_help_;
                break;
            case 't':
                show_text_ = !show_text_;
                break;
            case 'k':
                cut_ = !cut_;
                update_cut();
                break;
            default:
                return;
        }
        update_visibility();
        update_cells();
    }

    // The cell under display position (x, y), or -1 when the click meets no world surface.
    int32_t cell_at_display(int x, int y) {
        vtkNew<vtkCellPicker> picker;
        picker->SetTolerance(0.0005);
        picker->PickFromListOn();
        picker->AddPickList(world_opaque_);
        picker->AddPickList(world_translucent_);
        if (!picker->Pick(x, y, 0.0, renderer_)) return -1;
        double pos[3], eye[3];
        picker->GetPickPosition(pos);
        renderer_->GetActiveCamera()->GetPosition(eye);
        const glm::vec3 point{float(pos[0]), float(pos[1]), float(pos[2])};
        const glm::vec3 toward(float(eye[0] - pos[0]), float(eye[1] - pos[1]), float(eye[2] - pos[2]));
        return cell_for_surface_point(bake_.cells, point, toward, 0.25f, 12);
    }

    void render() { window_->Render(); }

    void write_png(const std::string& path) {
        window_->Render();
        vtkNew<vtkWindowToImageFilter> grab;
        grab->SetInput(window_);
        grab->SetInputBufferTypeToRGB();
        grab->ReadFrontBufferOff();
        grab->Update();
        AtomicOutput out(path, "the screenshot");
        vtkNew<vtkPNGWriter> writer;
        writer->SetInputConnection(grab->GetOutputPort());
        writer->SetFileName(out.temp_path().c_str());
        writer->Write();
        if (writer->GetErrorCode() != 0) throw io_error(path + ": cannot write the screenshot (VTK's PNG writer failed)");
        out.commit();
    }

private:
    void build() {
        renderer_->SetBackground(kBackground[0] / 255.0, kBackground[1] / 255.0, kBackground[2] / 255.0);
        renderer_->SetTwoSidedLighting(true);
        window_->SetNumberOfLayers(2);
        window_->AddRenderer(renderer_);
        // Layer 1, same camera: the picked cell's bounds, misses and the leak path are drawn over the world,
        // never hidden by it.
        top_->SetLayer(1);
        top_->SetActiveCamera(renderer_->GetActiveCamera());
        top_->InteractiveOff();
        window_->AddRenderer(top_);
        window_->SetWindowName("pvsview");
        window_->SetMultiSamples(0);

        // The world: one point set, two triangle sets (opaque, translucent) rebuilt when states change.
        world_points_->SetDataTypeToFloat();
        world_points_->SetNumberOfPoints(vtkIdType(world_.positions.size()));
        for (size_t i = 0; i < world_.positions.size(); ++i) {
            const glm::vec3& p = world_.positions[i];
            world_points_->SetPoint(vtkIdType(i), p.x, p.y, p.z);
        }
        for (vtkPolyData* d : {world_opaque_data_.Get(), world_translucent_data_.Get()})
            d->SetPoints(world_points_);
        world_opaque_ = make_actor(world_opaque_data_);
        world_translucent_ = make_actor(world_translucent_data_);
        for (vtkActor* a : {world_opaque_.Get(), world_translucent_.Get()}) {
            auto* m = vtkPolyDataMapper::SafeDownCast(a->GetMapper());
            m->SetScalarModeToUseCellData();
            m->SetColorModeToDirectScalars();
            a->GetProperty()->SetAmbient(0.15);
            a->GetProperty()->SetDiffuse(0.85);
            renderer_->AddActor(a);
        }
        world_translucent_->GetProperty()->SetOpacity(0.999);  // drawn in the translucent pass

        // Heat map of PVS sizes, shared by the outlines, the slice and the legend.
        uint32_t lo = 0, hi = 1;
        if (!pvs_counts_.empty()) {
            lo = *std::min_element(pvs_counts_.begin(), pvs_counts_.end());
            hi = std::max(lo + 1, *std::max_element(pvs_counts_.begin(), pvs_counts_.end()));
        }
        lut_->SetNumberOfTableValues(256);
        for (int i = 0; i < 256; ++i) {
            const Rgba c = heat_color(i / 255.0);
            lut_->SetTableValue(i, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, 1.0);
        }
        lut_->SetTableRange(lo, hi);
        scalar_bar_->SetLookupTable(lut_);
        scalar_bar_->SetTitle("PVS size (objects)");
        scalar_bar_->SetNumberOfLabels(5);
        scalar_bar_->SetLabelFormat("%.0f");
        scalar_bar_->SetPosition(0.90, 0.08);
        scalar_bar_->SetWidth(0.08);
        scalar_bar_->SetHeight(0.55);
        scalar_bar_->UnconstrainedFontSizeOn();
        scalar_bar_->GetTitleTextProperty()->SetFontSize(13);
        scalar_bar_->GetLabelTextProperty()->SetFontSize(12);
        renderer_->AddActor2D(scalar_bar_);

        build_cell_outlines();
        cells_actor_ = make_actor(cells_data_);
        slice_actor_ = make_actor(slice_data_);
        for (vtkActor* a : {cells_actor_.Get(), slice_actor_.Get()}) {
            auto* m = vtkPolyDataMapper::SafeDownCast(a->GetMapper());
            m->SetLookupTable(lut_);
            m->SetScalarModeToUseCellData();
            m->UseLookupTableScalarRangeOn();
            a->GetProperty()->SetLighting(false);
            a->PickableOff();
            renderer_->AddActor(a);
        }
        slice_actor_->GetProperty()->SetOpacity(0.55);

        // The picked cell's bounds, and its ranked occluders (cyan; format 1.2 bakes).
        picked_actor_ = make_line_actor(picked_data_, {255, 240, 60, 255}, 3.0f, top_);
        ranked_actor_ = make_line_actor(ranked_data_, {40, 230, 255, 255}, 2.5f, top_);

        build_occluders();
        build_misses();

        overlay_->GetTextProperty()->SetFontFamilyToCourier();
        overlay_->GetTextProperty()->SetFontSize(14);
        overlay_->GetTextProperty()->SetColor(0.95, 0.95, 0.95);
        overlay_->GetTextProperty()->SetVerticalJustificationToTop();
        overlay_->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
        overlay_->GetPositionCoordinate()->SetValue(0.01, 0.98);
        renderer_->AddActor2D(overlay_);
        help_->SetInput(help_text().c_str());
        help_->GetTextProperty()->SetFontFamilyToCourier();
        help_->GetTextProperty()->SetFontSize(14);
        help_->GetTextProperty()->SetColor(1.0, 1.0, 0.7);
        help_->GetTextProperty()->SetBackgroundColor(0.0, 0.0, 0.0);
        help_->GetTextProperty()->SetBackgroundOpacity(0.6);
        help_->GetTextProperty()->SetVerticalJustificationToBottom();
        help_->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
        help_->GetPositionCoordinate()->SetValue(0.01, 0.02);
        renderer_->AddActor2D(help_);

        update_visibility();
    }

    void build_cell_outlines() {
        vtkNew<vtkPoints> points;
        vtkNew<vtkCellArray> lines;
        vtkNew<vtkFloatArray> sizes;
        sizes->SetName("pvs_size");
        for (size_t c = 0; c < bake_.cells.size(); ++c) {
            add_box_edges(points, lines, bake_.cells.cells[c].bounds);
            const float v = c < pvs_counts_.size() ? float(pvs_counts_[c]) : 0.0f;
            for (int e = 0; e < 12; ++e) sizes->InsertNextValue(v);
        }
        cells_data_->SetPoints(points);
        cells_data_->SetLines(lines);
        cells_data_->GetCellData()->SetScalars(sizes);
    }

    // Cells meeting the horizontal plane at the picked cell's centre (or the middle of the cells), as
    // quads at that height.
    void build_slice() {
        float y = 0.0f;
        if (cell_ >= 0) {
            y = bake_.cells.cells[size_t(cell_)].bounds.center().y;
        } else {
            Aabb all;
            for (const Cell& c : bake_.cells.cells) all.extend(c.bounds);
            y = all.is_empty() ? 0.0f : all.center().y;
        }
        vtkNew<vtkPoints> points;
        vtkNew<vtkCellArray> polys;
        vtkNew<vtkFloatArray> sizes;
        for (size_t c = 0; c < bake_.cells.size(); ++c) {
            const Aabb& b = bake_.cells.cells[c].bounds;
            if (y < b.min.y || y >= b.max.y) continue;
            const vtkIdType base = points->GetNumberOfPoints();
            points->InsertNextPoint(b.min.x, y, b.min.z);
            points->InsertNextPoint(b.max.x, y, b.min.z);
            points->InsertNextPoint(b.max.x, y, b.max.z);
            points->InsertNextPoint(b.min.x, y, b.max.z);
            const vtkIdType ids[4] = {base, base + 1, base + 2, base + 3};
            polys->InsertNextCell(4, ids);
            sizes->InsertNextValue(c < pvs_counts_.size() ? float(pvs_counts_[c]) : 0.0f);
        }
        slice_data_->SetPoints(points);
        slice_data_->SetPolys(polys);
        slice_data_->GetCellData()->SetScalars(sizes);
        slice_data_->Modified();
    }

    void build_occluders() {
        vtkNew<vtkPoints> points;
        vtkNew<vtkCellArray> polys;
        vtkNew<vtkUnsignedCharArray> colors;
        colors->SetNumberOfComponents(4);
        for (const Occluder& o : bake_.occluders) {
            add_box_faces(points, polys, o.box);
            const uint8_t proven[4] = {255, 150, 40, 50}, unproven[4] = {170, 90, 220, 50};
            for (int f = 0; f < 6; ++f) colors->InsertNextTypedTuple(o.proven ? proven : unproven);
        }
        occluders_data_->SetPoints(points);
        occluders_data_->SetPolys(polys);
        occluders_data_->GetCellData()->SetScalars(colors);
        occluders_actor_ = make_actor(occluders_data_);
        auto* m = vtkPolyDataMapper::SafeDownCast(occluders_actor_->GetMapper());
        m->SetScalarModeToUseCellData();
        m->SetColorModeToDirectScalars();
        occluders_actor_->GetProperty()->SetOpacity(0.999);
        occluders_actor_->GetProperty()->EdgeVisibilityOn();
        occluders_actor_->GetProperty()->SetEdgeColor(1.0, 0.6, 0.2);
        occluders_actor_->PickableOff();
        renderer_->AddActor(occluders_actor_);
    }

    void build_misses() {
        misses_actor_ = make_line_actor(misses_data_, kMissColor, 2.0f, top_);
        misses_actor_->GetProperty()->SetPointSize(6.0f);  // the eye points
        update_misses();

        vtkNew<vtkPoints> lp;
        vtkNew<vtkCellArray> line;
        if (bake_.leak_path.size() >= 2) {
            std::vector<vtkIdType> ids;
            for (const glm::vec3& p : bake_.leak_path) ids.push_back(lp->InsertNextPoint(p.x, p.y, p.z));
            line->InsertNextCell(vtkIdType(ids.size()), ids.data());
        }
        leak_data_->SetPoints(lp);
        leak_data_->SetLines(line);
        leak_actor_ = make_line_actor(leak_data_, {255, 0, 255, 255}, 4.0f, top_);
    }

    // Built on first use: a big level's view volume has many faces.
    void build_view_volume() {
        if (view_volume_actor_) return;
        const VoxelMask& mask = bake_.cells.view.empty() ? bake_.cells.eyes : bake_.cells.view;
        const std::vector<glm::vec3> quads = voxel_mask_surface(mask);
        vtkNew<vtkPoints> points;
        vtkNew<vtkCellArray> polys;
        points->SetDataTypeToFloat();
        for (size_t q = 0; q + 3 < quads.size(); q += 4) {
            vtkIdType ids[4];
            for (int k = 0; k < 4; ++k)
                ids[k] = points->InsertNextPoint(quads[q + k].x, quads[q + k].y, quads[q + k].z);
            polys->InsertNextCell(4, ids);
        }
        vtkNew<vtkPolyData> data;
        data->SetPoints(points);
        data->SetPolys(polys);
        view_volume_actor_ = make_actor(data);
        set_color(view_volume_actor_, {80, 230, 120, 255}, 0.18);
        view_volume_actor_->PickableOff();
        renderer_->AddActor(view_volume_actor_);
    }

    void update_world() {
        const std::vector<Rgba> colors = triangle_colors(world_, object_states(bake_, cell_, hide_others_));
        vtkNew<vtkCellArray> opaque, translucent;
        vtkNew<vtkUnsignedCharArray> opaque_colors, translucent_colors;
        opaque_colors->SetNumberOfComponents(4);
        translucent_colors->SetNumberOfComponents(4);
        for (size_t t = 0; t < world_.triangles.size(); ++t) {
            const Rgba& c = colors[t];
            if (c[3] == 0) continue;
            const vtkIdType ids[3] = {vtkIdType(world_.triangles[t].v[0]),
                                      vtkIdType(world_.triangles[t].v[1]),
                                      vtkIdType(world_.triangles[t].v[2])};
            const bool is_opaque = c[3] == 255;
            (is_opaque ? opaque : translucent)->InsertNextCell(3, ids);
            (is_opaque ? opaque_colors : translucent_colors)->InsertNextTypedTuple(c.data());
        }
        world_opaque_data_->SetPolys(opaque);
        world_opaque_data_->GetCellData()->SetScalars(opaque_colors);
        world_opaque_data_->Modified();
        world_translucent_data_->SetPolys(translucent);
        world_translucent_data_->GetCellData()->SetScalars(translucent_colors);
        world_translucent_data_->Modified();
    }

    // Every miss with no cell picked, else the picked cell's: the rays that prove what its PVS left out.
    // Misses through openings narrower than the bake's gap tolerance (outside its promise) are amber, the
    // others red (kMissColor, kNarrowMissColor).
    void update_misses() {
        vtkNew<vtkPoints> points;
        vtkNew<vtkCellArray> lines, verts;
        std::vector<Rgba> colors;
        for (const Miss& m : bake_.verification.misses) {
            if (cell_ >= 0 && m.cell != uint32_t(cell_)) continue;
            const glm::vec3 end = m.eye + m.direction * m.distance_m;
            const vtkIdType a = points->InsertNextPoint(m.eye.x, m.eye.y, m.eye.z);
            const vtkIdType b = points->InsertNextPoint(end.x, end.y, end.z);
            const vtkIdType ids[2] = {a, b};
            lines->InsertNextCell(2, ids);
            verts->InsertNextCell(1, &a);
            colors.push_back(is_narrow_miss(m, gap_tolerance_) ? kNarrowMissColor : kMissColor);
        }
        // Cell data runs over the vertices first, then the lines.
        vtkNew<vtkUnsignedCharArray> cell_colors;
        cell_colors->SetNumberOfComponents(4);
        for (int pass = 0; pass < 2; ++pass)
            for (const Rgba& c : colors) cell_colors->InsertNextTypedTuple(c.data());
        misses_data_->SetPoints(points);
        misses_data_->SetLines(lines);
        misses_data_->SetVerts(verts);
        misses_data_->GetCellData()->SetScalars(cell_colors);
        misses_data_->Modified();
    }

    // The cut: with a cell picked, the world above its top (plus kCutAboveCellM) is clipped away, so
    // ceilings do not hide the room from a camera above.
    void update_cut() {
        for (vtkActor* a : {world_opaque_.Get(), world_translucent_.Get()}) {
            a->GetMapper()->RemoveAllClippingPlanes();
            if (!cut_ || cell_ < 0) continue;
            vtkNew<vtkPlane> plane;
            plane->SetOrigin(0.0, bake_.cells.cells[size_t(cell_)].bounds.max.y + kCutAboveCellM, 0.0);
            plane->SetNormal(0.0, -1.0, 0.0);
            a->GetMapper()->AddClippingPlane(plane);
        }
    }

    void update_picked() {
        vtkNew<vtkPoints> points;
        vtkNew<vtkCellArray> lines;
        if (cell_ >= 0) add_box_edges(points, lines, bake_.cells.cells[size_t(cell_)].bounds);
        picked_data_->SetPoints(points);
        picked_data_->SetLines(lines);
        picked_data_->Modified();
        vtkNew<vtkPoints> ranked_points;
        vtkNew<vtkCellArray> ranked_lines;
        for (const Aabb& b : ranked_occluder_boxes(bake_, cell_))
            add_box_edges(ranked_points, ranked_lines, b);
        ranked_data_->SetPoints(ranked_points);
        ranked_data_->SetLines(ranked_lines);
        ranked_data_->Modified();
    }

    void update_cells() {
        if (slice_ && show_cells_) build_slice();
        // With a cell picked, the other outlines step back.
        cells_actor_->GetProperty()->SetOpacity(cell_ >= 0 ? 0.12 : 0.8);
        misses_actor_->GetProperty()->SetLineWidth(cell_ >= 0 ? 2.0f : 1.0f);
    }

    void update_text() {
        if (cell_ >= 0) {
            overlay_->SetInput(cell_overlay_text(bake_, cell_figures(bake_, cell_), kOverlayNames).c_str());
        } else {
            overlay_->SetInput(bake_overlay_text(bake_, options_.world_path).c_str());
        }
    }

    void update_visibility() {
        cells_actor_->SetVisibility(show_cells_ && !slice_);
        slice_actor_->SetVisibility(show_cells_ && slice_);
        scalar_bar_->SetVisibility(show_cells_);
        occluders_actor_->SetVisibility(show_occluders_ && !bake_.occluders.empty());
        misses_actor_->SetVisibility(show_misses_ && !bake_.verification.misses.empty());
        leak_actor_->SetVisibility(show_misses_ && bake_.leak_path.size() >= 2);
        if (show_view_volume_) build_view_volume();
        if (view_volume_actor_) view_volume_actor_->SetVisibility(show_view_volume_);
        help_->SetVisibility(show_help_);
        overlay_->SetVisibility(show_text_);
    }

    Options options_;
    World world_;
    BakeData bake_;
    double gap_tolerance_ = kDefaultGapToleranceM;  // the bake's: which misses are narrow
    std::vector<uint32_t> pvs_counts_;
    int32_t cell_ = -1;
    bool hide_others_ = false, show_cells_ = true, slice_ = false, show_occluders_ = false;
    bool show_view_volume_ = false, show_misses_ = true, show_help_ = false, show_text_ = true, cut_ = false;

    vtkNew<vtkRenderer> renderer_;
    vtkNew<vtkRenderer> top_;
    vtkNew<vtkRenderWindow> window_;
    vtkNew<vtkPoints> world_points_;
    vtkNew<vtkPolyData> ranked_data_;
    vtkSmartPointer<vtkActor> ranked_actor_;
    vtkNew<vtkPolyData> world_opaque_data_, world_translucent_data_, cells_data_, slice_data_, picked_data_,
        occluders_data_, misses_data_, leak_data_;
    vtkSmartPointer<vtkActor> world_opaque_, world_translucent_, cells_actor_, slice_actor_, picked_actor_,
        occluders_actor_, misses_actor_, leak_actor_, view_volume_actor_;
    vtkNew<vtkLookupTable> lut_;
    vtkNew<vtkScalarBarActor> scalar_bar_;
    vtkNew<vtkTextActor> overlay_, help_;
};

void PickStyle::OnLeftButtonUp() {
    vtkInteractorStyleTrackballCamera::OnLeftButtonUp();
    int* pos = GetInteractor()->GetEventPosition();
    if (std::abs(pos[0] - press_[0]) > 3 || std::abs(pos[1] - press_[1]) > 3 || viewer == nullptr) return;
    const auto t0 = std::chrono::steady_clock::now();
    const int32_t cell = viewer->cell_at_display(pos[0], pos[1]);
    if (cell < 0) return;
    viewer->set_cell(cell);
    viewer->render();
    if (log != nullptr)
        std::fprintf(log, "pvsview: picked cell %d in %.1f ms\n", cell, 1000.0 * seconds_since(t0));
}

void PickStyle::OnKeyPress() {
    const std::string key = GetInteractor()->GetKeySym() ? GetInteractor()->GetKeySym() : "";
    int delta = 0;
    if (key == "Right") delta = 1;
    if (key == "Left") delta = -1;
    if (key == "Up") delta = 10;
    if (key == "Down") delta = -10;
    if (key == "Prior") delta = 100;
    if (key == "Next") delta = -100;
    if (delta != 0 && viewer != nullptr) {
        viewer->step_cell(delta);
        viewer->render();
        return;
    }
    if (key == "Escape" && viewer != nullptr) {
        viewer->set_cell(-1);
        viewer->render();
        return;
    }
    vtkInteractorStyleTrackballCamera::OnKeyPress();
}

void PickStyle::OnChar() {
    const char key = GetInteractor()->GetKeyCode();
    if (viewer == nullptr) return;
    switch (key) {
        case 'c':
        case 'x':
        case 'o':
        case 'v':
        case 'm':
        case 'f':
        case 'h':
        case 't':
        case 'k':
            viewer->toggle(key);
            viewer->render();
            return;
        case 'r':
            viewer->reset_camera();
            viewer->render();
            return;
        case 'q':
        case 'e':
            vtkInteractorStyleTrackballCamera::OnChar();
            return;  // quit
        default:
            return;  // VTK's other keys (wireframe, stereo, fly-to) would fight ours
    }
}

// Headless: press opt.keys (keysyms separated by commas: Right, Prior, c, f ...) in order, then click at
// opt.click, through the same interactor style as a window: the tests and bug reports drive the
// interactive code this way.
void replay_input(Viewer& viewer, const Options& opt, std::FILE* log) {
    vtkNew<vtkRenderWindowInteractor> interactor;
    vtkNew<PickStyle> style;
    style->viewer = &viewer;
    style->log = log;
    interactor->SetRenderWindow(viewer.window());
    interactor->SetInteractorStyle(style);
    viewer.render();
    std::string keys = opt.keys;
    size_t start = 0;
    while (start <= keys.size()) {
        const size_t end = std::min(keys.find(',', start), keys.size());
        const std::string sym = keys.substr(start, end - start);
        start = end + 1;
        if (sym.empty()) continue;
        const char code = sym.size() == 1 ? sym[0] : '\0';
        interactor->SetKeyEventInformation(0, 0, code, 1, sym.c_str());
        style->OnKeyPress();
        if (code != 'q' && code != 'e') style->OnChar();
    }
    if (opt.click.size() == 2) {
        int* size = viewer.window()->GetSize();
        interactor->SetEventInformation(opt.click[0], size[1] - 1 - opt.click[1]);
        style->OnLeftButtonDown();
        style->OnLeftButtonUp();
    }
}

int run(const Options& opt, std::FILE* err) {
    const auto t0 = std::chrono::steady_clock::now();
    Context ctx(Context::Options{opt.quiet ? LogLevel::kWarning : LogLevel::kInfo, opt.quiet, err});
    World world = load_world(ctx, opt.world_path);
    BakeData bake = read_bake_file(opt.bake_path);
    check_bake_matches_world(ctx, bake, world, hash_file_hex(opt.world_path));

    int32_t cell = opt.cell;
    if (cell >= 0 && size_t(cell) >= bake.cells.size()) {
        throw bad_input(fmt::format("--cell {}: the bake {} has {} cells (0 to {})", cell, opt.bake_path,
                                    bake.cells.size(), int64_t(bake.cells.size()) - 1));
    }
    if (opt.at.size() == 3) {
        const glm::vec3 p(opt.at[0], opt.at[1], opt.at[2]);
        cell = bake.cells.find(p);
        if (cell < 0) {
            throw bad_input(
                fmt::format("--at {} {} {}: no cell of {} holds that point (outside the view volume)", p.x,
                            p.y, p.z, opt.bake_path));
        }
    }
    std::optional<CameraPose> camera;
    if (!opt.camera.empty()) {
        camera = parse_camera(opt.camera);
        if (!camera) {
            throw bad_input("--camera '" + opt.camera +
                            "': expected nine numbers eye,target,up (ex,ey,ez,tx,ty,tz,ux,uy,uz) with the "
                            "view direction not along up");
        }
    }
    const auto size = parse_size(opt.size);
    if (!size)
        throw bad_input("--size '" + opt.size + "': expected WIDTHxHEIGHT, each 16 to 8192 (1280x720)");
    const double load_s = seconds_since(t0);

    const bool headless = !opt.screenshot_path.empty();
    Viewer viewer(opt, std::move(world), std::move(bake));
    if (headless) viewer.window()->SetOffScreenRendering(1);
    viewer.set_size((*size)[0], (*size)[1]);
    viewer.set_cell(cell);
    if (camera) {
        viewer.set_camera(*camera);
    } else {
        viewer.reset_camera();
    }
    if (headless) {
        if (!opt.keys.empty() || !opt.click.empty()) replay_input(viewer, opt, opt.quiet ? nullptr : err);
        viewer.write_png(opt.screenshot_path);
        if (!opt.quiet) {
            std::fprintf(err, "pvsview: wrote %s (%dx%d, cell %d); loaded in %.2f s, total %.2f s\n",
                         opt.screenshot_path.c_str(), (*size)[0], (*size)[1], viewer.cell(), load_s,
                         seconds_since(t0));
        }
        return 0;
    }
    vtkNew<vtkRenderWindowInteractor> interactor;
    vtkNew<PickStyle> style;
    style->viewer = &viewer;
    style->log = opt.quiet ? nullptr : err;
    interactor->SetInteractorStyle(style);
    interactor->SetRenderWindow(viewer.window());
    interactor->Initialize();
    viewer.render();
    if (!opt.quiet) std::fprintf(err, "pvsview: ready in %.2f s (h: help)\n", seconds_since(t0));
    interactor->Start();
    return 0;
}

}  // namespace

int run_pvsview(int argc, char** argv, std::FILE* err) {
    Options opt;
    CLI::App app{
        "pvsview: look at a bake: cells coloured by PVS size, a cell's PVS, occluders, misses, leaks.\n"
        "Interactive (h: keys), or headless with --screenshot (run under xvfb-run without a display)."};
    app.add_option("world", opt.world_path, "the world the bake was made from (.glb or .gltf)")->required();
    app.add_option("bake", opt.bake_path, "the bake file (.h5)")->required();
    auto* shot_opt = app.add_option("--screenshot", opt.screenshot_path,
                                    "render one PNG to this path, no window, and exit");
    auto* cell_opt = app.add_option("--cell", opt.cell, "pick this cell (index into the bake's cells)")
                         ->check(CLI::Range(0, 2147483647));
    app.add_option("--at", opt.at, "pick the cell holding this point (X Y Z, metres)")
        ->expected(3)
        ->excludes(cell_opt);
    app.add_option(
        "--camera", opt.camera,
        "eye,target,up as nine numbers (default: the whole world, or the picked cell and its PVS)");
    app.add_option("--size", opt.size, "image or window size WIDTHxHEIGHT in pixels")->capture_default_str();
    app.add_flag("--hide", opt.hide_others, "hide the objects the picked cell does not see (default: faded)");
    app.add_flag("--no-cells", opt.no_cells, "do not draw the cells");
    auto* slice_opt = app.add_flag("--slice", opt.slice,
                                   "draw the cells as a slice at the picked cell's height, not outlines");
    app.add_flag("--outlines", opt.outlines, "draw the cells as outlines even when there are more than 4000")
        ->excludes(slice_opt);
    app.add_flag("--occluders", opt.occluders, "draw the occluder boxes (orange: proven)");
    app.add_flag("--view-volume", opt.view_volume, "draw the view volume's surface");
    app.add_flag("--no-misses", opt.no_misses, "do not draw verification misses and the leak path");
    app.add_flag("--help-overlay", opt.help_overlay, "show the keys overlay");
    app.add_flag("--no-text", opt.no_text, "no figures overlay");
    app.add_flag("--cut", opt.cut, "clip the world 1 m above the picked cell (ceilings out of the way)");
    app.add_flag("--quiet", opt.quiet, "no timing line, warnings only");
    app.add_option("--keys", opt.keys,
                   "with --screenshot: press these keys first (comma-separated: Right,f,c)")
        ->needs(shot_opt);
    app.add_option("--click", opt.click, "with --screenshot: then click at X Y (pixels from the top-left)")
        ->expected(2)
        ->needs(shot_opt);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp&) {
        std::fputs(app.help().c_str(), stdout);
        return 0;
    } catch (const CLI::ParseError& e) {
        std::fprintf(err, "pvsview: %s (pvsview --help lists the options)\n", e.what());
        return 2;
    }
    try {
        return run(opt, err);
    } catch (const Error& e) {
        std::fprintf(err, "pvsview: %s\n", e.what());
        return exit_status(e.kind());
    } catch (const std::exception& e) {
        std::fprintf(err, "pvsview: %s\n", e.what());
        return 1;
    }
}

}  // namespace pvs::viewer
