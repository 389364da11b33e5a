// SPDX-License-Identifier: MIT
// bench_overestimation: where a conservative bake's overestimation comes from (tightness).
//
//   bench_overestimation WORLD.glb BAKE.h5 [--cells N] [--rays R] [--seed S]
//
// Rebuilds the bake's occluders from its stored parameters (driver/bake.h solver_occluders), then, for N
// seeded random cells, aims R rays at every object the cell's PVS lists, each from a random eye point of
// the cell to a random point on the object (area-weighted), and sorts each listed (cell, object) pair
// into the first class that holds:
// - visible:  some ray reaches it past the real triangles: rightly listed;
// - rule:     not reached, but every PVS lists it (pvs_always_visible, or bounds meeting the cell);
// - no_box:   some ray passes the unshrunk proven boxes and the (uninset) panels and slanted panels: no
//             occluder stands where the real triangles block (thin walls, detail, voxel erosion, solid the
//             sweep could not prove);
// - epsilon:  every ray is stopped by the unshrunk boxes and the panels, some passes the boxes shrunk by
//             the floor epsilon and the panels and slanted panels inset by it (the least the solver insets
//             them, at a face's centre): shrinking lost the blocker;
// - region:   every ray is stopped by the shrunk occluders, but a ray from a random point of the cell's eye
//             REGION (the box around its eye voxels, whose boundary the solver samples) passes them: the
//             solver proves hiddenness for the whole box, not just the eye voxels in it;
// - solver:   every ray from the region is stopped by the shrunk occluders, yet the solver listed it (split
//             by whether the shrunk boxes alone stop the rays, or they need the panels): the
//             patches' epsilon balls, pixel coverage, the boxes of triangle runs it tests.
// With R rays a class is a sample, not a proof: a pair that only a few sight lines reach reads as hidden.
// Prints JSON: pairs and triangles per class, the listed / visible ratio, and what it would be if each
// class were culled (the lever it offers). Objects a ray reaches that the PVS leaves out are counted as
// misses (a conservative bake has none).
#include "cells/eyes.h"
#include "core/config.h"
#include "core/random.h"
#include "driver/bake.h"
#include "io/bake_file.h"
#include "io/gltf_loader.h"
#include "occluders/panels.h"
#include "occluders/slanted_panels.h"
#include "rays/ray_scene.h"
#include "rays/surface_points.h"
#include "pvs/region_hiding.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

// The slanted panels with every edge moved inward by inset_m in their planes (the least the solver insets
// them, as inset_panels() does for panels); those that vanish are left out. Corner j of the inset polygon is
// where the moved lines of its two edges meet: c_j + inset (m_a + m_b) / (1 + m_a.m_b), with m_a, m_b their
// inward unit normals.
std::vector<pvs::SlantedPanel> inset_slanted(const std::vector<pvs::SlantedPanel>& panels, double inset_m) {
    std::vector<pvs::SlantedPanel> out;
    for (const pvs::SlantedPanel& p : panels) {
        const size_t n = p.corners.size();
        if (p.edge_normal.size() != n) continue;
        pvs::SlantedPanel q = p;
        q.bounds = pvs::Aabb{};
        for (size_t j = 0; j < n; ++j) {
            const glm::dvec3 ma = p.edge_normal[(j + n - 1) % n], mb = p.edge_normal[j];
            q.corners[j] = p.corners[j] + inset_m * (ma + mb) / (1.0 + glm::dot(ma, mb));
            q.bounds.extend(glm::vec3(q.corners[j]));
        }
        // Gone when some new corner lies outside a moved line (the polygon turned inside out).
        bool kept = pvs::set_slanted_edges(q);
        for (size_t j = 0; j < n && kept; ++j)
            for (size_t i = 0; i < n && kept; ++i)
                kept = glm::dot(p.edge_normal[i], q.corners[j]) >= p.edge_offset[i] + inset_m * (1.0 - 1e-9);
        if (kept) out.push_back(std::move(q));
    }
    return out;
}

enum Class { kVisible, kRule, kNoBox, kEpsilon, kRegion, kSolver, kClasses };
constexpr const char* kClassNames[kClasses] = {"visible", "rule", "no_box", "epsilon", "region", "solver"};

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr,
                     "usage: bench_overestimation WORLD.glb BAKE.h5 [--cells N] [--rays R] [--seed S]\n");
        return 2;
    }
    const std::string world_path = argv[1], bake_path = argv[2];
    uint32_t n_cells = 300, n_rays = 256;
    uint64_t seed = 1;
    for (int a = 3; a < argc; a += 2) {
        if (a + 1 >= argc) {
            std::fprintf(stderr, "error: %s wants a value\n", argv[a]);
            return 2;
        }
        const std::string k = argv[a];
        if (k == "--cells")
            n_cells = uint32_t(std::atoi(argv[a + 1]));
        else if (k == "--rays")
            n_rays = uint32_t(std::atoi(argv[a + 1]));
        else if (k == "--seed")
            seed = std::strtoull(argv[a + 1], nullptr, 10);
        else {
            std::fprintf(stderr, "error: unknown option %s\n", argv[a]);
            return 2;
        }
    }
    try {
        pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
        const pvs::World world = pvs::load_world(ctx, world_path);
        const pvs::BakeData bake = pvs::read_bake_file(bake_path);
        if (bake.objects.size() != world.objects.size() || !bake.conservative) {
            std::fprintf(stderr, "error: %s is not a conservative bake of %s\n", bake_path.c_str(),
                         world_path.c_str());
            return 2;
        }
        // The occluders the solver used, rebuilt as the bake built them.
        const pvs::BakeConfig config = pvs::config_from_parameters(bake.parameters);
        pvs::ViewVolumeConfig view_config = config.view;
        view_config.auto_voxel_size_m = pvs::conservative_voxel_size_m(config.conservative.epsilon_m);
        const pvs::ViewVolume view = pvs::build_view_volume(ctx, view_config, world);
        const pvs::RayScene scene(ctx, world, pvs::BuildQuality::kMedium, config.run.threads);
        pvs::OccluderFigures occ_figures;
        pvs::BlockFigures block_figures;
        pvs::ShrunkOccluders shrunk;
        const std::vector<pvs::Occluder> proven_boxes =
            pvs::solver_occluders(ctx, config, world, view, scene, occ_figures, block_figures, shrunk);
        // Per occluder set (the global one, then each block's): the unshrunk boxes, and the floor level.
        std::vector<pvs::Aabb> unshrunk;
        for (const pvs::Occluder& o : proven_boxes)
            if (o.proven) unshrunk.push_back(o.box);
        const size_t n_sets = 1 + shrunk.block_sets.size();
        std::vector<std::unique_ptr<pvs::RayScene>> full_scenes, shrunk_scenes, boxes_only_scenes;
        for (size_t s = 0; s < n_sets; ++s) {
            const pvs::ShrunkOccluders& set = shrunk.set(int32_t(s) - 1);
            // A block's unshrunk solid is not kept as boxes: its floor-level boxes stand in for it.
            const pvs::World full =
                pvs::box_world(s == 0 ? unshrunk : set.boxes[0], set.panels, true, set.slanted);
            const pvs::World thin =
                pvs::box_world(set.boxes[0], pvs::inset_panels(set.panels, set.epsilon_m.front()), true,
                               inset_slanted(set.slanted, set.epsilon_m.front()));
            full_scenes.push_back(std::make_unique<pvs::RayScene>(ctx, full));
            shrunk_scenes.push_back(std::make_unique<pvs::RayScene>(ctx, thin));
            boxes_only_scenes.push_back(
                std::make_unique<pvs::RayScene>(ctx, pvs::box_world(set.boxes[0], {})));
        }
        pvs::CellSet cells = bake.cells;
        cells.view = view.view;
        cells.eyes = view.eyes;
        const std::vector<double> cum_area = pvs::cumulative_areas(world);

        // Seeded random cells, distinct.
        std::vector<uint32_t> picks(cells.size());
        for (uint32_t c = 0; c < picks.size(); ++c) picks[c] = c;
        pvs::Rng pick_rng(seed, 0x43454c4c);
        n_cells = std::min<uint32_t>(n_cells, uint32_t(picks.size()));
        for (uint32_t i = 0; i < n_cells; ++i)
            std::swap(picks[i], picks[i + pick_rng.below(uint32_t(picks.size()) - i)]);
        picks.resize(n_cells);
        std::sort(picks.begin(), picks.end());

        std::vector<std::array<uint64_t, kClasses>> pairs(n_cells), tris(n_cells);
        std::vector<uint64_t> misses(n_cells, 0);
        // Solver pairs whose rays the shrunk boxes alone stop [0], or that need the panels too [1].
        std::vector<std::array<uint64_t, 2>> solver_needs_panels(n_cells, std::array<uint64_t, 2>{});
        // [no_box, epsilon][stopped within 0.5 m of the eye, within 0.3 m of the target, between]
        std::vector<std::array<std::array<uint64_t, 3>, 2>> stops(n_cells,
                                                                  std::array<std::array<uint64_t, 3>, 2>{});
        // [no_box, epsilon][stopper in an uninset panel, in an axis plane but no panel]
        const std::vector<pvs::Aabb>& raw_panels = shrunk.panels;  // as found, not inset
        std::vector<std::array<std::array<uint64_t, 3>, 2>> panel_hits(
            n_cells, std::array<std::array<uint64_t, 3>, 2>{});
        // [no_box, epsilon][axis plane in the panel cone, axis plane grazing, other plane]
        std::vector<std::array<std::array<uint64_t, 3>, 2>> kinds(n_cells,
                                                                  std::array<std::array<uint64_t, 3>, 2>{});
        const uint32_t n_objects = uint32_t(world.objects.size());
#pragma omp parallel for schedule(dynamic, 1)
        for (int64_t i = 0; i < int64_t(n_cells); ++i) {
            const uint32_t c = picks[size_t(i)];
            pairs[size_t(i)].fill(0);
            tris[size_t(i)].fill(0);
            const pvs::Aabb& box = cells.cells[c].bounds;
            const int32_t set = shrunk.set_for(pvs::eye_region(cells.eyes, box));
            std::vector<glm::vec3> eyes;
            pvs::sample_eye_points_in(cells, box, uint64_t(c), n_rays, seed, eyes);
            if (eyes.empty()) continue;
            std::vector<uint8_t> reached(n_objects, 0);
            std::vector<uint32_t> listed;
            for (uint32_t o = 0; o < n_objects; ++o)
                if (bake.pvs.test(c, o) && world.objects[o].triangle_count > 0) listed.push_back(o);
            // Rays of one eye at every listed object; R eyes (eye e aims at every object once).
            std::vector<glm::vec3> dirs, origins;
            std::vector<float> lengths;
            std::vector<pvs::RayTouch> touches;
            // Ray slot `slot` from `from` to a random point on `object` (area-weighted); its length stops a
            // millimetre short of the point, so the object itself never blocks it.
            auto aim_one = [&](glm::vec3 from, uint32_t object, pvs::Rng& rng, size_t slot) {
                const glm::vec3 d = pvs::random_point_on(world, cum_area, object, rng) - from;
                const float len = glm::length(d);
                origins[slot] = from;
                dirs[slot] = len > 0.0f ? d / len : glm::vec3(1, 0, 0);
                lengths[slot] = std::max(0.0f, len - 1e-3f);
            };
            // One ray from `eye` at each of `objects`, in their order.
            auto aim = [&](glm::vec3 eye, const std::vector<uint32_t>& objects, pvs::Rng& rng) {
                origins.resize(objects.size());
                dirs.resize(objects.size());
                lengths.resize(objects.size());
                for (size_t k = 0; k < objects.size(); ++k) aim_one(eye, objects[k], rng, k);
            };
            for (uint32_t e = 0; e < eyes.size(); ++e) {
                pvs::Rng rng(seed, (uint64_t(c) << 20) ^ e ^ 0x5a5a000000000000ULL);
                aim(eyes[e], listed, rng);
                touches.clear();
                scene.trace(eyes[e], dirs.data(), uint32_t(dirs.size()), touches);
                for (const pvs::RayTouch& t : touches) {
                    if (lengths[t.ray] <= 0.0f) continue;  // a target at the eye: no direction to trust
                    if (!bake.pvs.test(c, t.object)) {
                        if (reached[t.object] == 0) ++misses[size_t(i)];
                        reached[t.object] = 2;
                        continue;
                    }
                    reached[t.object] = 1;
                }
            }
            // The listed objects no ray reached: against the occluders, from fresh rays of the same eyes.
            std::vector<uint32_t> hidden;
            for (uint32_t o : listed)
                if (!reached[o]) hidden.push_back(o);
            std::vector<uint8_t> passes_full(n_objects, 0), passes_thin(n_objects, 0),
                passes_region(n_objects, 0), needs_panels(n_objects, 0), blocked;
            const pvs::Aabb region = pvs::eye_region(cells.eyes, box);
            struct Ray {
                glm::vec3 origin{0.0f}, direction{1.0f, 0.0f, 0.0f};
                float length = 0.0f;
            };
            std::vector<Ray> first_pass(hidden.size());
            for (uint32_t e = 0; e < eyes.size() && !hidden.empty(); ++e) {
                pvs::Rng rng(seed, (uint64_t(c) << 20) ^ e ^ 0xa5a5000000000000ULL);
                aim(eyes[e], hidden, rng);
                blocked.assign(hidden.size(), 0);
                full_scenes[size_t(set + 1)]->occluded_opaque(origins.data(), dirs.data(), lengths.data(),
                                                              uint32_t(hidden.size()), blocked.data());
                for (size_t h = 0; h < hidden.size(); ++h) {
                    if (!blocked[h] && !passes_full[hidden[h]])
                        first_pass[h] = {origins[h], dirs[h], lengths[h]};
                    passes_full[hidden[h]] |= !blocked[h];
                }
                blocked.assign(hidden.size(), 0);
                shrunk_scenes[size_t(set + 1)]->occluded_opaque(origins.data(), dirs.data(), lengths.data(),
                                                                uint32_t(hidden.size()), blocked.data());
                for (size_t h = 0; h < hidden.size(); ++h) {
                    if (!blocked[h] && !passes_thin[hidden[h]] && !passes_full[hidden[h]])
                        first_pass[h] = {origins[h], dirs[h], lengths[h]};
                    passes_thin[hidden[h]] |= !blocked[h];
                }
                // From random points of the eye region.
                for (size_t h = 0; h < hidden.size(); ++h)
                    aim_one(
                        region.min + region.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()),
                        hidden[h], rng, h);
                blocked.assign(hidden.size(), 0);
                shrunk_scenes[size_t(set + 1)]->occluded_opaque(origins.data(), dirs.data(), lengths.data(),
                                                                uint32_t(hidden.size()), blocked.data());
                for (size_t h = 0; h < hidden.size(); ++h) passes_region[hidden[h]] |= !blocked[h];
                // The same rays against the shrunk boxes without panels: do they need the panels?
                blocked.assign(hidden.size(), 0);
                boxes_only_scenes[size_t(set + 1)]->occluded_opaque(
                    origins.data(), dirs.data(), lengths.data(), uint32_t(hidden.size()), blocked.data());
                for (size_t h = 0; h < hidden.size(); ++h) needs_panels[hidden[h]] |= !blocked[h];
            }
            for (uint32_t o : listed) {
                const pvs::WorldObject& obj = world.objects[o];
                Class k = kSolver;
                if (reached[o])
                    k = kVisible;
                else if ((obj.flags & pvs::kObjectAlwaysVisible) || box.overlaps(obj.bounds))
                    k = kRule;
                else if (passes_full[o])
                    k = kNoBox;
                else if (passes_thin[o])
                    k = kEpsilon;
                else if (passes_region[o])
                    k = kRegion;
                if (k == kNoBox || k == kEpsilon) {
                    // Where the real triangles stop the first ray the occluders let through.
                    const size_t h =
                        size_t(std::lower_bound(hidden.begin(), hidden.end(), o) - hidden.begin());
                    const Ray& r = first_pass[h];
                    touches.clear();
                    scene.trace(r.origin, &r.direction, 1, touches);
                    float stop = r.length;
                    uint32_t stopper = UINT32_MAX;
                    for (const pvs::RayTouch& t : touches)
                        if (t.stops && t.t <= stop) {
                            stop = t.t;
                            stopper = t.object;
                        }
                    const int where = stop < 0.5f ? 0 : r.length - stop < 0.3f ? 1 : 2;
                    ++stops[size_t(i)][size_t(k == kNoBox ? 0 : 1)][size_t(where)];
                    // The stopping triangle: in an axis plane and within the panels' cone (tan <= sqrt 2
                    // from its normal), in an axis plane but grazing, or in no axis plane.
                    if (stopper != UINT32_MAX) {
                        const glm::vec3 p = r.origin + stop * r.direction;
                        const pvs::WorldObject& so = world.objects[stopper];
                        float best = 1e9f;
                        glm::vec3 normal(0.0f);
                        for (uint32_t ti = so.first_triangle; ti < so.first_triangle + so.triangle_count;
                             ++ti) {
                            const pvs::Triangle& tr = world.triangles[ti];
                            const glm::vec3 a = world.positions[tr.v[0]], b = world.positions[tr.v[1]],
                                            cc = world.positions[tr.v[2]];
                            glm::vec3 n = glm::cross(b - a, cc - a);
                            const float len = glm::length(n);
                            if (len <= 0.0f) continue;
                            n /= len;
                            const float d = std::abs(glm::dot(p - a, n));
                            if (d < best) {
                                best = d;
                                normal = n;
                            }
                        }
                        const glm::vec3 an = glm::abs(normal);
                        const bool axis = std::max(an.x, std::max(an.y, an.z)) > 0.9999f;
                        const bool in_cone = std::abs(glm::dot(normal, r.direction)) >= 0.57735f;
                        ++kinds[size_t(i)][size_t(k == kNoBox ? 0 : 1)][size_t(!axis ? 2 : in_cone ? 0 : 1)];
                        if (axis) {
                            // In an uninset panel of that plane? Then the inset lost it (only in the
                            // epsilon class: a no_box ray passed the uninset panels); else no panel.
                            bool in_panel = false;
                            for (const pvs::Aabb& pn : raw_panels) {
                                const int ax = pvs::panel_axis(pn);
                                if (ax < 0 || std::abs(pn.min[ax] - p[ax]) > 1e-3f) continue;
                                bool inside = true;
                                for (int d = 0; d < 3; ++d)
                                    if (d != ax && (p[d] < pn.min[d] - 1e-4f || p[d] > pn.max[d] + 1e-4f))
                                        inside = false;
                                if (inside) {
                                    in_panel = true;
                                    break;
                                }
                            }
                            ++panel_hits[size_t(i)][size_t(k == kNoBox ? 0 : 1)][size_t(in_panel ? 0 : 1)];
                        }
                    }
                }
                if (k == kSolver) ++solver_needs_panels[size_t(i)][needs_panels[o] ? 1 : 0];
                ++pairs[size_t(i)][k];
                tris[size_t(i)][k] += obj.triangle_count;
            }
        }

        // Figures: totals, and mean over cells of listed / visible, as is and with each class culled.
        std::array<uint64_t, kClasses> pair_sum{}, tri_sum{};
        uint64_t miss_sum = 0;
        std::array<double, kClasses> ratio_without{};
        double ratio = 0.0, ratio_tri = 0.0;
        uint32_t counted = 0;
        for (uint32_t i = 0; i < n_cells; ++i) {
            uint64_t listed = 0, listed_tris = 0;
            for (int k = 0; k < kClasses; ++k) {
                pair_sum[size_t(k)] += pairs[i][size_t(k)];
                tri_sum[size_t(k)] += tris[i][size_t(k)];
                listed += pairs[i][size_t(k)];
                listed_tris += tris[i][size_t(k)];
            }
            miss_sum += misses[i];
            if (pairs[i][kVisible] == 0) continue;
            ++counted;
            const double v = double(pairs[i][kVisible]);
            ratio += double(listed) / v;
            ratio_tri += double(listed_tris) / std::max(1.0, double(tris[i][kVisible]));
            for (int k = 1; k < kClasses; ++k)
                ratio_without[size_t(k)] += double(listed - pairs[i][size_t(k)]) / v;
        }
        nlohmann::ordered_json out;
        out["bench"] = "overestimation";
        out["world"] = world_path;
        out["bake"] = bake_path;
        out["cells"] = n_cells;
        out["rays_per_pair"] = n_rays;
        out["seed"] = seed;
        out["epsilon_m"] = config.conservative.epsilon_m;
        out["misses"] = miss_sum;
        out["cells_with_visible"] = counted;
        out["listed_over_visible_mean"] = counted ? ratio / counted : 0.0;
        out["listed_over_visible_triangles_mean"] = counted ? ratio_tri / counted : 0.0;
        uint64_t all_pairs = 0, all_tris = 0;
        for (int k = 0; k < kClasses; ++k) {
            all_pairs += pair_sum[size_t(k)];
            all_tris += tri_sum[size_t(k)];
        }
        for (int k = 0; k < kClasses; ++k) {
            nlohmann::ordered_json cls;
            cls["pairs"] = pair_sum[size_t(k)];
            cls["pair_share"] = all_pairs ? double(pair_sum[size_t(k)]) / double(all_pairs) : 0.0;
            cls["triangles"] = tri_sum[size_t(k)];
            cls["triangle_share"] = all_tris ? double(tri_sum[size_t(k)]) / double(all_tris) : 0.0;
            if (k > 0)
                cls["listed_over_visible_mean_if_culled"] =
                    counted ? ratio_without[size_t(k)] / counted : 0.0;
            out["classes"][kClassNames[k]] = cls;
        }
        const char* where_names[3] = {"stopped_near_eye", "stopped_near_target", "stopped_between"};
        const char* kind_names[3] = {"stopper_axis_plane_in_cone", "stopper_axis_plane_grazing",
                                     "stopper_other_plane"};
        for (int k = 0; k < 2; ++k) {
            for (int w = 0; w < 3; ++w) {
                uint64_t n = 0;
                for (uint32_t i = 0; i < n_cells; ++i) n += stops[i][size_t(k)][size_t(w)];
                out["classes"][k == 0 ? "no_box" : "epsilon"][where_names[w]] = n;
                uint64_t m = 0;
                for (uint32_t i = 0; i < n_cells; ++i) m += kinds[i][size_t(k)][size_t(w)];
                out["classes"][k == 0 ? "no_box" : "epsilon"][kind_names[w]] = m;
                if (w < 2) {
                    uint64_t q = 0;
                    for (uint32_t i = 0; i < n_cells; ++i) q += panel_hits[i][size_t(k)][size_t(w)];
                    out["classes"][k == 0 ? "no_box" : "epsilon"]
                       [w == 0 ? "stopper_in_panel" : "stopper_in_no_panel"] = q;
                }
            }
        }
        uint64_t sb = 0, sp = 0;
        for (uint32_t i = 0; i < n_cells; ++i) {
            sb += solver_needs_panels[i][0];
            sp += solver_needs_panels[i][1];
        }
        out["classes"]["solver"]["boxes_alone_stop_the_rays"] = sb;
        out["classes"]["solver"]["rays_need_the_panels"] = sp;
        std::cout << out.dump(2) << std::endl;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}
