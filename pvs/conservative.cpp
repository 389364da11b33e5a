// The conservative solver: every cell's boundary sampled within epsilon, a depth cube of the shrunk
// occluders from each sample, objects proven hidden from every sample left out.
#include "pvs/conservative.h"

#include "occluders/voxels.h"
#include "pvs/depth_cube.h"
#include "pvs/ray_sampler.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace pvs {

namespace {

// Sample points of the box's six faces: each face split into n_u x n_v squares of edge <= spacing, one
// sample at each square's centre (every face point is within spacing / sqrt(2) of a sample).
void boundary_samples(const Aabb& box, double spacing, std::vector<glm::vec3>& out) {
    out.clear();
    const glm::vec3 size = box.size();
    for (int axis = 0; axis < 3; ++axis) {
        const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
        const int nu = std::max(1, int(std::ceil(double(size[ua]) / spacing - 1e-9)));
        const int nv = std::max(1, int(std::ceil(double(size[va]) / spacing - 1e-9)));
        for (int side = 0; side < 2; ++side) {
            for (int j = 0; j < nv; ++j)
                for (int i = 0; i < nu; ++i) {
                    glm::vec3 p(0.0f);
                    p[axis] = side ? box.max[axis] : box.min[axis];
                    p[ua] = box.min[ua] + size[ua] * (float(i) + 0.5f) / float(nu);
                    p[va] = box.min[va] + size[va] * (float(j) + 0.5f) / float(nv);
                    out.push_back(p);
                }
        }
    }
}

// Finer occludee boxes per object: its triangles in runs of kTrianglesPerPart, each run's bounds. An
// object whose one box is not proven hidden may still be, part by part (all parts hidden = hidden).
constexpr uint32_t kTrianglesPerPart = 4;

std::vector<std::vector<Aabb>> object_parts(const World& world) {
    std::vector<std::vector<Aabb>> parts(world.objects.size());
    for (size_t o = 0; o < world.objects.size(); ++o) {
        const WorldObject& obj = world.objects[o];
        for (uint32_t t0 = 0; t0 < obj.triangle_count; t0 += kTrianglesPerPart) {
            Aabb b;
            for (uint32_t t = t0; t < std::min(obj.triangle_count, t0 + kTrianglesPerPart); ++t) {
                for (uint32_t v : world.triangles[obj.first_triangle + t].v) b.extend(world.positions[v]);
            }
            parts[o].push_back(b);
        }
    }
    return parts;
}

}  // namespace

VoxelMask sample_reach(const VoxelMask& view, double epsilon_m) {
    if (view.empty()) return view;
    VoxelGrid grid;
    grid.origin = view.origin;
    grid.voxel_size_m = view.voxel_size_m;
    grid.dims = view.dims;
    BitVolume bits;
    bits.words = view.bits;
    const int k = int(std::ceil(epsilon_m / double(view.voxel_size_m) - 1e-9)) + 1;
    VoxelMask out = view;
    out.bits = dilate(grid, bits, k).words;
    return out;
}

void conservative_box_rows(Context& ctx, const ConservativeConfig& config, const World& world,
                           const std::vector<Aabb>& boxes, const std::vector<Aabb>& shrunk,
                           const VoxelMask& reach, PvsSet& pvs, ConservativeFigures& figures) {
    const auto start = std::chrono::steady_clock::now();
    const uint32_t n_objects = uint32_t(world.objects.size());
    // Spacing epsilon * sqrt(2): the centre of a square of that edge is within epsilon of all of it.
    const double spacing = config.epsilon_m * std::sqrt(2.0);
    const std::vector<std::vector<Aabb>> parts = object_parts(world);
    uint64_t samples = 0, skipped = 0, far = 0, tests = 0;
#pragma omp parallel reduction(+ : samples, skipped, far, tests)
    {
        DepthCube cube(config.cube_resolution);
        std::vector<glm::vec3> points;
        std::vector<uint32_t> open;  // objects not yet proven visible from this cell
#pragma omp for schedule(dynamic, 1)
        for (int64_t ci = 0; ci < int64_t(boxes.size()); ++ci) {
            const uint32_t c = uint32_t(ci);
            uint64_t* row = pvs.row(c);
            open.clear();
            for (uint32_t o = 0; o < n_objects; ++o) {
                const WorldObject& obj = world.objects[o];
                if ((obj.flags & kObjectAlwaysVisible) || obj.bounds.overlaps(boxes[size_t(c)])) {
                    row[o >> 6] |= uint64_t(1) << (o & 63);
                } else {
                    open.push_back(o);
                }
            }
            boundary_samples(boxes[size_t(c)], spacing, points);
            for (const glm::vec3& s : points) {
                if (open.empty()) break;
                if (!reach.empty() && !reach.contains(s)) {
                    ++far;
                    continue;
                }
                bool in_occluder = false;
                for (const Aabb& b : shrunk) in_occluder = in_occluder || b.contains(s);
                if (in_occluder) {
                    ++skipped;
                    continue;
                }
                ++samples;
                cube.clear(s);
                for (const Aabb& b : shrunk) cube.add_occluder(b);
                size_t w = 0;
                for (uint32_t o : open) {
                    ++tests;
                    bool hidden = cube.is_hidden(world.objects[o].bounds);
                    if (!hidden && parts[o].size() > 1) {
                        hidden = true;
                        for (const Aabb& part : parts[o]) {
                            ++tests;
                            if (!cube.is_hidden(part)) {
                                hidden = false;
                                break;
                            }
                        }
                    }
                    if (hidden) {
                        open[w++] = o;  // still hidden: stays open for the next sample
                    } else {
                        row[o >> 6] |= uint64_t(1) << (o & 63);
                    }
                }
                open.resize(w);
            }
            ctx.progress_advance();
        }
    }
    figures.samples += samples;
    figures.samples_skipped += skipped;
    figures.samples_far += far;
    figures.object_tests += tests;
    figures.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

PvsSet bake_conservative_pvs(Context& ctx, const ConservativeConfig& config, const World& world,
                             const CellSet& cells, const std::vector<Aabb>& shrunk, const VoxelMask& reach,
                             ConservativeFigures& figures) {
    ScopedTimer timer(ctx, "conservative_pvs");
    ctx.info(fmt::format("conservative PVS: {} cells, {} shrunk occluders, epsilon {} m, cube {} px",
                         cells.size(), shrunk.size(), config.epsilon_m, config.cube_resolution));
    PvsSet pvs = PvsSet::make(uint32_t(cells.size()), uint32_t(world.objects.size()));
    std::vector<Aabb> boxes;
    for (const Cell& c : cells.cells) boxes.push_back(c.bounds);
    ctx.progress_begin("conservative PVS", cells.size(), "cells");
    conservative_box_rows(ctx, config, world, boxes, shrunk, reach, pvs, figures);
    ctx.progress_end();
    add_always_listed(world, cells, pvs);
    ctx.info(fmt::format(
        "conservative PVS: {} samples ({} inside occluders and {} far from the view region skipped), "
        "{:.1f} M object tests, {:.1f} s ({:.0f} cells/s)",
        figures.samples, figures.samples_skipped, figures.samples_far, double(figures.object_tests) * 1e-6,
        figures.seconds, double(cells.size()) / std::max(1e-9, figures.seconds)));
    return pvs;
}

}  // namespace pvs
