// The single-occluder pass (solver/region_hiding.h): exact tests of one panel or one box between a region
// and an object, checked against many random segments, and the hider on a small scene.
#include "core/random.h"
#include "solver/region_hiding.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

namespace pvs {
namespace {

Context quiet_context() {
    return Context(Context::Options{LogLevel::kError, true, nullptr});
}

glm::vec3 point_in(const Aabb& b, Rng& rng) {
    return b.min + b.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
}

Aabb random_box(Rng& rng, float span, float max_size) {
    const glm::vec3 c = (glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5f) * span;
    const glm::vec3 h = glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * max_size * 0.5f;
    return Aabb::of(c - h, c + h);
}

// Does the segment p -> x cross the closed flat rectangle `panel` (flat along `axis`)?
bool crosses(glm::vec3 p, glm::vec3 x, const Aabb& panel, int axis) {
    const double c = panel.min[axis];
    const double dp = p[axis] - c, dx = x[axis] - c;
    if (dp * dx > 0.0) return false;
    const double t = dp / (dp - dx);
    for (int k = 0; k < 3; ++k) {
        if (k == axis) continue;
        const double y = double(p[k]) + t * (double(x[k]) - double(p[k]));
        if (y < panel.min[k] || y > panel.max[k]) return false;
    }
    return true;
}

bool meets(glm::vec3 p, glm::vec3 x, const Aabb& box) {
    float t0, t1;
    const glm::vec3 d = x - p;
    const float len = glm::length(d);
    return len > 0.0f && ray_box_interval(p, d / len, box, len, t0, t1);
}

// Whenever panel_hides() says so, every one of many random segments from the region to the object crosses
// the panel; and it says so often enough for that to mean something.
TEST(RegionHiding, APanelThatHidesIsCrossedByEverySegment) {
    Rng rng(11, 3);
    int hides = 0, trials = 0;
    for (int i = 0; i < 20000 && hides < 300; ++i) {
        const int axis = int(rng.below(3));
        Aabb panel = random_box(rng, 4.0f, 12.0f);
        panel.min[axis] = panel.max[axis] = (rng.uniform() - 0.5f) * 2.0f;
        Aabb region = random_box(rng, 3.0f, 2.0f), object = random_box(rng, 3.0f, 2.0f);
        if (rng.uniform() < 0.3f) region.max[axis] = region.min[axis];  // flat regions (cell faces) too
        // Put the region before the plane and the object beyond it, most of the time.
        const float shift_r = panel.min[axis] - 0.2f - region.max[axis] - 3.0f * rng.uniform();
        const float shift_o = panel.min[axis] + 0.2f - object.min[axis] + 6.0f * rng.uniform();
        region.min[axis] += shift_r;
        region.max[axis] += shift_r;
        object.min[axis] += shift_o;
        object.max[axis] += shift_o;
        if (rng.uniform() < 0.5f) std::swap(region, object);
        ++trials;
        if (!panel_hides(region, object, panel, axis)) continue;
        ++hides;
        for (int s = 0; s < 2000; ++s) {
            const glm::vec3 p = point_in(region, rng), x = point_in(object, rng);
            ASSERT_TRUE(crosses(p, x, panel, axis)) << "trial " << i << ", segment " << s;
        }
        // Each corner too (the extremes).
        for (int a = 0; a < 8; ++a)
            for (int b = 0; b < 8; ++b) {
                const glm::vec3 p(a & 1 ? region.max.x : region.min.x, a & 2 ? region.max.y : region.min.y,
                                  a & 4 ? region.max.z : region.min.z);
                const glm::vec3 x(b & 1 ? object.max.x : object.min.x, b & 2 ? object.max.y : object.min.y,
                                  b & 4 ? object.max.z : object.min.z);
                ASSERT_TRUE(crosses(p, x, panel, axis));
            }
    }
    EXPECT_GE(hides, 100) << "of " << trials << " trials: the test is vacuous";
    EXPECT_LT(hides, trials);
}

TEST(RegionHiding, ABoxThatHidesIsMetByEverySegment) {
    Rng rng(12, 4);
    int hides = 0, trials = 0;
    for (int i = 0; i < 40000 && hides < 300; ++i) {
        const Aabb box = random_box(rng, 2.0f, 6.0f);
        const int axis = int(rng.below(3));
        Aabb region = random_box(rng, 3.0f, 1.5f), object = random_box(rng, 3.0f, 1.5f);
        const float shift_r = box.min[axis] - region.max[axis] - 3.0f * rng.uniform();
        const float shift_o = box.max[axis] - object.min[axis] + 3.0f * rng.uniform() - 0.5f;
        region.min[axis] += shift_r;
        region.max[axis] += shift_r;
        object.min[axis] += shift_o;
        object.max[axis] += shift_o;
        ++trials;
        if (!box_hides(region, object, box)) continue;
        ++hides;
        for (int s = 0; s < 2000; ++s) {
            const glm::vec3 p = point_in(region, rng), x = point_in(object, rng);
            ASSERT_TRUE(meets(p, x, box)) << "trial " << i << ", segment " << s;
        }
    }
    EXPECT_GE(hides, 100) << "of " << trials << " trials: the test is vacuous";
    EXPECT_LT(hides, trials);
}

// Touching the plane, or reaching past the panel's edge by a hair, is not hidden.
TEST(RegionHiding, EdgesAndContactAreNotHidden) {
    const Aabb panel = Aabb::of({0, 0, 5}, {4, 4, 5});  // flat along z at 5
    const Aabb region = Aabb::of({1, 1, 0}, {3, 3, 1});
    const Aabb behind = Aabb::of({1.5f, 1.5f, 6}, {2.5f, 2.5f, 7});
    EXPECT_TRUE(panel_hides(region, behind, panel, 2));
    EXPECT_TRUE(panel_hides(behind, region, panel, 2));  // either way round
    EXPECT_FALSE(panel_hides(region, Aabb::of({1.5f, 1.5f, 5}, {2.5f, 2.5f, 7}), panel, 2));  // touches it
    EXPECT_FALSE(panel_hides(region, Aabb::of({1.5f, 1.5f, 3}, {2.5f, 2.5f, 4}), panel, 2));  // in front
    // The object's far corner seen past the panel's edge: (3, 3, 1) -> (x, 3, 9) crosses z = 5 at
    // x = 2 + x / 2... make the object wide enough that some segment passes x > 4.
    EXPECT_FALSE(panel_hides(region, Aabb::of({1.5f, 1.5f, 8}, {5.2f, 2.5f, 9}), panel, 2));
    const Aabb box = Aabb::of({0, 0, 4}, {4, 4, 5});
    EXPECT_TRUE(box_hides(region, behind, box));
    EXPECT_FALSE(box_hides(region, Aabb::of({1.5f, 1.5f, 8}, {5.2f, 2.5f, 9}), box));
}

// The hider finds its candidates by tracing: an object behind a big wall panel is hidden from a region in
// front, one beside the wall, one the region meets and one in front of the wall are not; the same with
// the wall as a box.
TEST(RegionHiding, TheHiderOnASmallScene) {
    Context ctx = quiet_context();
    World w;
    auto add = [&](const Aabb& b) {
        WorldObject o;
        o.bounds = b;
        w.objects.push_back(o);
        return uint32_t(w.objects.size() - 1);
    };
    const uint32_t behind = add(Aabb::of({1, 1, 8}, {2, 2, 9}));
    const uint32_t beside = add(Aabb::of({12, 1, 8}, {13, 2, 9}));
    const uint32_t meets = add(Aabb::of({0, 0, 0}, {1, 1, 1}));
    const uint32_t front = add(Aabb::of({1, 1, 3}, {2, 2, 4}));
    const uint32_t empty = add(Aabb{});
    const std::vector<uint32_t> all{behind, beside, meets, front, empty};
    const Aabb region = Aabb::of({0.5f, 0.5f, 0.5f}, {2.5f, 2.5f, 2.5f});
    for (int as_box = 0; as_box < 2; ++as_box) {
        ShrunkOccluders set;
        set.epsilon_m = {0.1};
        set.boxes.resize(1);
        if (as_box) {
            set.boxes[0].push_back(Aabb::of({-5, -5, 5}, {7, 7, 6}));
        } else {
            set.panels.push_back(Aabb::of({-5, -5, 5}, {7, 7, 5}));
        }
        const RegionHider hider(ctx, set);
        std::vector<uint64_t> hidden(1, 0);
        EXPECT_EQ(hider.hide(w, region, all, hidden.data()), 1u) << (as_box ? "box" : "panel");
        EXPECT_EQ(hidden[0], uint64_t(1) << behind);
    }
}

}  // namespace
}  // namespace pvs
