// SPDX-License-Identifier: MIT
// make_crack_world: writes a world of the crack test set (samples/crack_set.h) to a .glb, and prints its
// cases (kind, width, wall, witness eye, target) as lines of text.
//
//   make_crack_world OUT.glb [--widths w1,w2,...] [--cases N] [--seed S]
//
// Defaults: widths 0.5, 1, 2, 5, 10, 50 and 500 mm, 8 cases each (every kind and wall in turn), seed 1.
// Deterministic: the same arguments give the same bytes.
#include "io/gltf_writer.h"
#include "samples/crack_set.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

int main(int argc, char** argv) {
    if (argc < 2 || argv[1][0] == '-') {
        std::fprintf(stderr, "usage: make_crack_world OUT.glb [--widths w1,w2,...] [--cases N] [--seed S]\n");
        return 2;
    }
    pvs::CrackSetSpec spec;
    spec.widths_m = {0.0005f, 0.001f, 0.002f, 0.005f, 0.01f, 0.05f, 0.5f};
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) {
            std::fprintf(stderr, "make_crack_world: %s wants a value\n", a.c_str());
            return 2;
        }
        const std::string v = argv[++i];
        char* end = nullptr;
        if (a == "--widths") {
            spec.widths_m.clear();
            size_t at = 0;
            while (at <= v.size()) {
                const size_t comma = std::min(v.find(',', at), v.size());
                const std::string item = v.substr(at, comma - at);
                const float w = std::strtof(item.c_str(), &end);
                if (item.empty() || *end != '\0' || !(w > 0.0f)) {
                    std::fprintf(stderr, "make_crack_world: --widths %s: '%s' is not a width in metres\n",
                                 v.c_str(), item.c_str());
                    return 2;
                }
                spec.widths_m.push_back(w);
                at = comma + 1;
            }
        } else if (a == "--cases" || a == "--seed") {
            const unsigned long long n = std::strtoull(v.c_str(), &end, 10);
            if (v.empty() || *end != '\0' || (a == "--cases" && n == 0)) {
                std::fprintf(stderr, "make_crack_world: %s %s: not a positive whole number\n", a.c_str(),
                             v.c_str());
                return 2;
            }
            if (a == "--cases") {
                spec.cases_per_width = uint32_t(std::min<unsigned long long>(n, 100000));
            } else {
                spec.seed = n;
            }
        } else {
            std::fprintf(stderr, "make_crack_world: unknown option %s\n", a.c_str());
            return 2;
        }
    }
    try {
        const pvs::CrackSet set = pvs::make_crack_set(spec);
        pvs::write_glb(set.scene, argv[1]);
        for (const pvs::CrackCase& c : set.cases) {
            std::printf("%s width %.4g m wall %.2f m witness (%.4f, %.4f, %.4f) target %s\n",
                        pvs::to_string(c.kind), double(c.width_m), double(c.wall_m), double(c.witness_eye.x),
                        double(c.witness_eye.y), double(c.witness_eye.z), c.target.c_str());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "make_crack_world: %s\n", e.what());
        return 1;
    }
    return 0;
}
