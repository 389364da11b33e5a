// SPDX-License-Identifier: MIT
// The incremental re-bake (docs/ALGORITHMS.md#reuse): the geometry print, and bakes of an edited sample world
// with --reuse of the bake before the edit, which must write the file a full bake of the edited world
// writes (the same outside /run, docs/FORMAT.md) while testing fewer pairs.
#include "core/context.h"
#include "core/error.h"
#include "io/gltf_loader.h"
#include "io/gltf_writer.h"
#include "pvs/conservative.h"
#include "pvs/reuse.h"
#include "samples/world_edit.h"
#include "tests/test_util.h"
#include "tests/world_builder.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include <sys/wait.h>

namespace pvs {
namespace {

// Runs pvsbake with `args` (its log in `log`); returns its exit status.
int run(const std::string& args, const std::string& log) {
    const int status =
        std::system((std::string(PVSBAKE_BINARY) + " " + args + " > '" + log + "' 2>&1").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The sample world's bake, made cheap: few probe eyes, no gap lines, no seal rays, no verification.
std::string bake_args(const std::string& world, const std::string& out) {
    return "bake '" + world + "' -o '" + out +
           "' -q --no-verify --threads 2 --occluder-probe-eyes 64 --occluder-gap-lines 0 "
           "--occluder-seal-rays 0";
}

double run_figure(const std::string& report, const std::string& name) {
    const nlohmann::json j = nlohmann::json::parse(test::read_file(report));
    return j.at("run").at("figures").at(name).get<double>();
}

Aabb bounds_of(const World& world, const std::string& name) {
    for (const WorldObject& o : world.objects)
        if (o.name == name) return o.bounds;
    ADD_FAILURE() << "no object " << name;
    return {};
}

struct EditCase {
    const char* name;
    std::vector<WorldEdit> (*edits)(const World&);
    const char* options = "";  // more bake options, for the old, the full and the re-bake alike
};

// Its name, so that the test's listed name is the same in every build (not the struct's bytes).
void PrintTo(const EditCase& e, std::ostream* os) { *os << e.name; }

// A crate moved within its room, and a closed wall between two rooms removed.
std::vector<WorldEdit> moved_crate_and_removed_wall(const World&) {
    WorldEdit move{WorldEdit::Kind::kMove, "crate_1_1_0", {}, glm::vec3(1.0f, 0.0f, 0.5f)};
    WorldEdit remove{WorldEdit::Kind::kRemove, "wall_1_1_x", {}, {}};
    return {move, remove};
}

// A door made in a closed wall (the wall replaced by its pieces around a doorway, as a level editor's CSG
// leaves it: the wall stays closed), and a crate added in a room.
std::vector<WorldEdit> door_and_new_crate(const World& world) {
    // 1.2 m wide and 2.2 m high along the wall's long side, through its whole thickness.
    const Aabb wall = bounds_of(world, "wall_1_2_x");
    const int along = wall.size().x > wall.size().z ? 0 : 2;
    const float d0 = wall.center()[along] - 0.6f, d1 = wall.center()[along] + 0.6f, top = wall.min.y + 2.2f;
    Aabb left = wall, right = wall, above = wall;
    left.max[along] = d0;
    right.min[along] = d1;
    above.min[along] = d0;
    above.max[along] = d1;
    above.min.y = top;
    std::vector<WorldEdit> edits{{WorldEdit::Kind::kRemove, "wall_1_2_x", {}, {}},
                                 {WorldEdit::Kind::kAddBox, "wall_1_2_x_left", left, {}},
                                 {WorldEdit::Kind::kAddBox, "wall_1_2_x_right", right, {}},
                                 {WorldEdit::Kind::kAddBox, "wall_1_2_x_above", above, {}}};
    const Aabb floor = bounds_of(world, "floor_2_2");
    const glm::vec3 f = floor.center();
    WorldEdit crate{
        WorldEdit::Kind::kAddBox,
        "crate_new",
        Aabb::of({f.x - 0.5f, floor.max.y, f.z + 1.0f}, {f.x + 0.5f, floor.max.y + 1.0f, f.z + 2.0f}),
        {}};
    edits.push_back(crate);
    return edits;
}

std::vector<WorldEdit> no_edit(const World&) {
    return {};
}

// A crate moved within its room: no object's triangles change.
std::vector<WorldEdit> moved_crate(const World&) {
    return {WorldEdit{WorldEdit::Kind::kMove, "crate_1_1_0", {}, glm::vec3(1.0f, 0.0f, 0.5f)}};
}

// Area and facing of a scene's triangles.
double scene_area(const SceneDesc& scene, glm::dvec3* normal_sum = nullptr) {
    double area = 0.0;
    for (const SceneNode& n : scene.nodes)
        for (size_t i = 0; i + 2 < n.indices.size(); i += 3) {
            const glm::dvec3 a(n.positions[n.indices[i]]), b(n.positions[n.indices[i + 1]]),
                c(n.positions[n.indices[i + 2]]);
            const glm::dvec3 e = glm::cross(b - a, c - a);
            area += 0.5 * glm::length(e);
            if (normal_sum) *normal_sum += 0.5 * e;
        }
    return area;
}

// A door cut through a wall takes exactly the door's part of its faces (triangles clipped, facing kept);
// nothing of what is left lies inside the door.
TEST(WorldEdit, ACutClipsTheTrianglesItMeets) {
    World w;
    test::add_box(w, "wall", Aabb::of({0, 0, 0}, {4, 3, 0.4f}));
    const Aabb door = Aabb::of({1.0f, -0.01f, -0.1f}, {2.2f, 2.2f, 0.5f});
    const SceneDesc before = edited_world(w, {}),
                    after = edited_world(w, {{WorldEdit::Kind::kCut, "", door, {}}});
    // Gone: the door's rectangle from both big faces (1.2 x 2.2 each) and the strip of the bottom face
    // under it (1.2 x 0.4); added: nothing (the cut leaves the hole's sides open).
    EXPECT_NEAR(scene_area(before) - scene_area(after), 2 * 1.2 * 2.2 + 1.2 * 0.4, 1e-4);
    glm::dvec3 facing(0.0);
    scene_area(after, &facing);
    EXPECT_NEAR(facing.z, 0.0, 1e-4);        // the two big faces lost the same area, and kept their facing
    EXPECT_NEAR(facing.y, 1.2 * 0.4, 1e-4);  // the top face is whole, the bottom (facing down) lost the strip
    // A niche whose floor lies in the bottom face's plane (down to it, half through the wall) keeps that
    // face whole, once: only the door's rectangle of the front face goes.
    Aabb niche = door;
    niche.min.y = 0.0f;
    niche.max.z = 0.2f;
    const SceneDesc cut_niche = edited_world(w, {{WorldEdit::Kind::kCut, "", niche, {}}});
    EXPECT_NEAR(scene_area(before) - scene_area(cut_niche), 1.2 * 2.2, 1e-4);
    for (const SceneNode& n : after.nodes)
        for (size_t i = 0; i + 2 < n.indices.size(); i += 3) {
            const glm::vec3 c =
                (n.positions[n.indices[i]] + n.positions[n.indices[i + 1]] + n.positions[n.indices[i + 2]]) /
                3.0f;
            EXPECT_FALSE(c.x > door.min.x + 1e-4f && c.x < door.max.x - 1e-4f && c.y < door.max.y - 1e-4f)
                << "a piece left in the door at " << c.x << ", " << c.y << ", " << c.z;
        }
}

// Tiling copies every object, seed and view-volume box, with names made unique by their copy.
TEST(WorldEdit, TilingCopiesTheWholeWorld) {
    World w;
    test::add_box(w, "crate", Aabb::of({0, 0, 0}, {1, 1, 1}));
    w.view_seeds.push_back({0.5f, 2.0f, 0.5f});
    WorldEdit tile{WorldEdit::Kind::kTile, "", {}, glm::vec3(10.0f, 0.0f, 20.0f)};
    tile.copies = glm::ivec2(2, 3);
    const SceneDesc scene = edited_world(w, {tile});
    ASSERT_EQ(scene.nodes.size(), 12u);
    int crates = 0, seeds = 0;
    for (const SceneNode& n : scene.nodes) {
        if (n.view_seed) {
            ++seeds;
            continue;
        }
        ++crates;
        int i = -1, j = -1;
        ASSERT_EQ(std::sscanf(n.name.c_str(), "crate@%d,%d", &i, &j), 2) << n.name;
        float lo_x = 1e9f, lo_z = 1e9f;
        for (const glm::vec3& p : n.positions) {
            lo_x = std::min(lo_x, p.x);
            lo_z = std::min(lo_z, p.z);
        }
        EXPECT_FLOAT_EQ(lo_x, 10.0f * float(i));
        EXPECT_FLOAT_EQ(lo_z, 20.0f * float(j));
    }
    EXPECT_EQ(crates, 6);
    EXPECT_EQ(seeds, 6);
    WorldEdit none = tile;
    none.copies = glm::ivec2(0, 2);
    EXPECT_THROW(edited_world(w, {none}), Error);
}

// The enclosure closes the world on its four sides: a ring of walls outside its bounds, from below its bottom
// up to its top. So a segment from inside to a point of a neighbouring copy (within the same heights) meets
// a wall: it leaves the ring's inside in x or z at a height within the walls'.
TEST(WorldEdit, TheEnclosureClosesTheWorldOnItsFourSides) {
    const Aabb bounds = Aabb::of({-3, -1, -2}, {5, 4, 8});
    const Enclosure e = enclosure(bounds, 0.5f);
    ASSERT_EQ(e.walls.size(), 4u);
    EXPECT_EQ(e.outer.min, glm::vec3(-4, -1.5f, -3));
    EXPECT_EQ(e.outer.max, glm::vec3(6, 4, 9));
    Aabb all;
    for (const WorldEdit& w : e.walls) {
        EXPECT_EQ(w.kind, WorldEdit::Kind::kAddBox);
        EXPECT_FALSE(w.box.overlaps(bounds)) << w.name << ": a wall inside the world";
        EXPECT_FLOAT_EQ(w.box.min.y, -1.5f);
        EXPECT_FLOAT_EQ(w.box.max.y, 4.0f);
        all.extend(w.box);
    }
    EXPECT_EQ(all.min, e.outer.min);
    EXPECT_EQ(all.max, e.outer.max);
    // Each wall spans the whole side (so the four close a ring around the world), 0.5 m thick.
    for (const WorldEdit& w : e.walls) {
        const glm::vec3 size = w.box.size();
        const bool along_x = size.x > size.z;
        EXPECT_FLOAT_EQ(along_x ? size.z : size.x, 0.5f) << w.name;
        EXPECT_FLOAT_EQ(along_x ? size.x : size.z, along_x ? 10.0f : 12.0f) << w.name;
    }
}

class ReuseEdit : public ::testing::TestWithParam<EditCase> {};

TEST_P(ReuseEdit, TheReBakeFromTheOldBakeIsTheFullBakeOfTheEditedWorld) {
    test::TempDir dir;
    Context ctx(Context::Options{LogLevel::kWarning, true, nullptr});
    const World sample = load_world(ctx, test::sample_world());
    const std::string old_world = dir.file("old.glb"), new_world = dir.file("new.glb");
    write_glb(edited_world(sample, {}), old_world);
    const std::vector<WorldEdit> edits = GetParam().edits(sample);
    write_glb(edited_world(sample, edits), new_world);
    const std::string log = dir.file("log.txt"), report = dir.file("reuse.json");
    const std::string options = GetParam().options;
    ASSERT_EQ(run(bake_args(old_world, dir.file("old.h5")) + options, log), 0) << test::read_file(log);
    ASSERT_EQ(run(bake_args(new_world, dir.file("full.h5")) + options, log), 0) << test::read_file(log);
    ASSERT_EQ(run(bake_args(new_world, dir.file("reuse.h5")) + options + " --reuse '" + dir.file("old.h5") +
                      "' --report '" + report + "'",
                  log),
              0)
        << test::read_file(log);
    EXPECT_EQ(test::h5diff_outside_run(dir.file("full.h5"), dir.file("reuse.h5"), dir.file("diff.txt")), 0)
        << test::read_file(dir.file("diff.txt"));
    const double pairs = run_figure(report, "reuse_pairs"), kept = run_figure(report, "reuse_pairs_kept");
    EXPECT_GT(pairs, 0.0);
    if (edits.empty()) {
        EXPECT_EQ(kept, pairs) << "nothing changed: every pair is kept";
        EXPECT_EQ(run_figure(report, "reuse_changed_tiles"), 0.0);
    } else {
        EXPECT_GT(kept, 0.0) << "the edit is local: some pairs are kept\n" << test::read_file(log);
        EXPECT_LT(kept, pairs) << "the edit changes the geometry: some pairs are tested again";
        EXPECT_GT(run_figure(report, "reuse_changed_tiles"), 0.0);
    }
}

INSTANTIATE_TEST_SUITE_P(Edits, ReuseEdit,
                         ::testing::Values(EditCase{"MovedCrateAndRemovedWall", moved_crate_and_removed_wall},
                                           EditCase{"DoorCutAndCrateAdded", door_and_new_crate},
                                           EditCase{"NoEdit", no_edit},
                                           // The shaft pass by blocks of 2 x 2 x 2 cells, with the blocks'
                                           // proofs before the faces and nodes giving up: a pair is kept only
                                           // when the edit misses the block's box and the object.
                                           EditCase{"DoorCutAndCrateAddedShaftBlocks", door_and_new_crate,
                                                    " --shaft-block 2 --shaft-early --shaft-give-up 1"},
                                           // Over the shaft pass's cap, 20 objects a cell (of the
                                           // sample world's 512 cells): the pass tries the heaviest only,
                                           // the same ones before and after an edit that keeps every
                                           // object's triangles.
                                           EditCase{"NoEditHeaviestFirst", no_edit,
                                                    " --shaft-max-pairs 10496 --shaft-min-share 0"},
                                           EditCase{"MovedCrateHeaviestFirst", moved_crate,
                                                    " --shaft-max-pairs 10496 --shaft-min-share 0"}),
                         [](const auto& info) { return std::string(info.param.name); });

// The ranking runs in full after the PVS and reads nothing of the old bake, so a re-bake may rank otherwise
// (other counts, polygons): its file is still the full bake's of those options.
TEST(Reuse, AReBakeMayRankOtherwiseAndWritesTheFullBakeOfItsOptions) {
    test::TempDir dir;
    const std::string log = dir.file("log.txt"), old = dir.file("old.h5");
    const std::string ranking = " --occluders-per-cell 8 --ranking-polygons";
    ASSERT_EQ(run(bake_args(test::sample_world(), old), log), 0) << test::read_file(log);
    ASSERT_EQ(run(bake_args(test::sample_world(), dir.file("full.h5")) + ranking, log), 0)
        << test::read_file(log);
    ASSERT_EQ(
        run(bake_args(test::sample_world(), dir.file("reuse.h5")) + ranking + " --reuse '" + old + "'", log),
        0)
        << test::read_file(log);
    EXPECT_EQ(test::h5diff_outside_run(dir.file("full.h5"), dir.file("reuse.h5"), dir.file("diff.txt")), 0)
        << test::read_file(dir.file("diff.txt"));
    EXPECT_NE(test::h5diff_outside_run(old, dir.file("reuse.h5"), dir.file("diff2.txt")), 0)
        << "the ranking should differ from the old bake's";
}

TEST(Reuse, AnOldBakeOfOtherParametersOrNoneIsRefusedBeforeAnyStage) {
    test::TempDir dir;
    const std::string log = dir.file("log.txt"), old = dir.file("old.h5");
    ASSERT_EQ(run(bake_args(test::sample_world(), old), log), 0) << test::read_file(log);
    EXPECT_EQ(
        run(bake_args(test::sample_world(), dir.file("new.h5")) + " --cell-size 4 --reuse '" + old + "'",
            log),
        2);
    EXPECT_NE(test::read_file(log).find("cells.cell_size_m"), std::string::npos) << test::read_file(log);
    EXPECT_EQ(
        run(bake_args(test::sample_world(), dir.file("new.h5")) + " --reuse '" + dir.file("none.h5") + "'",
            log),
        2);
    EXPECT_NE(test::read_file(log).find("none.h5"), std::string::npos) << test::read_file(log);
    EXPECT_EQ(
        run(bake_args(test::sample_world(), dir.file("new.h5")) + " --mode sampled --reuse '" + old + "'",
            log),
        2);
    EXPECT_FALSE(std::filesystem::exists(dir.file("new.h5"))) << "a refused bake writes nothing";
}

// The sample world baked with `option(cells, objects)` (built from its counts), then the world with a door
// cut and a crate added (four objects more) re-baked from it with the same option: the re-bake is refused,
// its log saying `says`, and writes nothing. Returns the old bake's report.
nlohmann::json expect_refused_after_an_edit(const std::function<std::string(uint64_t, uint64_t)>& option,
                                            const std::string& says) {
    test::TempDir dir;
    Context ctx(Context::Options{LogLevel::kWarning, true, nullptr});
    const World sample = load_world(ctx, test::sample_world());
    const std::string old_world = dir.file("old.glb"), new_world = dir.file("new.glb");
    write_glb(edited_world(sample, {}), old_world);
    write_glb(edited_world(sample, door_and_new_crate(sample)), new_world);
    const std::string log = dir.file("log.txt"), report = dir.file("old.json");
    EXPECT_EQ(run(bake_args(old_world, dir.file("probe.h5")) + " --report '" + report + "'", log), 0)
        << test::read_file(log);
    const nlohmann::json j = nlohmann::json::parse(test::read_file(report));
    const std::string o = option(j.at("cells").get<uint64_t>(), j.at("objects").get<uint64_t>());
    EXPECT_EQ(run(bake_args(old_world, dir.file("old.h5")) + o + " --report '" + report + "'", log), 0)
        << test::read_file(log);
    EXPECT_EQ(
        run(bake_args(new_world, dir.file("new.h5")) + o + " --reuse '" + dir.file("old.h5") + "'", log), 2);
    EXPECT_NE(test::read_file(log).find(says), std::string::npos) << test::read_file(log);
    EXPECT_FALSE(std::filesystem::exists(dir.file("new.h5"))) << "a refused bake writes nothing";
    return nlohmann::json::parse(test::read_file(report));
}

// The shaft pass's cap is decided by cells x objects (docs/ALGORITHMS.md#shaft-cap): an old bake whose pass
// tried every object, at a cap its world just meets, is refused for an edited world of more objects, whose
// pass would try only the heaviest (the old rows hold what only the pass proved of the others).
TEST(Reuse, AnOldBakeWhosePassTheShaftCapNowNarrowsIsRefused) {
    expect_refused_after_an_edit(
        [](uint64_t cells, uint64_t objects) {
            return " --shaft-max-pairs " + std::to_string(cells * objects);
        },
        "shaft pass");
}

// The pair budget of a small bake's pass follows its cells and objects (docs/ALGORITHMS.md#shaft-small): an
// old bake made with another budget holds rows this bake would not compute, so it is refused, naming the
// budgets. The spend: the old bake's candidates fit at 128 piece pairs each, the new one's do not.
TEST(Reuse, AnOldBakeWhosePassHadAnotherPairBudgetIsRefused) {
    const nlohmann::json old = expect_refused_after_an_edit(
        [](uint64_t cells, uint64_t objects) {
            return " --shaft-small-spend " + std::to_string(128 * cells * objects);
        },
        "piece pairs");
    EXPECT_EQ(old.at("figures").at("conservative_shaft_pair_budget").get<double>(), 128.0);
}

// A 16 m cube of eye voxels of 0.25 m from the origin, every voxel an eye: the print tests' eye space.
VoxelMask eye_cube() {
    VoxelMask eyes;
    eyes.origin = glm::vec3(0.0f);
    eyes.voxel_size_m = 0.25f;
    eyes.dims = glm::ivec3(64);
    eyes.bits.assign(size_t(eyes.count() + 63) / 64, ~uint64_t(0));
    return eyes;
}

// A print over a 16 m cube of eye voxels: a box moved changes the tiles its old and new bounds meet, and no
// other; the same world prints the same.
TEST(GeometryPrint, AMovedBoxChangesOnlyTheTilesItMeets) {
    const VoxelMask eyes = eye_cube();
    const ConservativeConfig config;
    const ShrunkOccluders none;
    const Aabb before = Aabb::of({2.1f, 0.1f, 2.1f}, {2.9f, 0.9f, 2.9f});
    const Aabb after = Aabb::of({10.1f, 0.1f, 6.1f}, {10.9f, 0.9f, 6.9f});
    World a, b;
    test::add_box(a, "wall", Aabb::of({0.1f, 0.1f, 8.1f}, {15.9f, 3.0f, 8.4f}));
    test::add_box(b, "wall", Aabb::of({0.1f, 0.1f, 8.1f}, {15.9f, 3.0f, 8.4f}));
    test::add_box(a, "crate", before);
    test::add_box(b, "crate", after);
    const GeometryPrint pa = geometry_print(config, a, none, eyes),
                        pb = geometry_print(config, b, none, eyes);
    EXPECT_EQ(pa.tiles, geometry_print(config, a, none, eyes).tiles);
    ASSERT_EQ(pa.header, pb.header);
    EXPECT_EQ(pa.objects[0], pb.objects[0]) << "the wall did not change";
    EXPECT_NE(pa.objects[1], pb.objects[1]) << "the crate moved";
    size_t changed = 0;
    for (uint64_t t = 0; t < pa.tiles.size(); ++t) {
        if (pa.tiles[t] == pb.tiles[t]) continue;
        ++changed;
        const Aabb tile = pa.tile_box(t);
        EXPECT_TRUE(tile.overlaps(before) || tile.overlaps(after)) << "tile " << t << " changed";
    }
    EXPECT_GE(changed, 2u);
}

// With the shaft pass over blocks (docs/ALGORITHMS.md#shaft-hierarchy), a cell's bit for an object depends on
// the other cells of its block: a plan must settle a block's cells alike, and keep a pair only when the
// edit misses the box around the whole block and the object. A 16 m cube of eye voxels in 2 m cells; a crate
// moves near one corner. Per cell, pairs of cells beside the crate's block are kept where the box around the
// cell and the object misses the edit; with blocks of 2, the plan keeps a subset of those, alike in every
// cell of a block, and leaves out some that per cell are kept.
TEST(ReusePlan, WithShaftBlocksABlocksCellsAreSettledAlike) {
    const VoxelMask eyes = eye_cube();
    World a, b;
    for (World* w : {&a, &b}) {
        test::add_box(*w, "wall", Aabb::of({0.1f, 0.1f, 12.1f}, {15.9f, 3.0f, 12.4f}));
        test::add_box(*w, "lamp", Aabb::of({14.1f, 14.1f, 14.1f}, {14.9f, 14.9f, 14.9f}));
    }
    test::add_box(a, "crate", Aabb::of({2.1f, 0.1f, 2.1f}, {2.9f, 0.9f, 2.9f}));
    test::add_box(b, "crate", Aabb::of({2.6f, 0.1f, 2.1f}, {3.4f, 0.9f, 2.9f}));
    CellSet cells;
    cells.kind = CellSet::Kind::kGrid;
    cells.cell_size_m = 2.0f;
    cells.dims = glm::ivec3(8);
    cells.eyes = eyes;
    for (int z = 0; z < 8; ++z)
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
                cells.grid_to_cell.push_back(int32_t(cells.cells.size()));
                const glm::vec3 lo = glm::vec3(x, y, z) * 2.0f;
                cells.cells.push_back(Cell{Aabb::of(lo, lo + 2.0f)});
            }
    ConservativeConfig config;
    const ShrunkOccluders none;
    const GeometryPrint old_print = geometry_print(config, a, none, eyes);
    const GeometryPrint now = geometry_print(config, b, none, eyes);
    PvsSet old_rows = PvsSet::make(uint32_t(cells.size()), uint32_t(a.objects.size()));
    std::fill(old_rows.words.begin(), old_rows.words.end(), ~uint64_t(0));
    Context ctx(Context::Options{LogLevel::kWarning, true, nullptr});
    const ReusePlan per_cell =
        plan_reuse(ctx, config, b, cells, now, ReuseSource{cells, old_rows, old_print});
    config.shaft_block = 2;
    const ReusePlan blocks = plan_reuse(ctx, config, b, cells, now, ReuseSource{cells, old_rows, old_print});
    ASSERT_TRUE(per_cell.whole.empty()) << per_cell.whole;
    EXPECT_GT(blocks.figures.kept, 0u);
    EXPECT_LT(blocks.figures.kept, per_cell.figures.kept);
    for (const std::vector<uint32_t>& block : grid_shaft_blocks(cells, 2))
        for (uint32_t o = 0; o < b.objects.size(); ++o)
            for (uint32_t c : block) {
                EXPECT_EQ(blocks.settled.test(c, o), blocks.settled.test(block[0], o))
                    << "cells " << block[0] << " and " << c << " of a block, object " << o;
                EXPECT_FALSE(blocks.settled.test(c, o) && !per_cell.settled.test(c, o))
                    << "cell " << c << ", object " << o << ": kept with blocks only";
            }
}

// With the shaft pass, a convex cap (pvs/convex_cap.h) is tried wherever a line meets its first polygon, but
// its hull reaches as far as its neighbours: a change to a neighbour must change the print all along the
// polygon, not only where the neighbour lies (docs/ALGORITHMS.md#reuse). A long wall A (x = 2, z from 1 to
// 14) meets a short one B (z = 1) at a corner; B grows from x = 6 to 7. The tile around A's far end, which B
// never meets, changes with the caps and not without.
TEST(GeometryPrint, AChangedNeighbourOfAConvexCapChangesThePrintAlongItsPolygon) {
    const VoxelMask eyes = eye_cube();
    const World w;
    ShrunkOccluders a, b;
    for (ShrunkOccluders* o : {&a, &b}) o->panels.push_back(Aabb::of({2.0f, 0.0f, 1.0f}, {2.0f, 3.0f, 14.0f}));
    a.panels.push_back(Aabb::of({2.0f, 0.0f, 1.0f}, {6.0f, 3.0f, 1.0f}));
    b.panels.push_back(Aabb::of({2.0f, 0.0f, 1.0f}, {7.0f, 3.0f, 1.0f}));
    const glm::vec3 far_end(2.0f, 1.0f, 13.0f);
    uint64_t tile = 0;
    GeometryPrint probe = geometry_print(ConservativeConfig{}, w, a, eyes);
    while (!probe.tile_box(tile).contains(far_end)) ++tile;
    ASSERT_FALSE(probe.tile_box(tile).overlaps(b.panels[1])) << "the scene is not what the test means";
    for (const bool caps : {true, false}) {
        ConservativeConfig config;
        config.shaft_budget = 64;
        config.shaft_caps = caps;
        const GeometryPrint pa = geometry_print(config, w, a, eyes), pb = geometry_print(config, w, b, eyes);
        EXPECT_EQ(pa.tiles[tile] != pb.tiles[tile], caps) << "caps " << caps;
    }
}

}  // namespace
}  // namespace pvs
