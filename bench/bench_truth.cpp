// SPDX-License-Identifier: MIT
// bench_truth: how much a bake's PVS over-lists against what its own cells really see, by rays aimed at
// every listed object (the truth bench).
//
//   bench_truth WORLD.glb BAKE.h5 [--cells N] [--eyes E] [--rays R] [--seed S] [--vis V.json]
//               [--lower-bound-eyes L] [--allow-few-rays] [--extreme-rays]
//
// Cells: N (default 30) distinct cells drawn at random (seed S, default 1) among the bake's cells (grid or
// octree) that have eye space: some voxel of the bake's eye mask (cells.eyes) meets the cell's box with
// volume. Eyes: E (default 4096) points per cell drawn uniformly in the cell's eye space, the union of its
// eye voxels clipped to the cell's box (a voxel by its clipped volume, then a uniform point in it; a bake
// with no eye mask: the whole box). Truth: for every object the cell's row lists (objects with triangles),
// up to R rays (default 65536; at least 16384, the least the definition allows, fewer only with
// --allow-few-rays, for smoke tests), each from the next eye (cycling from a random one) to a random point on
// the object (a triangle of the object picked by area, then a uniform point in it). The object is VISIBLE
// from the cell as soon as one ray reaches its point: no opaque triangle of the world, other than the one the
// point lies on, meets the segment from the eye to 1 - 1e-5 of the way to the point (see-through triangles
// never block; docs/ALGORITHMS.md#words). Rays are traced with Embree against the world's triangles alone:
// nothing of the solver (pvs/) decides. Visible objects are a lower bound of what the cell sees (R rays per
// object sample it), and with a conservative bake every one of them is listed.
// With --extreme-rays, a listed object no aimed ray reached gets rays from the eye space's 26 extreme points
// (per direction of the 3 x 3 x 3 block, the farthest corner of an eye voxel piece, a hair inside it) to a
// point near each corner of (up to 256 of) its triangles, inside the triangle by at least 1% of the way to
// its centre and 100 times the ray's end margin (1 - 1e-6 of the way): sight that passes an occluder's edge
// only from the rim of the eye space to the rim of an object, which random points rarely hit. What they reach
// is visible by the same definition; `visible_found_by_extreme_rays` counts it. Figures: listed and visible
// objects and triangles summed over the cells; listed / visible by triangles (the headline: sum of listed
// triangles / sum of visible triangles) and by objects; the listed and visible shares of the world's
// triangles (mean over cells); the median over cells of the per-cell ratio; the headline's 95% interval over
// the draw of cells (2.5 and 97.5 percentiles of it over 2,000 draws of as many cells, with replacement, from
// those measured: how much another seed may move it). Beside them: (a) the map compiler
// (WORLD.vis.json beside the world, or --vis): at every eye point the compiler's BSP calls playable, the
// share of the world's triangles its cluster PVS lets through (bench_util.h CompilerVis); bake share /
// compiler share and visible share / compiler share, ratios of the means over those eye points; (b) the lower
// bound (L eyes per cell, default 64, 0 = off): the AGGRESSIVE sampled PVS of the same cells, exactly the
// rows bake_sampled_pvs (rays/ray_sampler.h) gives them with eyes_per_cell = L in the whole bake (as in
// bench_vis_compare), its triangle share and bake / lower bound. Deterministic for a seed at any thread
// count: eyes from (seed, cell), rays from (seed, cell, object). Prints JSON on stdout, progress on stderr.
// Exit status 2 on bad input (the message names the file or option).
#include "bench/aimed_rays.h"
#include "bench/bench_util.h"
#include "core/error.h"
#include "core/random.h"
#include "io/bake_file.h"
#include "io/file_hash.h"
#include "io/gltf_loader.h"
#include "rays/ray_sampler.h"
#include "rays/ray_scene.h"
#include "rays/surface_points.h"

#include <embree3/rtcore.h>
#include <omp.h>
#include <pmmintrin.h>
#include <xmmintrin.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace {

using pvs::bench::kSegmentEnd;
using pvs::bench::mean;
using pvs::bench::median;
using pvs::bench::OpaqueScene;
using pvs::bench::random_point_on;
using pvs::bench::seconds_since;

constexpr uint32_t kMinRays = 16384;      // rays per listed object the definition asks for at least
constexpr uint32_t kDefaultRays = 65536;  // 16384 leave a few percent of what is visible unfound

// The eye space of a box: the set voxels of `eyes` meeting it with volume, clipped to it, and their running
// volumes (m3). Both empty when no eye voxel meets the box.
struct EyeSpace {
    std::vector<pvs::Aabb> pieces;
    std::vector<double> cum_volume;
};

EyeSpace eye_space_of(const pvs::VoxelMask& eyes, const pvs::Aabb& box) {
    EyeSpace out;
    if (eyes.empty()) {
        out.pieces.push_back(box);
        const glm::dvec3 s = glm::dvec3(box.size());
        out.cum_volume.push_back(s.x * s.y * s.z);
        if (!(out.cum_volume.back() > 0.0)) out = EyeSpace{};
        return out;
    }
    const float s = eyes.voxel_size_m;
    glm::ivec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = std::max(0, int(std::floor((box.min[a] - eyes.origin[a]) / s)));
        hi[a] = std::min(eyes.dims[a] - 1, int(std::ceil((box.max[a] - eyes.origin[a]) / s)) - 1);
    }
    double sum = 0.0;
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) {
                const uint64_t i =
                    uint64_t(x) + uint64_t(eyes.dims.x) * (uint64_t(y) + uint64_t(eyes.dims.y) * uint64_t(z));
                if (!eyes.get(i)) continue;
                const glm::vec3 v0 = eyes.origin + glm::vec3(x, y, z) * s;
                pvs::Aabb piece;
                piece.min = glm::max(v0, box.min);
                piece.max = glm::min(v0 + s, box.max);
                const glm::dvec3 e = glm::max(glm::dvec3(piece.max) - glm::dvec3(piece.min), glm::dvec3(0.0));
                const double volume = e.x * e.y * e.z;
                if (!(volume > 0.0)) continue;
                sum += volume;
                out.pieces.push_back(piece);
                out.cum_volume.push_back(sum);
            }
    return out;
}

// A uniform point of the eye space (pieces by volume, then uniform in the piece).
constexpr int kBootstrapDraws = 2000;  // draws of the cells for the headline's interval

glm::vec3 random_eye(const EyeSpace& space, pvs::Rng& rng) {
    const double pick = double(rng.uniform()) * space.cum_volume.back();
    const size_t k =
        std::min(size_t(std::upper_bound(space.cum_volume.begin(), space.cum_volume.end(), pick) -
                        space.cum_volume.begin()),
                 space.pieces.size() - 1);
    const pvs::Aabb& p = space.pieces[k];
    const glm::vec3 jitter(rng.uniform(), rng.uniform(), rng.uniform());
    return glm::clamp(p.min + (p.max - p.min) * jitter, p.min, p.max);
}

// Per chosen cell.
struct CellFigures {
    uint32_t cell = 0;
    std::vector<glm::vec3> eyes;
    std::vector<glm::vec3> extremes;  // with --extreme-rays: the eye space's extreme corners
    std::vector<uint32_t> listed;  // listed objects with triangles (and area)
    uint64_t listed_objects = 0, listed_triangles = 0;
    uint64_t listed_without_area = 0;  // listed objects with no triangle area: never visible
    uint64_t visible_objects = 0, visible_triangles = 0;
    // compiler
    uint64_t eyes_with_cluster = 0;
    double compiler_fraction_sum = 0.0;
    // lower bound
    uint64_t bound_objects = 0, bound_triangles = 0;
    uint64_t bound_unlisted = 0;          // objects the lower bound's rays touched that the row leaves out
    uint64_t bound_seen_not_visible = 0;  // listed objects its rays touched that the aimed rays did not reach
};

// --extreme-rays: at most this many triangles of an object (every k-th), each corner pulled at least this
// share of the way to the triangle's centre (a point of the triangle itself).
constexpr uint32_t kExtremeTriangles = 256;
constexpr float kExtremeInset = 0.01f;
constexpr float kExtremeEnd = 1.0f - 1e-6f;   // an extreme ray stops this far along to its point (the point
                                              // is on the aimed-at triangle, which never blocks it)
constexpr float kExtremeEndMargins = 100.0f;  // the inset is at least this many end margins of the segment

// The eye space's extreme points: for each of the 26 directions of the 3 x 3 x 3 block, the corner of a piece
// farthest along it, pulled a hair towards its piece's centre (into the closed eye space).
std::vector<glm::vec3> extreme_eyes(const EyeSpace& space) {
    std::vector<glm::vec3> out;
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                if (dx == 0 && dy == 0 && dz == 0) continue;
                const glm::vec3 d{float(dx), float(dy), float(dz)};
                float best = -INFINITY;
                glm::vec3 pick(0.0f);
                for (const pvs::Aabb& piece : space.pieces)
                    for (int c = 0; c < 8; ++c) {
                        const glm::vec3 q((c & 1) ? piece.max.x : piece.min.x,
                                          (c & 2) ? piece.max.y : piece.min.y,
                                          (c & 4) ? piece.max.z : piece.min.z);
                        const float v = glm::dot(d, q);
                        if (v > best) {
                            best = v;
                            pick = q + 1e-4f * (piece.center() - q);
                        }
                    }
                if (std::find(out.begin(), out.end(), pick) == out.end()) out.push_back(pick);
            }
    return out;
}

[[noreturn]] void bad_option(const std::string& message) {
    throw pvs::bad_input("bench_truth: " + message);
}

uint64_t parse_count(const char* option, const char* text, uint64_t min, uint64_t max) {
    return pvs::bench::parse_count("bench_truth", option, text, min, max);
}

}  // namespace

int main(int argc, char** argv) {
    const char* usage =
        "usage: bench_truth WORLD.glb BAKE.h5 [--cells N] [--eyes E] [--rays R] [--seed S] [--vis V.json]\n"
        "                   [--lower-bound-eyes L] [--allow-few-rays] [--extreme-rays]\n";
    if (argc < 3 || argv[1][0] == '-' || argv[2][0] == '-') {
        std::fputs(usage, stderr);
        return 2;
    }
    const auto t_start = std::chrono::steady_clock::now();
    const std::string world_path = argv[1], bake_path = argv[2];
    std::string vis_path = world_path.substr(0, world_path.rfind('.')) + ".vis.json";
    bool vis_given = false, allow_few_rays = false, extreme_rays = false;
    uint32_t n_cells = 30, n_eyes = 4096, n_rays = kDefaultRays, lower_bound_eyes = 64;
    uint64_t seed = 1;
    try {
        for (int a = 3; a < argc; ++a) {
            const std::string k = argv[a];
            if (k == "--allow-few-rays") {
                allow_few_rays = true;
                continue;
            }
            if (k == "--extreme-rays") {
                extreme_rays = true;
                continue;
            }
            if (k != "--cells" && k != "--eyes" && k != "--rays" && k != "--seed" && k != "--vis" &&
                k != "--lower-bound-eyes")
                bad_option("unknown option " + k + " (run it with no arguments for the usage)");
            if (a + 1 >= argc) bad_option(k + " wants a value");
            const char* v = argv[++a];
            if (k == "--cells")
                n_cells = uint32_t(parse_count("--cells", v, 1, 1'000'000));
            else if (k == "--eyes")
                n_eyes = uint32_t(parse_count("--eyes", v, 1, 1'000'000));
            else if (k == "--rays")
                n_rays = uint32_t(parse_count("--rays", v, 1, 1'000'000'000));
            else if (k == "--seed")
                seed = parse_count("--seed", v, 0, std::numeric_limits<uint64_t>::max());
            else if (k == "--lower-bound-eyes")
                lower_bound_eyes = uint32_t(parse_count("--lower-bound-eyes", v, 0, 1'000'000));
            else {
                vis_path = v;
                vis_given = true;
            }
        }
        if (n_rays < kMinRays && !allow_few_rays)
            bad_option("--rays " + std::to_string(n_rays) + " is below " + std::to_string(kMinRays) +
                       ", the fewest rays per listed object the definition allows (an object seen only "
                       "through a narrow gap needs them); add --allow-few-rays for a quick smoke test, whose "
                       "figures are not the truth bench's");
    } catch (const pvs::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }

    try {
        pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, false, stderr});
        std::fprintf(stderr, "bench_truth: loading %s and %s\n", world_path.c_str(), bake_path.c_str());
        const pvs::World world = pvs::load_world(ctx, world_path);
        const pvs::BakeData bake = pvs::read_bake_file(bake_path);
        bool same_objects = bake.objects.size() == world.objects.size();
        for (size_t o = 0; same_objects && o < world.objects.size(); ++o)
            same_objects = bake.objects[o].triangle_count == world.objects[o].triangle_count;
        if (!same_objects)
            throw pvs::bad_input(bake_path + ": was not baked from " + world_path +
                                 " (its objects or their triangle counts differ)");
        const bool hash_matches =
            bake.world_hash.empty() || bake.world_hash == pvs::hash_file_hex(world_path);
        if (!hash_matches)
            std::fprintf(stderr,
                         "bench_truth: warning: %s was baked from a world file whose content differs from %s "
                         "(same objects and triangle counts)\n",
                         bake_path.c_str(), world_path.c_str());
        const pvs::CellSet& cells = bake.cells;
        if (cells.size() == 0) throw pvs::bad_input(bake_path + ": the bake has no cells");
        if (cells.eyes.empty())
            std::fprintf(stderr,
                         "bench_truth: warning: %s holds no eye mask (no view volume): eyes are drawn in the "
                         "whole box of each cell\n",
                         bake_path.c_str());

        // The compiler's visibility, when there is one.
        pvs::bench::CompilerVis vis;
        bool have_vis = false;
        {
            std::ifstream in(vis_path);
            if (in) {
                nlohmann::json j;
                try {
                    j = nlohmann::json::parse(in);
                    vis = pvs::bench::CompilerVis::from_json(j);
                } catch (const std::exception& e) {
                    throw pvs::bad_input(vis_path + ": not the compiler's visibility (" + e.what() + ")");
                }
                have_vis = true;
            } else if (vis_given) {
                throw pvs::bad_input("--vis " + vis_path + ": cannot read the compiler's visibility");
            } else {
                std::fprintf(stderr, "bench_truth: no %s: no compiler ratio\n", vis_path.c_str());
            }
        }

        // Cells: a seeded shuffle of all cells, keeping the first n_cells that have eye space.
        const auto t_cells = std::chrono::steady_clock::now();
        std::vector<uint32_t> order(cells.size());
        for (uint32_t c = 0; c < order.size(); ++c) order[c] = c;
        pvs::Rng pick_rng(seed, 0x5452555443454c4cULL);
        std::vector<CellFigures> figs;
        std::vector<EyeSpace> spaces;
        uint32_t skipped_without_eyes = 0;
        for (uint32_t i = 0; i < order.size() && figs.size() < n_cells; ++i) {
            std::swap(order[i], order[i + pick_rng.below(uint32_t(order.size()) - i)]);
            EyeSpace space = eye_space_of(cells.eyes, cells.cells[order[i]].bounds);
            if (space.pieces.empty()) {
                ++skipped_without_eyes;
                continue;
            }
            CellFigures f;
            f.cell = order[i];
            figs.push_back(std::move(f));
            spaces.push_back(std::move(space));
        }
        if (figs.empty()) throw pvs::bad_input(bake_path + ": no cell of the bake has eye space");
        if (figs.size() < n_cells)
            std::fprintf(stderr, "bench_truth: only %zu cells have eye space (asked for %u)\n", figs.size(),
                         n_cells);
        const uint32_t n_objects = uint32_t(world.objects.size());
        const double world_triangles = double(world.triangles.size());
        const std::vector<double> cum_area = pvs::cumulative_areas(world);
#pragma omp parallel for schedule(dynamic, 1)
        for (int64_t i = 0; i < int64_t(figs.size()); ++i) {
            CellFigures& f = figs[size_t(i)];
            pvs::Rng rng(pvs::mix64(seed ^ 0x4559455300000000ULL), f.cell);
            f.eyes.reserve(n_eyes);
            for (uint32_t e = 0; e < n_eyes; ++e) f.eyes.push_back(random_eye(spaces[size_t(i)], rng));
            if (extreme_rays) f.extremes = extreme_eyes(spaces[size_t(i)]);
            for (uint32_t o = 0; o < n_objects; ++o) {
                if (!bake.pvs.test(f.cell, o) || world.objects[o].triangle_count == 0) continue;
                const pvs::WorldObject& obj = world.objects[o];
                ++f.listed_objects;
                f.listed_triangles += obj.triangle_count;
                if (cum_area[obj.first_triangle + obj.triangle_count - 1] > 0.0)
                    f.listed.push_back(o);
                else
                    ++f.listed_without_area;
            }
            if (have_vis)
                for (const glm::vec3& p : f.eyes) {
                    const int cluster = vis.cluster_of(p);
                    if (!vis.has_fraction(cluster)) continue;
                    ++f.eyes_with_cluster;
                    f.compiler_fraction_sum += vis.fraction_of(cluster);
                }
        }
        spaces.clear();
        const double cells_seconds = seconds_since(t_cells);

        // Aimed rays at every listed (cell, object) pair, in parallel over the pairs.
        const auto t_build = std::chrono::steady_clock::now();
        const OpaqueScene scene(world);
        const double build_seconds = seconds_since(t_build);
        struct Pair {
            uint32_t fig, object;
        };
        std::vector<Pair> pairs;
        for (uint32_t i = 0; i < figs.size(); ++i)
            for (uint32_t o : figs[i].listed) pairs.push_back({i, o});
        std::vector<int64_t> first_reach(pairs.size(), -1);  // index of the first ray that reached, or -1
        std::vector<uint64_t> pair_rays(pairs.size(), 0);
        std::fprintf(stderr,
                     "bench_truth: %zu cells, %zu listed pairs, %u eyes per cell, up to %u rays each\n",
                     figs.size(), pairs.size(), n_eyes, n_rays);
        const auto t_aim = std::chrono::steady_clock::now();
        ctx.progress_begin("aimed rays", pairs.size(), "pairs");
#pragma omp parallel
        {
            const unsigned csr = _mm_getcsr();  // denormals flushed while tracing, as Embree advises
            _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
            _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
            pvs::bench::AimScratch scratch;
#pragma omp for schedule(dynamic, 1)
            for (int64_t p = 0; p < int64_t(pairs.size()); ++p) {
                const CellFigures& f = figs[pairs[size_t(p)].fig];
                const uint32_t object = pairs[size_t(p)].object;
                pvs::Rng rng(pvs::mix64(seed ^ 0x41494d0000000000ULL), (uint64_t(f.cell) << 32) | object);
                const uint32_t first_eye = rng.below(uint32_t(f.eyes.size()));
                const pvs::bench::Aim aim =
                    pvs::bench::aim_at_object(scene, world, cum_area, object, f.eyes.data(), f.eyes.size(),
                                              first_eye, n_rays, rng, scratch);
                const int64_t reached = aim.first_reaching;
                const uint32_t done = aim.rays;
                first_reach[size_t(p)] = reached;
                pair_rays[size_t(p)] = done;
                ctx.progress_advance();
            }
            _mm_setcsr(csr);
        }
        ctx.progress_end();
        // (a') Extreme rays at the pairs no aimed ray reached: from each extreme corner of the cell's eye
        // space to a point just inside each corner of the object's triangles. Sight that passes an occluder's
        // edge only from the eye space's rim to an object's rim (a sliver of its lines) is found here.
        uint64_t extreme_found = 0, extreme_traced = 0;
        if (extreme_rays) {
            ctx.progress_begin("extreme rays", pairs.size(), "pairs");
#pragma omp parallel reduction(+ : extreme_found, extreme_traced)
            {
                const unsigned csr = _mm_getcsr();
                _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
                _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
                std::vector<RTCRay> rays;
                std::vector<uint32_t> target;
#pragma omp for schedule(dynamic, 1)
                for (int64_t p = 0; p < int64_t(pairs.size()); ++p) {
                    ctx.progress_advance();
                    if (first_reach[size_t(p)] >= 0) continue;
                    const CellFigures& f = figs[pairs[size_t(p)].fig];
                    const pvs::WorldObject& obj = world.objects[pairs[size_t(p)].object];
                    const uint32_t step = std::max<uint32_t>(1, obj.triangle_count / kExtremeTriangles);
                    rays.clear();
                    target.clear();
                    for (uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count;
                         t += step) {
                        const uint32_t prim = scene.prim_of(t);
                        if (prim == pvs::bench::kNoTarget) continue;
                        const pvs::Triangle& tri = world.triangles[t];
                        const glm::vec3 c = (world.positions[tri.v[0]] + world.positions[tri.v[1]] +
                                             world.positions[tri.v[2]]) /
                                            3.0f;
                        for (int k = 0; k < 3; ++k) {
                            const glm::vec3 v = world.positions[tri.v[k]];
                            const float to_centre = glm::length(c - v);
                            if (!(to_centre > 0.0f)) continue;
                            for (const glm::vec3& eye : f.extremes) {
                                // Far enough inside the triangle that the segment's end margin (kExtremeEnd)
                                // cannot let it pass a neighbouring face at the corner.
                                const float inset = std::min(
                                    0.5f, std::max(kExtremeInset, kExtremeEndMargins * (1.0f - kExtremeEnd) *
                                                                      glm::length(v - eye) / to_centre));
                                const glm::vec3 point = v + inset * (c - v);
                                const glm::vec3 d = point - eye;
                                if (d == glm::vec3(0.0f)) continue;
                                rays.push_back(pvs::bench::segment_ray(eye, d, kExtremeEnd, 0));
                                target.push_back(prim);
                            }
                        }
                    }
                    bool reached = false;
                    constexpr size_t kBatch = pvs::bench::AimScratch::kMaxBatch;
                    for (size_t b = 0; b < rays.size() && !reached; b += kBatch) {
                        const uint32_t n = uint32_t(std::min(kBatch, rays.size() - b));
                        for (uint32_t k = 0; k < n; ++k) rays[b + k].id = k;
                        scene.occluded(rays.data() + b, target.data() + b, n);
                        extreme_traced += n;
                        for (uint32_t k = 0; k < n && !reached; ++k) reached = rays[b + k].tfar >= 0.0f;
                    }
                    if (reached) {
                        first_reach[size_t(p)] = int64_t(pair_rays[size_t(p)]);
                        ++extreme_found;
                    }
                }
                _mm_setcsr(csr);
            }
            ctx.progress_end();
        }
        const double aim_seconds = seconds_since(t_aim);
        uint64_t rays_traced = 0, late_finds = 0, quarter_finds = 0;
        std::vector<double> find_index;
        for (size_t p = 0; p < pairs.size(); ++p) {
            rays_traced += pair_rays[p];
            if (first_reach[p] < 0) continue;
            CellFigures& f = figs[pairs[p].fig];
            ++f.visible_objects;
            f.visible_triangles += world.objects[pairs[p].object].triangle_count;
            find_index.push_back(double(first_reach[p]));
            late_finds += uint64_t(first_reach[p]) >= n_rays / 2;
            quarter_finds += uint64_t(first_reach[p]) >= n_rays / 4;
        }

        // (b) The lower bound: the sampled PVS rows of the chosen cells (bake_sampled_pvs's rows for them).
        double bound_seconds = 0.0;
        uint32_t bound_rays_per_eye = 0;
        if (lower_bound_eyes > 0) {
            const auto t_bound = std::chrono::steady_clock::now();
            std::fprintf(stderr, "bench_truth: lower bound, the sampled PVS of the cells with %u eyes each\n",
                         lower_bound_eyes);
            const pvs::RayScene ray_scene(ctx, world);
            pvs::SampledPvsConfig sampled;
            sampled.rays.eyes_per_cell = lower_bound_eyes;
            bound_rays_per_eye = pvs::rays_per_eye_within_budget(sampled.rays, cells.size());
            std::vector<pvs::Aabb> boxes;
            std::vector<uint64_t> streams;
            for (const CellFigures& f : figs) {
                boxes.push_back(cells.cells[f.cell].bounds);
                streams.push_back(f.cell);
            }
            pvs::PvsSet rows = pvs::PvsSet::make(uint32_t(figs.size()), n_objects);
            uint64_t guard_band_added = 0;
            ctx.progress_begin("lower bound", figs.size(), "cells");
            pvs::sample_box_rows(sampled, world, ray_scene, cells, boxes, streams, bound_rays_per_eye, rows,
                                 guard_band_added, &ctx);
            ctx.progress_end();
            for (uint32_t i = 0; i < figs.size(); ++i) {
                CellFigures& f = figs[i];
                std::vector<uint8_t> visible(n_objects, 0);
                for (size_t p = 0; p < pairs.size(); ++p)
                    if (pairs[p].fig == i && first_reach[p] >= 0) visible[pairs[p].object] = 1;
                for (uint32_t o = 0; o < n_objects; ++o) {
                    const pvs::WorldObject& obj = world.objects[o];
                    const bool touched = rows.test(i, o);
                    // add_always_listed(): marked always visible, or bounds meeting the cell's box.
                    const bool rule = (obj.flags & pvs::kObjectAlwaysVisible) ||
                                      cells.cells[f.cell].bounds.overlaps(obj.bounds);
                    if (!touched && !rule) continue;
                    ++f.bound_objects;
                    f.bound_triangles += obj.triangle_count;
                    if (touched && !bake.pvs.test(f.cell, o)) ++f.bound_unlisted;
                    if (touched && bake.pvs.test(f.cell, o) && obj.triangle_count > 0 && !visible[o]) {
                        ++f.bound_seen_not_visible;
                        std::fprintf(
                            stderr,
                            "bench_truth: cell %u: the lower bound's rays touched object %u (%s), no "
                            "aimed ray reached it\n",
                            f.cell, o, obj.name.c_str());
                    }
                }
            }
            bound_seconds = seconds_since(t_bound);
        }

        // Figures.
        uint64_t listed_objects = 0, listed_triangles = 0, visible_objects = 0, visible_triangles = 0,
                 without_area = 0;
        std::vector<double> listed_share, visible_share, ratio_tri, ratio_obj;
        for (const CellFigures& f : figs) {
            listed_objects += f.listed_objects;
            listed_triangles += f.listed_triangles;
            visible_objects += f.visible_objects;
            visible_triangles += f.visible_triangles;
            without_area += f.listed_without_area;
            listed_share.push_back(double(f.listed_triangles) / world_triangles);
            visible_share.push_back(double(f.visible_triangles) / world_triangles);
            if (f.visible_triangles > 0)
                ratio_tri.push_back(double(f.listed_triangles) / double(f.visible_triangles));
            if (f.visible_objects > 0)
                ratio_obj.push_back(double(f.listed_objects) / double(f.visible_objects));
        }
        auto ratio = [](double a, double b) { return b > 0.0 ? a / b : 0.0; };
        nlohmann::ordered_json out;
        out["bench"] = "truth";
        out["world"] = world_path;
        out["bake"] = bake_path;
        out["pvs_kind"] = bake.conservative ? "conservative" : "aggressive";
        out["cells_kind"] = cells.kind == pvs::CellSet::Kind::kOctree ? "octree" : "grid";
        out["world_hash_matches"] = hash_matches;
        out["world_objects"] = n_objects;
        out["world_triangles"] = world.triangles.size();
        out["bake_cells"] = cells.size();
        out["eye_space"] = cells.eyes.empty() ? "cell boxes (the bake holds no eye mask)" : "eye voxels";
        out["seed"] = seed;
        out["cells"] = figs.size();
        out["cells_skipped_without_eye_space"] = skipped_without_eyes;
        out["eyes_per_cell"] = n_eyes;
        out["rays_per_object"] = n_rays;
        out["allow_few_rays"] = n_rays < kMinRays;
        out["threads"] = omp_get_max_threads();
        out["listed_objects"] = listed_objects;
        out["listed_triangles"] = listed_triangles;
        out["visible_objects"] = visible_objects;
        out["visible_triangles"] = visible_triangles;
        out["listed_over_visible_triangles"] = ratio(double(listed_triangles), double(visible_triangles));
        out["listed_over_visible_objects"] = ratio(double(listed_objects), double(visible_objects));
        {  // how far the headline moves with the draw of cells: a bootstrap over them
            pvs::Rng boot(pvs::mix64(seed ^ 0x424f4f5400000000ULL), figs.size());
            std::vector<double> resampled;
            for (int b = 0; b < kBootstrapDraws && !figs.empty(); ++b) {
                double l = 0.0, v = 0.0;
                for (size_t i = 0; i < figs.size(); ++i) {
                    const CellFigures& f = figs[boot.below(uint32_t(figs.size()))];
                    l += double(f.listed_triangles);
                    v += double(f.visible_triangles);
                }
                resampled.push_back(ratio(l, v));
            }
            std::sort(resampled.begin(), resampled.end());
            const auto at = [&](double q) {
                return resampled.empty() ? 0.0 : resampled[size_t(q * double(resampled.size() - 1) + 0.5)];
            };
            out["listed_over_visible_triangles_interval95"] = {at(0.025), at(0.975)};
        }
        out["listed_triangle_share_mean"] = mean(listed_share);
        out["visible_triangle_share_mean"] = mean(visible_share);
        out["listed_objects_mean"] = double(listed_objects) / double(figs.size());
        out["visible_objects_mean"] = double(visible_objects) / double(figs.size());
        out["cells_with_visible"] = ratio_tri.size();
        out["listed_over_visible_triangles_cell_median"] = median(ratio_tri);
        out["listed_over_visible_objects_cell_median"] = median(ratio_obj);
        out["listed_objects_without_area"] = without_area;
        out["rays_traced"] = rays_traced;
        out["extreme_rays"] = extreme_rays;
        out["extreme_rays_traced"] = extreme_traced;
        out["visible_found_by_extreme_rays"] = extreme_found;
        out["first_reaching_ray_median"] = median(find_index);
        out["visible_found_after_quarter_of_rays"] = quarter_finds;
        out["visible_found_after_half_of_rays"] = late_finds;
        nlohmann::ordered_json comp;
        if (have_vis) {
            uint64_t with = 0;
            double fraction = 0.0, bake_sum = 0.0, visible_sum = 0.0;
            for (const CellFigures& f : figs) {
                with += f.eyes_with_cluster;
                fraction += f.compiler_fraction_sum;
                bake_sum += double(f.eyes_with_cluster) * double(f.listed_triangles) / world_triangles;
                visible_sum += double(f.eyes_with_cluster) * double(f.visible_triangles) / world_triangles;
            }
            const double n = double(std::max<uint64_t>(with, 1));
            comp["vis"] = vis_path;
            comp["eyes"] = with;
            comp["eyes_in_compiler_solid_share"] =
                1.0 - double(with) / double(uint64_t(figs.size()) * uint64_t(n_eyes));
            comp["compiler_triangle_share_mean"] = fraction / n;
            comp["bake_triangle_share_mean"] = bake_sum / n;
            comp["visible_triangle_share_mean"] = visible_sum / n;
            comp["bake_over_compiler_of_means"] = ratio(bake_sum, fraction);
            comp["visible_over_compiler_of_means"] = ratio(visible_sum, fraction);
            out["compiler"] = comp;
        } else {
            out["compiler"] = nullptr;
        }
        if (lower_bound_eyes > 0) {
            nlohmann::ordered_json lb;
            uint64_t objects = 0, triangles = 0, unlisted = 0, not_visible = 0;
            std::vector<double> share;
            for (const CellFigures& f : figs) {
                objects += f.bound_objects;
                triangles += f.bound_triangles;
                unlisted += f.bound_unlisted;
                not_visible += f.bound_seen_not_visible;
                share.push_back(double(f.bound_triangles) / world_triangles);
            }
            lb["eyes_per_cell"] = lower_bound_eyes;
            lb["rays_per_eye"] = bound_rays_per_eye;
            lb["objects"] = objects;
            lb["triangles"] = triangles;
            lb["triangle_share_mean"] = mean(share);
            lb["bake_over_lower_bound_triangles"] = ratio(double(listed_triangles), double(triangles));
            lb["visible_over_lower_bound_triangles"] = ratio(double(visible_triangles), double(triangles));
            lb["touched_not_listed"] = unlisted;
            lb["touched_listed_not_found_by_aimed_rays"] = not_visible;
            out["lower_bound"] = lb;
        } else {
            out["lower_bound"] = nullptr;
        }
        out["seconds"] = {{"cells_and_eyes", cells_seconds},
                          {"scene_build", build_seconds},
                          {"aimed_rays", aim_seconds},
                          {"lower_bound", bound_seconds},
                          {"total", seconds_since(t_start)}};
        out["aimed_rays_per_second"] = aim_seconds > 0.0 ? double(rays_traced) / aim_seconds : 0.0;
        std::cout << out.dump(2) << std::endl;
    } catch (const pvs::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return e.kind() == pvs::ErrorKind::kInternal ? 1 : 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
