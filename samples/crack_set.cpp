// SPDX-License-Identifier: MIT
// The crack test set: compartments with one opening each (crack_set.h).
#include "samples/crack_set.h"

#include "core/random.h"

#include <fmt/format.h>

#include <cmath>

namespace pvs {

namespace {

constexpr float kHalfLengthM = 2.0f;  // room A spans x in [-2, -wall / 2], room B [wall / 2, 2]
constexpr float kHeightM = 2.0f;      // y in [0, 2]
constexpr float kHalfDepthM = 1.0f;   // z in [-1, 1]
constexpr float kShellM = 0.2f;       // the closed boxes all round
constexpr float kSpacingM = 6.0f;     // between compartment centres
constexpr float kSlitLowM = 0.5f, kSlitHighM = 1.5f;  // the slits' vertical extent
constexpr float kArmM = 0.5f;                         // the L-slit's horizontal arm

// A uniformly random rotation (Shoemake's method: a uniform unit quaternion).
glm::mat3 random_rotation(Rng& rng) {
    const float u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
    const float a = std::sqrt(1.0f - u1), b = std::sqrt(u1);
    const float kTwoPi = 6.28318530718f;
    const float x = a * std::sin(kTwoPi * u2), y = a * std::cos(kTwoPi * u2);
    const float z = b * std::sin(kTwoPi * u3), w = b * std::cos(kTwoPi * u3);
    // Columns of the rotation matrix of (w, x, y, z).
    return glm::mat3(glm::vec3(1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)),
                     glm::vec3(2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)),
                     glm::vec3(2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)));
}

struct Compartment {
    SceneDesc& scene;
    std::string prefix;
    glm::mat3 rotation;
    glm::vec3 centre;

    glm::vec3 place(glm::vec3 local) const { return rotation * local + centre; }

    // A sheet in the plane x = x of the wall's extent (z in [-d, d], y in [0, top]) as a 3 x 3 grid of quads
    // with shared corners, less one triangle: the right triangle with its right angle at (y0, z0) and legs
    // `leg` along +y and +z.
    void holed_sheet(const std::string& name, float x, float d, float top, float y0, float z0, float leg) {
        SceneNode node;
        node.name = prefix + name;
        node.material = 0;
        const float ys[4] = {0.0f, y0, y0 + leg, top}, zs[4] = {-d, z0, z0 + leg, d};
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i) node.positions.push_back(place({x, ys[j], zs[i]}));
        auto at = [](int i, int j) { return uint32_t(j * 4 + i); };
        for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i) {
                // The quad's two halves, split along the diagonal from (i + 1, j) to (i, j + 1).
                if (!(i == 1 && j == 1))
                    node.indices.insert(node.indices.end(), {at(i, j), at(i + 1, j), at(i, j + 1)});
                node.indices.insert(node.indices.end(), {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
            }
        scene.nodes.push_back(std::move(node));
    }

    // A closed box of local bounds [lo, hi], turned and placed; skipped when empty.
    void box(const std::string& name, glm::vec3 lo, glm::vec3 hi) {
        if (hi.x - lo.x <= 1e-6f || hi.y - lo.y <= 1e-6f || hi.z - lo.z <= 1e-6f) return;
        SceneNode node = make_box_node(prefix + name, Aabb::of(lo, hi), 0);
        for (glm::vec3& p : node.positions) p = place(p);
        scene.nodes.push_back(std::move(node));
    }
};

// The wall between the rooms: x in [-wall / 2, wall / 2], less the opening of the case around z0.
void crack_wall(Compartment& c, CrackKind kind, float g, float wall, float z0) {
    const float x0 = -0.5f * wall, x1 = 0.5f * wall;
    const float h = 0.5f * g;
    const float top = kHeightM, d = kHalfDepthM;
    switch (kind) {
        case CrackKind::kSlit:
            c.box("wall_a", {x0, 0, -d}, {x1, top, z0 - h});
            c.box("wall_b", {x0, 0, z0 + h}, {x1, top, d});
            c.box("wall_above", {x0, kSlitHighM, z0 - h}, {x1, top, z0 + h});
            c.box("wall_below", {x0, 0, z0 - h}, {x1, kSlitLowM, z0 + h});
            break;
        case CrackKind::kLSlit:
            // The gap: a vertical arm z in [z0 - h, z0 + h], y in [low - h, high], and a horizontal one
            // z in [z0 - h, z0 + arm], y in [low - h, low + h].
            c.box("wall_a", {x0, 0, -d}, {x1, top, z0 - h});
            c.box("wall_above", {x0, kSlitHighM, z0 - h}, {x1, top, z0 + h});
            c.box("wall_right", {x0, kSlitLowM + h, z0 + h}, {x1, top, d});
            c.box("wall_below", {x0, 0, z0 - h}, {x1, kSlitLowM - h, d});
            c.box("wall_end", {x0, kSlitLowM - h, z0 + kArmM}, {x1, kSlitLowM + h, d});
            break;
        case CrackKind::kSeam:
            c.box("wall_a", {x0, 0, -d}, {x1, top, z0 - h});
            c.box("wall_b", {x0, 0, z0 + h}, {x1, top, d});
            break;
        case CrackKind::kTJunction:
            c.box("wall_a", {x0, 0, -d}, {x1, top, z0 - h});
            c.box("wall_b_low", {x0, 0, z0 + h}, {x1, 0.7f, d});
            c.box("wall_b_mid", {x0, 0.7f, z0 + h}, {x1, 1.3f, d});
            c.box("wall_b_high", {x0, 1.3f, z0 + h}, {x1, top, d});
            break;
        case CrackKind::kHole: {
            // The inscribed circle of a right triangle of legs a has diameter a (2 - sqrt 2): centred on
            // (y = 1, z = z0), the witness line's, when the right angle is at (1 - g / 2, z0 - g / 2).
            const float leg = g / (2.0f - std::sqrt(2.0f));
            c.holed_sheet("sheet_a", x0, d, top, 1.0f - h, z0 - h, leg);
            c.holed_sheet("sheet_b", x1, d, top, 1.0f - h, z0 - h, leg);
            break;
        }
    }
}

}  // namespace

const char* to_string(CrackKind kind) {
    switch (kind) {
        case CrackKind::kSlit:
            return "slit";
        case CrackKind::kLSlit:
            return "l_slit";
        case CrackKind::kSeam:
            return "seam";
        case CrackKind::kTJunction:
            return "t_junction";
        case CrackKind::kHole:
            return "hole";
    }
    return "?";
}

CrackSet make_crack_set(const CrackSetSpec& spec) {
    CrackSet out;
    out.scene.materials = {{"stone", {0.62f, 0.60f, 0.56f, 1.0f}, SceneMaterial::Alpha::kOpaque, false},
                           {"target", {0.85f, 0.25f, 0.2f, 1.0f}, SceneMaterial::Alpha::kOpaque, false}};
    const uint32_t total = uint32_t(spec.widths_m.size()) * spec.cases_per_width;
    const int side = std::max(1, int(std::ceil(std::cbrt(double(total)))));
    Rng rng(spec.seed, 0x637261636bULL);
    uint32_t index = 0;
    for (size_t wi = 0; wi < spec.widths_m.size(); ++wi) {
        for (uint32_t k = 0; k < spec.cases_per_width; ++k, ++index) {
            CrackCase cc;
            cc.kind = spec.kinds[k % spec.kinds.size()];
            cc.width_m = spec.widths_m[wi];
            cc.wall_m = spec.walls_m[(k / spec.kinds.size()) % spec.walls_m.size()];
            const glm::ivec3 slot(int(index) % side, (int(index) / side) % side, int(index) / (side * side));
            // Random orientation, and a random offset within the slot (the voxels cut it anywhere).
            const glm::vec3 jitter(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
            Compartment c{out.scene, fmt::format("case{}_", index), random_rotation(rng),
                          glm::vec3(slot) * kSpacingM + jitter * 0.5f};
            // Where along the wall the opening is (the L's arm needs room on its right).
            const float z0 = (rng.uniform() - 0.5f) * 0.6f - (cc.kind == CrackKind::kLSlit ? 0.2f : 0.0f);
            const float L = kHalfLengthM, H = kHeightM, D = kHalfDepthM, s = kShellM;
            c.box("floor", {-L - s, -s, -D - s}, {L + s, 0, D + s});
            c.box("ceiling", {-L - s, H, -D - s}, {L + s, H + s, D + s});
            c.box("end_a", {-L - s, 0, -D - s}, {-L, H, D + s});
            c.box("end_b", {L, 0, -D - s}, {L + s, H, D + s});
            c.box("side_near", {-L, 0, -D - s}, {L, H, -D});
            c.box("side_far", {-L, 0, D}, {L, H, D + s});
            crack_wall(c, cc.kind, cc.width_m, cc.wall_m, z0);
            // The target in room B, facing the opening; the spawn point and the witness in room A.
            const float xb = 0.5f * cc.wall_m;
            SceneNode target = make_box_node(
                c.prefix + "target", Aabb::of({xb + 0.8f, 0.8f, z0 - 0.2f}, {xb + 1.1f, 1.2f, z0 + 0.2f}), 1);
            for (glm::vec3& p : target.positions) p = c.place(p);
            cc.target = target.name;
            out.scene.nodes.push_back(std::move(target));
            const glm::vec3 eye_local(-xb - 0.9f, 1.0f, z0);
            cc.witness_eye = c.place(eye_local);
            cc.room_b_point = c.place(glm::vec3(xb + 0.4f, 1.0f, z0));
            SceneNode seed;
            seed.name = c.prefix + "spawn";
            seed.translation = cc.witness_eye;
            seed.view_seed = true;
            out.scene.nodes.push_back(std::move(seed));
            out.cases.push_back(cc);
        }
    }
    return out;
}

}  // namespace pvs
