// The JSON report of a bake.
#include "pvs/report.h"

#include <nlohmann/json.hpp>

namespace pvs {

std::string pvs_kind(const BakeData& bake) {
    return bake.conservative ? "conservative" : "aggressive (" + bake.mode + ": may miss visible objects)";
}

namespace {
nlohmann::ordered_json values_json(const NamedValues& values) {
    nlohmann::ordered_json j = nlohmann::ordered_json::object();
    for (const auto& [k, v] : values) j[k] = v;
    return j;
}
double figure(const NamedValues& values, const std::string& key, double fallback) {
    for (const auto& [k, v] : values)
        if (k == key) return v;
    return fallback;
}
}  // namespace

std::string bake_report_json(const BakeData& bake, const std::vector<std::string>& warnings) {
    nlohmann::ordered_json j;
    j["tool"] = "pvsbake";
    j["version"] = bake.tool_version;
    j["format"] = std::to_string(bake.format_major) + "." + std::to_string(bake.format_minor);
    j["world"] = bake.world_path;
    j["world_hash"] = bake.world_hash;
    j["mode"] = bake.mode;
    j["conservative"] = bake.conservative;
    j["pvs_kind"] = pvs_kind(bake);
    j["objects"] = bake.objects.size();
    j["triangles"] = uint64_t(figure(bake.figures, "triangles", 0));
    j["cells"] = bake.cells.size();
    nlohmann::ordered_json params = nlohmann::ordered_json::object();
    for (const auto& [k, v] : bake.parameters) params[k] = v;
    j["parameters"] = params;
    j["timings_s"] = values_json(bake.timings_s);
    j["figures"] = values_json(bake.figures);
    nlohmann::ordered_json ranked;
    ranked["stored"] = !bake.ranked.empty();
    ranked["entries"] = bake.ranked.entries.size();
    ranked["per_cell_mean"] =
        bake.cells.size() ? double(bake.ranked.entries.size()) / double(bake.cells.size()) : 0.0;
    j["ranked_occluders"] = ranked;
    nlohmann::ordered_json leak = nlohmann::ordered_json::array();
    for (const glm::vec3& p : bake.leak_path) leak.push_back({p.x, p.y, p.z});
    j["leak_path"] = leak;
    nlohmann::ordered_json ver;
    ver["ran"] = bake.verification.ran;
    if (bake.verification.ran) {
        ver["figures"] = values_json(bake.verification.figures);
        nlohmann::ordered_json misses = nlohmann::ordered_json::array();
        for (const Miss& m : bake.verification.misses) {
            nlohmann::ordered_json mj;
            mj["cell"] = m.cell;
            mj["object"] = m.object;
            mj["object_name"] = m.object < bake.objects.size() ? bake.objects[m.object].name : "";
            mj["eye"] = {m.eye.x, m.eye.y, m.eye.z};
            mj["direction"] = {m.direction.x, m.direction.y, m.direction.z};
            mj["distance_m"] = m.distance_m;
            misses.push_back(mj);
        }
        ver["misses"] = misses;
    }
    j["verification"] = ver;
    j["warnings"] = warnings;
    return j.dump(2) + "\n";
}

}  // namespace pvs
