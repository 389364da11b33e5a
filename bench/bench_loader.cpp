// SPDX-License-Identifier: MIT
// bench_loader: the runtime loader (pvsbake/loader.h) on real bakes and on a synthetic 3,000-object bake.
//
//   bench_loader [BAKE.h5 ...] [--repeats R] [--queries Q] [--no-synthetic] [--rewrite] [--warm-heap MIB]
//
// For each bake: load time (median of R loads in one process, and the first of them: a game loads once,
// into memory the process has not used yet), memory after load against the compressed PVS in the
// file (bytes_stored: the deflated rows plus cell_row) and against the file size, bytes per cell (in
// memory, in the file, raw), and the time of one frame's work: find_cell of a random point in a random
// cell plus walking that cell's PVS (median over batches of Q queries), and the walk of the fullest row.
// The synthetic bake is FORMAT.md's test case: 20,000 cells (40 x 25 x 20 grid) and 3,000 objects, each
// visible from the cells within a random radius, with 10% of the visible bits dropped and 0.2% added
// (as sampling gives). With --rewrite, each bake is also written again in the current format (read and
// written by io/bake_file.h, into the temporary folder) and measured the same way, right after it:
// "current_format" in its entry, and the ratio of the load medians. With --warm-heap, the process first
// touches and frees MIB of heap that it keeps (glibc: no trimming, no mmap'd chunks), as a game's warm heap
// would: loads then pay for the loader's work, not for the kernel's first touch of fresh pages (which
// costs about 11 us a page on the shared test machine, about 0.2 us on bare metal). Prints one JSON object.
#include "bench/bench_util.h"
#include "io/bake_file.h"

#include <pvsbake/loader.h>

#include <nlohmann/json.hpp>

#include <malloc.h>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <vector>

namespace pvs {
namespace {

using bench::median;
using bench::seconds_since;

// FORMAT.md's "noisy" PVS: 3,000 objects over a 40 x 25 x 20 grid of 2 m cells.
pvs::BakeData synthetic_bake() {
    pvs::BakeData b;
    b.tool_version = "bench_loader";
    b.mode = "sampled";
    const glm::ivec3 dims(40, 25, 20);
    const uint32_t objects = 3000;
    b.cells.origin = glm::vec3(0.0f);
    b.cells.cell_size_m = 2.0f;
    b.cells.dims = dims;
    for (int z = 0; z < dims.z; ++z)
        for (int y = 0; y < dims.y; ++y)
            for (int x = 0; x < dims.x; ++x) {
                const glm::vec3 lo = glm::vec3(x, y, z) * 2.0f;
                b.cells.grid_to_cell.push_back(int32_t(b.cells.cells.size()));
                b.cells.cells.push_back(pvs::Cell{pvs::Aabb::of(lo, lo + glm::vec3(2.0f)), -1});
            }
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<glm::vec3> where(objects);
    std::vector<float> radius(objects);
    for (uint32_t o = 0; o < objects; ++o) {
        where[o] = glm::vec3(u(rng) * 80.0f, u(rng) * 50.0f, u(rng) * 40.0f);
        radius[o] = 5.0f + u(rng) * 20.0f;
        b.objects.push_back(
            {"object " + std::to_string(o), pvs::Aabb::of(where[o], where[o] + 1.0f), 12 + o % 500, 1});
    }
    const uint32_t cells = uint32_t(b.cells.cells.size());
    b.pvs = pvs::PvsSet::make(cells, objects);
    for (uint32_t c = 0; c < cells; ++c) {
        const glm::vec3 at = b.cells.cells[c].bounds.center();
        for (uint32_t o = 0; o < objects; ++o) {
            const bool seen = glm::length(at - where[o]) < radius[o];
            if ((seen && u(rng) >= 0.1f) || (!seen && u(rng) < 0.002f)) b.pvs.set(c, o);
        }
    }
    b.verification.figures = {};
    return b;
}

nlohmann::json measure(const std::string& path, int repeats, int queries) {
    nlohmann::json j;
    j["bake"] = path;
    std::vector<double> load_ms;
    pvsbake::Bake bake;
    for (int r = 0; r < repeats; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        const pvsbake::LoadResult res = bake.load(path);
        load_ms.push_back(1e3 * seconds_since(t0));
        if (!res) {
            j["error"] = res.message;
            return j;
        }
    }
    const pvsbake::PvsStats& s = bake.pvs_stats();
    const double cells = double(std::max<uint64_t>(1, s.cell_count));
    const uint64_t file_bytes = std::filesystem::file_size(path);
    j["format"] = std::to_string(bake.format_major()) + "." + std::to_string(bake.format_minor());
    j["cells"] = s.cell_count;
    j["objects"] = s.object_count;
    j["unique_rows"] = s.unique_rows;
    j["load_ms_first"] = load_ms.front();
    j["load_ms_median"] = median(load_ms);
    j["load_ms_min"] = *std::min_element(load_ms.begin(), load_ms.end());
    j["file_bytes"] = file_bytes;
    j["memory_bytes"] = s.memory_bytes;
    j["pvs_bytes_raw"] = s.bytes_raw;
    j["pvs_bytes_stored"] = s.bytes_stored;
    j["pvs_bytes_in_memory"] = s.bytes_code;
    j["pvs_memory_over_stored"] = double(s.bytes_code) / double(std::max<uint64_t>(1, s.bytes_stored));
    j["memory_over_file"] = double(s.memory_bytes) / double(file_bytes);
    j["bytes_per_cell"] = {{"raw", double(s.bytes_raw) / cells},
                           {"stored", double(s.bytes_stored) / cells},
                           {"in_memory", double(s.bytes_code) / cells}};

    // One frame's work: a random point in a random cell, find its cell, walk its PVS.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> points;
    for (int q = 0; q < queries && s.cell_count > 0; ++q) {
        const pvsbake::Box b = bake.cell_bounds(uint32_t(rng() % s.cell_count));
        for (int a = 0; a < 3; ++a) points.push_back(b.min[a] + u(rng) * (b.max[a] - b.min[a]));
    }
    uint64_t sink = 0, walked = 0, found = 0;
    std::vector<double> per_query_ns;
    for (int r = 0; r < 25 && !points.empty(); ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        for (size_t q = 0; q < points.size(); q += 3) {
            const int32_t c = bake.find_cell(&points[q]);
            if (c < 0) continue;
            ++found;
            bake.for_each_visible(uint32_t(c), [&](uint32_t o) {
                sink += o;
                ++walked;
            });
        }
        per_query_ns.push_back(1e9 * seconds_since(t0) / double(points.size() / 3));
    }
    j["lookup_walk_ns_median"] = median(per_query_ns);
    // The two parts alone: the lookups, and walks of the same cells' rows.
    std::vector<uint32_t> hit;
    for (size_t q = 0; q < points.size(); q += 3) {
        const int32_t c = bake.find_cell(&points[q]);
        if (c >= 0) hit.push_back(uint32_t(c));
    }
    std::vector<double> lookup_ns, walk_only_ns;
    for (int r = 0; r < 25 && !points.empty(); ++r) {
        auto t0 = std::chrono::steady_clock::now();
        for (size_t q = 0; q < points.size(); q += 3) sink += uint32_t(bake.find_cell(&points[q]));
        lookup_ns.push_back(1e9 * seconds_since(t0) / double(points.size() / 3));
        t0 = std::chrono::steady_clock::now();
        for (uint32_t c : hit) bake.for_each_visible(c, [&](uint32_t o) { sink += o; });
        walk_only_ns.push_back(1e9 * seconds_since(t0) / double(std::max<size_t>(1, hit.size())));
    }
    j["lookup_only_ns_median"] = median(lookup_ns);
    j["walk_only_ns_median"] = median(walk_only_ns);
    j["found_share"] =
        double(found) / double(std::max<uint64_t>(1, per_query_ns.size() * (points.size() / 3)));
    j["visible_per_query_mean"] = double(walked) / double(std::max<uint64_t>(1, found));

    // The fullest row, walked alone.
    uint32_t fullest = 0, most = 0;
    for (uint32_t c = 0; c < s.cell_count; ++c) {
        const uint32_t n = bake.visible_count(c);
        if (n > most) {
            most = n;
            fullest = c;
        }
    }
    std::vector<double> walk_ns;
    for (int r = 0; r < 25 && s.cell_count > 0; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int k = 0; k < 200; ++k) bake.for_each_visible(fullest, [&](uint32_t o) { sink += o; });
        walk_ns.push_back(1e9 * seconds_since(t0) / 200.0);
    }
    j["fullest_row_visible"] = most;
    j["fullest_row_walk_ns_median"] = median(walk_ns);
    j["checksum"] = sink % 1000;
    return j;
}

}  // namespace
}  // namespace pvs

int main(int argc, char** argv) {
    int repeats = 11, queries = 10000;
    bool synthetic = true, rewrite = false;
    int warm_mib = 0;
    std::vector<std::string> bakes;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--repeats") == 0 && i + 1 < argc) {
            repeats = std::max(1, std::atoi(argv[++i]));
        } else if (std::strcmp(argv[i], "--queries") == 0 && i + 1 < argc) {
            queries = std::max(1, std::atoi(argv[++i]));
        } else if (std::strcmp(argv[i], "--no-synthetic") == 0) {
            synthetic = false;
        } else if (std::strcmp(argv[i], "--rewrite") == 0) {
            rewrite = true;
        } else if (std::strcmp(argv[i], "--warm-heap") == 0 && i + 1 < argc) {
            warm_mib = std::max(0, std::atoi(argv[++i]));
        } else {
            bakes.push_back(argv[i]);
        }
    }
    if (warm_mib > 0) {
        mallopt(M_MMAP_THRESHOLD, 1 << 30);
        mallopt(M_TRIM_THRESHOLD, 1 << 30);
        std::vector<char*> blocks;
        for (int m = 0; m < warm_mib; ++m) {
            blocks.push_back(static_cast<char*>(std::malloc(1 << 20)));
            if (blocks.back() != nullptr) std::memset(blocks.back(), 1, 1 << 20);
        }
        for (char* b : blocks) std::free(b);
    }
    nlohmann::json out;
    out["repeats"] = repeats;
    out["warm_heap_mib"] = warm_mib;
    out["queries"] = queries;
    const std::string tmp = (std::filesystem::temp_directory_path() / "bench_loader_synthetic.h5").string();
    if (synthetic) {
        pvs::write_bake_file(tmp, pvs::synthetic_bake());
        out["synthetic_3000_objects"] = pvs::measure(tmp, repeats, queries);
        std::filesystem::remove(tmp);
    }
    for (const std::string& b : bakes) {
        nlohmann::json j = pvs::measure(b, repeats, queries);
        if (rewrite && !j.contains("error")) {
            const std::string again =
                (std::filesystem::temp_directory_path() / "bench_loader_current_format.h5").string();
            pvs::write_bake_file(again, pvs::read_bake_file(b));
            j["current_format"] = pvs::measure(again, repeats, queries);
            j["current_format"]["bake"] = "(rewritten)";
            j["current_format_load_ratio"] =
                j["current_format"]["load_ms_median"].get<double>() / j["load_ms_median"].get<double>();
            std::filesystem::remove(again);
        }
        out["bakes"].push_back(j);
    }
    std::cout << out.dump(2) << std::endl;
    return 0;
}
