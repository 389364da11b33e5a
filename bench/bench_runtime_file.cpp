// SPDX-License-Identifier: MIT
// bench_runtime_file: the runtime file (io/runtime_file.h) and the C99 runtime (runtime/pvsr.h) against the
// HDF5 loader (pvsbake/loader.h), on bakes.
//
//   bench_runtime_file BAKE.h5 [BAKE.h5 ...] [--repeats R] [--queries Q] [--max-chain N] [--merge-cells K]
//                      [--row-order blocks|bake]
//
// For each bake: the runtime file's size and its sections' sizes, against the HDF5 file's size and what the
// HDF5 loader holds in memory (its footprint); the time of pvsr_open (checksum and every check) on the
// bytes mapped from a file written to the temporary folder, first on a fresh mapping (the pages come from the
// page cache as a game's first touch would) and then the median of R opens; the HDF5 loader's load (median
// of R); and one frame's work in each: find_cell of a random point in a random cell plus walking that cell's
// PVS (median over batches of Q queries; the same points for all): the runtime through its C++ wrapper
// (runtime/pvsr.hpp, the visit inlined), through the C callback, and the HDF5 loader; and the mean share of
// the world's triangles the runtime file's cells list (what --merge-cells costs); and how many answers differ
// from the HDF5 loader's (every cell's objects, box and ranked occluder boxes, and the cell and eye space of
// the query points: 0 expected). Prints one JSON object.
#include "bench/bench_util.h"
#include "io/runtime_file.h"
#include "runtime/pvsr.h"
#include "runtime/pvsr.hpp"

#include <pvsbake/loader.h>

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <vector>

namespace {

using pvs::bench::median;
using pvs::bench::seconds_since;

struct Mapping {
    void* at = MAP_FAILED;
    size_t size = 0;
    explicit Mapping(const std::string& path) {
        const int fd = ::open(path.c_str(), O_RDONLY);
        if (fd < 0) return;
        size = size_t(std::filesystem::file_size(path));
        at = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
        ::close(fd);
    }
    ~Mapping() {
        if (at != MAP_FAILED) ::munmap(at, size);
    }
};

struct Point {
    float p[3];
};

nlohmann::ordered_json measure(const std::string& bake_path, int repeats, int queries, uint32_t max_chain,
                               uint32_t merge_cells, bool block_order) {
    nlohmann::ordered_json j;
    j["bake"] = bake_path;
    j["bake_file_bytes"] = std::filesystem::file_size(bake_path);
    pvs::RuntimeFileFigures figures;
    pvs::RuntimeFileOptions options;
    options.max_chain = max_chain;
    options.merge_cells = merge_cells;
    options.block_order = block_order;
    j["max_chain"] = max_chain;
    j["row_order"] = block_order ? "blocks" : "bake";
    j["merge_cells"] = merge_cells;
    const std::string bytes = pvs::runtime_file_bytes(bake_path, options, &figures);
    j["runtime_file_bytes"] = figures.file_bytes;
    nlohmann::ordered_json sections;
    for (const auto& [tag, size] : figures.sections) sections[tag] = size;
    j["sections"] = sections;
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("bench_runtime_file_" + std::to_string(::getpid()) + ".pvsr"))
                                 .string();
    {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f || std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) {
            std::fprintf(stderr, "cannot write %s\n", path.c_str());
            std::exit(1);
        }
        std::fclose(f);
    }

    // pvsr_open: a fresh mapping first, then R more.
    pvsr_level level;
    char why[256];
    std::vector<double> opens;
    double first_open = 0.0;
    {
        Mapping m(path);
        const auto start = std::chrono::steady_clock::now();
        const pvsr_status s = pvsr_open(&level, m.at, m.size, why, sizeof why);
        first_open = seconds_since(start);
        if (s != PVSR_OK) {
            std::fprintf(stderr, "%s: %s\n", bake_path.c_str(), why);
            std::exit(1);
        }
    }
    Mapping m(path);
    for (int r = 0; r < repeats; ++r) {
        const auto start = std::chrono::steady_clock::now();
        pvsr_open(&level, m.at, m.size, why, sizeof why);
        opens.push_back(seconds_since(start));
    }
    j["runtime_open_first_ms"] = first_open * 1e3;
    j["runtime_open_median_ms"] = median(opens) * 1e3;

    // The HDF5 loader.
    pvsbake::Bake bake;
    std::vector<double> loads;
    for (int r = 0; r < repeats; ++r) {
        const auto start = std::chrono::steady_clock::now();
        const pvsbake::LoadResult res = bake.load(bake_path);
        loads.push_back(seconds_since(start));
        if (!res) {
            std::fprintf(stderr, "%s\n", res.message.c_str());
            std::exit(1);
        }
    }
    j["hdf5_load_median_ms"] = median(loads) * 1e3;
    j["hdf5_loader_memory_bytes"] = bake.pvs_stats().memory_bytes;
    j["runtime_over_hdf5_memory"] = double(figures.file_bytes) / double(bake.pvs_stats().memory_bytes);
    j["cells"] = bake.cell_count();
    j["objects"] = bake.object_count();

    // One frame's work: a random point of a random cell, its cell, its PVS walked.
    std::mt19937 rng(11);
    std::vector<Point> points;
    for (int i = 0; i < queries && bake.cell_count() > 0; ++i) {
        const pvsbake::Box b = bake.cell_bounds(uint32_t(rng() % bake.cell_count()));
        Point p;
        for (int a = 0; a < 3; ++a)
            p.p[a] = b.min[a] + (b.max[a] - b.min[a]) * std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
        points.push_back(p);
    }
    uint64_t sink = 0;
    std::vector<double> runtime_us, runtime_c_us, hdf5_us;
    pvsr::Level wrapped;
    wrapped.open(m.at, m.size);
    for (int r = 0; r < repeats && !points.empty(); ++r) {
        auto start = std::chrono::steady_clock::now();
        for (const Point& p : points) {
            const int32_t c = wrapped.find_cell(p.p[0], p.p[1], p.p[2]);
            if (c >= 0) wrapped.for_each_visible(uint32_t(c), [&](uint32_t o) { sink += o; });
        }
        runtime_us.push_back(seconds_since(start) * 1e6 / double(points.size()));
        start = std::chrono::steady_clock::now();
        for (const Point& p : points) {
            const int32_t c = pvsr_find_cell(&level, p.p[0], p.p[1], p.p[2]);
            if (c >= 0) sink += pvsr_visit_visible(&level, uint32_t(c), [](void* u, uint32_t o) { *static_cast<uint64_t*>(u) += o; }, &sink);
        }
        runtime_c_us.push_back(seconds_since(start) * 1e6 / double(points.size()));
        start = std::chrono::steady_clock::now();
        for (const Point& p : points) {
            const int32_t c = bake.find_cell(p.p[0], p.p[1], p.p[2]);
            if (c >= 0) bake.for_each_visible(uint32_t(c), [&](uint32_t o) { sink += o; });
        }
        hdf5_us.push_back(seconds_since(start) * 1e6 / double(points.size()));
    }
    j["runtime_query_median_us"] = runtime_us.empty() ? 0.0 : median(runtime_us);
    j["runtime_c_callback_query_median_us"] = runtime_c_us.empty() ? 0.0 : median(runtime_c_us);
    j["hdf5_query_median_us"] = hdf5_us.empty() ? 0.0 : median(hdf5_us);
    // What the cells list: the mean share of the world's triangles, over every cell (the cost of a merge).
    double share = 0.0;
    for (uint32_t c = 0; c < wrapped.cell_count(); ++c) {
        uint64_t tris = 0;
        wrapped.for_each_visible(c, [&](uint32_t o) { tris += wrapped.object_triangles(o); });
        share += double(tris) / double(std::max<uint64_t>(1, wrapped.total_triangles()));
    }
    j["listed_triangle_share_mean"] = wrapped.cell_count() ? share / double(wrapped.cell_count()) : 0.0;
    // Every answer the same as the HDF5 loader's (a merged file lists more by design: not compared): every
    // cell's objects, box and ranked occluder boxes, and the cell and eye space of the Q points above.
    uint64_t mismatches = 0;
    if (merge_cells == 1) {
        std::vector<uint32_t> got, want;
        for (uint32_t c = 0; c < bake.cell_count(); ++c) {
            got.clear();
            want.clear();
            wrapped.for_each_visible(c, [&](uint32_t o) { got.push_back(o); });
            bake.for_each_visible(c, [&](uint32_t o) { want.push_back(o); });
            mismatches += got != want;
            float box[6];
            wrapped.cell_bounds(c, box);
            const pvsbake::Box w = bake.cell_bounds(c);
            mismatches += std::memcmp(box, w.min, 12) != 0 || std::memcmp(box + 3, w.max, 12) != 0;
            std::vector<float> boxes(6 * size_t(bake.occluder_count(c)) + 6);
            std::vector<pvsbake::Box> want_boxes(bake.occluder_count(c) + 1);
            const uint32_t n = wrapped.occluder_boxes(c, boxes.data(), bake.occluder_count(c));
            const uint32_t m = bake.occluder_boxes(c, want_boxes.data(), bake.occluder_count(c));
            mismatches += n != m || (n > 0 && std::memcmp(boxes.data(), want_boxes.data(), size_t(n) * 24) != 0);
        }
        for (const Point& p : points) {
            mismatches += wrapped.find_cell(p.p[0], p.p[1], p.p[2]) != bake.find_cell(p.p[0], p.p[1], p.p[2]);
            mismatches += wrapped.in_eye_space(p.p[0], p.p[1], p.p[2]) != bake.in_eye_space(p.p[0], p.p[1], p.p[2]);
        }
        j["answers_differing_from_hdf5_loader"] = mismatches;
    }
    j["checksum_of_walks"] = sink % 1000;  // keeps the walks from being optimized away
    std::filesystem::remove(path);
    return j;
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> bakes;
    int repeats = 11, queries = 2000;
    uint32_t max_chain = pvs::RuntimeFileOptions{}.max_chain, merge_cells = 1;
    bool block_order = true;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--repeats" && i + 1 < argc) {
            repeats = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--merge-cells" && i + 1 < argc) {
            merge_cells = uint32_t(std::max(1, std::atoi(argv[++i])));
        } else if (a == "--max-chain" && i + 1 < argc) {
            max_chain = uint32_t(std::max(1, std::atoi(argv[++i])));
        } else if (a == "--row-order" && i + 1 < argc) {
            const std::string v = argv[++i];
            if (v != "blocks" && v != "bake") {
                std::fprintf(stderr, "bench_runtime_file: --row-order %s: wants blocks or bake\n", v.c_str());
                return 2;
            }
            block_order = v == "blocks";
        } else if (a == "--queries" && i + 1 < argc) {
            queries = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--help" || a.rfind("--", 0) == 0) {
            std::fprintf(stderr,
                         "usage: bench_runtime_file BAKE.h5 [BAKE.h5 ...] [--repeats R] [--queries Q] "
                         "[--max-chain N] [--merge-cells K] [--row-order blocks|bake]\n");
            return a == "--help" ? 0 : 2;
        } else {
            bakes.push_back(a);
        }
    }
    if (bakes.empty()) {
        std::fprintf(stderr,
                     "usage: bench_runtime_file BAKE.h5 [BAKE.h5 ...] [--repeats R] [--queries Q] "
                     "[--max-chain N] [--merge-cells K] [--row-order blocks|bake]\n");
        return 2;
    }
    nlohmann::ordered_json out;
    out["bench"] = "runtime_file";
    out["repeats"] = repeats;
    out["queries"] = queries;
    for (const std::string& b : bakes) {
        try {
            out["bakes"].push_back(measure(b, repeats, queries, max_chain, merge_cells, block_order));
        } catch (const std::exception& e) {
            std::fprintf(stderr, "%s: %s\n", b.c_str(), e.what());
            return 2;
        }
    }
    std::cout << out.dump(1) << "\n";
    return 0;
}
