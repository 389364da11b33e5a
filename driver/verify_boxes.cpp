// SPDX-License-Identifier: MIT
// The ranked occluders checked by rays (driver/verify_boxes.h).
#include "driver/verify_boxes.h"

#include "cells/eyes.h"
#include "core/random.h"

#include <fmt/format.h>

#include <algorithm>

namespace pvs {

namespace {

constexpr uint32_t kCellsPerBox = 4;   // cells whose eyes look at a box
constexpr uint32_t kEyesPerCell = 16;  // eye points of each
constexpr uint32_t kPointsPerEye = 8;  // points inside the box each eye aims at

}  // namespace

RankedBoxCheck check_ranked_boxes(Context& ctx, const RayScene& scene, const CellSet& cells,
                                  const std::vector<Occluder>& occluders, const RankedOccluders& ranked,
                                  uint64_t seed) {
    ScopedTimer timer(ctx, "verify_ranked_boxes");
    RankedBoxCheck out;
    if (ranked.empty()) return out;
    // The first kCellsPerBox cells ranking each box, in cell order.
    std::vector<std::vector<uint32_t>> rankers(occluders.size());
    for (uint32_t c = 0; c < cells.size() && c + 1 < ranked.offsets.size(); ++c)
        for (uint32_t k = ranked.offsets[c]; k < ranked.offsets[c + 1]; ++k) {
            const uint32_t box = ranked.entries[k].box;
            if (box < rankers.size() && rankers[box].size() < kCellsPerBox) rankers[box].push_back(c);
        }
    std::vector<uint32_t> boxes;  // not the panels (flat: proven by their triangles, nothing inside to see)
    for (uint32_t b = 0; b < rankers.size(); ++b) {
        const glm::vec3 size = occluders[b].box.size();
        if (!rankers[b].empty() && size.x != 0.0f && size.y != 0.0f && size.z != 0.0f) boxes.push_back(b);
    }
    std::vector<uint64_t> rays(boxes.size(), 0);
    std::vector<std::string> seen(boxes.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (int64_t i = 0; i < int64_t(boxes.size()); ++i) {
        const Occluder& o = occluders[boxes[size_t(i)]];
        if (!o.proven) {
            seen[size_t(i)] = "not proven";
            continue;
        }
        Rng rng(seed, boxes[size_t(i)]);
        std::vector<glm::vec3> eyes, origins, dirs;
        std::vector<float> tfar;
        for (uint32_t c : rankers[boxes[size_t(i)]]) sample_eye_points(cells, c, kEyesPerCell, seed, eyes);
        for (const glm::vec3& e : eyes)
            for (uint32_t k = 0; k < kPointsPerEye; ++k) {
                const glm::vec3 p = o.box.min + o.box.size() * glm::vec3(rng.uniform(), rng.uniform(), rng.uniform());
                const float d = glm::length(p - e);
                if (!(d > 0.0f)) continue;
                origins.push_back(e);
                dirs.push_back((p - e) / d);
                tfar.push_back(d);
            }
        std::vector<uint8_t> blocked(origins.size());
        scene.occluded_opaque(origins.data(), dirs.data(), tfar.data(), uint32_t(origins.size()), blocked.data());
        rays[size_t(i)] = origins.size();
        for (size_t r = 0; r < blocked.size(); ++r) {
            if (blocked[r]) continue;
            const glm::vec3 e = origins[r], p = e + dirs[r] * tfar[r];
            seen[size_t(i)] = fmt::format("an eye at ({:.2f}, {:.2f}, {:.2f}) sees ({:.2f}, {:.2f}, {:.2f}) inside it",
                                          e.x, e.y, e.z, p.x, p.y, p.z);
            break;
        }
    }
    out.boxes = uint32_t(boxes.size());
    for (size_t i = 0; i < boxes.size(); ++i) {
        out.rays += rays[i];
        if (seen[i].empty()) continue;
        if (out.seen_into++ == 0) {
            const Aabb& b = occluders[boxes[i]].box;
            out.first = fmt::format("ranked box {} ({:.2f}, {:.2f}, {:.2f})-({:.2f}, {:.2f}, {:.2f}): {}", boxes[i],
                                    b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z, seen[i]);
        }
    }
    const std::string line = fmt::format("verify: {} ranked occluder boxes, {:.2f} M rays into them from the eyes "
                                         "of the cells ranking them: {} seen into{}{}",
                                         out.boxes, double(out.rays) * 1e-6, out.seen_into,
                                         out.first.empty() ? "" : "; first: ", out.first);
    if (out.seen_into > 0) {
        ctx.warn(line);
    } else {
        ctx.info(line);
    }
    return out;
}

}  // namespace pvs
