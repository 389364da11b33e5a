// SPDX-License-Identifier: MIT
#include "core/config.h"

#include "core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
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

const char* to_string(OptionGroup group) {
    switch (group) {
        case OptionGroup::kGeneral:
            return "General";
        case OptionGroup::kOutput:
            return "Output";
        case OptionGroup::kViewVolume:
            return "View volume";
        case OptionGroup::kCells:
            return "Cells";
        case OptionGroup::kOccluders:
            return "Occluders";
        case OptionGroup::kRanking:
            return "Ranked occluders (run-time culling of moving objects)";
        case OptionGroup::kConservative:
            return "Conservative solver";
        case OptionGroup::kSampled:
            return "Sampled mode (AGGRESSIVE: may miss visible objects)";
        case OptionGroup::kVerification:
            return "Verification";
        case OptionGroup::kExperimental:
            return "Experimental (not proven, or for measurement only)";
    }
    return "?";
}

double largest_cell_edge_m(const CellConfig& config) {
    if (config.kind == CellKind::kGrid) return config.cell_size_m;
    const int levels =
        std::max(0, int(std::lround(std::log2(config.root_cell_size_m / config.min_cell_size_m))));
    return config.min_cell_size_m * std::ldexp(1.0, levels);
}

int conservative_levels_used(const ConservativeConfig& config, double cell_edge_m) {
    int levels = 0;
    while (levels < config.refine_levels && std::ldexp(config.epsilon_m, levels) < 0.5 * cell_edge_m)
        ++levels;
    return levels;
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

namespace {

double parse_number(const std::string& key, const std::string& text) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size())
        throw bad_input(fmt::format("parameter {}: '{}' is not a number", key, text));
    return v;
}

bool parse_bool(const std::string& key, const std::string& text) {
    if (text == "true") return true;
    if (text == "false") return false;
    throw bad_input(fmt::format("parameter {}: '{}' is neither true nor false", key, text));
}

// "a,b,c;d,e,f" -> numbers in groups of `group`.
std::vector<double> parse_groups(const std::string& key, const std::string& text, size_t group) {
    std::vector<double> out;
    size_t start = 0;
    while (start < text.size()) {
        size_t end = text.find_first_of(",;", start);
        if (end == std::string::npos) end = text.size();
        out.push_back(parse_number(key, text.substr(start, end - start)));
        start = end + 1;
    }
    if (out.size() % group != 0)
        throw bad_input(fmt::format("parameter {}: '{}' is not groups of {} numbers", key, text, group));
    return out;
}

}  // namespace

BakeConfig config_from_parameters(const std::vector<std::pair<std::string, std::string>>& parameters) {
    BakeConfig config;
    for (const auto& [key, value] : parameters) {
        if (key == "mode") {
            if (value != "sampled" && value != "conservative")
                throw bad_input(fmt::format("parameter mode: '{}' is not a bake mode", value));
            config.mode = value == "sampled" ? BakeMode::kSampled : BakeMode::kConservative;
        } else if (key == "cells.kind") {
            if (value != "grid" && value != "octree")
                throw bad_input(fmt::format("parameter cells.kind: '{}' is not a cell kind", value));
            config.cells.kind = value == "octree" ? CellKind::kOctree : CellKind::kGrid;
        } else if (key == "verify.enabled") {
            config.verify.enabled = parse_bool(key, value);
        } else if (key == "occluders.enabled") {
            config.occluders.enabled = parse_bool(key, value);
        } else if (key == "view.use_world_seeds") {
            config.view.use_world_seeds = parse_bool(key, value);
        } else if (key == "view.use_world_boxes") {
            config.view.use_world_boxes = parse_bool(key, value);
        } else if (key == "view.boxes") {
            const std::vector<double> v = parse_groups(key, value, 6);
            for (size_t i = 0; i < v.size(); i += 6)
                config.view.boxes.push_back(
                    Aabb::of(glm::vec3(float(v[i]), float(v[i + 1]), float(v[i + 2])),
                             glm::vec3(float(v[i + 3]), float(v[i + 4]), float(v[i + 5]))));
        } else if (key == "view.seeds") {
            const std::vector<double> v = parse_groups(key, value, 3);
            for (size_t i = 0; i < v.size(); i += 3)
                config.view.seeds.emplace_back(float(v[i]), float(v[i + 1]), float(v[i + 2]));
        } else {
            visit_options(config, [&](const OptionSpec& spec, auto& field) {
                if (key != spec.key) return;
                using T = std::decay_t<decltype(field)>;
                if constexpr (std::is_same_v<T, bool>) {
                    field = parse_bool(key, value);
                } else if constexpr (std::is_integral_v<T>) {
                    // Whole numbers as text: seeds pass 2^53, where a double would round them.
                    char* end = nullptr;
                    const long long v = std::strtoll(value.c_str(), &end, 10);
                    const unsigned long long u = std::strtoull(value.c_str(), &end, 10);
                    if (value.empty() || end != value.c_str() + value.size())
                        throw bad_input(fmt::format("parameter {}: '{}' is not a whole number", key, value));
                    field = std::is_signed_v<T> ? T(v) : T(u);
                } else {
                    field = T(parse_number(key, value));
                }
            });
        }
    }
    return config;
}

}  // namespace pvs
