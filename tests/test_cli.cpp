// SPDX-License-Identifier: MIT
// The command line end to end, in-process: bake, info, query, verify, and bad input.
#include "core/config.h"
#include "core/error.h"
#include "driver/cli.h"
#include "io/bake_file.h"
#include "io/gltf_writer.h"
#include "samples/town_world.h"
#include "samples/world_edit.h"
#include "tests/gltf_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace pvs {
namespace {

struct CliRun {
    int status = -1;
    std::string out;
    std::string log;
};

CliRun run(std::vector<std::string> args) {
    args.insert(args.begin(), "pvsbake");
    std::vector<const char*> argv;
    for (const std::string& a : args) argv.push_back(a.c_str());
    std::ostringstream out;
    std::FILE* log = std::tmpfile();
    CliRun r;
    r.status = run_cli(int(argv.size()), argv.data(), out, log);
    std::fflush(log);
    std::rewind(log);
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, log)) > 0) r.log.append(buf, n);
    std::fclose(log);
    r.out = out.str();
    return r;
}

bool contains(const std::string& hay, const std::string& needle) {
    return hay.find(needle) != std::string::npos;
}

// Big cells and small sampling so the whole bake of the sample world takes seconds.
const std::vector<std::string> kFast = {
    "--cell-size",           "4",   "--eyes",        "4",     "--rays", "256", "--verify-eyes", "4",
    "--verify-rays-per-eye", "256", "--verify-rays", "200000"};

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

TEST(Cli, BakeInfoQueryOnTheSampleWorld) {
    test::TempDir dir;
    const std::string out = dir.file("rooms.h5"), report = dir.file("rooms.json");
    const CliRun bake = run(with({"bake", test::sample_world(), "-o", out, "--report", report}, kFast));
    ASSERT_EQ(bake.status, 0) << bake.log;
    ASSERT_TRUE(std::filesystem::exists(out));
    const auto j = nlohmann::json::parse(test::read_file(report));
    EXPECT_EQ(j["objects"], 149);
    EXPECT_EQ(j["triangles"], 1788);
    EXPECT_GT(j["cells"].get<int>(), 30);
    EXPECT_TRUE(j["conservative"].get<bool>()) << "the default mode is conservative";
    EXPECT_FALSE(contains(j["pvs_kind"].get<std::string>(), "aggressive"));
    EXPECT_TRUE(j["run"]["timings_s"].contains("conservative_pvs"));
    // Each stage's thread utilisation: CPU seconds over wall seconds and threads, so at most about 1.
    for (const char* stage : {"voxelize", "occluders", "conservative_pvs"}) {
        ASSERT_TRUE(j["run"]["utilisation"].contains(stage)) << stage;
        const double u = j["run"]["utilisation"][stage].get<double>();
        EXPECT_GT(u, 0.0) << stage;
        EXPECT_LT(u, 1.5) << stage;
    }
    EXPECT_GT(j["run"]["figures"]["threads"].get<double>(), 0.0);
    EXPECT_EQ(j["verification"]["figures"]["missed_pairs"].get<double>(), 0.0);
    EXPECT_TRUE(j["verification"]["ran"].get<bool>());
    EXPECT_TRUE(j["verification"]["figures"].contains("overestimation_mean"));
    // No file left behind but the two outputs.
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 2);

    const CliRun info = run({"info", out});
    ASSERT_EQ(info.status, 0) << info.log;
    EXPECT_TRUE(contains(info.out, "objects     149")) << info.out;
    EXPECT_FALSE(contains(info.out, "aggressive"));
    // Every bake ranks its proven occluders per cell (docs/ALGORITHMS.md#ranking), and info sums them up.
    EXPECT_TRUE(contains(info.out, "ranked      16.00 per cell")) << info.out;
    EXPECT_EQ(j["figures"]["ranked_occluders_per_cell_mean"].get<double>(), 16.0);
    const CliRun info_json = run({"info", out, "--json"});
    ASSERT_EQ(info_json.status, 0);
    EXPECT_EQ(nlohmann::json::parse(info_json.out)["objects"], 149);
    EXPECT_TRUE(nlohmann::json::parse(info_json.out)["ranked_occluders"]["stored"].get<bool>());

    // The spawn point of room (0, 0) sees that room's floor; much of the maze is behind its walls.
    const CliRun q = run({"query", out, "4", "1.6", "4", "--json"});
    ASSERT_EQ(q.status, 0) << q.log;
    const auto qj = nlohmann::json::parse(q.out);
    ASSERT_FALSE(qj["cell"].is_null());
    const auto names = qj["visible"].get<std::vector<std::string>>();
    EXPECT_NE(std::find(names.begin(), names.end(), "floor_0_0"), names.end());
    EXPECT_LT(names.size(), 100u) << "much of the maze is hidden from room (0, 0)";
    const CliRun outside = run({"query", out, "500", "0", "0", "--json"});
    ASSERT_EQ(outside.status, 0);
    EXPECT_TRUE(nlohmann::json::parse(outside.out)["cell"].is_null());
}

TEST(Cli, TheSampledModeIsLabelledAggressive) {
    test::TempDir dir;
    const std::string out = dir.file("rooms.h5"), report = dir.file("rooms.json");
    const CliRun bake =
        run(with({"bake", test::sample_world(), "-o", out, "--report", report, "--mode", "sampled"}, kFast));
    ASSERT_EQ(bake.status, 0) << bake.log;
    const auto j = nlohmann::json::parse(test::read_file(report));
    EXPECT_FALSE(j["conservative"].get<bool>());
    EXPECT_TRUE(contains(j["pvs_kind"].get<std::string>(), "aggressive"));
    EXPECT_TRUE(j["run"]["timings_s"].contains("sampled_pvs"));
    const CliRun info = run({"info", out});
    ASSERT_EQ(info.status, 0) << info.log;
    EXPECT_TRUE(contains(info.out, "aggressive"));
}

TEST(Cli, VerifyNamesTheObjectAnEditedBakeDropped) {
    test::TempDir dir;
    const std::string good = dir.file("good.h5"), edited = dir.file("edited.h5"), report = dir.file("v.json");
    ASSERT_EQ(run(with({"bake", test::sample_world(), "-o", good, "--no-verify"}, kFast)).status, 0);
    BakeData bake = read_bake_file(good);
    // Drop floor_0_0 (seen from everywhere in its room) from every PVS.
    uint32_t floor = UINT32_MAX;
    for (uint32_t o = 0; o < bake.objects.size(); ++o)
        if (bake.objects[o].name == "floor_0_0") floor = o;
    ASSERT_NE(floor, UINT32_MAX);
    for (uint32_t c = 0; c < bake.cells.size(); ++c) bake.pvs.clear(c, floor);
    write_bake_file(edited, bake);

    const CliRun v = run({"verify", test::sample_world(), edited, "--report", report, "--verify-eyes", "4",
                          "--verify-rays-per-eye", "256", "--verify-rays", "200000"});
    EXPECT_EQ(v.status, kExitMisses) << v.log;
    EXPECT_TRUE(contains(v.log, "floor_0_0")) << v.log;
    const auto j = nlohmann::json::parse(test::read_file(report));
    bool named = false;
    for (const auto& m : j["verification"]["misses"]) named |= m["object_name"] == "floor_0_0";
    EXPECT_TRUE(named);
    // The misses are also written into the bake file's verification group.
    const BakeData after = read_bake_file(edited);
    ASSERT_TRUE(after.verification.ran);
    ASSERT_FALSE(after.verification.misses.empty());
    bool in_file = false;
    for (const Miss& m : after.verification.misses) in_file |= m.object == floor;
    EXPECT_TRUE(in_file);
}

TEST(Cli, BadInputGetsStatusTwoAClearMessageAndNoOutput) {
    test::TempDir dir;
    const std::string out = dir.file("out.h5");
    test::write_file(dir.file("notgltf.glb"), "this is not a glTF file at all");
    struct Case {
        std::vector<std::string> args;
        std::string says;
    };
    const std::vector<Case> cases = {
        {{"bake", dir.file("missing.glb"), "-o", out}, "missing.glb"},
        {{"bake", dir.file("notgltf.glb"), "-o", out}, "notgltf.glb"},
        {{"bake", test::sample_world(), "-o", out, "--cell-size", "-1"}, "--cell-size"},
        {{"bake", test::sample_world(), "-o", out, "--cell-size", "0.01"}, "--cell-size"},
        {{"bake", test::sample_world(), "-o", out, "--mode", "fast"}, "--mode"},
        {{"bake", test::sample_world()}, "--output"},
        {{"bake", test::sample_world(), "-o", out, "--view-box", "1,2,3"}, "--view-box"},
        {{"bake", test::sample_world(), "-o", out, "--view-box", "5,5,5,1,1,1"}, "--view-box"},
        {{"bake", test::sample_world(), "-o", out, "--view-seed", "1,x,3"}, "--view-seed"},
        {{"bake", test::sample_world(), "-o", out, "--no-world-seeds", "--view-seed", "500,500,500"},
         "view seed"},
        {{"bake", test::sample_world(), "-o", out, "--root-cell-size", "0.5", "--min-cell-size", "1"},
         "--root-cell-size"},
        {{"bake", test::sample_world(), "-o", out, "--verify-aimed-share", "0.99"}, "--verify-aimed-share"},
        {{"bake", test::sample_world(), "-o", out, "--verify-aimed-listed-share", "1.5"},
         "--verify-aimed-listed-share"},
        {{"bake", test::sample_world(), "-o", out, "--verify-neighbour-share", "-0.1"},
         "--verify-neighbour-share"},
        {{"bake", test::sample_world(), "-o", out, "--occluder-seal-reach", "0"}, "--occluder-seal-reach"},
        {{"bake", test::sample_world(), "-o", out, "--occluder-seal-rays", "-3"}, "--occluder-seal-rays"},
        {{"bake", test::sample_world(), "-o", out, "--no-world-seeds"}, "--eyes-anywhere"},
        {{"bake", test::sample_world(), "-o", out, "--voxel-size", "0.001"}, "more than a voxel grid can hold"},
        {{"bake", test::sample_world(), "-o", out, "--max-memory", "20"}, "memory plan"},
        {{"occluders", dir.file("missing.glb"), "-o", dir.file("boxes.glb")}, "missing.glb"},
        {{"info", dir.file("notgltf.glb")}, "notgltf.glb"},
        {{"info", dir.file("missing.h5")}, "missing.h5"},
        {{"query", dir.file("missing.h5"), "1", "2"}, "point"},
        {{"frobnicate"}, "frobnicate"},
    };
    for (const Case& c : cases) {
        const CliRun r = run(c.args);
        EXPECT_EQ(r.status, kExitBadInput) << c.args[0] << " " << c.args.back() << "\n" << r.log;
        EXPECT_TRUE(contains(r.log, c.says)) << "expected '" << c.says << "' in: " << r.log;
        size_t error_lines = 0;
        for (size_t at = r.log.find("error:"); at != std::string::npos; at = r.log.find("error:", at + 1))
            ++error_lines;
        EXPECT_EQ(error_lines, 1u) << "one error line: " << r.log;
        EXPECT_FALSE(std::filesystem::exists(out));
    }
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);  // notgltf.glb only
}

// A closed 8 x 3 x 8 m room, a crate and a spawn point, as a .glb; the crate's vertex 7 moved to
// z = 1000 km, either in its data alone (flipped bytes: the accessor's min/max still say the crate's box) or
// honestly (min/max say so too).
std::string stray_vertex_world(const test::TempDir& dir, const std::string& stem, bool lying) {
    const auto box = [](glm::vec3 lo, glm::vec3 hi) {
        std::vector<glm::vec3> v;
        for (int k = 0; k < 8; ++k) v.emplace_back(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
        return v;
    };
    const std::vector<uint32_t> faces = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 4, 6, 0, 6, 2,
                                         1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3};
    test::GltfBuilder b;
    const int room = b.add_mesh({test::GltfBuilder::primitive(b.add_positions(box({-4, 0, -4}, {4, 3, 4})),
                                                              b.add_indices(faces, test::kGlUnsignedShort))});
    std::vector<glm::vec3> crate = box({1, 0, 1}, {2, 1, 2});
    if (!lying) crate[7].z = 1.0e6f;
    const int crate_positions = b.add_positions(crate);
    if (lying) {
        const size_t at = size_t(b.json["bufferViews"][size_t(crate_positions)]["byteOffset"]) + 7 * 12 + 8;
        const float far = 1.0e6f;
        std::memcpy(b.bin.data() + at, &far, 4);
    }
    const int crate_mesh = b.add_mesh({test::GltfBuilder::primitive(crate_positions, b.add_indices(faces))});
    b.set_scene({b.add_node("room", room), b.add_node("crate", crate_mesh),
                 b.add_node("spawn", -1, {{"translation", {-2, 1.5, -2}}, {"extras", {{"pvs_view_seed", true}}}})});
    return b.write_glb(dir, stem);
}

// The two stray-vertex files: refused at once (before any voxel), naming what is wrong, with no output.
TEST(Cli, StrayVertexFilesAreRefusedAtOnce) {
    test::TempDir dir;
    const std::string out = dir.file("out.h5");
    const CliRun lying = run({"bake", stray_vertex_world(dir, "lying", true), "-o", out, "--threads", "1"});
    EXPECT_EQ(lying.status, kExitBadInput) << lying.log;
    for (const char* says : {"accessor 2", "vertex 7 = (2, 1, 1e+06)", "declared bounds"})
        EXPECT_TRUE(contains(lying.log, says)) << says << " in: " << lying.log;
    const CliRun honest = run({"bake", stray_vertex_world(dir, "honest", false), "-o", out, "--threads", "1"});
    EXPECT_EQ(honest.status, kExitBadInput) << honest.log;
    for (const char* says : {"object 'crate' has a vertex 1000.0 km", "--allow-coarse-voxels"})
        EXPECT_TRUE(contains(honest.log, says)) << says << " in: " << honest.log;
    EXPECT_FALSE(std::filesystem::exists(out));
}

// A big level is not a fault: a small town baked with --max-voxels far below what it needs keeps voxels of
// --max-voxel-size (0.25 m), more of them, and bakes; the memory plan alone could refuse it.
TEST(Cli, AWorldPastMaxVoxelsKeepsVoxelsOfTheLimitAndBakes) {
    test::TempDir dir;
    TownParams town;
    town.size_m = 60.0f;
    town.max_height_m = 12.0f;
    const std::string world = dir.file("town.glb"), out = dir.file("town.h5");
    write_glb(edited_world(make_town_world(town), {}), world);
    const CliRun r = run({"bake", world, "-o", out, "--play-height", "3", "--max-voxels", "100000", "--no-verify",
                          "--occluder-probe-eyes", "64", "--occluder-gap-lines", "0", "--occluder-seal-rays", "0",
                          "--eyes", "2", "--rays", "64"});
    EXPECT_EQ(r.status, 0) << r.log;
    EXPECT_TRUE(contains(r.log, "view volume: 0.25 m voxels")) << r.log;
    EXPECT_TRUE(std::filesystem::exists(out));
}

// An output that cannot be written is bad input (status 2), found before the world is even loaded: the
// log holds no stage, and nothing is left behind. Likewise a folder given as the output, a report in a
// missing folder, and the occluders command.
TEST(Cli, UnwritableOutputFailsBeforeAnyStageAndLeavesNothing) {
    test::TempDir dir;
    const std::string out = dir.file("no/such/folder/out.h5");
    const CliRun r = run(with({"bake", test::sample_world(), "-o", out, "--no-verify"}, kFast));
    EXPECT_EQ(r.status, 2);
    EXPECT_TRUE(contains(r.log, "out.h5")) << r.log;
    EXPECT_TRUE(contains(r.log, "does not exist")) << r.log;
    EXPECT_FALSE(contains(r.log, "triangles")) << r.log;  // the world's load line
    EXPECT_FALSE(contains(r.log, "view volume")) << r.log;
    const CliRun folder = run(with({"bake", test::sample_world(), "-o", dir.path(), "--no-verify"}, kFast));
    EXPECT_EQ(folder.status, 2);
    EXPECT_TRUE(contains(folder.log, "is a folder")) << folder.log;
    const CliRun report = run(with({"bake", test::sample_world(), "-o", dir.file("ok.h5"), "--report",
                                    dir.file("none/r.json"), "--no-verify"},
                                   kFast));
    EXPECT_EQ(report.status, 2);
    EXPECT_TRUE(contains(report.log, "the report")) << report.log;
    const CliRun occ = run({"occluders", test::sample_world(), "-o", out});
    EXPECT_EQ(occ.status, 2);
    EXPECT_TRUE(contains(occ.log, "does not exist")) << occ.log;
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 0);
}

// Deterministic bakes (docs/FORMAT.md, "/run"): other thread counts give the same file but for the run's own
// record, in every mode and partition; the run record does differ (the thread count is in it).
TEST(Cli, OtherThreadCountsGiveTheSameFileOutsideRun) {
    test::TempDir dir;
    // The grid verified (its figures are compared too); the octree and the sampled mode without.
    const std::vector<std::vector<std::string>> kinds = {
        {}, {"--cells", "octree", "--no-verify"}, {"--mode", "sampled", "--no-verify"}};
    for (size_t k = 0; k < kinds.size(); ++k) {
        SCOPED_TRACE("bake kind " + std::to_string(k));
        std::vector<std::string> files;
        for (const char* threads : {"1", "2"}) {
            const std::string out = dir.file("t" + std::to_string(k) + "_" + threads + ".h5");
            const CliRun r = run(
                with(with({"bake", test::sample_world(), "-o", out, "--threads", threads}, kFast), kinds[k]));
            ASSERT_EQ(r.status, 0) << r.log;
            files.push_back(out);
        }
        const std::string log = dir.file("h5diff.txt");
        EXPECT_EQ(test::h5diff_outside_run(files[0], files[1], log), 0) << test::read_file(log);
        const BakeData one = read_bake_file(files[0]), two = read_bake_file(files[1]);
        EXPECT_NE(one.run.parameters, two.run.parameters);
        EXPECT_EQ(one.parameters, two.parameters);
        EXPECT_FALSE(one.run.timings_s.empty());
    }
}

TEST(Cli, HelpOnEverySubcommandAndTheRealBinary) {
    for (const char* sub : {"bake", "verify", "info", "query"}) {
        const CliRun r = run({sub, "--help"});
        EXPECT_EQ(r.status, 0) << sub;
        EXPECT_TRUE(contains(r.out, "--help")) << r.out;
    }
    const CliRun bake_help = run({"bake", "--help"});
    EXPECT_TRUE(contains(bake_help.out, "--cell-size")) << bake_help.out;
    EXPECT_TRUE(contains(bake_help.out, "[m]"));  // units in the help text
    EXPECT_TRUE(contains(bake_help.out, "--occluder-seal-rays")) << bake_help.out;
    const CliRun verify_help = run({"verify", "--help"});
    EXPECT_TRUE(contains(verify_help.out, "--verify-aimed-share")) << verify_help.out;
    EXPECT_TRUE(contains(verify_help.out, "--verify-aimed-listed-share")) << verify_help.out;
    EXPECT_TRUE(contains(verify_help.out, "--verify-neighbour-share")) << verify_help.out;
    EXPECT_EQ(std::system((std::string(PVSBAKE_BINARY) + " --help > /dev/null").c_str()), 0);
}

// `bake --help` lists every declared option once, under its group's title, the groups in the order of
// kOptionGroups; what is unproven or only measures sits under Experimental and says so.
TEST(Cli, BakeHelpListsEveryOptionOnceUnderItsGroup) {
    const std::string help = run({"bake", "--help"}).out;
    std::vector<size_t> title_at;
    for (const OptionGroup group : kOptionGroups) {
        const std::string title = std::string("\n") + to_string(group) + ":\n";
        const size_t at = help.find(title);
        ASSERT_NE(at, std::string::npos) << "no group " << to_string(group) << " in\n" << help;
        EXPECT_EQ(help.find(title, at + 1), std::string::npos) << "group listed twice: " << to_string(group);
        if (!title_at.empty()) EXPECT_GT(at, title_at.back()) << to_string(group) << " out of order";
        title_at.push_back(at);
    }
    BakeConfig config;
    visit_options(config, [&](const OptionSpec& spec, auto&) {
        const std::string flag = std::string("  ") + spec.flag + " ";
        const size_t at = help.find(flag);
        ASSERT_NE(at, std::string::npos) << spec.flag << " missing from\n" << help;
        EXPECT_EQ(help.find(flag, at + 1), std::string::npos) << spec.flag << " listed twice";
        // The option sits between its group's title and the next one.
        size_t group_index = 0;
        while (kOptionGroups[group_index] != spec.group) ++group_index;
        EXPECT_GT(at, title_at[group_index]) << spec.flag;
        if (group_index + 1 < title_at.size()) EXPECT_LT(at, title_at[group_index + 1]) << spec.flag;
        if (spec.group == OptionGroup::kExperimental) {
            const std::string text = spec.help;
            EXPECT_TRUE(text.find("NOT PROVEN") != std::string::npos ||
                        text.find("FOR MEASUREMENT ONLY") != std::string::npos ||
                        text.find("with --occluder-block") != std::string::npos)
                << spec.flag << ": an experimental option must say why it is one";
        }
    });
}

}  // namespace
}  // namespace pvs

namespace pvs {
namespace {

// The real levels (../shared/worlds) when present: a quick bake that info and query read back.
TEST(Cli, BakesTheRealWorldsWhenPresent) {
    int baked = 0;
    for (const char* name : {"oa_dm4.glb", "ctf_inyard.glb"}) {
        const std::string world = test::shared_world(name);
        if (world.empty()) continue;
        test::TempDir dir;
        const std::string out = dir.file("bake.h5");
        // The sampled mode: this checks the command line end to end; the conservative mode on these worlds is
        // measured by bench_conservative (minutes, not seconds).
        const CliRun bake = run({"bake", world, "-o", out, "--mode", "sampled", "--cell-size", "4", "--eyes",
                                 "2", "--rays", "128", "--verify-eyes", "2", "--verify-rays-per-eye", "64"});
        ASSERT_EQ(bake.status, 0) << bake.log;
        const CliRun info = run({"info", out, "--json"});
        ASSERT_EQ(info.status, 0) << info.log;
        const auto j = nlohmann::json::parse(info.out);
        EXPECT_EQ(j["objects"], std::string(name) == "oa_dm4.glb" ? 445 : 2636);
        EXPECT_TRUE(j["verification"]["ran"].get<bool>());
        // A spawn point of oa_dm4 and of ctf_inyard (their pvs_view_seed nodes).
        const std::vector<std::string> spawn = std::string(name) == "oa_dm4.glb"
                                                   ? std::vector<std::string>{"9.7536", "0.8128", "24.384"}
                                                   : std::vector<std::string>{"-4.8768", "2.6416", "8.128"};
        const CliRun q = run({"query", out, spawn[0], spawn[1], spawn[2], "--json"});
        ASSERT_EQ(q.status, 0) << q.log;
        const auto qj = nlohmann::json::parse(q.out);
        ASSERT_FALSE(qj["cell"].is_null());
        EXPECT_GT(qj["visible_count"].get<int>(), 0);
        EXPECT_LT(qj["visible_count"].get<int>(), j["objects"].get<int>());  // something is culled
        ++baked;
    }
    if (baked == 0) GTEST_SKIP() << "../shared/worlds is absent";
}

}  // namespace
}  // namespace pvs

// The parameters a bake stores give back the config it was made with (bench_overestimation rebuilds a
// bake's occluders from them), and a value that does not parse is named.
TEST(Config, ParametersGiveBackTheConfig) {
    pvs::BakeConfig config;
    config.mode = pvs::BakeMode::kSampled;
    config.cells.kind = pvs::CellKind::kOctree;
    config.cells.cell_size_m = 1.5;
    config.view.play_height_m = 3.0;
    config.view.use_world_boxes = false;
    config.view.boxes.push_back(pvs::Aabb::of(glm::vec3(-1.5f, 0.0f, 2.0f), glm::vec3(4.0f, 3.25f, 8.0f)));
    config.view.seeds.emplace_back(0.5f, 1.0f, -2.0f);
    config.verify.enabled = false;
    config.verify.rays.seed = (uint64_t(1) << 60) + 1;  // a double would round it
    config.conservative.epsilon_m = 0.0625;
    const auto params = pvs::resolved_parameters(config);
    const pvs::BakeConfig back = pvs::config_from_parameters(params);
    EXPECT_EQ(pvs::resolved_parameters(back), params);
    EXPECT_EQ(back.verify.rays.seed, config.verify.rays.seed);
    EXPECT_EQ(back.mode, pvs::BakeMode::kSampled);
    ASSERT_EQ(back.view.boxes.size(), 1u);
    EXPECT_EQ(back.view.boxes[0].max.y, 3.25f);

    auto bad = params;
    for (auto& [k, v] : bad)
        if (k == "cells.cell_size_m") v = "two";
    try {
        pvs::config_from_parameters(bad);
        FAIL() << "a cell size of 'two' was accepted";
    } catch (const pvs::Error& e) {
        EXPECT_NE(std::string(e.what()).find("cells.cell_size_m"), std::string::npos) << e.what();
    }
}
