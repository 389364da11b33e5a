// SPDX-License-Identifier: MIT
// The glTF document's ids, counts, offsets and enums checked against the schema (io/gltf_references.h).
#include "io/gltf_references.h"

#include "core/error.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <initializer_list>
#include <limits>

namespace pvs {

namespace {

using Json = nlohmann::json;

class ReferenceCheck {
public:
    ReferenceCheck(const std::string& path, const Json& doc) : path_(path), doc_(doc) {}

    void run() {
        integer(doc_, "scene", "", ref("scenes"));
        each("scenes", [&](const Json& s, const std::string& at) { ids(s, "nodes", at, "nodes"); });
        each("nodes", [&](const Json& n, const std::string& at) {
            ids(n, "children", at, "nodes");
            integer(n, "mesh", at, ref("meshes"));
            integer(n, "skin", at, ref("skins"));
            integer(n, "camera", at, ref("cameras"));
        });
        each("meshes", [&](const Json& m, const std::string& at) {
            members(m, "primitives", at, [&](const Json& p, const std::string& pat) {
                if (p.contains("attributes") && p["attributes"].is_object()) {
                    for (const auto& [name, value] : p["attributes"].items())
                        check(value, fmt::format("{}.attributes.{}", pat, name), ref("accessors"));
                }
                integer(p, "indices", pat, ref("accessors"));
                integer(p, "material", pat, ref("materials"));
                integer(p, "mode", pat, {0, 6, ""});
            });
        });
        each("accessors", [&](const Json& a, const std::string& at) {
            integer(a, "bufferView", at, ref("bufferViews"));
            integer(a, "byteOffset", at, {0, kMax, ""});
            integer(a, "count", at, {1, kMax, ""});
            component_type(a, "componentType", at, {5120, 5121, 5122, 5123, 5125, 5126});
            if (a.contains("sparse") && a["sparse"].is_object()) {
                const Json& s = a["sparse"];
                const std::string sat = at + ".sparse";
                integer(s, "count", sat, {1, kMax, ""});
                for (const char* part : {"indices", "values"}) {
                    if (!s.contains(part) || !s[part].is_object()) continue;
                    const std::string pat = fmt::format("{}.{}", sat, part);
                    integer(s[part], "bufferView", pat, ref("bufferViews"));
                    integer(s[part], "byteOffset", pat, {0, kMax, ""});
                    if (std::string(part) == "indices")
                        component_type(s[part], "componentType", pat, {5121, 5123, 5125});
                }
            }
        });
        each("bufferViews", [&](const Json& v, const std::string& at) {
            integer(v, "buffer", at, ref("buffers"));
            integer(v, "byteOffset", at, {0, kMax, ""});
            integer(v, "byteLength", at, {1, kMax, ""});
            integer(v, "byteStride", at, {4, 252, ""});
        });
        each("buffers", [&](const Json& b, const std::string& at) { integer(b, "byteLength", at, {1, kMax, ""}); });
    }

private:
    static constexpr double kMax = 9007199254740992.0;  // 2^53: the largest integer a JSON number keeps

    struct Range {
        double min, max;
        const char* of;  // the array an id names ("" for a plain range)
    };

    Range ref(const char* array) const {
        const Json* a = doc_.contains(array) ? &doc_[array] : nullptr;
        const double n = a && a->is_array() ? double(a->size()) : 0.0;
        return {0, n - 1, array};
    }

    [[noreturn]] void fail(const std::string& what) const {
        throw bad_input(fmt::format("{}: {}", path_, what));
    }

    static std::string shown(const Json& v) {
        std::string s = v.dump();
        if (s.size() > 40) s = s.substr(0, 37) + "...";
        return s;
    }

    void check(const Json& v, const std::string& at, const Range& range) const {
        const bool number = v.is_number();
        const double x = number ? v.get<double>() : 0.0;
        if (!number || !std::isfinite(x) || x != std::floor(x)) fail(fmt::format("{} is {}, not an integer", at, shown(v)));
        if (x >= range.min && x <= range.max) return;
        if (*range.of) {
            fail(fmt::format("{} is {}, not an index of {} ({} of them)", at, shown(v), range.of,
                             range.max + 1));
        }
        fail(fmt::format("{} is {}, outside [{}, {}]", at, shown(v), range.min, range.max));
    }

    void integer(const Json& object, const char* key, const std::string& at, const Range& range) const {
        if (!object.is_object() || !object.contains(key)) return;
        check(object[key], at.empty() ? key : fmt::format("{}.{}", at, key), range);
    }

    void component_type(const Json& object, const char* key, const std::string& at,
                        std::initializer_list<int> allowed) const {
        if (!object.is_object() || !object.contains(key)) return;
        const std::string where = fmt::format("{}.{}", at, key);
        check(object[key], where, {0, kMax, ""});
        const double v = object[key].get<double>();
        for (int a : allowed)
            if (v == a) return;
        fail(fmt::format("{} is {}, not a component type allowed there", where, shown(object[key])));
    }

    void ids(const Json& object, const char* key, const std::string& at, const char* array) const {
        if (!object.is_object() || !object.contains(key)) return;
        const Json& list = object[key];
        const std::string where = fmt::format("{}.{}", at, key);
        if (!list.is_array()) fail(fmt::format("{} is {}, not an array", where, shown(list)));
        const Range r = ref(array);
        for (size_t i = 0; i < list.size(); ++i) check(list[i], fmt::format("{}[{}]", where, i), r);
    }

    template <typename Visit>
    void members(const Json& object, const char* key, const std::string& at, Visit&& visit) const {
        if (!object.is_object() || !object.contains(key) || !object[key].is_array()) return;
        const Json& list = object[key];
        for (size_t i = 0; i < list.size(); ++i) {
            const std::string where = at.empty() ? fmt::format("{}[{}]", key, i) : fmt::format("{}.{}[{}]", at, key, i);
            if (list[i].is_object()) visit(list[i], where);
        }
    }

    template <typename Visit>
    void each(const char* array, Visit&& visit) const {
        members(doc_, array, "", visit);
    }

    const std::string& path_;
    const Json& doc_;
};

}  // namespace

void check_gltf_references(const std::string& path, const std::string& json_text, int64_t bin_bytes) {
    const Json doc = Json::parse(json_text, nullptr, /*allow_exceptions=*/false);
    if (doc.is_discarded() || !doc.is_object()) return;
    ReferenceCheck(path, doc).run();
    // A .glb's buffer 0 without a uri is the BIN chunk: it must hold the buffer's byteLength (the chunk
    // may be up to 3 bytes longer, its padding).
    const Json* buffers = doc.contains("buffers") ? &doc["buffers"] : nullptr;
    if (bin_bytes == kNotGlb || !buffers || !buffers->is_array() || buffers->empty()) return;
    const Json& b = (*buffers)[0];
    if (!b.is_object() || b.contains("uri") || !b.contains("byteLength")) return;
    const double declared = b["byteLength"].get<double>();
    if (bin_bytes == kNoBinChunk) {
        throw bad_input(fmt::format("{}: buffers[0] has no uri and the .glb has no BIN chunk to hold its {} bytes",
                                    path, declared));
    }
    if (declared > double(bin_bytes)) {
        throw bad_input(fmt::format("{}: buffers[0].byteLength is {}, longer than the .glb's BIN chunk ({} bytes)",
                                    path, declared, bin_bytes));
    }
}

}  // namespace pvs
