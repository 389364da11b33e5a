// SPDX-License-Identifier: MIT
// Tests the runtime file from the baker's side: a real bake (a random world, grid and octree) exported
// answers every query as the HDF5 loader does, and `pvsbake export` and `pvsbake bake --runtime-output`
// write it (the same bytes), or fail with exit 2 and no file.
#include "driver/bake.h"
#include "driver/cli.h"
#include "io/bake_file.h"
#include "io/gltf_writer.h"
#include "rays/ray_scene.h"
#include "samples/random_world.h"
#include "samples/world_edit.h"
#include "tests/runtime_file_checks.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace pvs {
namespace {

using test::round_trip;

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

// pvsbake's command line in this process: its exit status.
int run_pvsbake(std::vector<std::string> args) {
    args.insert(args.begin(), "pvsbake");
    std::vector<const char*> argv;
    for (const std::string& a : args) argv.push_back(a.c_str());
    std::ostringstream out;
    std::FILE* log = std::tmpfile();
    const int status = run_cli(int(argv.size()), argv.data(), out, log);
    std::fclose(log);
    return status;
}

TEST(RuntimeExport, ARealBakeAnswersAsTheHdf5Loader) {
    for (const CellKind kind : {CellKind::kGrid, CellKind::kOctree}) {
        SCOPED_TRACE(kind == CellKind::kGrid ? "grid" : "octree");
        const RandomWorld random = make_random_world(2, 0);
        BakeConfig config;
        config.cells.kind = kind;
        config.ranking.polygons = kind == CellKind::kGrid;  // the turned walls' sides as polygon occluders
        config.verify.enabled = false;
        config.run.threads = 2;
        Context ctx = quiet_context();
        const BakeData bake = bake_world(ctx, config, random.world, "random.glb", "");
        ASSERT_GT(bake.cells.size(), 0u);
        if (config.ranking.polygons) {
            ASSERT_FALSE(bake.polygons.empty());
            EXPECT_TRUE(std::any_of(bake.ranked.entries.begin(), bake.ranked.entries.end(),
                                    [&](const RankedOccluder& e) { return e.box >= bake.occluders.size(); }));
        }
        uint64_t horizon_culled = 0;
        ASSERT_FALSE(bake.horizon.empty());
        round_trip(bake, 13, nullptr, &horizon_culled);
        EXPECT_GT(horizon_culled, 0u) << "the cells' horizons should cull some object of the PVS";
    }
}

// Lists per cell (ALGORITHMS 10.7): on a small world each cell gets its own horizon list, a subset of the
// list its block gets without them (the blocks' eyes are the same), shorter on the whole, and the exported
// runtime reads each cell's own; past --horizon-cell-lists-max, or with no cell eyes, the lists are per
// block. Each cell also keeps its tests (ALGORITHMS 10.7, "A frame's tests"): ascending objects of its PVS,
// fewer than the PVS over the cells and some; none with --horizon-cell-tests false (the same lists) or with
// lists per block; the runtime draws what the loader draws (round_trip).
TEST(RuntimeExport, ACellsHorizonListIsPartOfItsBlocksList) {
    const RandomWorld random = make_random_world(2, 0);
    BakeConfig config;
    config.verify.enabled = false;
    config.run.threads = 2;
    Context ctx = quiet_context();
    const BakeData cell = bake_world(ctx, config, random.world, "random.glb", "");
    config.ranking.horizon_cell_eyes = 0;
    const BakeData block = bake_world(ctx, config, random.world, "random.glb", "");
    config.ranking.horizon_cell_eyes = 16;
    config.ranking.horizon_cell_lists_max = 0;
    const BakeData capped = bake_world(ctx, config, random.world, "random.glb", "");
    config.ranking.horizon_cell_lists_max = 2e6;
    config.ranking.horizon_cell_tests = false;
    const BakeData untested = bake_world(ctx, config, random.world, "random.glb", "");
    EXPECT_EQ(untested.horizon.entries, cell.horizon.entries);
    EXPECT_EQ(untested.horizon.cell_list, cell.horizon.cell_list);
    EXPECT_TRUE(untested.horizon.test_offsets.empty() && block.horizon.test_offsets.empty() &&
                capped.horizon.test_offsets.empty());
    ASSERT_EQ(cell.horizon.test_offsets.size(), cell.cells.size() + 1);
    uint64_t tests = 0, listed = 0;
    for (uint32_t c = 0; c < cell.cells.size(); ++c) {
        for (uint32_t k = cell.horizon.test_offsets[c]; k < cell.horizon.test_offsets[c + 1]; ++k) {
            EXPECT_TRUE(cell.pvs.test(c, cell.horizon.tests[k])) << "cell " << c;
            if (k > cell.horizon.test_offsets[c]) EXPECT_GT(cell.horizon.tests[k], cell.horizon.tests[k - 1]);
        }
        tests += cell.horizon.test_offsets[c + 1] - cell.horizon.test_offsets[c];
        listed += cell.pvs.count(c);
    }
    EXPECT_GT(tests, 0u);
    EXPECT_LT(tests, listed);
    ASSERT_EQ(cell.horizon.lists(), cell.cells.size());
    ASSERT_LT(block.horizon.lists(), block.cells.size());
    EXPECT_EQ(capped.horizon.entries, block.horizon.entries);
    EXPECT_EQ(capped.horizon.cell_list, block.horizon.cell_list);
    // The occluders by their boxes (the two bakes keep different sets, numbered apart).
    const auto named = [](const HorizonLists& h, uint32_t c) {
        std::vector<std::vector<float>> out;
        const uint32_t l = h.cell_list[c];
        for (uint32_t e = h.offsets[l]; e < h.offsets[l + 1]; ++e) {
            const uint32_t o = h.entries[e];
            if (o < h.boxes.size()) {
                const Aabb& b = h.boxes[o];
                out.push_back({b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z});
            } else {
                std::vector<float> t;
                for (const glm::vec3& p : h.tiles[o - h.boxes.size()].corners)
                    t.insert(t.end(), {p.x, p.y, p.z});
                out.push_back(t);
            }
        }
        std::sort(out.begin(), out.end());
        return out;
    };
    size_t cell_entries = 0, block_entries = 0, shorter = 0;
    for (uint32_t c = 0; c < cell.cells.size(); ++c) {
        const auto mine = named(cell.horizon, c), theirs = named(block.horizon, c);
        EXPECT_TRUE(std::includes(theirs.begin(), theirs.end(), mine.begin(), mine.end())) << "cell " << c;
        cell_entries += mine.size();
        block_entries += theirs.size();
        shorter += mine.size() < theirs.size();
    }
    EXPECT_LT(cell_entries, block_entries);
    EXPECT_GT(shorter, 0u);
    uint64_t horizon_culled = 0;
    round_trip(cell, 13, nullptr, &horizon_culled);
    EXPECT_GT(horizon_culled, 0u);
}

// The bundled sample world, a grid and an octree (quick sampled bakes): every query the same.
TEST(RuntimeExport, TheSampleWorldAnswersAsTheHdf5Loader) {
    test::TempDir dir;
    for (const std::string cells : {"grid", "octree"}) {
        SCOPED_TRACE(cells);
        const std::string h5 = dir.file(cells + ".h5");
        ASSERT_EQ(run_pvsbake({"bake", test::sample_world(), "-o", h5, "--cells", cells, "--mode", "sampled",
                               "--no-verify", "-q", "--eyes", "4", "--rays", "256"}),
                  0);
        BakeData bake = read_bake_file(h5);
        uint64_t culled = 0;
        round_trip(bake, 17, &culled);
        EXPECT_GT(culled, 0u) << "the ranked occluders should cull some object of the PVS from some eye";
    }
}

// What a game draws, against rays: random worlds baked with their ranked occluders (proven boxes of the
// solid, panels, and the turned walls' sides as polygon occluders) and their horizon lists, exported; the
// walk culled by the cell's culler and its horizon (pvsr_visit_drawn_horizon) is the PVS less exactly the
// objects whose bounds either hides or each of whose parts one of them hides; from random eyes in random
// cells' eye space, every object the culled walk leaves out of the cell's PVS is checked with segments from
// the eye to points of its triangles (vertices pulled in a hair, centroids and random points): none may reach
// one (a wrong cull). Not vacuous: some are culled.
TEST(RuntimeExport, TheDrawnWalkCullsNothingARayReaches) {
    uint64_t culled = 0, segments = 0, wrong = 0, frames = 0, polygons = 0, horizon_given = 0,
             horizon_culled = 0, parts_with_culls = 0;
    for (const uint64_t seed : {3u, 5u}) {
        SCOPED_TRACE("world seed " + std::to_string(seed));
        const RandomWorld random = make_random_world(seed, 0);
        BakeConfig config;
        config.verify.enabled = false;
        config.run.threads = 2;
        config.ranking.polygons = true;
        Context ctx = quiet_context();
        const World& w = random.world;
        const BakeData bake = bake_world(ctx, config, w, "random.glb", "");
        test::TempDir dir;
        const std::string h5 = dir.file("b.h5");
        write_bake_file(h5, bake);
        const test::Bytes bytes(runtime_file_bytes(h5));
        pvsr::Level level;
        ASSERT_EQ(level.open(bytes.data(), bytes.size), PVSR_OK);
        pvsr::Culler culler(32);
        pvsr::Horizon horizon(256, 1 << 16);
        ASSERT_TRUE(horizon.ok());
        ASSERT_FALSE(bake.horizon.empty());
        const RayScene scene(ctx, w, BuildQuality::kMedium, 1);
        std::mt19937 rng{uint32_t(seed)};
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        for (int f = 0; f < (test::in_ci() ? 150 : 600); ++f) {
            const uint32_t cell = uint32_t(rng() % level.cell_count());
            float box[6], eye[3];
            level.cell_bounds(cell, box);
            bool found = false;
            for (int d = 0; d < 64 && !found; ++d) {
                for (int a = 0; a < 3; ++a) eye[a] = box[a] + u(rng) * (box[3 + a] - box[a]);
                found = level.in_eye_space(eye[0], eye[1], eye[2]) &&
                        level.find_cell(eye[0], eye[1], eye[2]) == int32_t(cell);
            }
            if (!found) continue;
            ++frames;
            culler.begin_cell(level, cell, eye);
            polygons += culler.c_culler().polygon_count;
            horizon_given += horizon.begin_cell(level, cell, eye);
            std::vector<uint32_t> listed, drawn, culler_drawn, expected;
            level.for_each_visible(cell, [&](uint32_t o) { listed.push_back(o); });
            level.for_each_drawn(cell, culler, [&](uint32_t o) { culler_drawn.push_back(o); });
            // Culled by both: the PVS less exactly the objects whose bounds the culler or the horizon hides,
            // or each of whose parts one of them hides.
            level.for_each_drawn(cell, &culler, horizon, [&](uint32_t o) { drawn.push_back(o); });
            const auto hidden = [&](const float* b) { return culler.is_hidden(b) || horizon.is_hidden(b); };
            for (const uint32_t o : listed) {
                float b[6];
                const bool always = (level.object_flags(o) & PVSR_OBJECT_ALWAYS_VISIBLE) != 0;
                bool parts_hidden = level.object_part_count(o) > 0;
                for (uint32_t k = 0; k < level.object_part_count(o) && parts_hidden; ++k)
                    parts_hidden = level.object_part(o, k, b) && hidden(b);
                parts_with_culls += parts_hidden;
                if (always || !level.object_bounds(o, b) || (!hidden(b) && !parts_hidden))
                    expected.push_back(o);
            }
            ASSERT_EQ(drawn, expected);
            horizon_culled += culler_drawn.size() - drawn.size();
            std::vector<uint32_t> gone;
            std::set_difference(listed.begin(), listed.end(), drawn.begin(), drawn.end(),
                                std::back_inserter(gone));
            const glm::vec3 e(eye[0], eye[1], eye[2]);
            for (const uint32_t o : gone) {
                ++culled;
                const WorldObject& obj = w.objects[o];
                std::vector<glm::vec3> origins, dirs;
                std::vector<float> tfar;
                for (uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count; ++t) {
                    const glm::vec3 p0 = w.positions[w.triangles[t].v[0]],
                                    p1 = w.positions[w.triangles[t].v[1]],
                                    p2 = w.positions[w.triangles[t].v[2]], mid = (p0 + p1 + p2) / 3.0f;
                    std::vector<glm::vec3> points = {mid, p0 + 0.01f * (mid - p0), p1 + 0.01f * (mid - p1),
                                                     p2 + 0.01f * (mid - p2)};
                    for (int k = 0; k < 12; ++k) {
                        const float r1 = std::sqrt(u(rng)), r2 = u(rng);
                        points.push_back((1.0f - r1) * p0 + r1 * (1.0f - r2) * p1 + r1 * r2 * p2);
                    }
                    for (const glm::vec3& p : points) {
                        const glm::vec3 d = p - e;
                        const float len = glm::length(d);
                        if (!(len > 1e-3f)) continue;
                        origins.push_back(e);
                        dirs.push_back(d / len);
                        tfar.push_back(len * (1.0f - 1e-4f));  // stop short of the point's own surface
                    }
                }
                std::vector<uint8_t> blocked(origins.size());
                scene.occluded_opaque(origins.data(), dirs.data(), tfar.data(), uint32_t(origins.size()),
                                      blocked.data());
                segments += origins.size();
                const uint64_t reached = uint64_t(std::count(blocked.begin(), blocked.end(), uint8_t(0)));
                wrong += reached;
                EXPECT_EQ(reached, 0u) << "cell " << cell << " eye " << eye[0] << " " << eye[1] << " "
                                       << eye[2] << " culls '" << obj.name << "', which a segment reaches";
            }
        }
    }
    std::printf(
        "drawn walks: %llu frames (%llu polygons, %llu horizon occluders given), %llu objects culled (%llu "
        "by the "
        "horizon alone; %llu with every part hidden), %llu segments, %llu wrong\n",
        (unsigned long long)frames, (unsigned long long)polygons, (unsigned long long)horizon_given,
        (unsigned long long)culled, (unsigned long long)horizon_culled, (unsigned long long)parts_with_culls,
        (unsigned long long)segments, (unsigned long long)wrong);
    EXPECT_GT(horizon_culled, 0u) << "the cells' horizons should cull some object the culler draws";
    EXPECT_GT(frames, 0u);
    EXPECT_GT(polygons, 0u) << "the frames should use some polygon occluder";
    EXPECT_GT(culled, 0u) << "the ranked occluders should cull some object of the PVS";
    EXPECT_EQ(wrong, 0u);
}

TEST(RuntimeExport, ExportAndBakeWriteIt) {
    test::TempDir dir;
    const std::string h5 = dir.file("b.h5"), out = dir.file("level.pvsr");
    write_bake_file(h5, test::coherent_bake(40, {3, 2, 3}, false, true, 6));
    EXPECT_EQ(run_pvsbake({"export", h5, "-o", out, "-q"}), 0);
    const std::string written = test::read_file(out);
    EXPECT_EQ(written, runtime_file_bytes(h5));
    // A missing bake: exit 2 and no file.
    EXPECT_EQ(run_pvsbake({"export", dir.file("none.h5"), "-o", dir.file("x.pvsr"), "-q"}), 2);
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.pvsr")));
    // From bake: the same bytes as exporting its bake file.
    const std::string world = dir.file("random.glb");
    write_glb(edited_world(make_random_world(4, 0).world, {}), world);
    const std::string baked = dir.file("r.h5"), level = dir.file("r.pvsr");
    ASSERT_EQ(run_pvsbake({"bake", world, "-o", baked, "--runtime-output", level, "--no-verify", "-q",
                           "--cell-size", "4"}),
              0);
    EXPECT_EQ(test::read_file(level), runtime_file_bytes(baked));
}

}  // namespace
}  // namespace pvs
