// SPDX-License-Identifier: MIT
// pvsview headless: renders screenshots of a tiny world and checks pixels for what they must show.
// The world: box "a" (object 0) left of box "b" (object 1), seen from straight above (camera on +Z);
// four cells of 2 m in a row below them on screen; cells 0 and 1 see "a" only, cells 2 and 3 "b" only;
// one verification miss drawn as a red ray above the boxes. Without a display, pvsview runs under
// `xvfb-run -a`.
#include "viewer/png_image.h"
#include "viewer/view_model.h"

#include "core/world.h"
#include "io/bake_file.h"
#include "io/file_hash.h"
#include "io/gltf_writer.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace pvs::viewer {
namespace {

constexpr int kWidth = 400, kHeight = 300;
const char* const kCamera = "0,0,20,0,0,0,0,1,0";
const CameraPose kPose{{0, 0, 20}, {0, 0, 0}, {0, 1, 0}};

const Aabb kBoxA = Aabb::of({-3, -1, -1}, {-1, 1, 1});
const Aabb kBoxB = Aabb::of({1, -1, -1}, {3, 1, 1});
const Aabb kGlass = Aabb::of({-0.5f, 1.5f, -1}, {0.5f, 2.5f, 1});  // object 2, see-through (BLEND)
const Miss kMiss{2, 1, {0, 3, 0}, {1, 0, 0}, 3.0f};

struct Scene {
    test::TempDir dir;
    std::string world = dir.file("two_boxes.glb");
    std::string bake = dir.file("two_boxes.h5");

    // `miss_width_m`: the opening width stored with the miss (-1: not measured; below the default gap
    // tolerance of 1 mm: a narrow miss).
    explicit Scene(float miss_width_m = -1.0f) {
        SceneDesc desc;
        desc.nodes.push_back(make_box_node("a", kBoxA));
        desc.nodes.push_back(make_box_node("b", kBoxB));
        desc.materials.push_back(
            SceneMaterial{"glass", {0.5f, 0.7f, 1.0f, 0.3f}, SceneMaterial::Alpha::kBlend, false});
        desc.nodes.push_back(make_box_node("glass", kGlass, 0));
        write_glb(desc, world);
        BakeData b;
        b.tool_version = "pvsview test";
        b.world_path = world;
        b.world_hash = hash_file_hex(world);
        b.mode = "sampled";
        b.objects = {{"a", kBoxA, 12, kObjectHasOpaque},
                     {"b", kBoxB, 12, kObjectHasOpaque},
                     {"glass", kGlass, 12, kObjectHasSeeThrough}};
        b.cells.origin = {-4, -6, -1};
        b.cells.cell_size_m = 2;
        b.cells.dims = {4, 1, 1};
        b.cells.grid_to_cell = {0, 1, 2, 3};
        for (int i = 0; i < 4; ++i) {
            const glm::vec3 lo(-4.0f + 2.0f * float(i), -6.0f, -1.0f);
            b.cells.cells.push_back(Cell{Aabb::of(lo, lo + 2.0f), -1});
        }
        b.pvs = PvsSet::make(4, 3);
        b.pvs.set(0, 0);
        b.pvs.set(1, 0);
        b.pvs.set(2, 1);
        b.pvs.set(3, 1);
        b.verification.ran = true;
        b.verification.cell_sampled_visible = {1, 1, 1, 1};
        b.verification.misses = {kMiss};
        b.verification.misses[0].opening_width_m = miss_width_m;
        write_bake_file(bake, b);
    }
};

// Runs pvsview with `args` after WORLD BAKE; returns its exit status. stderr goes to `log`.
int run_pvsview(const Scene& s, const std::string& args, const std::string& log) {
    const char* display = std::getenv("DISPLAY");
    const std::string xvfb =
        display != nullptr && *display != '\0' ? "" : "xvfb-run -a -s '-screen 0 1280x1024x24' ";
    const std::string cmd = xvfb + "'" + PVSVIEW_BINARY + "' '" + s.world + "' '" + s.bake + "' " + args +
                            " > '" + log + "' 2>&1";
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

RgbImage screenshot(const Scene& s, const std::string& args) {
    const std::string png = s.dir.file("shot.png"), log = s.dir.file("shot.log");
    std::filesystem::remove(png);
    const int status =
        run_pvsview(s, "--screenshot '" + png + "' --size 400x300 --camera " + kCamera + " " + args, log);
    EXPECT_EQ(status, 0) << test::read_file(log);
    RgbImage img = read_png(png);
    EXPECT_EQ(img.width, kWidth);
    EXPECT_EQ(img.height, kHeight);
    return img;
}

// The pixel where a box's top face (facing the camera) has its centre.
std::array<int, 2> pixel_of(const Aabb& box) {
    const auto p =
        project_to_pixel(kPose, 30.0, kWidth, kHeight, {box.center().x, box.center().y, box.max.z});
    return {int(p->x), int(p->y)};
}

bool near(std::array<uint8_t, 3> got, Rgba want, int tolerance) {
    for (int k = 0; k < 3; ++k)
        if (std::abs(int(got[size_t(k)]) - int(want[size_t(k)])) > tolerance) return false;
    return true;
}

std::string str(std::array<uint8_t, 3> c) {
    return std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]);
}

TEST(PvsviewScreenshot, PickedCellShowsItsVisibleObjectInColourAndHidesTheOther) {
    Scene s;
    const RgbImage img = screenshot(s, "--cell 0 --hide --no-text");
    const auto [ax, ay] = pixel_of(kBoxA);
    const auto [bx, by] = pixel_of(kBoxB);
    EXPECT_TRUE(near(img.at(ax, ay), object_color(0), 40))
        << "a at " << ax << "," << ay << ": " << str(img.at(ax, ay));
    EXPECT_TRUE(near(img.at(bx, by), kBackground, 3))
        << "b at " << bx << "," << by << ": " << str(img.at(bx, by));
}

TEST(PvsviewScreenshot, AtPicksTheCellHoldingThePoint) {
    Scene s;
    const RgbImage img = screenshot(s, "--at 3 -5 0 --hide --no-text");  // cell 3: sees b only
    const auto [ax, ay] = pixel_of(kBoxA);
    const auto [bx, by] = pixel_of(kBoxB);
    EXPECT_TRUE(near(img.at(bx, by), object_color(1), 40)) << str(img.at(bx, by));
    EXPECT_TRUE(near(img.at(ax, ay), kBackground, 3)) << str(img.at(ax, ay));
}

TEST(PvsviewScreenshot, KeysStepCellsAndToggleFadedAndHidden) {
    Scene s;
    // Cell 0 sees a; Right twice is cell 2, which sees b; f turns --hide back to faded.
    const RgbImage img = screenshot(s, "--cell 0 --hide --no-text --keys Right,Right,f");
    const auto [ax, ay] = pixel_of(kBoxA);
    const auto [bx, by] = pixel_of(kBoxB);
    EXPECT_TRUE(near(img.at(bx, by), object_color(1), 40)) << str(img.at(bx, by));
    const auto a = img.at(ax, ay);
    EXPECT_FALSE(near(a, kBackground, 3)) << str(a);
    EXPECT_FALSE(near(a, object_color(0), 60)) << str(a);
    // Left from cell 0 wraps to the last cell (3, sees b); Escape unpicks: both neutral.
    const RgbImage wrapped = screenshot(s, "--cell 0 --hide --no-text --keys Left");
    EXPECT_TRUE(near(wrapped.at(bx, by), object_color(1), 40)) << str(wrapped.at(bx, by));
    const RgbImage none = screenshot(s, "--cell 0 --hide --no-text --keys Escape");
    EXPECT_TRUE(near(none.at(ax, ay), kNeutralOpaque, 40)) << str(none.at(ax, ay));
    EXPECT_TRUE(near(none.at(bx, by), kNeutralOpaque, 40)) << str(none.at(bx, by));
}

TEST(PvsviewScreenshot, ClickOnAnObjectPicksTheNearestCellAndAnswersAtOnce) {
    Scene s;
    const auto [ax, ay] = pixel_of(kBoxA);
    const auto [bx, by] = pixel_of(kBoxB);
    const std::string png = s.dir.file("click.png"), log = s.dir.file("click.log");
    ASSERT_EQ(run_pvsview(s,
                          "--screenshot '" + png + "' --size 400x300 --camera " + kCamera +
                              " --hide --no-text --click " + std::to_string(bx) + " " + std::to_string(by),
                          log),
              0)
        << test::read_file(log);
    // b's top face is above cells 2 and 3 (both see b only): b in colour, a hidden.
    const RgbImage img = read_png(png);
    EXPECT_TRUE(near(img.at(bx, by), object_color(1), 40)) << str(img.at(bx, by));
    EXPECT_TRUE(near(img.at(ax, ay), kBackground, 3)) << str(img.at(ax, ay));
    const std::string text = test::read_file(log);
    EXPECT_NE(text.find("pvsview: picked cell 2 in"), std::string::npos) << text;
}

TEST(PvsviewScreenshot, ObjectsNotInThePvsAreFadedByDefault) {
    Scene s;
    const RgbImage img = screenshot(s, "--cell 0 --no-text");
    const auto [bx, by] = pixel_of(kBoxB);
    const auto c = img.at(bx, by);
    EXPECT_FALSE(near(c, kBackground, 3)) << str(c);       // drawn,
    EXPECT_FALSE(near(c, object_color(1), 60)) << str(c);  // but not in its colour,
    EXPECT_LT(std::max({c[0], c[1], c[2]}) - std::min({c[0], c[1], c[2]}), 25) << str(c);  // grey
}

TEST(PvsviewScreenshot, NoPickShowsTheWorldNeutralAndMissesInRed) {
    Scene s;
    const RgbImage img = screenshot(s, "--no-text");
    const auto [ax, ay] = pixel_of(kBoxA);
    EXPECT_TRUE(near(img.at(ax, ay), kNeutralOpaque, 40)) << str(img.at(ax, ay));
    // The miss: a red ray from (0, 3, 0) to (3, 3, 0); look around its middle.
    const glm::vec3 mid = kMiss.eye + kMiss.direction * (0.5f * kMiss.distance_m);
    const auto p = project_to_pixel(kPose, 30.0, kWidth, kHeight, mid);
    bool red = false;
    for (int dy = -3; dy <= 3 && !red; ++dy) {
        const auto c = img.at(int(p->x), int(p->y) + dy);
        red = c[0] > 180 && c[1] < 90 && c[2] < 90;
    }
    EXPECT_TRUE(red) << "no red miss ray near " << p->x << "," << p->y;
    const RgbImage without = screenshot(s, "--no-text --no-misses");
    const auto c = without.at(int(p->x), int(p->y));
    EXPECT_FALSE(c[0] > 180 && c[1] < 90 && c[2] < 90) << str(c);
}

// A miss through an opening narrower than the gap tolerance is drawn amber, not red.
TEST(PvsviewScreenshot, NarrowMissesAreAmber) {
    Scene s(0.0001f);
    const RgbImage img = screenshot(s, "--no-text");
    const glm::vec3 mid = kMiss.eye + kMiss.direction * (0.5f * kMiss.distance_m);
    const auto p = project_to_pixel(kPose, 30.0, kWidth, kHeight, mid);
    bool amber = false, red = false;
    for (int dy = -3; dy <= 3; ++dy) {
        const auto c = img.at(int(p->x), int(p->y) + dy);
        amber |= c[0] > 180 && c[1] > 110 && c[1] < 220 && c[2] < 90;
        red |= c[0] > 180 && c[1] < 90 && c[2] < 90;
    }
    EXPECT_TRUE(amber) << "no amber miss ray near " << p->x << "," << p->y;
    EXPECT_FALSE(red);
}

TEST(PvsviewScreenshot, SeeThroughObjectsAreTranslucent) {
    Scene s;
    const RgbImage img = screenshot(s, "--no-text --no-misses");
    const auto [gx, gy] = pixel_of(kGlass);
    const auto c = img.at(gx, gy);
    // Blended over the background: bluish, lighter than the background, darker than the glass colour.
    EXPECT_FALSE(near(c, kBackground, 5)) << str(c);
    EXPECT_GT(int(c[2]), int(c[0]) + 15) << str(c);
    EXPECT_LT(int(c[2]), int(kNeutralSeeThrough[2]) - 30) << str(c);
}

TEST(PvsviewScreenshot, CellsAreDrawnAsAHeatMapBelowTheBoxes) {
    Scene s;
    const auto count_bright = [](const RgbImage& img) {
        int n = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width / 2; ++x)  // the left half: cells, no legend
                n += near(img.at(x, y), kBackground, 12) ? 0 : 1;
        return n;
    };
    const RgbImage with_cells = screenshot(s, "--no-text --no-misses --slice");
    const RgbImage without = screenshot(s, "--no-text --no-misses --no-cells");
    EXPECT_GT(count_bright(with_cells), count_bright(without) + 500);
}

TEST(PvsviewScreenshot, DefaultCameraOverlaysAndEveryLayerRender) {
    Scene s;
    const std::string png = s.dir.file("all.png"), log = s.dir.file("all.log");
    ASSERT_EQ(
        run_pvsview(
            s, "--screenshot '" + png + "' --size 320x200 --cell 1 --occluders --view-volume --help-overlay",
            log),
        0)
        << test::read_file(log);
    const RgbImage img = read_png(png);
    EXPECT_EQ(img.width, 320);
    EXPECT_EQ(img.height, 200);
    EXPECT_NE(test::read_file(log).find("pvsview: wrote"), std::string::npos);
}

TEST(PvsviewScreenshot, BadInputExitsTwoWithAMessage) {
    Scene s;
    const std::string log = s.dir.file("bad.log"), png = s.dir.file("bad.png");
    EXPECT_EQ(run_pvsview(s, "--screenshot '" + png + "' --cell 9", log), 2);
    EXPECT_NE(test::read_file(log).find("--cell 9"), std::string::npos) << test::read_file(log);
    EXPECT_EQ(run_pvsview(s, "--screenshot '" + png + "' --at 50 50 50", log), 2);
    EXPECT_EQ(run_pvsview(s, "--screenshot '" + png + "' --camera 1,2,3", log), 2);
    EXPECT_EQ(run_pvsview(s, "--screenshot '" + png + "' --size 12", log), 2);
    EXPECT_EQ(run_pvsview(s, "--keys Right", log), 2);  // keys replay only before a headless shot
    EXPECT_FALSE(std::filesystem::exists(png));
    // A bake of another world.
    SceneDesc other;
    other.nodes.push_back(make_box_node("c", kBoxA));
    write_glb(other, s.world);
    EXPECT_EQ(run_pvsview(s, "--screenshot '" + png + "'", log), 2);
    EXPECT_NE(test::read_file(log).find("not the world it was baked from"), std::string::npos)
        << test::read_file(log);
}

}  // namespace
}  // namespace pvs::viewer
