#include "core/config.h"

#include "core/error.h"

#include <fmt/format.h>

#include <cmath>
#include <type_traits>

namespace pvs {

const char* to_string(BakeMode mode) {
    switch (mode) {
        case BakeMode::kSampled:
            return "sampled";
        case BakeMode::kConservative:
            return "conservative";
    }
    return "?";
}

const char* to_string(CellKind kind) {
    return kind == CellKind::kOctree ? "octree" : "grid";
}

void validate(const BakeConfig& config) {
    if (config.cells.root_cell_size_m < config.cells.min_cell_size_m) {
        throw bad_input(fmt::format("option --root-cell-size ({} m) must not be below --min-cell-size ({} m)",
                                    config.cells.root_cell_size_m, config.cells.min_cell_size_m));
    }
    BakeConfig copy = config;
    visit_options(copy, [](const OptionSpec& spec, auto& field) {
        using T = std::decay_t<decltype(field)>;
        if constexpr (!std::is_same_v<T, bool>) {
            const double v = double(field);
            if (!std::isfinite(v) || v < spec.min || v > spec.max) {
                throw bad_input(fmt::format("option {} ({}): {} is outside [{}, {}]{}", spec.flag, spec.key,
                                            v, spec.min, spec.max,
                                            *spec.units ? fmt::format(" {}", spec.units) : ""));
            }
        }
    });
}

std::vector<std::pair<std::string, std::string>> resolved_parameters(const BakeConfig& config) {
    std::vector<std::pair<std::string, std::string>> out;
    out.emplace_back("mode", to_string(config.mode));
    out.emplace_back("cells.kind", to_string(config.cells.kind));
    out.emplace_back("verify.enabled", config.verify.enabled ? "true" : "false");
    out.emplace_back("occluders.enabled", config.occluders.enabled ? "true" : "false");
    out.emplace_back("view.use_world_seeds", config.view.use_world_seeds ? "true" : "false");
    out.emplace_back("view.use_world_boxes", config.view.use_world_boxes ? "true" : "false");
    std::string boxes, seeds;
    for (const Aabb& b : config.view.boxes) {
        boxes += fmt::format("{}{},{},{},{},{},{}", boxes.empty() ? "" : ";", b.min.x, b.min.y, b.min.z,
                             b.max.x, b.max.y, b.max.z);
    }
    for (const glm::vec3& p : config.view.seeds) {
        seeds += fmt::format("{}{},{},{}", seeds.empty() ? "" : ";", p.x, p.y, p.z);
    }
    out.emplace_back("view.boxes", boxes);
    out.emplace_back("view.seeds", seeds);
    BakeConfig copy = config;
    visit_options(copy, [&](const OptionSpec& spec, auto& field) {
        using T = std::decay_t<decltype(field)>;
        if constexpr (std::is_same_v<T, bool>) {
            out.emplace_back(spec.key, field ? "true" : "false");
        } else {
            out.emplace_back(spec.key, fmt::format("{}", field));
        }
    });
    return out;
}

}  // namespace pvs
