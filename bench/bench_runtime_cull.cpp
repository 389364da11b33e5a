// SPDX-License-Identifier: MIT
// bench_runtime_cull: the run-time culler of moving objects (pvsbake/occlusion.h).
//
//   bench_runtime_cull [--repeats R] [--frames F]
//       Synthetic, two scenes: a city of 6 x 6 blocks (16 m buildings, 8 to 30 m high, 8 m streets), where
//       one building usually hides a box alone, and a field of 150 short walls (2-5 m, 0.3 m thick, 3 m high)
//       over 60 x 60 m, where culling needs fusion. Eyes at 1.7 m in the free space; occluders: the K boxes
//       of largest solid angle from the eye (as a bake ranks them); N moving boxes (people, one in five a
//       vehicle) in the free space. For K = 4, 8, 16 and N = 100, 300, 1,000: the cost of one frame
//       (begin_frame + classify of the N boxes; median over R repeats of F frames, one thread), of
//       begin_frame alone, and the share culled, by single shadow frusta and by the fused depth cube only;
//       then K = 8, N = 300 at cube resolutions 0 (frusta only), 16, 32, 64.
//   bench_runtime_cull --world W.glb --bake B.h5 [--frames F] [--objects M] [--occluders K] [--seed S]
//                      [--resolution R] [--shrink-voxels V]
//       Ground truth on a real world: follows the walkthrough example's camera path and moves its objects
//       (io/loader/examples/walk.h, same seed), culls them against K occluders a frame, and checks every
//       culled box with Embree rays against the world's triangles (27 points of the box plus 40 random
//       ones): a ray that reaches its point unblocked is a wrong cull. The occluders of a frame are the
//       cell's ranked occluders (format 1.2); for older bakes, the K proven boxes of the bake's /occluders
//       with the largest solid angle from the eye. As in the example, only frames whose eye is in the eye
//       space (Bake::in_eye_space) cull; the others draw every moving object. Also: how many boxes the same
//       rays find hidden (every ray blocked), an upper estimate of what any culler could cull.
// Prints one JSON object.
#include "bench/bench_util.h"
#include "core/context.h"
#include "io/bake_file.h"
#include "io/gltf_loader.h"
#include "io/loader/examples/walk.h"
#include "rays/ray_scene.h"

#include <pvsbake/loader.h>
#include <pvsbake/occlusion.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <random>
#include <string>
#include <vector>

namespace pvs {
namespace {

using bench::median;
using bench::seconds_since;
using pvsbake::Box;
using Culler = pvsbake::OcclusionCuller;
using Path = pvsbake::OcclusionCuller::Path;

// Area-angle estimate of the solid angle of a box from a point (docs/ALGORITHMS.md#ranking): the sum over the
// faces facing the point of area * (n . v) / |v|^3, v from the point to the face centre. 0 when inside.
double solid_angle_estimate(const Box& b, const float eye[3]) {
    double sum = 0.0;
    bool inside = true;
    for (int a = 0; a < 3; ++a) inside = inside && eye[a] >= b.min[a] && eye[a] <= b.max[a];
    if (inside) return 0.0;
    for (int a = 0; a < 3; ++a) {
        const int u = (a + 1) % 3, v = (a + 2) % 3;
        const double area = double(b.max[u] - b.min[u]) * double(b.max[v] - b.min[v]);
        const double face = eye[a] < b.min[a] ? b.min[a] : eye[a] > b.max[a] ? b.max[a] : std::nan("");
        if (std::isnan(face)) continue;
        const double d[3] = {0.5 * (b.min[0] + b.max[0]) - eye[0], 0.5 * (b.min[1] + b.max[1]) - eye[1],
                             0.5 * (b.min[2] + b.max[2]) - eye[2]};
        double dd[3] = {d[0], d[1], d[2]};
        dd[a] = face - eye[a];
        const double len = std::sqrt(dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]);
        sum += area * std::abs(dd[a]) / (len * len * len);
    }
    return sum;
}

// The k boxes of largest solid angle from the eye, best first.
void pick_occluders(const std::vector<Box>& all, const float eye[3], size_t k, std::vector<Box>& out,
                    std::vector<std::pair<double, uint32_t>>& scratch) {
    scratch.clear();
    for (uint32_t i = 0; i < all.size(); ++i) scratch.push_back({-solid_angle_estimate(all[i], eye), i});
    const size_t n = std::min(k, scratch.size());
    std::partial_sort(scratch.begin(), scratch.begin() + ptrdiff_t(n), scratch.end());
    out.clear();
    for (size_t i = 0; i < n; ++i) {
        if (scratch[i].first < 0.0) out.push_back(all[scratch[i].second]);
    }
}

// Does the segment from the eye to p pass through the closed box b (exact enough: double slabs)?
bool segment_meets(const float eye[3], const glm::vec3& p, const Box& b) {
    double t0 = 0.0, t1 = 1.0;
    for (int a = 0; a < 3; ++a) {
        const double d = double(p[a]) - eye[a];
        if (d == 0.0) {
            if (eye[a] < b.min[a] || eye[a] > b.max[a]) return false;
            continue;
        }
        double ta = (double(b.min[a]) - eye[a]) / d, tb = (double(b.max[a]) - eye[a]) / d;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 <= t1;
}

// ---- Synthetic city.

struct City {
    std::vector<Box> buildings;
    float extent_m = 0.0f;
    bool in_building(float x, float z, float pad) const {
        for (const Box& b : buildings) {
            if (x > b.min[0] - pad && x < b.max[0] + pad && z > b.min[2] - pad && z < b.max[2] + pad)
                return true;
        }
        return false;
    }
};

// Short wall segments (2-5 m long, 0.3 m thick, 3 m high) strewn over 60 x 60 m: no single segment hides
// much, so culling needs fusion (the depth cube).
City make_wall_field(std::mt19937& rng) {
    City field;
    std::uniform_real_distribution<float> at(0.0f, 60.0f), len(2.0f, 5.0f);
    for (int i = 0; i < 150; ++i) {
        const float x = at(rng), z = at(rng), l = len(rng);
        field.buildings.push_back(i % 2 ? Box{{x, 0.0f, z}, {x + l, 3.0f, z + 0.3f}}
                                        : Box{{x, 0.0f, z}, {x + 0.3f, 3.0f, z + l}});
    }
    field.extent_m = 60.0f;
    return field;
}

City make_city(std::mt19937& rng) {
    City city;
    std::uniform_real_distribution<float> h(8.0f, 30.0f);
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j) {
            const float x = 24.0f * float(i), z = 24.0f * float(j);
            city.buildings.push_back(Box{{x, 0.0f, z}, {x + 16.0f, h(rng), z + 16.0f}});
        }
    city.extent_m = 24.0f * 6.0f - 8.0f;
    return city;
}

struct Frame {
    float eye[3];
    std::vector<Box> occluders;
    std::vector<Box> movers;
};

std::vector<Frame> make_frames(const City& city, int frames, size_t k, size_t n, std::mt19937& rng) {
    const auto street_point = [&](float pad) {
        std::uniform_real_distribution<float> p(-4.0f, city.extent_m + 4.0f);
        for (;;) {
            const float x = p(rng), z = p(rng);
            if (!city.in_building(x, z, pad)) return std::pair<float, float>(x, z);
        }
    };
    std::vector<Frame> out(static_cast<size_t>(frames));
    std::vector<std::pair<double, uint32_t>> scratch;
    for (Frame& f : out) {
        const auto [x, z] = street_point(0.5f);
        f.eye[0] = x;
        f.eye[1] = 1.7f;
        f.eye[2] = z;
        pick_occluders(city.buildings, f.eye, k, f.occluders, scratch);
        for (size_t i = 0; i < n; ++i) {
            const bool vehicle = i % 5 == 4;
            const float hx = vehicle ? 1.0f : 0.3f, hy = vehicle ? 0.8f : 0.9f, hz = vehicle ? 2.25f : 0.3f;
            const auto [mx, mz] = street_point(std::max(hx, hz));
            f.movers.push_back(Box{{mx - hx, 0.0f, mz - hz}, {mx + hx, 2 * hy, mz + hz}});
        }
    }
    return out;
}

struct Tally {
    uint64_t tested = 0, frusta = 0, cube = 0;
};

// One pass over the frames; returns seconds.
double run_frames(Culler& culler, const std::vector<Frame>& frames, bool classify, Tally* tally) {
    const auto t0 = std::chrono::steady_clock::now();
    uint64_t sink = 0;
    for (const Frame& f : frames) {
        culler.begin_frame(f.eye, f.occluders);
        if (!classify) continue;
        for (const Box& b : f.movers) {
            const Path p = culler.classify(b);
            sink += uint64_t(p);
            if (tally != nullptr) {
                ++tally->tested;
                tally->frusta += p == Path::kShadowFrustum;
                tally->cube += p == Path::kDepthBuffer;
            }
        }
    }
    const double s = seconds_since(t0);
    if (sink == UINT64_MAX) std::printf("%llu\n", (unsigned long long)sink);  // keep the work
    return s;
}

nlohmann::json measure(const City& city, size_t k, size_t n, int resolution, int frame_count, int repeats,
                       uint32_t seed) {
    std::mt19937 rng(seed);
    const std::vector<Frame> frames = make_frames(city, frame_count, k, n, rng);
    Culler culler(resolution);
    Tally tally;
    run_frames(culler, frames, true, &tally);  // warm up, and the shares
    std::vector<double> frame_us, begin_us;
    for (int r = 0; r < repeats; ++r) {
        frame_us.push_back(1e6 * run_frames(culler, frames, true, nullptr) / double(frames.size()));
        begin_us.push_back(1e6 * run_frames(culler, frames, false, nullptr) / double(frames.size()));
    }
    nlohmann::json j;
    j["occluders"] = k;
    j["objects"] = n;
    j["resolution"] = culler.resolution();
    j["frames"] = frames.size();
    j["frame_us"] = median(frame_us);
    j["begin_frame_us"] = median(begin_us);
    j["classify_ns_per_object"] = 1e3 * (median(frame_us) - median(begin_us)) / double(n);
    const double tested = std::max<double>(1.0, double(tally.tested));
    j["culled_share"] = double(tally.frusta + tally.cube) / tested;
    j["culled_by_frusta_share"] = double(tally.frusta) / tested;
    j["culled_by_cube_only_share"] = double(tally.cube) / tested;
    return j;
}

nlohmann::json synthetic(int repeats, int frames) {
    nlohmann::json j;
    for (int scene = 0; scene < 2; ++scene) {
        std::mt19937 rng(11);
        const City city = scene == 0 ? make_city(rng) : make_wall_field(rng);
        measure(city, 8, 300, Culler::kDefaultResolution, frames, 1, 3);  // warm up
        nlohmann::json runs = nlohmann::json::array();
        for (size_t k : {4, 8, 16})
            for (size_t n : {100, 300, 1000})
                runs.push_back(measure(city, k, n, Culler::kDefaultResolution, frames, repeats, 3));
        nlohmann::json res = nlohmann::json::array();
        for (int r : {0, 16, 32, 64}) res.push_back(measure(city, 8, 300, r, frames, repeats, 3));
        nlohmann::json one;
        one["scene"] =
            scene == 0 ? "city of 6 x 6 blocks, 16 m buildings 8-30 m high, 8 m streets; eyes at 1.7 m"
                       : "150 wall segments 2-5 m long, 0.3 m thick, 3 m high over 60 x 60 m; eyes at 1.7 m";
        one["by_occluders_and_objects"] = runs;
        one["by_resolution"] = res;
        j[scene == 0 ? "city" : "wall_field"] = one;
    }
    return j;
}

// ---- Ground truth on a real world.

Context quiet_context() {
    return Context(Context::Options{LogLevel::kWarning, true, stderr});
}

nlohmann::json ground_truth(const std::string& world_path, const std::string& bake_path, int frames,
                            uint32_t objects, size_t k, unsigned seed, float shrink_voxels, int resolution) {
    Context ctx = quiet_context();
    pvsbake::Bake bake;
    const pvsbake::LoadResult loaded = bake.load(bake_path);
    if (!loaded) {
        std::fprintf(stderr, "%s\n", loaded.message.c_str());
        std::exit(1);
    }
    const BakeData data = read_bake_file(bake_path);
    std::vector<Box> proven;
    for (const Occluder& o : data.occluders) {
        if (!o.proven) continue;
        const float s = shrink_voxels * o.voxel_size_m;  // --shrink-voxels: a diagnostic
        const Box b{{o.box.min.x + s, o.box.min.y + s, o.box.min.z + s},
                    {o.box.max.x - s, o.box.max.y - s, o.box.max.z - s}};
        if (b.min[0] < b.max[0] && b.min[1] < b.max[1] && b.min[2] < b.max[2]) proven.push_back(b);
    }
    const World world = load_world(ctx, world_path);
    const RayScene scene(ctx, world);

    // The example's camera path and moving objects (pvsbake_walkthrough, same seed).
    const std::vector<pvsbake::walk::Vec3> way =
        pvsbake::walk::waypoints(bake, uint32_t(frames / pvsbake::walk::kFramesPerSegment + 2));
    std::mt19937 rng(seed);
    std::vector<pvsbake::walk::Mover> movers = pvsbake::walk::spawn_movers(bake, objects, rng);
    std::mt19937 aim_rng(12345);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);

    Culler culler(resolution);
    std::vector<Box> occ;
    std::vector<std::pair<double, uint32_t>> scratch;
    std::vector<double> frame_us, pick_us, begin_us;
    uint64_t tested = 0, culled = 0, by_frusta = 0, wrong_boxes = 0, wrong_rays = 0, rays = 0, ray_hidden = 0;
    uint64_t frames_in_volume = 0, occluders_used = 0, wrong_by_culler = 0, wrong_by_leaky_occluder = 0;
    uint64_t occluders_checked = 0, leaky_occluders = 0, frames_in_eye_space = 0, eye_space_disagreements = 0;
    bool ranked = false;
    for (uint32_t c = 0; c < bake.cell_count() && !ranked; ++c) ranked = bake.occluder_count(c) > 0;
    uint64_t eye_space_tested = 0, eye_space_culled = 0, eye_space_wrong = 0, eye_space_ray_hidden = 0;
    uint64_t eye_space_occluders_checked = 0, eye_space_leaky_occluders = 0;
    std::vector<glm::vec3> origins, dirs;
    std::vector<float> tfar;
    std::vector<uint8_t> blocked;
    nlohmann::json wrong_examples = nlohmann::json::array(), leaky_examples = nlohmann::json::array();
    for (int f = 0; f < frames && !way.empty(); ++f) {
        const pvsbake::walk::Vec3 e = pvsbake::walk::camera_eye(way, f);
        pvsbake::walk::step_movers(bake, movers, 1.0f / 30.0f, rng);
        const float eye[3] = {e.x, e.y, e.z};
        const int32_t cell = bake.find_cell(eye);
        // The bake's promises hold for eyes in the eye space (free space a player reaches; core/cell_set.h
        // `eyes`). The view volume around it is one voxel wider and can reach behind one-sided walls, where
        // the void sees into every occluder; the example's path passes there (cell centres of that margin).
        // As the example does, the culler gets occluders only there (Bake::in_eye_space), and culls
        // nothing elsewhere. The loader's answer is checked against the baker's own mask.
        const bool in_eyes = bake.in_eye_space(eye);
        eye_space_disagreements +=
            in_eyes != (cell >= 0 && (data.cells.eyes.empty() ||
                                      data.cells.eyes.contains(glm::vec3(eye[0], eye[1], eye[2]))));
        frames_in_eye_space += in_eyes;
        const auto p0 = std::chrono::steady_clock::now();
        occ.clear();
        // The cell's ranked occluders (format 1.2); for older bakes, the k proven boxes of largest solid
        // angle from the eye.
        if (cell >= 0 && in_eyes) {
            if (ranked) {
                for (const pvsbake::RankedOccluder& r : bake.occluders(uint32_t(cell))) occ.push_back(r.box);
            } else {
                pick_occluders(proven, eye, k, occ, scratch);
            }
        }
        pick_us.push_back(1e6 * seconds_since(p0));
        frames_in_volume += cell >= 0;

        std::vector<Path> paths(movers.size());
        const auto t0 = std::chrono::steady_clock::now();
        culler.begin_frame(eye, occ);
        begin_us.push_back(1e6 * seconds_since(t0));
        for (size_t i = 0; i < movers.size(); ++i)
            paths[i] = culler.classify(pvsbake::walk::mover_box(movers[i]));
        frame_us.push_back(1e6 * seconds_since(t0));
        occluders_used += culler.occluders_used();

        // The frame's occluders against the world: rays from the eye to 64 points on each box's faces,
        // stopped 1 mm short (the boxes are not in the scene). A ray that gets there unblocked sees into the
        // box.
        for (const Box& o : occ) {
            bool skipped = true;  // the culler skips a box holding the eye
            for (int a = 0; a < 3; ++a)
                skipped = skipped && eye[a] >= o.min[a] - 1e-3f && eye[a] <= o.max[a] + 1e-3f;
            if (skipped) continue;
            origins.clear();
            dirs.clear();
            tfar.clear();
            for (int r = 0; r < 64; ++r) {
                float q[3] = {u(aim_rng), u(aim_rng), u(aim_rng)};
                q[r % 3] = float((r / 3) % 2);
                const glm::vec3 p(o.min[0] + q[0] * (o.max[0] - o.min[0]),
                                  o.min[1] + q[1] * (o.max[1] - o.min[1]),
                                  o.min[2] + q[2] * (o.max[2] - o.min[2]));
                const glm::vec3 d = p - glm::vec3(eye[0], eye[1], eye[2]);
                const float len = glm::length(d);
                if (!(len > 2e-3f)) continue;
                origins.emplace_back(eye[0], eye[1], eye[2]);
                dirs.push_back(d / len);
                tfar.push_back(len - 1e-3f);
            }
            blocked.resize(origins.size());
            scene.occluded_opaque(origins.data(), dirs.data(), tfar.data(), uint32_t(origins.size()),
                                  blocked.data());
            ++occluders_checked;
            const auto open = std::count(blocked.begin(), blocked.end(), uint8_t(0));
            leaky_occluders += open > 0;
            eye_space_occluders_checked += in_eyes;
            eye_space_leaky_occluders += in_eyes && open > 0;
            if (open > 0 && leaky_examples.size() < 10) {
                const size_t r =
                    size_t(std::find(blocked.begin(), blocked.end(), uint8_t(0)) - blocked.begin());
                const glm::vec3 p = origins[r] + dirs[r] * tfar[r];
                leaky_examples.push_back(
                    {{"frame", f},
                     {"cell", cell},
                     {"eye", {eye[0], eye[1], eye[2]}},
                     {"box", {o.min[0], o.min[1], o.min[2], o.max[0], o.max[1], o.max[2]}},
                     {"open_rays", open},
                     {"of_rays", blocked.size()},
                     {"reached", {p.x, p.y, p.z}}});
            }
        }

        // Rays from the eye to 27 + 40 points of every box: wrong culls, and what the rays find hidden.
        for (size_t i = 0; i < movers.size(); ++i) {
            const Box b = pvsbake::walk::mover_box(movers[i]);
            origins.clear();
            dirs.clear();
            tfar.clear();
            const auto aim = [&](float fx, float fy, float fz) {
                const glm::vec3 p(b.min[0] + fx * (b.max[0] - b.min[0]),
                                  b.min[1] + fy * (b.max[1] - b.min[1]),
                                  b.min[2] + fz * (b.max[2] - b.min[2]));
                const glm::vec3 d = p - glm::vec3(eye[0], eye[1], eye[2]);
                const float len = glm::length(d);
                if (!(len > 0.0f)) return;
                origins.emplace_back(eye[0], eye[1], eye[2]);
                dirs.push_back(d / len);
                tfar.push_back(len);
            };
            for (float fx : {0.0f, 0.5f, 1.0f})
                for (float fy : {0.0f, 0.5f, 1.0f})
                    for (float fz : {0.0f, 0.5f, 1.0f}) aim(fx, fy, fz);
            for (int r = 0; r < 40; ++r) {
                float q[3] = {u(aim_rng), u(aim_rng), u(aim_rng)};
                if (r % 3 != 0) q[r % 3] = float(r % 2);
                aim(q[0], q[1], q[2]);
            }
            blocked.resize(origins.size());
            scene.occluded_opaque(origins.data(), dirs.data(), tfar.data(), uint32_t(origins.size()),
                                  blocked.data());
            rays += origins.size();
            const uint64_t open = uint64_t(std::count(blocked.begin(), blocked.end(), uint8_t(0)));
            ++tested;
            ray_hidden += open == 0;
            eye_space_tested += in_eyes;
            eye_space_ray_hidden += in_eyes && open == 0;
            if (paths[i] == Path::kVisible) continue;
            ++culled;
            eye_space_culled += in_eyes;
            eye_space_wrong += in_eyes && open > 0;
            by_frusta += paths[i] == Path::kShadowFrustum;
            if (open > 0) {
                ++wrong_boxes;
                wrong_rays += open;
                // Whose fault: a ray that reaches its point through one of this frame's occluder boxes proves
                // that box is not sight-proof from this eye (the bake's ray check samples, it does not
                // prove); a ray that passes no occluder box is the culler's error.
                bool culler_error = false;
                for (size_t r = 0; r < blocked.size(); ++r) {
                    if (blocked[r] != 0) continue;
                    const glm::vec3 p = origins[r] + dirs[r] * tfar[r];
                    bool through = false;
                    for (const Box& o : occ) through = through || segment_meets(eye, p, o);
                    culler_error = culler_error || !through;
                }
                (culler_error ? wrong_by_culler : wrong_by_leaky_occluder) += 1;
                if (wrong_examples.size() < 10) {
                    wrong_examples.push_back(
                        {{"frame", f},
                         {"eye", {eye[0], eye[1], eye[2]}},
                         {"box", {b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]}},
                         {"path", int(paths[i])},
                         {"open_rays", open}});
                }
            }
        }
    }
    nlohmann::json j;
    j["world"] = world_path;
    j["bake"] = bake_path;
    j["proven_occluder_boxes"] = proven.size();
    j["occluders_shrunk_by_voxels"] = shrink_voxels;
    j["occluders_per_frame"] = k;
    j["occluders_used_per_frame"] = double(occluders_used) / std::max(1, frames);
    j["frames"] = frames;
    j["frames_in_view_volume"] = frames_in_volume;
    j["frames_in_eye_space"] = frames_in_eye_space;
    j["eye_space_loader_disagreements"] = eye_space_disagreements;
    j["occluders"] = ranked ? "ranked (the bake's, per cell)" : "the k proven boxes of largest solid angle";
    j["eye_space"] = {
        {"boxes_tested", eye_space_tested},
        {"culled", eye_space_culled},
        {"culled_share", double(eye_space_culled) / std::max<double>(1.0, double(eye_space_tested))},
        {"ray_hidden_share", double(eye_space_ray_hidden) / std::max<double>(1.0, double(eye_space_tested))},
        {"wrong_culls", eye_space_wrong},
        {"occluder_boxes_checked", eye_space_occluders_checked},
        {"occluder_boxes_seen_into", eye_space_leaky_occluders}};
    j["moving_objects"] = movers.size();
    j["boxes_tested"] = tested;
    j["culled"] = culled;
    j["culled_share"] = double(culled) / std::max<double>(1.0, double(tested));
    j["culled_by_frusta"] = by_frusta;
    j["culled_by_cube_only"] = culled - by_frusta;
    j["ray_hidden"] = ray_hidden;
    j["ray_hidden_share"] = double(ray_hidden) / std::max<double>(1.0, double(tested));
    j["rays"] = rays;
    j["wrong_culls"] = wrong_boxes;
    j["wrong_rays"] = wrong_rays;
    j["wrong_culls_by_the_culler"] = wrong_by_culler;  // an open ray through no occluder box: must be 0
    j["wrong_culls_through_a_leaky_occluder"] = wrong_by_leaky_occluder;
    j["occluder_boxes_checked"] = occluders_checked;  // frame x occluder pairs
    j["occluder_boxes_seen_into"] = leaky_occluders;  // of those, a ray from the eye reached the box's face
    j["wrong_examples"] = wrong_examples;
    j["seen_into_examples"] = leaky_examples;
    j["frame_us_median"] = median(frame_us);
    std::sort(frame_us.begin(), frame_us.end());
    j["frame_us_p95"] = frame_us.empty() ? 0.0 : frame_us[frame_us.size() * 95 / 100];
    j["begin_frame_us_median"] = median(begin_us);
    j["resolution"] = culler.resolution();
    j["pick_occluders_us_median"] = median(pick_us);
    return j;
}

}  // namespace
}  // namespace pvs

int main(int argc, char** argv) {
    int repeats = 9, frames = 200, occluders = 8;
    uint32_t objects = 300;
    unsigned seed = 1;
    float shrink_voxels = 0.0f;
    int resolution = pvsbake::OcclusionCuller::kDefaultResolution;
    std::string world, bake;
    bool frames_given = false;
    for (int i = 1; i < argc; ++i) {
        const auto next = [&]() -> const char* {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "bench_runtime_cull: %s needs a value\n", argv[i]);
                std::exit(2);
            }
            return argv[++i];
        };
        if (std::strcmp(argv[i], "--repeats") == 0) {
            repeats = std::max(1, std::atoi(next()));
        } else if (std::strcmp(argv[i], "--frames") == 0) {
            frames = std::max(1, std::atoi(next()));
            frames_given = true;
        } else if (std::strcmp(argv[i], "--objects") == 0) {
            objects = uint32_t(std::max(0, std::atoi(next())));
        } else if (std::strcmp(argv[i], "--occluders") == 0) {
            occluders = std::max(0, std::atoi(next()));
        } else if (std::strcmp(argv[i], "--seed") == 0) {
            seed = unsigned(std::strtoul(next(), nullptr, 10));
        } else if (std::strcmp(argv[i], "--resolution") == 0) {
            resolution = std::atoi(next());
        } else if (std::strcmp(argv[i], "--shrink-voxels") == 0) {
            shrink_voxels = float(std::atof(next()));
        } else if (std::strcmp(argv[i], "--world") == 0) {
            world = next();
        } else if (std::strcmp(argv[i], "--bake") == 0) {
            bake = next();
        } else {
            std::fprintf(stderr,
                         "usage: %s [--repeats R] [--frames F] | --world W.glb --bake B.h5 [--frames F] "
                         "[--objects M] [--occluders K] [--seed S] [--resolution R] [--shrink-voxels V]\n",
                         argv[0]);
            return 2;
        }
    }
    try {
        nlohmann::json out;
        if (!world.empty() || !bake.empty()) {
            if (world.empty() || bake.empty()) {
                std::fprintf(stderr, "bench_runtime_cull: --world and --bake go together\n");
                return 2;
            }
            out["ground_truth"] = pvs::ground_truth(world, bake, frames_given ? frames : 240, objects,
                                                    size_t(occluders), seed, shrink_voxels, resolution);
        } else {
            out["synthetic"] = pvs::synthetic(repeats, frames);
        }
        std::cout << out.dump(2) << std::endl;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_runtime_cull: %s\n", e.what());
        return 1;
    }
    return 0;
}
