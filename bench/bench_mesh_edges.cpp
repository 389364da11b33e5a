// SPDX-License-Identifier: MIT
// bench_mesh_edges: how closed a world's opaque surface is. The edges of its opaque triangles (vertices
// welded by exact position) that an odd number of triangles use are the surface's mod-2 boundary; where a
// long edge meets two shorter ones along one line (a T-junction) the three cancel, so the odd edges are then
// grouped by their line and what an odd number of them covers along it is kept. What is left is where the
// opaque surface is open: the rim of a real opening, the level's outer edge, or a crack between meshes.
//
//   bench_mesh_edges WORLD.glb [--min-open M]
//
// Lines are grouped by direction (to 1e-6) and by their point nearest the origin (to 1e-5 m): a census, not
// a proof. Prints JSON: opaque triangles and edges, odd edges and their length, the length left open after
// T-junctions, in how many pieces and how many of them at least --min-open long (default 0.01 m), the total
// edge length for scale, and the objects with and without open length.
#include "core/context.h"
#include "io/gltf_loader.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <map>
#include <tuple>
#include <unordered_map>
#include <vector>

namespace {

struct VecKey {
    float x, y, z;
    bool operator==(const VecKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct VecHash {
    size_t operator()(const VecKey& k) const {
        uint32_t a, b, c;
        std::memcpy(&a, &k.x, 4);
        std::memcpy(&b, &k.y, 4);
        std::memcpy(&c, &k.z, 4);
        return size_t(a) * 73856093u ^ size_t(b) * 19349663u ^ size_t(c) * 83492791u;
    }
};

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: bench_mesh_edges WORLD.glb [--min-open M]\n");
        return 2;
    }
    double min_open = 0.01;
    for (int a = 2; a + 1 < argc; a += 2)
        if (!std::strcmp(argv[a], "--min-open")) min_open = std::atof(argv[a + 1]);
    try {
        pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, true, stderr});
        const pvs::World world = pvs::load_world(ctx, argv[1]);
        // Welded vertices.
        std::unordered_map<VecKey, uint32_t, VecHash> weld;
        std::vector<uint32_t> id(world.positions.size());
        std::vector<glm::dvec3> point;
        for (size_t v = 0; v < world.positions.size(); ++v) {
            const glm::vec3 p = world.positions[v];
            const auto [it, fresh] = weld.try_emplace(VecKey{p.x, p.y, p.z}, uint32_t(point.size()));
            if (fresh) point.push_back(glm::dvec3(p));
            id[v] = it->second;
        }
        // Edge uses, and the object of each edge's first use.
        std::map<std::pair<uint32_t, uint32_t>, std::pair<uint32_t, uint32_t>> uses;  // -> (count, object)
        uint64_t opaque = 0;
        double total_length = 0.0;
        for (uint32_t o = 0; o < world.objects.size(); ++o) {
            const pvs::WorldObject& obj = world.objects[o];
            for (uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count; ++t) {
                if (!world.triangle_opaque[t]) continue;
                ++opaque;
                for (int e = 0; e < 3; ++e) {
                    uint32_t a = id[world.triangles[t].v[e]], b = id[world.triangles[t].v[(e + 1) % 3]];
                    if (a == b) continue;
                    if (a > b) std::swap(a, b);
                    auto [it, fresh] = uses.try_emplace({a, b}, std::make_pair(0u, o));
                    if (fresh) total_length += glm::length(point[a] - point[b]);
                    ++it->second.first;
                }
            }
        }
        // Odd edges, grouped by line.
        struct Span {
            double a, b;
            uint32_t object;
        };
        std::map<std::tuple<int64_t, int64_t, int64_t, int64_t, int64_t, int64_t>, std::vector<Span>> lines;
        uint64_t odd = 0;
        double odd_length = 0.0;
        for (const auto& [edge, use] : uses) {
            if (use.first % 2 == 0) continue;
            ++odd;
            const glm::dvec3 p = point[edge.first], q = point[edge.second];
            glm::dvec3 d = glm::normalize(q - p);
            // One sign per direction: the first nonzero component positive.
            if (d.x < 0 || (d.x == 0 && (d.y < 0 || (d.y == 0 && d.z < 0)))) d = -d;
            const glm::dvec3 foot = p - d * glm::dot(p, d);
            const auto r = [](double v, double s) { return int64_t(std::llround(v / s)); };
            const auto key = std::make_tuple(r(d.x, 1e-6), r(d.y, 1e-6), r(d.z, 1e-6), r(foot.x, 1e-5),
                                             r(foot.y, 1e-5), r(foot.z, 1e-5));
            double a = glm::dot(p, d), b = glm::dot(q, d);
            if (a > b) std::swap(a, b);
            lines[key].push_back({a, b, use.second});
            odd_length += b - a;
        }
        // What an odd number of a line's spans covers.
        double open_length = 0.0, resting_length = 0.0;
        uint64_t pieces = 0, long_pieces = 0, open_lines = 0;
        // Does the point lie on an opaque triangle other than those whose edge it is on (within 0.1 mm of
        // its plane and inside it)? Then the open edge rests on a surface (a wall standing on a floor).
        const auto rests = [&](const glm::dvec3& m, const glm::dvec3& dir) {
            for (size_t t = 0; t < world.triangles.size(); ++t) {
                if (!world.triangle_opaque[t]) continue;
                const glm::dvec3 a = point[id[world.triangles[t].v[0]]],
                                 b = point[id[world.triangles[t].v[1]]],
                                 c = point[id[world.triangles[t].v[2]]];
                glm::dvec3 n = glm::cross(b - a, c - a);
                const double len = glm::length(n);
                if (len == 0.0) continue;
                n /= len;
                if (std::abs(glm::dot(m - a, n)) > 1e-4) continue;
                if (std::abs(glm::dot(dir, n)) > 1e-3) continue;  // the edge must lie in the plane
                const auto inside = [&](const glm::dvec3& p, const glm::dvec3& q) {
                    return glm::dot(glm::cross(q - p, m - p), n) > 1e-6;
                };
                if (inside(a, b) && inside(b, c) && inside(c, a)) return true;
            }
            return false;
        };
        std::vector<double> object_open(world.objects.size(), 0.0);
        for (auto& [key, spans] : lines) {
            const glm::dvec3 dir =
                glm::dvec3(double(std::get<0>(key)), double(std::get<1>(key)), double(std::get<2>(key))) *
                1e-6;
            const glm::dvec3 foot =
                glm::dvec3(double(std::get<3>(key)), double(std::get<4>(key)), double(std::get<5>(key))) *
                1e-5;
            std::vector<std::pair<double, uint32_t>> ev;  // position, object of the span that starts/ends
            for (const Span& s : spans) {
                ev.push_back({s.a, s.object});
                ev.push_back({s.b, s.object});
            }
            std::sort(ev.begin(), ev.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
            bool open = false, line_open = false;
            double start = 0.0;
            for (size_t i = 0; i < ev.size(); ++i) {
                const double x = ev[i].first;
                if (open && x > start) {
                    const double len = x - start;
                    open_length += len;
                    object_open[ev[i].second] += len;
                    line_open = true;
                }
                open = !open;
                start = x;
            }
            // Pieces: maximal runs of odd coverage.
            open = false;
            double run = 0.0, last = 0.0;
            for (size_t i = 0; i < ev.size(); ++i) {
                const double x = ev[i].first;
                if (open) {
                    run += x - last;
                    if (x > last && rests(foot + dir * (0.5 * (x + last)), dir)) resting_length += x - last;
                }
                open = !open;
                last = x;
                const bool joined = i + 1 < ev.size() && ev[i + 1].first == x;
                if (!open && !joined && run > 0.0) {
                    ++pieces;
                    if (run >= min_open) ++long_pieces;
                    run = 0.0;
                }
            }
            if (line_open) ++open_lines;
        }
        uint32_t with_open = 0, opaque_objects = 0;
        for (uint32_t o = 0; o < world.objects.size(); ++o) {
            if (!(world.objects[o].flags & pvs::kObjectHasOpaque)) continue;
            ++opaque_objects;
            if (object_open[o] >= min_open) ++with_open;
        }
        nlohmann::json j;
        j["world"] = argv[1];
        j["opaque_triangles"] = opaque;
        j["welded_vertices"] = point.size();
        j["edges"] = uses.size();
        j["edge_length_m"] = total_length;
        j["odd_edges"] = odd;
        j["odd_edge_length_m"] = odd_length;
        j["open_length_m"] = open_length;
        j["open_length_resting_on_a_surface_m"] = resting_length;
        j["open_share_of_edge_length"] = total_length > 0 ? open_length / total_length : 0.0;
        j["open_lines"] = open_lines;
        j["open_pieces"] = pieces;
        j["open_pieces_at_least_min"] = long_pieces;
        j["min_open_m"] = min_open;
        j["opaque_objects"] = opaque_objects;
        j["objects_with_open_length"] = with_open;
        std::cout << j.dump(2) << "\n";
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_mesh_edges: %s\n", e.what());
        return 1;
    }
}
