// SPDX-License-Identifier: MIT
// bench_ranking: ranked occluders per cell (occluders/ranking.h, occluders/cell_ranking.h). The
// time of the ranking stage against the sampled PVS of the same cells (one run, so the ratio holds on a
// shared machine), and the "knee" of Hudson et al.: how much of what the FULL set of proven boxes hides,
// the best k of a cell alone hide.
//
//   bench_ranking [WORLD.glb ...] [--cell-size M] [--repeats R] [--eval-eyes E] [--threads T]
//                 [--voxel-size M] [--no-pvs]
//
// Default worlds: samples/rooms.glb and ../shared/worlds/oa_dm4.glb (when present). The pipeline is the
// bake's up to the PVS: view volume, Embree scene, occluder synthesis (at the voxel size a conservative bake
// uses by default: min(0.25 m, epsilon 0.125 m)), a uniform grid clipped to the view volume; then the
// ranking with the default options (8 per cell) timed `repeats` times (median), and once more with 16 per
// cell for the knee.
//
// The knee: from E FRESH eye points per cell (seed 0x6b6e6565, not the ranking's), "hidden by the full
// set" is every object wholly in the shadow frustum of at least ONE proven box (single-box shadows, no
// fusion of boxes), and "hidden by the top k" the same for the cell's k best ranked boxes only; the figure
// is sum over eyes and cells of (top k hidden) / sum of (full set hidden), for objects and for triangles,
// k = 1, 2, 4, 8, 16. The same for the k boxes of largest solid angle (Hudson's own criterion, from the
// ranking's eyes) as a baseline. Prints one JSON object.
#include "bench/bench_util.h"
#include "cells/eyes.h"
#include "cells/grid.h"
#include "cells/view_volume.h"
#include "io/gltf_loader.h"
#include "occluders/cell_ranking.h"
#include "occluders/ranking.h"
#include "occluders/synthesis.h"
#include "rays/ray_sampler.h"
#include "rays/ray_scene.h"

#include <omp.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <string>
#include <vector>

#include <sys/resource.h>

#ifndef PVSBAKE_SOURCE_DIR
#define PVSBAKE_SOURCE_DIR "."
#endif

namespace {

using pvs::bench::median;
using pvs::bench::seconds_since;

constexpr std::array<uint32_t, 5> kKs = {1, 2, 4, 8, 16};
constexpr uint64_t kEvalSeed = 0x6b6e6565ULL;

// CPU seconds of the whole process (all threads): steadier than wall time on a shared machine.
double cpu_seconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

std::string find_world(const std::string& relative) {
    namespace fs = std::filesystem;
    if (fs::exists(relative)) return relative;
    const fs::path in_tree = fs::path(PVSBAKE_SOURCE_DIR) / relative;
    if (fs::exists(in_tree)) return in_tree.lexically_normal().string();
    return {};
}

struct Args {
    std::vector<std::string> worlds;
    double cell_size_m = 2.0;
    double voxel_size_m = 0.0;  // 0: as a conservative bake
    int repeats = 3;
    uint32_t eval_eyes = 8;
    int threads = 0;
    bool pvs = true;
};

// Objects and triangles hidden, summed.
struct Hidden {
    double objects = 0.0;
    double triangles = 0.0;
};

// The knee of one ordering: full[i] and topk[k][i] summed over eyes of one cell.
struct CellKnee {
    Hidden full;
    std::array<Hidden, kKs.size()> ranked{};
    std::array<Hidden, kKs.size()> by_solid_angle{};
};

Hidden count_bits(const std::vector<uint8_t>& hidden, const pvs::World& world) {
    Hidden h;
    for (size_t o = 0; o < hidden.size(); ++o) {
        if (!hidden[o]) continue;
        h.objects += 1.0;
        h.triangles += world.objects[o].triangle_count;
    }
    return h;
}

nlohmann::ordered_json knee_json(const std::array<Hidden, kKs.size()>& k, const Hidden& full) {
    nlohmann::ordered_json j = nlohmann::ordered_json::array();
    for (size_t i = 0; i < kKs.size(); ++i) {
        j.push_back({{"k", kKs[i]},
                     {"objects_share", full.objects > 0 ? k[i].objects / full.objects : 0.0},
                     {"triangles_share", full.triangles > 0 ? k[i].triangles / full.triangles : 0.0}});
    }
    return j;
}

nlohmann::ordered_json bench_world(const std::string& path, const Args& args) {
    pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
    const pvs::World world = pvs::load_world(ctx, path);
    pvs::BakeConfig config;
    config.cells.cell_size_m = args.cell_size_m;
    config.view.voxel_size_m = args.voxel_size_m;
    config.view.auto_voxel_size_m = pvs::conservative_voxel_size_m(config.conservative.epsilon_m);

    auto t0 = std::chrono::steady_clock::now();
    const pvs::ViewVolume view = pvs::build_view_volume(ctx, config.view, world);
    pvs::RayScene scene(ctx, world, pvs::BuildQuality::kMedium, config.run.threads);
    pvs::OccluderFigures occ;
    const std::vector<pvs::Occluder> occluders =
        pvs::synthesize_occluders(ctx, config.occluders, world, view, scene, occ);
    const double occluder_s = seconds_since(t0);
    pvs::CellSet cells = pvs::build_uniform_grid(ctx, config.cells, view.view_bounds);
    pvs::clip_grid_to_view(ctx, cells, view.view, view.eyes);

    // The ranking as a bake runs it (defaults), timed.
    std::vector<double> times, cpu_times;
    pvs::RankingFigures figures;
    pvs::RankedOccluders ranked;
    for (int r = 0; r < args.repeats; ++r) {
        t0 = std::chrono::steady_clock::now();
        const double c0 = cpu_seconds();
        ranked = pvs::rank_occluders(ctx, config.ranking, world, cells, occluders, figures);
        times.push_back(seconds_since(t0));
        cpu_times.push_back(cpu_seconds() - c0);
    }
    double pvs_s = 0.0, pvs_cpu_s = 0.0;
    if (args.pvs) {
        t0 = std::chrono::steady_clock::now();
        const double c0 = cpu_seconds();
        const pvs::SampledPvs sampled = pvs::bake_sampled_pvs(ctx, config.sampled, world, scene, cells);
        pvs_s = seconds_since(t0);
        pvs_cpu_s = cpu_seconds() - c0;
    }
    // 16 per cell for the knee (the order of the first 8 is the same: each box is scored on its own).
    pvs::RankingConfig deep = config.ranking;
    deep.occluders_per_cell = kKs.back();
    pvs::RankingFigures deep_figures;
    t0 = std::chrono::steady_clock::now();
    const pvs::RankedOccluders ranked16 =
        pvs::rank_occluders(ctx, deep, world, cells, occluders, deep_figures);
    const double ranking16_s = seconds_since(t0);

    // The knee.
    std::vector<pvs::Aabb> boxes;
    std::vector<uint32_t> proven;
    for (uint32_t i = 0; i < occluders.size(); ++i) {
        boxes.push_back(occluders[i].box);
        if (occluders[i].proven) proven.push_back(i);
    }
    const pvs::Occludees occludees(world);
    const int64_t n_cells = int64_t(cells.size());
    std::vector<CellKnee> knees(static_cast<size_t>(n_cells));
    t0 = std::chrono::steady_clock::now();
#pragma omp parallel
    {
        std::vector<glm::vec3> eyes, rank_eyes;
        std::vector<uint8_t> full(world.objects.size()), part(world.objects.size());
        std::vector<std::pair<double, uint32_t>> by_angle;
        std::vector<uint32_t> angle_order, rank_order;
#pragma omp for schedule(dynamic, 8)
        for (int64_t c = 0; c < n_cells; ++c) {
            CellKnee& knee = knees[size_t(c)];
            // Baseline order: the largest solid angle from the ranking's own eyes (what Hudson et al. rank
            // by).
            rank_eyes.clear();
            pvs::sample_eye_points(cells, uint32_t(c), config.ranking.eyes_per_cell, config.ranking.seed,
                                   rank_eyes);
            by_angle.clear();
            for (uint32_t i : proven) {
                double w = 0.0;
                for (const glm::vec3& e : rank_eyes) {
                    const double a = pvs::box_solid_angle_sr(boxes[i], e);
                    if (a < pvs::kFourPi) w = std::max(w, a);
                }
                if (w >= config.ranking.min_solid_angle_sr && w > 0.0) by_angle.emplace_back(-w, i);
            }
            std::sort(by_angle.begin(), by_angle.end());
            angle_order.clear();
            for (size_t k = 0; k < by_angle.size() && k < kKs.back(); ++k)
                angle_order.push_back(by_angle[k].second);
            rank_order.clear();
            for (uint32_t k = ranked16.offsets[size_t(c)]; k < ranked16.offsets[size_t(c) + 1]; ++k)
                rank_order.push_back(ranked16.entries[k].box);

            eyes.clear();
            pvs::sample_eye_points(cells, uint32_t(c), args.eval_eyes, kEvalSeed, eyes);
            for (const glm::vec3& e : eyes) {
                std::fill(full.begin(), full.end(), 0);
                for (uint32_t i : proven)
                    occludees.for_each_hidden(pvs::shadow_frustum(boxes[i], e),
                                              [&](uint32_t o) { full[o] = 1; });
                const Hidden f = count_bits(full, world);
                knee.full.objects += f.objects;
                knee.full.triangles += f.triangles;
                for (int which = 0; which < 2; ++which) {
                    const std::vector<uint32_t>& order = which == 0 ? rank_order : angle_order;
                    auto& out = which == 0 ? knee.ranked : knee.by_solid_angle;
                    std::fill(part.begin(), part.end(), 0);
                    size_t used = 0;
                    for (size_t ki = 0; ki < kKs.size(); ++ki) {
                        for (; used < kKs[ki] && used < order.size(); ++used) {
                            occludees.for_each_hidden(pvs::shadow_frustum(boxes[order[used]], e),
                                                      [&](uint32_t o) { part[o] = 1; });
                        }
                        const Hidden h = count_bits(part, world);
                        out[ki].objects += h.objects;
                        out[ki].triangles += h.triangles;
                    }
                }
            }
        }
    }
    const double knee_s = seconds_since(t0);
    CellKnee total;
    for (const CellKnee& k : knees) {  // in cell order: the same sums for any thread count
        total.full.objects += k.full.objects;
        total.full.triangles += k.full.triangles;
        for (size_t i = 0; i < kKs.size(); ++i) {
            total.ranked[i].objects += k.ranked[i].objects;
            total.ranked[i].triangles += k.ranked[i].triangles;
            total.by_solid_angle[i].objects += k.by_solid_angle[i].objects;
            total.by_solid_angle[i].triangles += k.by_solid_angle[i].triangles;
        }
    }
    const double eye_count = double(n_cells) * args.eval_eyes;
    uint64_t total_triangles = 0;
    for (const pvs::WorldObject& o : world.objects) total_triangles += o.triangle_count;

    nlohmann::ordered_json j;
    j["world"] = path;
    j["objects"] = world.objects.size();
    j["triangles"] = total_triangles;
    j["cells"] = cells.size();
    j["cell_size_m"] = args.cell_size_m;
    j["voxel_size_m"] = view.view.voxel_size_m;
    j["occluder_boxes"] = occluders.size();
    j["occluder_boxes_proven"] = proven.size();
    j["occluder_synthesis_s"] = occluder_s;
    j["ranking_s_median"] = median(times);
    j["ranking_cpu_s_median"] = median(cpu_times);
    j["ranking_per_cell_us"] = n_cells > 0 ? 1e6 * median(times) / double(n_cells) : 0.0;
    j["ranking16_s"] = ranking16_s;
    if (args.pvs) {
        j["sampled_pvs_s"] = pvs_s;
        j["sampled_pvs_cpu_s"] = pvs_cpu_s;
        j["ranking_over_sampled_pvs"] = pvs_s > 0 ? median(times) / pvs_s : 0.0;
        j["ranking_over_sampled_pvs_cpu"] = pvs_cpu_s > 0 ? median(cpu_times) / pvs_cpu_s : 0.0;
    }
    j["ranked_per_cell_mean"] = n_cells > 0 ? double(ranked.entries.size()) / double(n_cells) : 0.0;
    j["cells_with_none"] = figures.cells_with_none;
    j["ranked_score_mean"] = figures.score_mean;
    j["ranked_solid_angle_mean_sr"] = figures.solid_angle_mean_sr;
    j["knee_eyes"] = eye_count;
    j["knee_s"] = knee_s;
    j["full_set_hides_objects_per_eye"] = eye_count > 0 ? total.full.objects / eye_count : 0.0;
    j["full_set_hides_triangle_share_per_eye"] =
        eye_count > 0 && total_triangles > 0 ? total.full.triangles / eye_count / double(total_triangles)
                                             : 0.0;
    j["knee_ranked"] = knee_json(total.ranked, total.full);
    j["knee_by_solid_angle"] = knee_json(total.by_solid_angle, total.full);
    return j;
}

}  // namespace

int main(int argc, char** argv) {
    Args args;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        const bool has_value = a + 1 < argc;
        if (arg == "--cell-size" && has_value) {
            args.cell_size_m = std::atof(argv[++a]);
        } else if (arg == "--voxel-size" && has_value) {
            args.voxel_size_m = std::atof(argv[++a]);
        } else if (arg == "--repeats" && has_value) {
            args.repeats = std::max(1, std::atoi(argv[++a]));
        } else if (arg == "--eval-eyes" && has_value) {
            args.eval_eyes = uint32_t(std::max(1, std::atoi(argv[++a])));
        } else if (arg == "--threads" && has_value) {
            args.threads = std::atoi(argv[++a]);
        } else if (arg == "--no-pvs") {
            args.pvs = false;
        } else if (!arg.empty() && arg[0] == '-') {
            std::fprintf(
                stderr,
                "usage: bench_ranking [WORLD.glb ...] [--cell-size M] [--voxel-size M] [--repeats R] "
                "[--eval-eyes E] [--threads T] [--no-pvs]\n");
            return 2;
        } else {
            args.worlds.push_back(arg);
        }
    }
    if (args.worlds.empty()) {
        for (const char* w : {"samples/rooms.glb", "../shared/worlds/oa_dm4.glb"}) {
            const std::string found = find_world(w);
            if (!found.empty()) args.worlds.push_back(found);
        }
    }
    if (args.threads > 0) omp_set_num_threads(args.threads);
    nlohmann::ordered_json out;
    out["bench"] = "ranking";
    out["threads"] = omp_get_max_threads();
    out["repeats"] = args.repeats;
    out["eval_eyes_per_cell"] = args.eval_eyes;
    out["worlds"] = nlohmann::ordered_json::array();
    try {
        for (const std::string& w : args.worlds) out["worlds"].push_back(bench_world(w, args));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_ranking: %s\n", e.what());
        return 1;
    }
    std::cout << out.dump(2) << "\n";
    return 0;
}
