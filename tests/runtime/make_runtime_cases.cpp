// SPDX-License-Identifier: MIT
// make_runtime_cases OUT_DIR: runtime files and what the HDF5 loader (pvsbake/loader.h) answers on their bake
// files, as OUT_DIR/cases.txt, for runtime_check (tests/runtime/runtime_check.c) to compare the C99 runtime
// against on other machines: grids and octrees with masks and ranked occluders, no objects, and more objects
// than the runtime's stack bit set holds. Floats are written as their bits (hex), names as hex bytes.
#include "io/bake_file.h"
#include "io/runtime_file.h"
#include "tests/bake_fixtures.h"

#include <pvsbake/loader.h>
#include <pvsbake/occlusion.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace {

unsigned bits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}

void write_case(std::FILE* out, const std::filesystem::path& dir, const std::string& name, const pvs::BakeData& bake,
                uint32_t seed, bool measures) {
    const std::string h5 = (dir / (name + ".h5")).string();
    pvs::write_bake_file(h5, bake);
    pvs::RuntimeFileOptions options;
    options.occluder_measures = measures;
    std::ofstream((dir / (name + ".pvsr")).string(), std::ios::binary) << pvs::runtime_file_bytes(h5, options);
    pvsbake::Bake b;
    const pvsbake::LoadResult r = b.load(h5);
    if (!r) {
        std::fprintf(stderr, "make_runtime_cases: %s\n", r.message.c_str());
        std::exit(1);
    }
    std::filesystem::remove(h5);
    std::fprintf(out, "case %s.pvsr\nlevel %u %u %d %d %llu\n", name.c_str(), b.cell_count(), b.object_count(),
                 int(b.cell_kind()), b.is_conservative() ? 1 : 0, (unsigned long long)b.total_triangles());
    for (uint32_t c = 0; c < b.cell_count(); ++c) {
        std::fprintf(out, "cell %u %u", c, b.visible_count(c));
        b.for_each_visible(c, [&](uint32_t o) { std::fprintf(out, " %u", o); });
        const pvsbake::Box box = b.cell_bounds(c);
        std::fprintf(out, "\nbounds %x %x %x %x %x %x\noccluders %u", bits(box.min[0]), bits(box.min[1]), bits(box.min[2]),
                     bits(box.max[0]), bits(box.max[1]), bits(box.max[2]), b.occluder_count(c));
        for (const pvsbake::RankedOccluder& o : b.occluders(c))
            std::fprintf(out, "\n%x %x %x %x %x %x %x %x %x %x", bits(o.box.min[0]), bits(o.box.min[1]), bits(o.box.min[2]),
                         bits(o.box.max[0]), bits(o.box.max[1]), bits(o.box.max[2]), bits(o.score), bits(o.solid_angle_sr),
                         bits(o.hidden_objects), bits(o.hidden_triangle_share));
        std::fprintf(out, "\n");
    }
    for (uint32_t o = 0; o < b.object_count(); ++o) {
        const pvsbake::Box box = b.object_bounds(o);
        std::string hex;
        char h[3];
        for (const char ch : b.object_name(o)) {
            std::snprintf(h, sizeof h, "%02x", unsigned(uint8_t(ch)));
            hex += h;
        }
        std::fprintf(out, "object %u %u %u %x %x %x %x %x %x %s\n", o, b.object_triangles(o), b.object_flags(o),
                     bits(box.min[0]), bits(box.min[1]), bits(box.min[2]), bits(box.max[0]), bits(box.max[1]),
                     bits(box.max[2]), hex.empty() ? "-" : hex.c_str());
        for (uint32_t k = 0; k < b.object_part_count(o); ++k) {  // bit for bit on every platform (file 5.1)
            const pvsbake::Box p = b.object_part(o, k);
            std::fprintf(out, "part %u %u %x %x %x %x %x %x\n", o, k, bits(p.min[0]), bits(p.min[1]),
                         bits(p.min[2]), bits(p.max[0]), bits(p.max[1]), bits(p.max[2]));
        }
    }
    // Points in and around the cells, a third of them on a 1/8 m lattice (on cell and voxel faces).
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (uint32_t c = 0; c < b.cell_count(); ++c) {
        const pvsbake::Box box = b.cell_bounds(c);
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], box.min[a]);
            hi[a] = std::max(hi[a], box.max[a]);
        }
    }
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-0.2f, 1.2f);
    for (int i = 0; i < 2000 && b.cell_count() > 0; ++i) {
        float p[3];
        for (int a = 0; a < 3; ++a) {
            p[a] = lo[a] + u(rng) * (hi[a] - lo[a]);
            if (i % 3 == 1) p[a] = lo[a] + float(int((p[a] - lo[a]) * 8.0f)) / 8.0f;
        }
        std::fprintf(out, "point %x %x %x %d %d\n", bits(p[0]), bits(p[1]), bits(p[2]), b.find_cell(p[0], p[1], p[2]),
                     b.in_eye_space(p[0], p[1], p[2]) ? 1 : 0);
    }
    // The culler of moving objects: from a random eye in a cell, with the cell's ranked occluders (and, for
    // more fusion, the next cells' too) at 32 pixels a face, the path of random boxes around it.
    pvsbake::OcclusionCuller culler(32);
    // A "cull" line (the frame: eye and occluders, as the culler begins it) and a "box" line (a box, its path).
    const auto begin_cull = [&](const float eye[3], const std::vector<pvsbake::Box>& boxes) {
        culler.begin_frame(eye, boxes);
        std::fprintf(out, "cull %x %x %x %zu", bits(eye[0]), bits(eye[1]), bits(eye[2]), boxes.size());
        for (const pvsbake::Box& o : boxes)
            for (int a = 0; a < 6; ++a) std::fprintf(out, " %x", bits(a < 3 ? o.min[a] : o.max[a - 3]));
        std::fprintf(out, "\n");
    };
    const auto cull_box = [&](const pvsbake::Box& box) {
        std::fprintf(out, "box %x %x %x %x %x %x %d\n", bits(box.min[0]), bits(box.min[1]), bits(box.min[2]),
                     bits(box.max[0]), bits(box.max[1]), bits(box.max[2]), int(culler.classify(box)));
    };
    for (uint32_t c = 0; c < b.cell_count() && c < 40; ++c) {
        std::vector<pvsbake::Box> boxes;
        for (uint32_t k = c; k < b.cell_count() && k < c + 4; ++k)
            for (const pvsbake::RankedOccluder& o : b.occluders(k)) boxes.push_back(o.box);
        if (boxes.empty()) continue;
        const pvsbake::Box cell = b.cell_bounds(c);
        float eye[3];
        for (int a = 0; a < 3; ++a) eye[a] = cell.min[a] + (cell.max[a] - cell.min[a]) * std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
        begin_cull(eye, boxes);
        for (int q = 0; q < 30; ++q) {
            pvsbake::Box box;
            for (int a = 0; a < 3; ++a) {
                box.min[a] = lo[a] + u(rng) * (hi[a] - lo[a]);
                box.max[a] = box.min[a] + 0.1f + 2.0f * std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
            }
            cull_box(box);
        }
    }
    // What a game draws: from a random eye in each of the first 40 cells, with the best 1 to 7 or all of the
    // cell's ranked occluders, the objects of the culled walk ("drawn" line: cell, eye, the most occluders,
    // the count and the objects).
    for (uint32_t c = 0; c < b.cell_count() && c < 40; ++c) {
        const pvsbake::Box cell = b.cell_bounds(c);
        float eye[3];
        for (int a = 0; a < 3; ++a)
            eye[a] = cell.min[a] +
                     (cell.max[a] - cell.min[a]) * std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
        const uint32_t most = c % 8 == 0 ? 64u : c % 8;
        culler.begin_cell(b, c, eye, most);
        std::vector<uint32_t> drawn;
        pvsbake::for_each_drawn(b, c, culler, [&](uint32_t o) { drawn.push_back(o); });
        std::fprintf(out, "drawn %u %x %x %x %u %zu", c, bits(eye[0]), bits(eye[1]), bits(eye[2]), most,
                     drawn.size());
        for (const uint32_t o : drawn) std::fprintf(out, " %u", o);
        std::fprintf(out, "\n");
    }
    // Random scenes of walls and blocks around the eye, where the depth cube fuses occluders.
    std::uniform_real_distribution<float> w(-20.0f, 20.0f), size(0.2f, 6.0f), thin(0.05f, 0.6f);
    for (int scene = 0; scene < 40; ++scene) {
        std::vector<pvsbake::Box> boxes;
        const int n = 4 + int(rng() % 40);
        for (int k = 0; k < n; ++k) {
            pvsbake::Box o;
            const int flat = int(rng() % 3);
            for (int a = 0; a < 3; ++a) {
                o.min[a] = w(rng) * 0.6f;
                o.max[a] = o.min[a] + (k % 2 == 0 && a == flat ? (k % 6 == 0 ? 0.0f : thin(rng))
                                                               : size(rng));  // k % 6 == 0: a panel
            }
            boxes.push_back(o);
        }
        const float eye[3] = {w(rng) * 0.2f, w(rng) * 0.2f, w(rng) * 0.2f};
        begin_cull(eye, boxes);
        for (int q = 0; q < 100; ++q) {
            pvsbake::Box box;
            for (int a = 0; a < 3; ++a) {
                box.min[a] = w(rng);
                box.max[a] = box.min[a] + size(rng) * 0.5f;
            }
            cull_box(box);
        }
    }
    std::fprintf(out, "end\n");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: make_runtime_cases OUT_DIR\n");
        return 2;
    }
    const std::filesystem::path dir = argv[1];
    std::filesystem::create_directories(dir);
    std::FILE* out = std::fopen((dir / "cases.txt").string().c_str(), "w");
    if (!out) return 1;
    {  // with the objects' parts (file 2.2): the culled walks test them on every platform
        pvs::BakeData grid = pvs::test::coherent_bake(133, {7, 3, 6}, false, true, 4, true);
        pvs::test::add_object_parts(grid);
        write_case(out, dir, "grid", grid, 1, true);
        pvs::BakeData octree = pvs::test::coherent_bake(70, {4, 2, 3}, true, true, 8, true);
        pvs::test::add_object_parts(octree);
        write_case(out, dir, "octree", octree, 2, false);
    }
    write_case(out, dir, "sampled_grid_without_masks", pvs::test::coherent_bake(64, {3, 2, 4}, false, false, 5), 3, true);
    write_case(out, dir, "no_objects", pvs::test::coherent_bake(0, {2, 2, 2}, false, true, 6), 4, false);
    write_case(out, dir, "many_objects", pvs::test::coherent_bake(16400, {3, 1, 2}, true, false, 7), 5, false);
    write_case(out, dir, "grid_of_every_position",
               pvs::test::coherent_bake(90, {5, 3, 4}, false, true, 9, true, /*every_position=*/true), 6,
               true);
    pvs::BakeData palettes = pvs::test::coherent_bake(80, {13, 3, 13}, false, true, 31);
    pvs::test::rank_many_boxes(palettes, 600, 12, 5);
    write_case(out, dir, "grid_with_palettes", palettes, 7, true);
    std::fclose(out);
    std::printf("make_runtime_cases: 7 cases in %s\n", argv[1]);
    return 0;
}
