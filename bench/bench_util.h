// SPDX-License-Identifier: MIT
// Helpers shared by the benchmarks: medians and means of repeats, wall-clock seconds, and the map compiler's
// visibility (WORLD.vis.json).
// Every benchmark prints one JSON document on stdout; figures are medians of repeats and ratios taken
// within one run (the machines are shared and noisy). The commands are in docs/RESULTS.md.
#pragma once

#include "core/error.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace pvs::bench {

// The median (the mean of the two middle values when there is an even number of them); 0 when empty.
inline double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The arithmetic mean; 0 when empty.
inline double mean(const std::vector<double>& v) {
    return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
}

// A whole number in [min, max] given to `option` of the bench named `bench`; throws pvs::bad_input naming
// both (exit status 2) on anything else.
inline uint64_t parse_count(const char* bench, const char* option, const char* text, uint64_t min,
                            uint64_t max) {
    char* end = nullptr;
    errno = 0;
    const unsigned long long v = std::strtoull(text, &end, 10);
    if (errno != 0 || end == text || *end != '\0' || text[0] == '-' || v < min || v > max)
        throw pvs::bad_input(std::string(bench) + ": " + option + " " + text +
                             ": wants a whole number from " + std::to_string(min) + " to " +
                             std::to_string(max));
    return v;
}

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The map compiler's own visibility, from the WORLD.vis.json written beside a world: its BSP tree (start at
// nodes[0]; go to children[0] when dot(normal, p) >= dist, else children[1]; a negative child c is leaf
// -c - 1) and, per cluster, the share of the world's triangles its cluster PVS lets through
// (cluster_visible_triangle_fraction). Cluster -1 is solid or outside. `Json` is nlohmann::json (a template,
// so that this header needs no JSON library); from_json throws on a malformed file.
struct CompilerVis {
    struct Node {
        float normal[3] = {0.0f, 0.0f, 0.0f};
        float dist = 0.0f;
        int children[2] = {0, 0};
    };
    std::vector<Node> nodes;
    std::vector<int> leaf_cluster;
    std::vector<double> fraction;  // per cluster (where has_fraction)
    std::vector<uint8_t> given;    // per cluster: does the file give its fraction?

    template <class Json>
    static CompilerVis from_json(const Json& vis) {
        CompilerVis out;
        const auto& nodes = vis.at("nodes");
        const auto& leaves = vis.at("leaves");
        for (const auto& leaf : leaves) out.leaf_cluster.push_back(leaf.at("cluster").template get<int>());
        for (const auto& n : nodes) {
            Node node;
            for (int a = 0; a < 3; ++a) node.normal[a] = n.at("normal").at(size_t(a)).template get<float>();
            node.dist = n.at("dist").template get<float>();
            for (int c = 0; c < 2; ++c) {
                node.children[c] = n.at("children").at(size_t(c)).template get<int>();
                const long long k = node.children[c];
                if (k >= (long long)nodes.size() || (k < 0 && -k - 1 >= (long long)leaves.size()))
                    throw std::runtime_error("compiler visibility: node child " + std::to_string(k) +
                                             " is out of range");
            }
            out.nodes.push_back(node);
        }
        if (out.nodes.empty()) throw std::runtime_error("compiler visibility: no BSP nodes");
        for (const auto& [key, value] : vis.at("cluster_visible_triangle_fraction").items()) {
            const int cluster = std::stoi(key);
            if (cluster < 0 || std::to_string(cluster) != key) continue;
            if (cluster >= (1 << 24))
                throw std::runtime_error("compiler visibility: cluster " + key + " is out of range");
            if (size_t(cluster) >= out.fraction.size()) {
                out.fraction.resize(size_t(cluster) + 1, 0.0);
                out.given.resize(size_t(cluster) + 1, 0);
            }
            out.fraction[size_t(cluster)] = value.template get<double>();
            out.given[size_t(cluster)] = 1;
        }
        return out;
    }

    // The cluster holding p (anything with float x, y, z), -1 for solid or outside (or a tree that loops).
    template <class Point>
    int cluster_of(const Point& p) const {
        int n = 0;
        for (size_t steps = 0; n >= 0; ++steps) {
            if (steps > nodes.size()) return -1;
            const Node& node = nodes[size_t(n)];
            const float d = node.normal[0] * p.x + node.normal[1] * p.y + node.normal[2] * p.z;
            n = node.children[d >= node.dist ? 0 : 1];
        }
        return leaf_cluster[size_t(-n - 1)];
    }

    bool has_fraction(int cluster) const {
        return cluster >= 0 && size_t(cluster) < given.size() && given[size_t(cluster)];
    }
    // The cluster's share of the world's triangles (has_fraction(cluster) must hold).
    double fraction_of(int cluster) const { return fraction[size_t(cluster)]; }
};

}  // namespace pvs::bench
