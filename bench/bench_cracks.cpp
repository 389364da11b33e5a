// SPDX-License-Identifier: MIT
// bench_cracks: the crack test set at full size (samples/crack_set.h; docs/ALGORITHMS.md#crack-test-set).
//
//   bench_cracks [--tolerance T] [--widths w1,w2,...] [--cases N] [--seeds s1,s2,...] [--threads N]
//                [--keep DIR] [--epsilon E] [--solid-only]
//
// For each seed and each width (default: 0.5 T, T, 2 T, 5 mm, 1 cm, 5 cm, 50 cm at T = 1 mm) a world of N
// cases (default 200; slits, L-slits, seams, T-junction seams and holes in turn, walls 2, 10 and 30 cm thick,
// at random orientations and positions) is baked in the conservative mode with gap tolerance T and no
// verification; a case is FOUND when room B left the proven solid (the occluder stage opened the opening;
// its PVS must then list the target: "listed" counts that too). Prints JSON: per width and kind, cases found
// of cases, listed, and the time; "pass" is true when every case at or above T was found and none below
// T / 2 was. A line per width on stderr. --solid-only runs the occluder stage alone (no PVS: "listed" is
// null), for many cases fast.
#include "bench/bench_util.h"
#include "cells/view_volume.h"
#include "core/config.h"
#include "core/context.h"
#include "core/error.h"
#include "driver/bake.h"
#include "io/gltf_loader.h"
#include "io/gltf_writer.h"
#include "rays/ray_scene.h"
#include "samples/crack_set.h"

#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace {

using Json = nlohmann::ordered_json;
using pvs::bench::seconds_since;

std::vector<double> parse_list(const char* flag, const char* text) {
    std::vector<double> out;
    const std::string s(text);
    size_t at = 0;
    while (at <= s.size()) {
        const size_t comma = std::min(s.find(',', at), s.size());
        char* end = nullptr;
        const std::string item = s.substr(at, comma - at);
        const double v = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0')
            throw pvs::bad_input(fmt::format("{} {}: '{}' is not a number", flag, text, item));
        out.push_back(v);
        at = comma + 1;
    }
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        double tolerance = pvs::kDefaultGapToleranceM;
        std::vector<double> widths, seeds = {1};
        uint32_t cases = 200;
        int threads = 0;
        std::string keep;
        bool solid_only = false;
        pvs::BakeConfig config;
        for (int i = 1; i < argc; ++i) {
            const std::string a = argv[i];
            const bool has_value = i + 1 < argc;
            if (a == "--tolerance" && has_value) {
                tolerance = std::strtod(argv[++i], nullptr);
            } else if (a == "--widths" && has_value) {
                widths = parse_list("--widths", argv[++i]);
            } else if (a == "--seeds" && has_value) {
                seeds = parse_list("--seeds", argv[++i]);
            } else if (a == "--cases" && has_value) {
                cases = uint32_t(std::strtoul(argv[++i], nullptr, 10));
            } else if (a == "--threads" && has_value) {
                threads = std::atoi(argv[++i]);
            } else if (a == "--keep" && has_value) {
                keep = argv[++i];
            } else if (a == "--solid-only") {
                solid_only = true;
            } else if (a == "--epsilon" && has_value) {
                config.conservative.epsilon_m = std::strtod(argv[++i], nullptr);
            } else {
                std::fprintf(stderr,
                             "bench_cracks: unknown argument '%s' (see the comment at the top of "
                             "bench/bench_cracks.cpp)\n",
                             a.c_str());
                return 2;
            }
        }
        if (!(tolerance > 0.0) || cases == 0)
            throw pvs::bad_input("bench_cracks: --tolerance and --cases must be > 0");
        if (widths.empty()) widths = {0.5 * tolerance, tolerance, 2 * tolerance, 0.005, 0.01, 0.05, 0.5};
        if (threads > 0) omp_set_num_threads(threads);
        config.mode = pvs::BakeMode::kConservative;
        config.gap.tolerance_m = tolerance;
        config.verify.enabled = false;
        config.run.threads = threads;
        pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
        const std::filesystem::path dir =
            keep.empty() ? std::filesystem::temp_directory_path() / fmt::format("bench_cracks_{}", ::getpid())
                         : std::filesystem::path(keep);
        std::filesystem::create_directories(dir);

        Json runs = Json::array();
        bool pass = true;
        for (const double seed : seeds) {
            for (const double width : widths) {
                pvs::CrackSetSpec spec;
                spec.widths_m = {float(width)};
                spec.cases_per_width = cases;
                spec.seed = uint64_t(seed);
                const pvs::CrackSet set = pvs::make_crack_set(spec);
                const std::string path =
                    (dir / fmt::format("cracks_{}_{}.glb", uint64_t(seed), width)).string();
                pvs::write_glb(set.scene, path);
                const auto t0 = std::chrono::steady_clock::now();
                const pvs::World world = pvs::load_world(ctx, path);
                pvs::BakeData bake;
                if (!solid_only) bake = pvs::bake_world(ctx, config, world, path, "");
                // The proven solid of the same occluder stage (deterministic).
                const pvs::ViewVolume view =
                    pvs::build_view_volume(ctx, pvs::view_volume_config(config), world);
                const pvs::RayScene scene(ctx, world);
                pvs::OccluderFigures figures;
                pvs::BlockFigures blocks;
                pvs::ShrunkOccluders shrunk;
                pvs::solver_occluders(ctx, config, world, view, scene, figures, blocks, shrunk);
                const double seconds = seconds_since(t0);
                std::map<std::string, uint32_t> object_of;
                for (uint32_t o = 0; o < world.objects.size(); ++o) object_of[world.objects[o].name] = o;
                struct Count {
                    uint32_t found = 0, listed = 0, cases = 0;
                };
                std::map<std::string, Count> by_kind;
                uint32_t found = 0, listed_all = 0, no_cell = 0;
                for (const pvs::CrackCase& c : set.cases) {
                    const int32_t cell = solid_only ? 0 : bake.cells.find(c.witness_eye);
                    const bool listed =
                        !solid_only && cell >= 0 && bake.pvs.test(uint32_t(cell), object_of.at(c.target));
                    const bool opened = !shrunk.solid.contains(c.room_b_point);
                    no_cell += cell < 0;
                    found += opened;
                    listed_all += listed;
                    Count& k = by_kind[pvs::to_string(c.kind)];
                    k.found += opened;
                    k.listed += listed;
                    ++k.cases;
                }
                const bool must_find = width >= tolerance, must_close = width < 0.5 * tolerance;
                const bool ok = (!must_find || found == set.cases.size()) && (!must_close || found == 0);
                pass = pass && ok;
                Json kinds = Json::object();
                for (const auto& [name, k] : by_kind)
                    kinds[name] = {{"found", k.found},
                                   {"listed", solid_only ? Json() : Json(k.listed)},
                                   {"cases", k.cases}};
                Json run = {{"seed", uint64_t(seed)},
                            {"width_m", width},
                            {"cases", set.cases.size()},
                            {"found", found},
                            {"listed", solid_only ? Json() : Json(listed_all)},
                            {"no_cell", no_cell},
                            {"kinds", kinds},
                            {"ok", ok},
                            {"seconds", seconds},
                            {"cells", bake.cells.size()}};
                std::fprintf(stderr, "bench_cracks: seed %llu width %.4g m: %u of %zu found (%s), %.1f s\n",
                             (unsigned long long)seed, width, found, set.cases.size(), ok ? "ok" : "FAIL",
                             seconds);
                runs.push_back(run);
                if (keep.empty()) std::filesystem::remove(path);
            }
        }
        if (keep.empty()) std::filesystem::remove_all(dir);
        const Json out = {{"bench", "cracks"},
                          {"tolerance_m", tolerance},
                          {"cases_per_width", cases},
                          {"pass", pass},
                          {"runs", runs}};
        std::cout << out.dump(2) << "\n";
        return pass ? 0 : 1;
    } catch (const pvs::Error& e) {
        std::fprintf(stderr, "bench_cracks: %s\n", e.what());
        return e.kind() == pvs::ErrorKind::kBadInput ? 2 : 1;
    }
}
