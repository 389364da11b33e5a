// SPDX-License-Identifier: MIT
// bench_panels: what the panel finders cover in a world: axis-aligned panels (occluders/panels.h) and
// slanted panels (occluders/slanted_panels.h), with their time.
//
//   bench_panels WORLD.glb [--thickness M] [--min-area M2]
//
// Slanted panels: opaque triangles off the axis planes grown into convex polygons (default thickness 1e-4 m,
// polygons of any area); prints JSON: counts, the off-axis opaque area, the area in slanted panels and its
// share, the area in panels of at least 1, 4, 16 and 64 m2, and seconds.
#include "bench/bench_util.h"
#include "core/context.h"
#include "io/gltf_loader.h"
#include "occluders/panels.h"
#include "occluders/slanted_panels.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: bench_panels WORLD.glb [--thickness M] [--min-area M2]\n");
        return 2;
    }
    double thickness = 1e-4, min_area = 0.0;
    for (int a = 2; a + 1 < argc; a += 2) {
        if (!std::strcmp(argv[a], "--thickness"))
            thickness = std::atof(argv[a + 1]);
        else if (!std::strcmp(argv[a], "--min-area"))
            min_area = std::atof(argv[a + 1]);
    }
    try {
        pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
        const pvs::World world = pvs::load_world(ctx, argv[1]);
        auto t0 = std::chrono::steady_clock::now();
        pvs::PanelFigures axis;
        const std::vector<pvs::Aabb> panels = pvs::find_panels(world, &axis);
        const double axis_s = pvs::bench::seconds_since(t0);
        t0 = std::chrono::steady_clock::now();
        pvs::SlantedPanelFigures fig;
        const std::vector<pvs::SlantedPanel> slanted =
            pvs::find_slanted_panels(world, thickness, min_area, &fig);
        const double slanted_s = pvs::bench::seconds_since(t0);
        nlohmann::ordered_json out;
        out["bench"] = "panels";
        out["world"] = argv[1];
        out["axis_panels"] = panels.size();
        out["axis_flat_triangles"] = axis.flat_triangles;
        out["axis_seconds"] = axis_s;
        out["slanted_thickness_m"] = thickness;
        out["slanted_min_area_m2"] = min_area;
        out["slanted_triangles"] = fig.slanted_triangles;
        out["slanted_area_m2"] = fig.slanted_area_m2;
        out["slanted_panels"] = fig.panels;
        out["slanted_triangles_in_panels"] = fig.triangles_in_panels;
        out["slanted_panel_area_m2"] = fig.panel_area_m2;
        out["slanted_panel_area_share"] =
            fig.slanted_area_m2 > 0 ? fig.panel_area_m2 / fig.slanted_area_m2 : 0.0;
        for (double at_least : {1.0, 4.0, 16.0, 64.0}) {
            double a = 0.0;
            size_t n = 0;
            for (const pvs::SlantedPanel& p : slanted) {
                if (p.area_m2 < at_least) continue;
                a += p.area_m2;
                ++n;
            }
            out["slanted_panels_at_least_m2"].push_back(
                {{"area_m2", at_least},
                 {"panels", n},
                 {"share_of_slanted_area", fig.slanted_area_m2 > 0 ? a / fig.slanted_area_m2 : 0.0}});
        }
        out["slanted_seconds"] = slanted_s;
        std::cout << out.dump(2) << std::endl;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}
