// SPDX-License-Identifier: MIT
// edit_world: writes a world again, with edits of the kind a level designer makes between two bakes:
// an object moved or removed, objects within a box removed (a wall), a hole cut (a door), a crate added;
// and, for measures of scale, the whole world tiled NX x NZ times (closed in walls first with --enclose,
// for a big world of sealed copies).
// The incremental re-bake (`pvsbake bake NEW.glb --reuse OLD.h5`) is measured and tested on its output.
//
//   edit_world IN.glb OUT.glb [--move NAME dx,dy,dz] [--remove NAME] [--remove-in BOX] [--cut BOX]
//                             [--add-box NAME BOX] [--enclose T] [--tile NX,NZ [--tile-gap M]]
//                                                           (BOX: x0,y0,z0,x1,y1,z1 in metres)
//
// Every object is written as it was loaded (world-space triangles, one node per object and kind of
// triangle: opaque or see-through, one- or two-sided), with its flags, the view seeds and the view-volume
// boxes; so write the world before the edit with this tool too (no edit), and bake both. Edits apply in
// the order given. Deterministic: the same arguments give the same bytes.
#include "core/context.h"
#include "core/world.h"
#include "io/gltf_loader.h"
#include "io/gltf_writer.h"
#include "samples/world_edit.h"

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <array>
#include <cstdio>
#include <exception>
#include <map>
#include <string>
#include <vector>

namespace {

pvs::Aabb parse_box(const std::vector<double>& v, const std::string& option) {
    if (v.size() != 6 || v[0] > v[3] || v[1] > v[4] || v[2] > v[5])
        throw CLI::ValidationError(option, "a box is x0,y0,z0,x1,y1,z1 with x0 <= x1, y0 <= y1, z0 <= z1");
    return pvs::Aabb::of(glm::vec3(float(v[0]), float(v[1]), float(v[2])),
                         glm::vec3(float(v[3]), float(v[4]), float(v[5])));
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "edit_world: write a world again, with edits (objects moved, removed, a hole cut, a crate "
        "added)"};
    std::string in_path, out_path;
    std::vector<pvs::WorldEdit> edits;
    app.add_option("in", in_path, "the world, glTF 2.0")->required()->check(CLI::ExistingFile);
    app.add_option("out", out_path, "the edited world to write (.glb)")->required();
    app.add_option_function<std::vector<std::string>>(
           "--move",
           [&](const std::vector<std::string>& v) {
               double dx, dy, dz;
               if (std::sscanf(v[1].c_str(), "%lf,%lf,%lf", &dx, &dy, &dz) != 3)
                   throw CLI::ValidationError("--move", "the offset is dx,dy,dz");
               edits.push_back(
                   {pvs::WorldEdit::Kind::kMove, v[0], {}, glm::vec3(float(dx), float(dy), float(dz))});
           },
           "move the object NAME by dx,dy,dz")
        ->expected(2)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
        ->trigger_on_parse();
    app.add_option_function<std::string>(
           "--remove",
           [&](const std::string& name) {
               edits.push_back({pvs::WorldEdit::Kind::kRemove, name, {}, {}});
           },
           "remove the object NAME")
        ->trigger_on_parse();
    app.add_option_function<std::vector<double>>(
           "--remove-in",
           [&](const std::vector<double>& v) {
               edits.push_back({pvs::WorldEdit::Kind::kRemoveIn, "", parse_box(v, "--remove-in"), {}});
           },
           "remove every object lying wholly in the box x0,y0,z0,x1,y1,z1")
        ->delimiter(',')
        ->trigger_on_parse();
    app.add_option_function<std::vector<double>>(
           "--cut",
           [&](const std::vector<double>& v) {
               edits.push_back({pvs::WorldEdit::Kind::kCut, "", parse_box(v, "--cut"), {}});
           },
           "cut away what lies in the box x0,y0,z0,x1,y1,z1 (a hole: triangles are clipped; the hole's "
           "sides stay open, so through a closed wall it opens the wall's inside: for a door in such a wall, "
           "--remove it and --add-box its pieces)")
        ->delimiter(',')
        ->trigger_on_parse();
    app.add_option_function<std::vector<std::string>>(
           "--add-box",
           [&](const std::vector<std::string>& v) {
               std::vector<double> b(6);
               if (std::sscanf(v[1].c_str(), "%lf,%lf,%lf,%lf,%lf,%lf", &b[0], &b[1], &b[2], &b[3], &b[4],
                               &b[5]) != 6)
                   throw CLI::ValidationError("--add-box", "the box is x0,y0,z0,x1,y1,z1");
               edits.push_back({pvs::WorldEdit::Kind::kAddBox, v[0], parse_box(b, "--add-box"), {}});
           },
           "add a closed opaque box (a crate) NAME x0,y0,z0,x1,y1,z1")
        ->expected(2)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
        ->trigger_on_parse();
    std::vector<int> tile;
    double tile_gap = 1.0;
    app.add_option("--tile", tile,
                   "copy the whole edited world NX,NZ times along x and z (a big world; applied after the "
                   "other edits, names get \"@i,j\")")
        ->delimiter(',')
        ->expected(2)
        ->check(CLI::Range(1, 64));
    app.add_option("--tile-gap", tile_gap, "metres between tiled copies")->check(CLI::Range(0.0, 1e6));
    double enclose = 0.0;
    app.add_option(
           "--enclose", enclose,
           "close the world in four walls T metres thick, T metres outside its bounds in x and z, from "
           "T below its bottom up to its top: sight out through a leaking level's openings stops "
           "there, so with --tile the copies do not see each other (applied after the other edits, "
           "before --tile, whose step then includes the walls)")
        ->check(CLI::Range(0.0, 1e3));
    CLI11_PARSE(app, argc, argv);
    try {
        pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
        const pvs::World world = pvs::load_world(ctx, in_path);
        pvs::Aabb outer = world.bounds;  // the world with its walls
        if (enclose > 0.0) {
            const pvs::Enclosure e = pvs::enclosure(world.bounds, float(enclose));
            edits.insert(edits.end(), e.walls.begin(), e.walls.end());
            outer = e.outer;
        }
        if (!tile.empty()) {
            pvs::WorldEdit t{pvs::WorldEdit::Kind::kTile, "", {}, outer.size() + float(tile_gap)};
            t.copies = glm::ivec2(tile[0], tile[1]);
            edits.push_back(t);
        }
        const pvs::SceneDesc scene = pvs::edited_world(world, edits);
        pvs::write_glb(scene, out_path);
        std::fprintf(stderr, "wrote %s: %zu nodes after %zu edits\n", out_path.c_str(), scene.nodes.size(),
                     edits.size());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
