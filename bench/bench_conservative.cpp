// SPDX-License-Identifier: MIT
// bench_conservative: the conservative bake (BakeMode::kConservative) end to end, and how its time grows.
//
//   bench_conservative --suite [WORLD.glb ...] [--cells grid|octree|both] [--verify-rays N] [--repeats R]
//                      [BAKE OPTIONS]
//   bench_conservative --scaling [WORLD.glb] [--copies K] [--gap M] [--repeats R] [BAKE OPTIONS]
//
// BAKE OPTIONS are the declared options of core/config.h visit_options (--cell-size 2, --play-height 1.8,
// --epsilon 0.25, --threads 2 ...), with the limits pvsbake applies. The bake is always conservative.
//
// --suite: for each world (default: ../shared/worlds/oa_dm4.glb and ../shared/worlds/ctf_inyard.glb when
//   they exist, then samples/rooms.glb) and each cell kind, bake_world without its own verification, then
//   a verification (driver/verify.h) whose rays per eye are set from the eye points the cells really get, so
//   that at least --verify-rays rays (default 10,000,000) are traced. Per run: cells, conservative and
//   whole-bake seconds, seconds and share of the bake per stage (stages nest: view_volume holds voxelize
//   and flood, occluders holds solid, boxes, sight_probe and shrink, so shares do not add up to 1), cells
//   per second, misses (must be 0), rays, overestimation (objects and triangles, mean and median), the
//   share of the world's triangles the PVS lets through against the share the rays saw. Exit status 3
//   when any run has a miss (as pvsbake bake does).
// --scaling: WORLD (default ../shared/worlds/oa_dm4.glb, else samples/rooms.glb) and the same world K
//   times side by side along +X (default K = 4, at least --gap metres apart, default 10, the step rounded
//   up to whole cells so each copy gets the same cells), baked without verification; for 1x and Kx:
//   triangles, objects, cells, conservative and whole-bake seconds, and the ratios Kx / 1x of time, cells,
//   triangles and time per cell.
// Times are medians of --repeats (default 1) bakes. Prints one JSON document on stdout; a line per bake on
// stderr.
#include "bench/bench_util.h"
#include "cells/eyes.h"
#include "core/config.h"
#include "core/context.h"
#include "core/error.h"
#include "core/world.h"
#include "driver/bake.h"
#include "driver/verify.h"
#include "io/gltf_loader.h"
#include "rays/ray_scene.h"

#include <fmt/format.h>
#include <omp.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <type_traits>
#include <unordered_set>
#include <vector>

#ifndef PVSBAKE_SOURCE_DIR
#define PVSBAKE_SOURCE_DIR "."
#endif

namespace {

using pvs::bench::median;
using pvs::bench::seconds_since;

using Json = nlohmann::ordered_json;

constexpr int kExitMisses = 3;

struct Args {
    bool suite = false, scaling = false;
    std::vector<std::string> worlds;
    std::vector<pvs::CellKind> kinds{pvs::CellKind::kGrid, pvs::CellKind::kOctree};
    uint64_t verify_rays = 10'000'000;
    int repeats = 1;
    int copies = 4;
    double gap_m = 10.0;
    pvs::BakeConfig config;
};

double figure(const pvs::NamedValues& values, std::string_view key) {
    for (const auto& [k, v] : values)
        if (k == key) return v;
    return 0.0;
}

double ratio(double a, double b) {
    return b > 0.0 ? a / b : 0.0;
}

const char* kind_name(pvs::CellKind kind) {
    return kind == pvs::CellKind::kGrid ? "grid" : "octree";
}

// `relative` when it exists from the working directory, else under the source tree; empty when neither.
std::string find_world(const std::string& relative) {
    namespace fs = std::filesystem;
    if (fs::exists(relative)) return relative;
    const fs::path in_tree = fs::path(PVSBAKE_SOURCE_DIR) / relative;
    if (fs::exists(in_tree)) return in_tree.lexically_normal().string();
    return {};
}

// Parses `text` into a declared option's field, within the option's limits.
template <class T>
void parse_option_value(const pvs::OptionSpec& spec, const std::string& text, T& field) {
    if constexpr (std::is_same_v<T, bool>) {
        if (text == "1" || text == "true") {
            field = true;
        } else if (text == "0" || text == "false") {
            field = false;
        } else {
            throw pvs::bad_input(fmt::format("{} {}: wants true or false", spec.flag, text));
        }
    } else {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
            throw pvs::bad_input(fmt::format("{} {}: not a number", spec.flag, text));
        if (v < spec.min || v > spec.max)
            throw pvs::bad_input(fmt::format("{} {}: outside [{}, {}]", spec.flag, text, spec.min, spec.max));
        if constexpr (std::is_integral_v<T>) {
            if (v != std::floor(v) || v < double(std::numeric_limits<T>::min()) ||
                v > double(std::numeric_limits<T>::max()))
                throw pvs::bad_input(fmt::format("{} {}: wants a whole number", spec.flag, text));
        }
        field = static_cast<T>(v);
    }
}

// A number of this benchmark's own options, within [lo, hi].
double parse_number(const std::string& flag, const std::string& text, double lo, double hi, bool whole) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !(v >= lo && v <= hi) ||
        (whole && v != std::floor(v)))
        throw pvs::bad_input(fmt::format("{} {}: wants a {} in [{}, {}]", flag, text,
                                         whole ? "whole number" : "number", lo, hi));
    return v;
}

// Sets a declared bake option by flag; false when `flag` is not one. The verification's ray counts are
// this benchmark's own (--verify-rays is a floor here, not pvsbake's cap).
bool set_bake_option(pvs::BakeConfig& config, const std::string& flag, const std::string& value) {
    bool found = false;
    pvs::visit_options(config, [&](const pvs::OptionSpec& spec, auto& field) {
        if (found || flag != spec.flag) return;
        const std::string_view key(spec.key);
        if (key == "verify.ray_budget" || key == "verify.rays_per_eye") return;
        parse_option_value(spec, value, field);
        found = true;
    });
    return found;
}

void print_usage() {
    std::fprintf(stderr,
                 "usage: bench_conservative --suite [WORLD.glb ...] [--cells grid|octree|both] "
                 "[--verify-rays N] [--repeats R] [BAKE OPTIONS]\n"
                 "       bench_conservative --scaling [WORLD.glb] [--copies K] [--gap M] [--repeats R] "
                 "[BAKE OPTIONS]\n"
                 "BAKE OPTIONS: the options of pvsbake bake (--cell-size, --play-height, --epsilon, "
                 "--threads ...)\n");
}

Args parse_args(int argc, char** argv) {
    Args args;
    args.config.mode = pvs::BakeMode::kConservative;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        if (arg == "--suite") {
            args.suite = true;
            continue;
        }
        if (arg == "--scaling") {
            args.scaling = true;
            continue;
        }
        if (arg.rfind("--", 0) != 0) {
            args.worlds.push_back(arg);
            continue;
        }
        if (a + 1 >= argc) throw pvs::bad_input(fmt::format("{}: wants a value", arg));
        const std::string value = argv[++a];
        if (arg == "--cells") {
            if (value == "grid") {
                args.kinds = {pvs::CellKind::kGrid};
            } else if (value == "octree") {
                args.kinds = {pvs::CellKind::kOctree};
            } else if (value == "both") {
                args.kinds = {pvs::CellKind::kGrid, pvs::CellKind::kOctree};
            } else {
                throw pvs::bad_input(fmt::format("--cells {}: use grid, octree or both", value));
            }
        } else if (arg == "--verify-rays") {
            args.verify_rays = uint64_t(parse_number(arg, value, 1, 1e12, true));
        } else if (arg == "--repeats") {
            args.repeats = int(parse_number(arg, value, 1, 1000, true));
        } else if (arg == "--copies") {
            args.copies = int(parse_number(arg, value, 2, 64, true));
        } else if (arg == "--gap") {
            args.gap_m = parse_number(arg, value, 0.01, 1e5, false);
        } else if (!set_bake_option(args.config, arg, value)) {
            throw pvs::bad_input(fmt::format("{}: unknown option", arg));
        }
    }
    if (args.suite == args.scaling) throw pvs::bad_input("give exactly one of --suite and --scaling");
    if (args.scaling && args.worlds.size() > 1) throw pvs::bad_input("--scaling takes one world");
    if (args.worlds.empty()) {
        std::vector<std::string> defaults;
        if (args.suite) {
            defaults = {"../shared/worlds/oa_dm4.glb", "../shared/worlds/ctf_inyard.glb",
                        "samples/rooms.glb"};
        } else {
            defaults = {"../shared/worlds/oa_dm4.glb", "samples/rooms.glb"};
        }
        for (const std::string& d : defaults) {
            const std::string found = find_world(d);
            if (found.empty()) continue;
            args.worlds.push_back(found);
            if (args.scaling) break;
        }
        if (args.worlds.empty()) throw pvs::bad_input("no world given and none of the default worlds found");
    }
    args.config.verify.enabled = false;  // verification is run here, with its ray count set per run
    pvs::validate(args.config);
    return args;
}

// The resolved bake options, less those this benchmark sets per run (`skipped`).
Json parameters_json(const pvs::BakeConfig& config, std::initializer_list<std::string_view> skipped) {
    Json out = Json::object();
    for (const auto& [k, v] : pvs::resolved_parameters(config))
        if (std::find(skipped.begin(), skipped.end(), k) == skipped.end()) out[k] = v;
    return out;
}

pvs::Context quiet_context() {
    return pvs::Context(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
}

// One bake: its data, wall time and stage timings.
struct TimedBake {
    pvs::BakeData bake;
    double seconds = 0.0;
    std::vector<std::pair<std::string, double>> timings;
};

TimedBake timed_bake(const pvs::BakeConfig& config, const pvs::World& world) {
    pvs::Context ctx = quiet_context();
    TimedBake out;
    const auto t0 = std::chrono::steady_clock::now();
    out.bake = pvs::bake_world(ctx, config, world, world.source_path, "");
    out.seconds = seconds_since(t0);
    out.timings = ctx.timings();
    return out;
}

// Bakes `repeats` times; the first bake's data, medians of the times. Stage seconds are summed per name
// within a bake (a stage may run twice), then the median over bakes is taken, in first-seen order.
struct RepeatedBake {
    pvs::BakeData bake;
    double seconds = 0.0;
    double conservative_seconds = 0.0;
    std::vector<std::pair<std::string, double>> stages;
    bool same_pvs = true;  // every repeat gave the same PVS and cells
};

RepeatedBake repeated_bake(const pvs::BakeConfig& config, const pvs::World& world, int repeats,
                           const std::string& label) {
    RepeatedBake out;
    std::vector<double> wall, conservative;
    std::vector<std::string> order;
    std::map<std::string, std::vector<double>> per_stage;
    for (int r = 0; r < repeats; ++r) {
        TimedBake b = timed_bake(config, world);
        std::fprintf(stderr, "bench_conservative: %s: %zu cells, bake %.2f s (conservative %.2f s)\n",
                     label.c_str(), b.bake.cells.size(), b.seconds,
                     figure(b.bake.run.figures, "conservative_seconds"));
        wall.push_back(b.seconds);
        conservative.push_back(figure(b.bake.run.figures, "conservative_seconds"));
        std::map<std::string, double> sums;
        for (const auto& [stage, s] : b.timings) {
            if (!per_stage.count(stage) && !sums.count(stage)) order.push_back(stage);
            sums[stage] += s;
        }
        for (const auto& [stage, s] : sums) per_stage[stage].push_back(s);
        if (r == 0) {
            out.bake = std::move(b.bake);
        } else {
            out.same_pvs =
                out.same_pvs && b.bake.pvs == out.bake.pvs && b.bake.cells.size() == out.bake.cells.size();
        }
    }
    out.seconds = median(wall);
    out.conservative_seconds = median(conservative);
    for (const std::string& stage : order) out.stages.emplace_back(stage, median(per_stage[stage]));
    return out;
}

// Eye points the verification will draw in each cell (cells without eye space get none), summed.
uint64_t count_verify_eyes(const pvs::CellSet& cells, const pvs::SampleConfig& rays) {
    uint64_t eyes = 0;
#pragma omp parallel
    {
        std::vector<glm::vec3> points;
#pragma omp for schedule(dynamic, 16) reduction(+ : eyes)
        for (int64_t c = 0; c < int64_t(cells.size()); ++c) {
            points.clear();
            pvs::sample_eye_points(cells, uint32_t(c), rays.eyes_per_cell, rays.seed, points);
            eyes += points.size();
        }
    }
    return eyes;
}

struct Verification {
    pvs::VerifyResult result;
    uint64_t eyes = 0;
    double scene_seconds = 0.0;
};

// Verifies with rays per eye = ceil(target / eyes), no cap, so at least `target` rays are traced.
Verification verify_at_least(const pvs::BakeConfig& config, const pvs::World& world,
                             const pvs::BakeData& bake, uint64_t target) {
    Verification out;
    pvs::VerifyConfig vc = config.verify;
    vc.enabled = true;
    out.eyes = count_verify_eyes(bake.cells, vc.rays);
    if (out.eyes == 0) throw pvs::bad_input(fmt::format("{}: no cell holds an eye point", world.source_path));
    const uint64_t per_eye = std::max<uint64_t>((target + out.eyes - 1) / out.eyes, 16);
    if (per_eye > std::numeric_limits<uint32_t>::max())
        throw pvs::bad_input(fmt::format("--verify-rays {}: too many rays per eye point", target));
    vc.rays.rays_per_eye = uint32_t(per_eye);
    vc.rays.ray_budget = 0;
    pvs::Context ctx = quiet_context();
    const auto t0 = std::chrono::steady_clock::now();
    pvs::RayScene scene(ctx, world, pvs::BuildQuality::kMedium, config.run.threads);
    out.scene_seconds = seconds_since(t0);
    out.result = pvs::verify_pvs(ctx, vc, world, scene, bake.cells, bake.pvs);
    return out;
}

int run_suite(const Args& args) {
    Json runs = Json::array();
    bool any_miss = false, short_of_rays = false;
    for (const std::string& path : args.worlds) {
        pvs::Context load_ctx = quiet_context();
        const auto t0 = std::chrono::steady_clock::now();
        const pvs::World world = pvs::load_world(load_ctx, path);
        const double load_seconds = seconds_since(t0);
        for (pvs::CellKind kind : args.kinds) {
            pvs::BakeConfig config = args.config;
            config.cells.kind = kind;
            const std::string label = fmt::format("{} {}", path, kind_name(kind));
            const RepeatedBake b = repeated_bake(config, world, args.repeats, label);
            const Verification v = verify_at_least(config, world, b.bake, args.verify_rays);
            const pvs::VerifyResult& r = v.result;
            std::fprintf(stderr,
                         "bench_conservative: %s: verified %.1f M rays in %.2f s, %llu missed pairs\n",
                         label.c_str(), double(r.rays) / 1e6, r.seconds, (unsigned long long)r.missed_pairs);
            any_miss |= r.missed_pairs > 0 || r.missed_rays > 0;
            short_of_rays |= r.rays < args.verify_rays;
            const double cells = double(b.bake.cells.size());

            Json run;
            run["world"] = path;
            run["cells_kind"] = kind_name(kind);
            run["objects"] = world.objects.size();
            run["triangles"] = world.triangles.size();
            run["load_seconds"] = load_seconds;
            run["cells"] = b.bake.cells.size();
            run["cell_size_mean_m"] = figure(b.bake.figures, "cell_size_mean_m");
            run["view_voxel_size_m"] = figure(b.bake.figures, "view_voxel_size_m");
            run["occluder_boxes_proven"] = figure(b.bake.figures, "occluder_boxes_proven");
            run["conservative_seconds"] = b.conservative_seconds;
            run["bake_seconds"] = b.seconds;
            run["conservative_share_of_bake"] = ratio(b.conservative_seconds, b.seconds);
            run["cells_per_second"] = ratio(cells, b.conservative_seconds);
            Json stages = Json::object(), shares = Json::object();
            for (const auto& [stage, s] : b.stages) {
                stages[stage] = s;
                shares[stage] = ratio(s, b.seconds);
            }
            run["stage_seconds"] = stages;
            run["stage_share_of_bake"] = shares;
            run["repeats"] = args.repeats;
            run["same_pvs_every_repeat"] = b.same_pvs;
            run["pvs_objects_mean"] = figure(b.bake.figures, "pvs_objects_mean");
            run["pvs_share_of_objects_mean"] = figure(b.bake.figures, "pvs_share_of_objects_mean");
            run["verify_rays_target"] = args.verify_rays;
            run["verify_rays"] = r.rays;
            run["verify_eyes"] = v.eyes;
            run["verify_rays_per_eye"] = r.rays_per_eye;
            run["verify_seconds"] = r.seconds;
            run["verify_scene_seconds"] = v.scene_seconds;
            run["misses"] = r.missed_pairs;
            run["missed_rays"] = r.missed_rays;
            run["cells_with_misses"] = r.cells_with_misses;
            run["cells_with_empty_sample"] = r.cells_with_empty_sample;
            run["overestimation_objects_mean"] = r.overestimation_mean;
            run["overestimation_objects_median"] = r.overestimation_median;
            run["overestimation_triangles_mean"] = r.overestimation_tri_mean;
            run["overestimation_triangles_median"] = r.overestimation_tri_median;
            run["pvs_triangle_share_mean"] = r.pvs_triangle_share_mean;
            run["rays_triangle_share_mean"] = r.sampled_triangle_share_mean;
            run["pvs_over_rays_triangle_share"] =
                ratio(r.pvs_triangle_share_mean, r.sampled_triangle_share_mean);
            runs.push_back(run);
        }
    }
    Json out;
    out["bench"] = "conservative_suite";
    out["threads"] = omp_get_max_threads();
    out["parameters"] = parameters_json(
        args.config, {"cells.kind", "verify.enabled", "verify.rays_per_eye", "verify.ray_budget"});
    out["runs"] = runs;
    out["any_miss"] = any_miss;
    out["every_run_traced_verify_rays"] = !short_of_rays;
    std::cout << out.dump(2) << std::endl;
    if (short_of_rays)
        std::fprintf(stderr, "bench_conservative: a verification traced fewer rays than asked\n");
    return any_miss ? kExitMisses : (short_of_rays ? 1 : 0);
}

// `world` `copies` times along +X, copy k moved by k * step: positions, triangles and their flags, objects
// (copy k > 0 renamed "<name>#copy<k>", unique; node path under "copy<k>/"), view seeds and view volume
// boxes, load stats summed; bounds recomputed over all triangles.
pvs::World replicate_world(const pvs::World& world, int copies, float step) {
    pvs::World out;
    out.source_path = fmt::format("{} x{}", world.source_path, copies);
    out.positions.reserve(world.positions.size() * copies);
    out.triangles.reserve(world.triangles.size() * copies);
    out.objects.reserve(world.objects.size() * copies);
    std::unordered_set<std::string> names;
    for (const pvs::WorldObject& o : world.objects) names.insert(o.name);
    for (int k = 0; k < copies; ++k) {
        const glm::vec3 offset(step * float(k), 0.0f, 0.0f);
        const uint32_t first_vertex = uint32_t(out.positions.size());
        const uint32_t first_triangle = uint32_t(out.triangles.size());
        for (const glm::vec3& p : world.positions) out.positions.push_back(p + offset);
        for (const pvs::Triangle& t : world.triangles)
            out.triangles.push_back(
                pvs::Triangle{{t.v[0] + first_vertex, t.v[1] + first_vertex, t.v[2] + first_vertex}});
        out.triangle_opaque.insert(out.triangle_opaque.end(), world.triangle_opaque.begin(),
                                   world.triangle_opaque.end());
        out.triangle_double_sided.insert(out.triangle_double_sided.end(), world.triangle_double_sided.begin(),
                                         world.triangle_double_sided.end());
        for (const pvs::WorldObject& o : world.objects) {
            pvs::WorldObject c = o;
            c.first_triangle += first_triangle;
            if (!c.bounds.is_empty()) c.bounds = pvs::Aabb::of(o.bounds.min + offset, o.bounds.max + offset);
            if (k > 0) {
                std::string name = fmt::format("{}#copy{}", o.name, k);
                while (!names.insert(name).second) name += "_";
                c.name = name;
                c.node_path = fmt::format("copy{}/{}", k, o.node_path);
            }
            out.objects.push_back(std::move(c));
        }
        for (const glm::vec3& s : world.view_seeds) out.view_seeds.push_back(s + offset);
        for (const pvs::Aabb& b : world.view_volume_boxes)
            out.view_volume_boxes.push_back(pvs::Aabb::of(b.min + offset, b.max + offset));
        out.stats.degenerate_triangles_dropped += world.stats.degenerate_triangles_dropped;
        out.stats.primitives_skipped += world.stats.primitives_skipped;
        out.stats.nodes_visited += world.stats.nodes_visited;
    }
    for (const pvs::Triangle& t : out.triangles)
        for (uint32_t v : t.v) out.bounds.extend(out.positions[v]);
    return out;
}

Json scale_figures(const pvs::World& world, int copies, const RepeatedBake& b) {
    Json j;
    j["copies"] = copies;
    j["triangles"] = world.triangles.size();
    j["objects"] = world.objects.size();
    j["cells"] = b.bake.cells.size();
    j["view_voxel_size_m"] = figure(b.bake.figures, "view_voxel_size_m");
    j["occluder_boxes_proven"] = figure(b.bake.figures, "occluder_boxes_proven");
    j["pvs_objects_mean"] = figure(b.bake.figures, "pvs_objects_mean");
    j["conservative_seconds"] = b.conservative_seconds;
    j["bake_seconds"] = b.seconds;
    j["conservative_seconds_per_cell"] = ratio(b.conservative_seconds, double(b.bake.cells.size()));
    j["bake_seconds_per_cell"] = ratio(b.seconds, double(b.bake.cells.size()));
    Json stages = Json::object();
    for (const auto& [stage, s] : b.stages) stages[stage] = s;
    j["stage_seconds"] = stages;
    return j;
}

int run_scaling(const Args& args) {
    const std::string& path = args.worlds.front();
    pvs::Context load_ctx = quiet_context();
    const pvs::World one = pvs::load_world(load_ctx, path);
    // Copies `gap_m` apart at least, the step rounded up to whole cells (grid cells or octree root cells, a
    // multiple of the default voxel), so every copy gets the same cells as the original.
    const double cell_m = args.config.cells.kind == pvs::CellKind::kGrid ? args.config.cells.cell_size_m
                                                                         : args.config.cells.root_cell_size_m;
    const double step_m = std::ceil((double(one.bounds.size().x) + args.gap_m) / cell_m) * cell_m;
    const pvs::World many = replicate_world(one, args.copies, float(step_m));
    const RepeatedBake b1 = repeated_bake(args.config, one, args.repeats, fmt::format("{} 1x", path));
    const RepeatedBake bk =
        repeated_bake(args.config, many, args.repeats, fmt::format("{} {}x", path, args.copies));
    const double c1 = double(b1.bake.cells.size()), ck = double(bk.bake.cells.size());

    Json out;
    out["bench"] = "conservative_scaling";
    out["world"] = path;
    out["cells_kind"] = kind_name(args.config.cells.kind);
    out["copies"] = args.copies;
    out["gap_m"] = args.gap_m;
    out["step_m"] = step_m;
    out["repeats"] = args.repeats;
    out["threads"] = omp_get_max_threads();
    out["parameters"] = parameters_json(
        args.config, {"verify.enabled", "verify.eyes_per_cell", "verify.rays_per_eye", "verify.aimed_share",
                      "verify.aimed_listed_share", "verify.neighbour_share", "verify.ray_budget",
                      "verify.seed", "verify.max_misses_reported"});
    out["one"] = scale_figures(one, 1, b1);
    out["many"] = scale_figures(many, args.copies, bk);
    Json r;
    r["triangles"] = ratio(double(many.triangles.size()), double(one.triangles.size()));
    r["objects"] = ratio(double(many.objects.size()), double(one.objects.size()));
    r["cells"] = ratio(ck, c1);
    r["conservative_seconds"] = ratio(bk.conservative_seconds, b1.conservative_seconds);
    r["bake_seconds"] = ratio(bk.seconds, b1.seconds);
    r["conservative_seconds_per_cell"] =
        ratio(ratio(bk.conservative_seconds, ck), ratio(b1.conservative_seconds, c1));
    r["bake_seconds_per_cell"] = ratio(ratio(bk.seconds, ck), ratio(b1.seconds, c1));
    out["ratios_many_over_one"] = r;
    std::cout << out.dump(2) << std::endl;
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2) {
            print_usage();
            return 2;
        }
        const Args args = parse_args(argc, argv);
        if (args.config.run.threads > 0) omp_set_num_threads(args.config.run.threads);
        return args.suite ? run_suite(args) : run_scaling(args);
    } catch (const pvs::Error& e) {
        std::fprintf(stderr, "bench_conservative: %s\n", e.what());
        if (e.kind() == pvs::ErrorKind::kBadInput) print_usage();
        return pvs::exit_status(e.kind());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_conservative: internal error: %s\n", e.what());
        return 1;
    }
}
