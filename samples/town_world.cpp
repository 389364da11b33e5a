// SPDX-License-Identifier: MIT
#include "samples/town_world.h"

#include "core/random.h"
#include "samples/random_world.h"

#include <fmt/format.h>

#include <cmath>

namespace pvs {

World make_town_world(const TownParams& p) {
    World w;
    const float half = 0.5f * p.size_m;
    add_box_object(w, "ground", Aabb::of({-half, -1.0f, -half}, {half, 0.0f, half}));
    const float pitch = p.block_m + p.street_m;
    const int blocks = std::max(1, int(std::floor((p.size_m - p.street_m) / pitch)));
    const float start = -0.5f * (float(blocks) * pitch - p.street_m);  // the blocks centred on the ground
    const float lot = 0.5f * (p.block_m - 2.0f);                       // 2 m lanes inside a block
    Rng rng(p.seed, 77);
    for (int i = 0; i < blocks; ++i) {
        for (int j = 0; j < blocks; ++j) {
            const glm::vec2 corner(start + float(i) * pitch, start + float(j) * pitch);
            for (int k = 0; k < 4; ++k) {
                const glm::vec2 lo =
                    corner + glm::vec2(float(k & 1) * (lot + 2.0f), float(k >> 1) * (lot + 2.0f));
                const bool tallest = i == blocks / 2 && j == blocks / 2 && k == 0;
                const float h = tallest ? p.max_height_m
                                        : p.min_height_m + (p.max_height_m - p.min_height_m) * rng.uniform();
                add_box_object(w, fmt::format("building_{}_{}_{}", i, j, k),
                               Aabb::of({lo.x, 0.0f, lo.y}, {lo.x + lot, h, lo.y + lot}));
            }
        }
    }
    // A seed over every crossing of the streets between blocks (and around them).
    for (int i = 0; i <= blocks; ++i)
        for (int j = 0; j <= blocks; ++j)
            w.view_seeds.push_back({start - 0.5f * p.street_m + float(i) * pitch, 1.5f,
                                    start - 0.5f * p.street_m + float(j) * pitch});
    return w;
}

}  // namespace pvs
