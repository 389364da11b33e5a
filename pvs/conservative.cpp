// The conservative solver: every cell's boundary sampled within epsilon, a depth cube of the shrunk
// occluders from each sample, objects proven hidden from every sample left out.
#include "pvs/conservative.h"

#include "occluders/voxels.h"
#include "pvs/depth_cube.h"
#include "pvs/ray_sampler.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <unordered_map>

namespace pvs {

namespace {

// Sample points of one face (the side of `box` at box.min[axis] when !at_max, else at box.max[axis]),
// split into n_u x n_v squares of edge <= spacing, one sample at each square's centre: every point of the
// face is within spacing / sqrt(2) of a sample. Appends to `out`.
void append_face_samples(const Aabb& box, int axis, bool at_max, double spacing,
                         std::vector<glm::vec3>& out) {
    const glm::vec3 size = box.size();
    const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    const int nu = std::max(1, int(std::ceil(double(size[ua]) / spacing - 1e-9)));
    const int nv = std::max(1, int(std::ceil(double(size[va]) / spacing - 1e-9)));
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            glm::vec3 p(0.0f);
            p[axis] = at_max ? box.max[axis] : box.min[axis];
            p[ua] = box.min[ua] + size[ua] * (float(i) + 0.5f) / float(nu);
            p[va] = box.min[va] + size[va] * (float(j) + 0.5f) / float(nv);
            out.push_back(p);
        }
}

void face_samples(const Aabb& face, int axis, double spacing, std::vector<glm::vec3>& out) {
    out.clear();
    append_face_samples(face, axis, false, spacing, out);
}

// Sample points of the box's six faces.
void boundary_samples(const Aabb& box, double spacing, std::vector<glm::vec3>& out) {
    out.clear();
    for (int axis = 0; axis < 3; ++axis) {
        append_face_samples(box, axis, false, spacing, out);
        append_face_samples(box, axis, true, spacing, out);
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

namespace {

struct SampleCounts {
    uint64_t samples = 0, skipped = 0, far = 0, tests = 0;
    SampleCounts& operator+=(const SampleCounts& o) {
        samples += o.samples;
        skipped += o.skipped;
        far += o.far;
        tests += o.tests;
        return *this;
    }
};

// Proves objects of `open` hidden from every point of `points`; sets the row bit of every object some
// point cannot prove hidden and removes it from `open`.
void prove_from_samples(const ConservativeConfig& config, const World& world,
                        const std::vector<std::vector<Aabb>>& parts, const std::vector<Aabb>& shrunk,
                        const VoxelMask& reach, const std::vector<glm::vec3>& points, DepthCube& cube,
                        std::vector<uint32_t>& open, uint64_t* row, SampleCounts& n) {
    for (const glm::vec3& s : points) {
        if (open.empty()) break;
        if (!reach.empty() && !reach.contains(s)) {
            ++n.far;
            continue;
        }
        bool in_occluder = false;
        for (const Aabb& b : shrunk) in_occluder = in_occluder || b.contains(s);
        if (in_occluder) {
            ++n.skipped;
            continue;
        }
        ++n.samples;
        cube.clear(s);
        for (const Aabb& b : shrunk) cube.add_occluder(b);
        size_t w = 0;
        for (uint32_t o : open) {
            ++n.tests;
            bool hidden = cube.is_hidden(world.objects[o].bounds);
            if (!hidden && parts[o].size() > 1) {
                hidden = true;
                for (const Aabb& part : parts[o]) {
                    ++n.tests;
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
}

void add_counts(ConservativeFigures& figures, const SampleCounts& n,
                std::chrono::steady_clock::time_point start) {
    figures.samples += n.samples;
    figures.samples_skipped += n.skipped;
    figures.samples_far += n.far;
    figures.object_tests += n.tests;
    figures.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void conservative_box_rows(Context& ctx, const ConservativeConfig& config, const World& world,
                           const std::vector<Aabb>& boxes, const std::vector<Aabb>& shrunk,
                           const VoxelMask& reach, PvsSet& pvs, ConservativeFigures& figures) {
    const auto start = std::chrono::steady_clock::now();
    const uint32_t n_objects = uint32_t(world.objects.size());
    // Spacing epsilon * sqrt(2): the centre of a square of that edge is within epsilon of all of it.
    const double spacing = config.epsilon_m * std::sqrt(2.0);
    const std::vector<std::vector<Aabb>> parts = object_parts(world);
    SampleCounts total;
#pragma omp parallel
    {
        DepthCube cube(config.cube_resolution);
        std::vector<glm::vec3> points;
        std::vector<uint32_t> open;  // objects not yet proven visible from this box
        SampleCounts n;
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
            prove_from_samples(config, world, parts, shrunk, reach, points, cube, open, row, n);
            ctx.progress_advance();
        }
#pragma omp critical
        total += n;
    }
    add_counts(figures, total, start);
}

// A grid: each face shared by two cells is computed once. A face's row lists every object some sample of
// the face cannot prove hidden; a cell's row is the union of its six faces' rows and add_always_listed().
static void conservative_grid_rows(Context& ctx, const ConservativeConfig& config, const World& world,
                                   const CellSet& cells, const std::vector<Aabb>& shrunk,
                                   const VoxelMask& reach, PvsSet& pvs, ConservativeFigures& figures) {
    const auto start = std::chrono::steady_clock::now();
    const uint32_t n_objects = uint32_t(world.objects.size());
    const double spacing = config.epsilon_m * std::sqrt(2.0);
    const std::vector<std::vector<Aabb>> parts = object_parts(world);
    // Faces: key (axis, plane index along it, cell indices along the other two), in cell order.
    struct Face {
        int axis;
        Aabb rect;  // flat along `axis`
    };
    std::vector<Face> faces;
    std::unordered_map<uint64_t, uint32_t> face_of;
    std::vector<std::array<uint32_t, 6>> cell_faces(cells.size());
    const float s = cells.cell_size_m;
    for (size_t g = 0; g < cells.grid_to_cell.size(); ++g) {
        const int32_t c = cells.grid_to_cell[g];
        if (c < 0) continue;
        const glm::ivec3 idx(int(g % size_t(cells.dims.x)),
                             int((g / size_t(cells.dims.x)) % size_t(cells.dims.y)),
                             int(g / (size_t(cells.dims.x) * size_t(cells.dims.y))));
        const Aabb box = cells.cells[size_t(c)].bounds;
        for (int axis = 0; axis < 3; ++axis) {
            for (int side = 0; side < 2; ++side) {
                glm::ivec3 k = idx;
                k[axis] += side;
                const uint64_t key =
                    (uint64_t(axis) << 62) | (uint64_t(k.x) << 41) | (uint64_t(k.y) << 20) | uint64_t(k.z);
                auto [it, fresh] = face_of.emplace(key, uint32_t(faces.size()));
                if (fresh) {
                    Aabb rect = box;
                    rect.min[axis] = rect.max[axis] = cells.origin[axis] + float(k[axis]) * s;
                    faces.push_back(Face{axis, rect});
                }
                cell_faces[size_t(c)][size_t(2 * axis + side)] = it->second;
            }
        }
    }
    PvsSet face_rows = PvsSet::make(uint32_t(faces.size()), n_objects);
    SampleCounts total;
    ctx.progress_begin("conservative PVS", faces.size(), "faces");
#pragma omp parallel
    {
        DepthCube cube(config.cube_resolution);
        std::vector<glm::vec3> points;
        std::vector<uint32_t> open;
        SampleCounts n;
#pragma omp for schedule(dynamic, 4)
        for (int64_t fi = 0; fi < int64_t(faces.size()); ++fi) {
            const Face& f = faces[size_t(fi)];
            open.clear();
            for (uint32_t o = 0; o < n_objects; ++o)
                if (!(world.objects[o].flags & kObjectAlwaysVisible)) open.push_back(o);
            face_samples(f.rect, f.axis, spacing, points);
            prove_from_samples(config, world, parts, shrunk, reach, points, cube, open,
                               face_rows.row(uint32_t(fi)), n);
            ctx.progress_advance();
        }
#pragma omp critical
        total += n;
    }
    ctx.progress_end();
    for (uint32_t c = 0; c < cells.size(); ++c) {
        uint64_t* row = pvs.row(c);
        for (uint32_t f : cell_faces[c]) {
            const uint64_t* fr = face_rows.row(f);
            for (uint32_t w = 0; w < pvs.words_per_row; ++w) row[w] |= fr[w];
        }
    }
    add_counts(figures, total, start);
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
    if (cells.kind == CellSet::Kind::kGrid) {
        conservative_grid_rows(ctx, config, world, cells, shrunk, reach, pvs, figures);
    } else {
        ctx.progress_begin("conservative PVS", cells.size(), "cells");
        conservative_box_rows(ctx, config, world, boxes, shrunk, reach, pvs, figures);
        ctx.progress_end();
    }
    add_always_listed(world, cells, pvs);
    ctx.info(fmt::format(
        "conservative PVS: {} samples ({} inside occluders and {} far from the view region skipped), "
        "{:.1f} M object tests, {:.1f} s ({:.0f} cells/s)",
        figures.samples, figures.samples_skipped, figures.samples_far, double(figures.object_tests) * 1e-6,
        figures.seconds, double(cells.size()) / std::max(1e-9, figures.seconds)));
    return pvs;
}

}  // namespace pvs
