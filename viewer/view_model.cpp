// SPDX-License-Identifier: MIT
// pvsbake viewer: what pvsview shows, as plain data. See view_model.h.
#include "viewer/view_model.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace pvs::viewer {

namespace {

uint8_t to_byte(double v) {
    return uint8_t(std::clamp(std::lround(v * 255.0), 0L, 255L));
}

// HSV (h in [0, 1)) to RGB bytes.
Rgba hsv(double h, double s, double v) {
    const double hh = (h - std::floor(h)) * 6.0;
    const int i = int(hh) % 6;
    const double f = hh - std::floor(hh);
    const double p = v * (1.0 - s), q = v * (1.0 - s * f), t = v * (1.0 - s * (1.0 - f));
    // Which of v, t, p, q is red, green and blue in each sixth of the hue circle.
    const double values[4] = {v, t, p, q};
    static const int kPick[6][3] = {{0, 1, 2}, {3, 0, 2}, {2, 0, 1}, {2, 3, 0}, {1, 2, 0}, {0, 2, 3}};
    const double r = values[kPick[i][0]], g = values[kPick[i][1]], b = values[kPick[i][2]];
    return {to_byte(r), to_byte(g), to_byte(b), 255};
}

bool parse_numbers(std::string text, std::vector<double>& out) {
    std::replace(text.begin(), text.end(), ',', ' ');
    std::istringstream in(text);
    double v = 0.0;
    while (in >> v) {
        if (!std::isfinite(v)) return false;
        out.push_back(v);
    }
    return in.eof();
}

}  // namespace

Rgba object_color(uint32_t object) {
    // Hues by the golden ratio, kept out of the reds (misses are red): h in [0.08, 0.92).
    const double h = 0.08 + 0.84 * std::fmod(0.13 + double(object) * 0.618033988749895, 1.0);
    const double v = object % 3 == 1 ? 0.80 : 0.95;
    return hsv(h, 0.85, v);
}

Rgba heat_color(double t) {
    t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
    return hsv((1.0 - t) * (2.0 / 3.0), 0.9, 0.95);  // hue 240 degrees (blue) down to 0 (red)
}

std::vector<ObjectState> object_states(const BakeData& bake, int32_t cell, bool hide_others) {
    const uint32_t n = uint32_t(bake.objects.size());
    std::vector<ObjectState> states(n, ObjectState::kNeutral);
    if (cell < 0 || uint32_t(cell) >= bake.pvs.cell_count) return states;
    for (uint32_t o = 0; o < n; ++o) {
        const bool seen = o < bake.pvs.object_count && bake.pvs.test(uint32_t(cell), o);
        states[o] = seen ? ObjectState::kVisible : hide_others ? ObjectState::kHidden : ObjectState::kFaded;
    }
    return states;
}

std::vector<Rgba> triangle_colors(const World& world, const std::vector<ObjectState>& states) {
    std::vector<Rgba> colors(world.triangles.size(), kNeutralOpaque);
    for (uint32_t o = 0; o < world.objects.size(); ++o) {
        const WorldObject& obj = world.objects[o];
        const ObjectState state = o < states.size() ? states[o] : ObjectState::kNeutral;
        Rgba visible = object_color(o);
        for (uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count; ++t) {
            if (t >= colors.size()) break;
            const bool opaque = t < world.triangle_opaque.size() && world.triangle_opaque[t] != 0;
            Rgba& c = colors[t];
            switch (state) {
                case ObjectState::kNeutral:
                    c = opaque ? kNeutralOpaque : kNeutralSeeThrough;
                    break;
                case ObjectState::kVisible:
                    c = visible;
                    if (!opaque) c[3] = kVisibleSeeThroughAlpha;
                    break;
                case ObjectState::kFaded:
                    c = opaque ? kFadedOpaque : kFadedSeeThrough;
                    break;
                case ObjectState::kHidden:
                    c = {0, 0, 0, 0};
                    break;
            }
        }
    }
    return colors;
}

std::vector<uint32_t> cell_pvs_counts(const BakeData& bake) {
    std::vector<uint32_t> counts(bake.pvs.cell_count);
    for (uint32_t c = 0; c < bake.pvs.cell_count; ++c) counts[c] = bake.pvs.count(c);
    return counts;
}

CellFigures cell_figures(const BakeData& bake, int32_t cell) {
    CellFigures f;
    f.objects_total = uint32_t(bake.objects.size());
    for (const ObjectRecord& o : bake.objects) f.triangles_total += o.triangle_count;
    if (cell < 0 || size_t(cell) >= bake.cells.cells.size() || uint32_t(cell) >= bake.pvs.cell_count)
        return f;
    f.cell = cell;
    f.bounds = bake.cells.cells[size_t(cell)].bounds;
    for (uint32_t o = 0; o < bake.objects.size() && o < bake.pvs.object_count; ++o) {
        if (!bake.pvs.test(uint32_t(cell), o)) continue;
        f.listed.push_back(o);
        ++f.objects_visible;
        f.triangles_visible += bake.objects[o].triangle_count;
    }
    const auto& sampled = bake.verification.cell_sampled_visible;
    if (bake.verification.ran && size_t(cell) < sampled.size()) {
        f.sampled_visible = sampled[size_t(cell)];
        if (f.sampled_visible > 0) f.overestimation = double(f.objects_visible) / double(f.sampled_visible);
    }
    for (const Miss& m : bake.verification.misses) f.misses += m.cell == uint32_t(cell) ? 1u : 0u;
    const RankedOccluders& r = bake.ranked;
    for (uint32_t k = 0; k < r.count(uint32_t(cell)); ++k)
        f.ranked.push_back(r.entries[r.offsets[size_t(cell)] + k]);
    return f;
}

std::vector<Aabb> ranked_occluder_boxes(const BakeData& bake, int32_t cell) {
    std::vector<Aabb> boxes;
    if (cell < 0 || size_t(cell) >= bake.cells.size()) return boxes;
    const RankedOccluders& r = bake.ranked;
    for (uint32_t k = 0; k < r.count(uint32_t(cell)); ++k) {
        const uint32_t box = r.entries[r.offsets[size_t(cell)] + k].box;
        if (box < bake.occluders.size()) boxes.push_back(bake.occluders[box].box);
    }
    return boxes;
}

std::string cell_overlay_text(const BakeData& bake, const CellFigures& f, size_t max_names) {
    if (f.cell < 0) return "no cell picked";
    const auto pct = [](double a, double b) { return b > 0.0 ? 100.0 * a / b : 0.0; };
    std::string s = fmt::format("cell {} of {}   [{:.2f} {:.2f} {:.2f}] - [{:.2f} {:.2f} {:.2f}]\n", f.cell,
                                bake.cells.size(), f.bounds.min.x, f.bounds.min.y, f.bounds.min.z,
                                f.bounds.max.x, f.bounds.max.y, f.bounds.max.z);
    s += fmt::format("PVS: {} of {} objects ({:.1f}%), {} of {} triangles ({:.1f}%)\n", f.objects_visible,
                     f.objects_total, pct(f.objects_visible, f.objects_total), f.triangles_visible,
                     f.triangles_total, pct(double(f.triangles_visible), double(f.triangles_total)));
    if (f.sampled_visible >= 0) {
        s += fmt::format("sampled visible set: {} objects", f.sampled_visible);
        if (f.overestimation >= 0.0) s += fmt::format("   overestimation: {:.2f}x", f.overestimation);
        s += fmt::format("   misses here: {}\n", f.misses);
    } else {
        s += "sampled visible set: not verified\n";
    }
    if (!f.ranked.empty()) {
        const RankedOccluder& best = f.ranked.front();
        s += fmt::format(
            "ranked occluders (cyan): {}; the best scores {:.3f}, {:.2f} sr, hides {:.1f} objects, {:.1f}% "
            "of "
            "the triangles\n",
            f.ranked.size(), best.score, best.solid_angle_sr, best.hidden_objects,
            100.0 * best.hidden_triangle_share);
    } else if (!bake.ranked.empty()) {
        s += "ranked occluders: none\n";
    }
    const size_t shown = std::min(max_names, f.listed.size());
    for (size_t i = 0; i < shown; ++i) {
        const ObjectRecord& o = bake.objects[f.listed[i]];
        s += fmt::format("  {} {} ({} tris)\n", f.listed[i], o.name, o.triangle_count);
    }
    if (shown < f.listed.size()) s += fmt::format("  ... and {} more\n", f.listed.size() - shown);
    return s;
}

std::string bake_overlay_text(const BakeData& bake, const std::string& world_path) {
    const std::vector<uint32_t> counts = cell_pvs_counts(bake);
    uint64_t sum = 0;
    uint32_t lo = counts.empty() ? 0 : std::numeric_limits<uint32_t>::max(), hi = 0;
    for (uint32_t c : counts) {
        sum += c;
        lo = std::min(lo, c);
        hi = std::max(hi, c);
    }
    std::string s = fmt::format("{}   {} bake ({})\n", world_path, bake.mode,
                                bake.conservative ? "conservative" : "aggressive: may miss");
    s += fmt::format("{} cells ({}), {} objects; PVS size min {} / mean {:.1f} / max {}\n", bake.cells.size(),
                     bake.cells.kind == CellSet::Kind::kOctree ? "octree" : "grid", bake.objects.size(), lo,
                     counts.empty() ? 0.0 : double(sum) / double(counts.size()), hi);
    if (bake.verification.ran) {
        s += fmt::format("verification: {} misses recorded\n", bake.verification.misses.size());
    } else {
        s += "verification: not run\n";
    }
    if (!bake.leak_path.empty())
        s += fmt::format("LEAK: path of {} points (magenta)\n", bake.leak_path.size());
    s += "click or arrow keys: pick a cell   h: help";
    return s;
}

std::string help_text() {
    return "keys\n"
           "  click         pick the cell under the pointer\n"
           "  Right / Left  next / previous cell\n"
           "  Up / Down     10 cells on / back\n"
           "  PgUp / PgDn   100 cells on / back\n"
           "  Escape        no cell picked\n"
           "  c             cells (outlines coloured by PVS size)\n"
           "  x             cells as a slice at the picked cell's height\n"
           "  o             occluder boxes\n"
           "  v             view volume\n"
           "  m             verification misses (the picked cell's) and leak path\n"
           "  f             objects not in the PVS: faded / hidden\n"
           "  k             cut the world 1 m above the picked cell\n"
           "  t             overlay text\n"
           "  r             reset the camera\n"
           "  h             this help\n"
           "  q             quit";
}

int32_t cell_for_surface_point(const CellSet& cells, glm::vec3 point, glm::vec3 toward_eye, float step_m,
                               int max_steps) {
    if (cells.cells.empty()) return -1;
    const float len = glm::length(toward_eye);
    const glm::vec3 dir = len > 0.0f ? toward_eye / len : glm::vec3(0.0f);
    for (int k = 0; k <= max_steps; ++k) {
        const int32_t c = cells.find(point + dir * (step_m * float(k)));
        if (c >= 0) return c;
    }
    int32_t best = -1;
    float best_d2 = std::numeric_limits<float>::infinity();
    for (size_t c = 0; c < cells.cells.size(); ++c) {
        const Aabb& b = cells.cells[c].bounds;
        const glm::vec3 q = glm::clamp(point, b.min, b.max);
        const float d2 = glm::dot(q - point, q - point);
        if (d2 < best_d2) best_d2 = d2, best = int32_t(c);
    }
    return best;
}

std::optional<CameraPose> parse_camera(const std::string& text) {
    std::vector<double> v;
    if (!parse_numbers(text, v) || v.size() != 9) return std::nullopt;
    CameraPose p;
    p.eye = glm::vec3(float(v[0]), float(v[1]), float(v[2]));
    p.target = glm::vec3(float(v[3]), float(v[4]), float(v[5]));
    p.up = glm::vec3(float(v[6]), float(v[7]), float(v[8]));
    const glm::vec3 d = p.target - p.eye;
    if (glm::length(d) <= 0.0f || glm::length(p.up) <= 0.0f) return std::nullopt;
    if (glm::length(glm::cross(glm::normalize(d), glm::normalize(p.up))) < 1e-4f) return std::nullopt;
    return p;
}

std::optional<std::array<int, 2>> parse_size(const std::string& text) {
    const size_t x = text.find_first_of("xX");
    if (x == std::string::npos) return std::nullopt;
    std::array<int, 2> wh{};
    const std::string parts[2] = {text.substr(0, x), text.substr(x + 1)};
    for (int i = 0; i < 2; ++i) {
        if (parts[i].empty() || parts[i].size() > 5 ||
            !std::all_of(parts[i].begin(), parts[i].end(), [](char c) { return c >= '0' && c <= '9'; }))
            return std::nullopt;
        wh[size_t(i)] = std::stoi(parts[i]);
        if (wh[size_t(i)] < 16 || wh[size_t(i)] > 8192) return std::nullopt;
    }
    return wh;
}

CameraPose camera_for_box(const Aabb& box, double view_angle_deg, double aspect, double elevation_deg) {
    const Aabb b = box.is_empty() ? Aabb::of(glm::vec3(-1.0f), glm::vec3(1.0f)) : box;
    std::vector<glm::vec3> corners;
    for (int i = 0; i < 8; ++i) {
        corners.emplace_back(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z);
    }
    return camera_for_points(corners, view_angle_deg, aspect, elevation_deg);
}

CameraPose camera_for_points(const std::vector<glm::vec3>& points, double view_angle_deg, double aspect,
                             double elevation_deg) {
    CameraPose p;
    Aabb b;
    for (const glm::vec3& q : points) b.extend(q);
    if (b.is_empty()) b = Aabb::of(glm::vec3(-1.0f), glm::vec3(1.0f));
    p.target = b.center();
    const double el = elevation_deg * M_PI / 180.0, az = 30.0 * M_PI / 180.0;
    const glm::dvec3 to_eye(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
    const glm::dvec3 forward = -to_eye;
    const glm::dvec3 right = glm::normalize(glm::cross(forward, glm::dvec3(0.0, 1.0, 0.0)));
    const glm::dvec3 up = glm::cross(right, forward);
    const double tan_y = std::tan(0.5 * view_angle_deg * M_PI / 180.0);
    const double tan_x = tan_y * std::max(aspect, 1e-3);
    // The nearest eye on this line that has every corner of the box inside the view frustum.
    double distance = 0.5;
    for (const glm::vec3& q : points) {
        const glm::dvec3 rel = glm::dvec3(q) - glm::dvec3(p.target);
        const double depth_beyond_target = glm::dot(rel, forward);
        distance = std::max(distance, std::abs(glm::dot(rel, right)) / tan_x - depth_beyond_target);
        distance = std::max(distance, std::abs(glm::dot(rel, up)) / tan_y - depth_beyond_target);
    }
    distance *= 1.05;  // a margin
    p.eye = p.target + glm::vec3(to_eye * distance);
    p.up = glm::vec3(0.0f, 1.0f, 0.0f);
    return p;
}

Aabb focus_box(const BakeData& bake, const World& world, int32_t cell) {
    if (cell < 0 || size_t(cell) >= bake.cells.cells.size()) return world.bounds;
    const Aabb& cb = bake.cells.cells[size_t(cell)].bounds;
    Aabb box = cb;
    for (uint32_t o = 0; o < bake.objects.size() && o < bake.pvs.object_count; ++o) {
        if (bake.pvs.test(uint32_t(cell), o)) box.extend(bake.objects[o].bounds);
    }
    if (!world.bounds.is_empty()) {
        Aabb limit = world.bounds;
        limit.extend(cb);
        box.min = glm::max(box.min, limit.min);
        box.max = glm::min(box.max, limit.max);
    }
    return box;
}

std::optional<glm::vec2> project_to_pixel(const CameraPose& camera, double view_angle_deg, int width,
                                          int height, glm::vec3 point) {
    const glm::vec3 forward = glm::normalize(camera.target - camera.eye);
    const glm::vec3 right = glm::normalize(glm::cross(forward, camera.up));
    const glm::vec3 up = glm::cross(right, forward);
    const glm::vec3 rel = point - camera.eye;
    const float depth = glm::dot(rel, forward);
    if (depth <= 0.0f) return std::nullopt;
    const double f = 0.5 * double(height) / std::tan(0.5 * view_angle_deg * M_PI / 180.0);
    const double px = 0.5 * double(width) + f * double(glm::dot(rel, right)) / double(depth);
    const double py = 0.5 * double(height) - f * double(glm::dot(rel, up)) / double(depth);
    return glm::vec2(float(px), float(py));
}

std::vector<glm::vec3> voxel_mask_surface(const VoxelMask& mask) {
    std::vector<glm::vec3> quads;
    if (mask.empty()) return quads;
    const glm::ivec3 d = mask.dims;
    const auto set = [&](int x, int y, int z) {
        if (x < 0 || y < 0 || z < 0 || x >= d.x || y >= d.y || z >= d.z) return false;
        return mask.get(uint64_t(x) + uint64_t(d.x) * (uint64_t(y) + uint64_t(d.y) * uint64_t(z)));
    };
    const float s = mask.voxel_size_m;
    for (int z = 0; z < d.z; ++z) {
        for (int y = 0; y < d.y; ++y) {
            for (int x = 0; x < d.x; ++x) {
                if (!set(x, y, z)) continue;
                const glm::vec3 lo = mask.origin + glm::vec3(float(x), float(y), float(z)) * s;
                for (int axis = 0; axis < 3; ++axis) {
                    for (int side = 0; side < 2; ++side) {
                        glm::ivec3 n(x, y, z);
                        n[axis] += side ? 1 : -1;
                        if (set(n.x, n.y, n.z)) continue;
                        const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
                        glm::vec3 c = lo;
                        c[axis] += side ? s : 0.0f;
                        glm::vec3 e1(0.0f), e2(0.0f);
                        e1[a1] = s;
                        e2[a2] = s;
                        if (!side) std::swap(e1, e2);  // outward winding on both sides
                        quads.push_back(c);
                        quads.push_back(c + e1);
                        quads.push_back(c + e1 + e2);
                        quads.push_back(c + e2);
                    }
                }
            }
        }
    }
    return quads;
}

}  // namespace pvs::viewer
