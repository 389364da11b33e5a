// SPDX-License-Identifier: MIT
// bench_frame: what a game draws per frame against what the eye really sees, through the shipped C99 runtime
// (runtime/pvsr.h) as a game calls it.
//
//   bench_frame WORLD.glb LEVEL.pvsr [--frames F] [--check-frames C] [--rays R] [--occluders K]
//                                    [--resolution N] [--seed S] [--bake BAKE.h5] [--split M]
//                                    [--eye-occluders E] [--eye-panels 0|1] [--eye-select
//                                    solid-angle|first-hit]
//                                    [--parts 0|1] [--eye-polygons P] [--horizon N]
//                                    [--horizon-cell-eyes K]
//                                    [--horizon-exact-polygons 0|1|2] [--horizon-list-cells B]
//                                    [--horizon-record FILE] [--horizon-min-uses U]
//                                    [--horizon-lists file|bench]
//
// Frames: F (default 200) eyes, each uniform in the eye space of a cell drawn at random (seed S, default 1):
// a cell uniform among the level's cells, then a point uniform in its box kept when pvsr_in_eye_space() holds
// and pvsr_find_cell() gives that cell (up to 256 draws, else another cell). Per frame, with one thread:
// the cell's PVS (pvsr_visible_objects), then pvsr_culler_begin_cell() with the cell's best K (default all)
// ranked occluders on a culler of N (default 32) pixels a cube face and pvsr_drawn_objects(): the objects the
// game draws. Truth: for every listed object, up to R (default 4096) rays from the frame's eye at random
// points of the object (bench/aimed_rays.h: Embree against the world's opaque triangles, nothing of the
// bake decides); the object is visible from the eye when one reaches. A WRONG CULL is a culled object a ray
// reaches that also crosses no triangle when checked in double (segment_blocked_exactly); a culled object
// only float rays reach (a sight line Embree lets through within a few float steps of an edge that closes
// it) is counted in `wrong_culls_float_artifacts` instead, and both are listed in `wrong_cull_examples`.
// Then C (default 0) more frames whose culled objects alone are traced, for the wrong-cull count.
// Figures: the shares of the level's triangles (mean over frames) in the PVS, drawn, and visible;
// drawn / visible and PVS / visible (ratios of the sums); the share of the PVS's triangles culled, and of
// the PVS's invisible triangles culled (what the run-time level could take); the cost per frame (median
// and 90th percentile of begin_cell + drawn walk, and of the plain walk alone, microseconds, one thread);
// wrong culls in all frames. Deterministic for a seed; the rays run on every thread. Prints JSON on stdout,
// progress on stderr. Exit status 2 on bad input (the message names the file or option).
//
// Measurement only (what other run-time occluders would give; not what a game gets from the file):
// --eye-polygons P (with --bake): the culler also takes, per frame, the P polygon occluders of the bake with
// the largest solid angle from the eye (after the cell's own, up to PVSR_CULLER_MAX_POLYGONS in all);
// --eye-occluders E (with --bake, the level's bake file): the culler takes, per frame, the E proven boxes of
// the bake with the largest solid angle from the eye instead of the cell's ranked ones (--eye-panels 1: the
// world's panels, occluders/panels.h, among them; the culler takes them as panels; --eye-select first-hit:
// ranked instead by how many of 32 segments from the eye to random points of each listed object they are
// the first of them to meet, an oracle of what blocks this eye's sight); --parts 1: an object
// is also culled when the culler hides each of its M (--split, default 8) part boxes (cut as the bake cuts
// them, core/object_parts.h): a finer test of the object. Both make the
// bench walk the PVS itself (the timing is then not the runtime's). --horizon N (with --bake): after the
// culler, the runtime's occlusion horizon (pvsr_horizon) of N columns a side frame around the eye, built from
// every proven box of the bake and every panel and slanted panel of the world, culls what it hides of the
// drawn objects (with --parts 1, also an object all of whose part boxes it hides); its time per frame is
// `horizon_us_median`, apart from the frame's. --horizon-cell-eyes K: the horizon takes only the occluders
// whose pieces proved some cull (pvsr_horizon_hidden_by, every occluder given, tagged) from K other eyes of
// the frame's cell, drawn there as the frame's is, `horizon_used_mean` of them: what a list of occluders per
// cell would hold (--horizon-min-uses U: only those used in U proofs or more; --horizon-list-cells B: those K
// eyes drawn in the block of B x B x B grid positions holding the cell instead, the frame's PVS tried from
// each: a list per block). --horizon-exact-polygons 1: the slanted panels go to the horizon as found, only
// rounded to floats (no float margin); 2: as tiles (pvsr_horizon_add_tile, occluders/slanted_panels.h's
// runtime_tiles); 0: in the culler's polygon form. --horizon-lists file: the horizon takes the cell's list of
// the runtime file (pvsr_horizon_begin_cell, as a game does; no --bake needed), `horizon_used_mean` occluders
// a frame, and the frame is the game's: the cell's culler and horizon set up and the walk culled by both
// (pvsr_drawn_objects_horizon, with the file's object parts), all of it in `horizon_us_median`, and its parts
// in `horizon_build_us_median` (pvsr_horizon_begin_cell), `culler_setup_us_median` (pvsr_culler_begin_cell)
// and `drawn_walk_us_median` (the culled walk); bench (the
// default): the occluders above. --horizon-record FILE: each frame's eye, the occluders
// given to the horizon and the bounds it tests, written for bench_horizon to replay (format there).
// Where the drawn but invisible triangles go (the "waste" object, of the full frames' drawn objects no ray
// reached): split_culls: the culler hides each of the object's M part boxes; given_boxes: each of
// kOracleRays segments from the eye to random points of the object meets one of the frame's occluder boxes
// (what they hide, exactly, that the culler misses); all_proven_boxes (with --bake): ... meets one of every
// proven box of the bake; all_proven_boxes_and_panels: ... or one of the world's panels (occluders/panels.h,
// exact covered rectangles of the opaque surface); all_proven_boxes_panels_and_slanted_panels: ... or one of
// the slanted panels the bake finds (occluders/slanted_panels.h), more than 1 cm before the point;
// no_box_set: neither box set. Boxes sharing volume with the object's bounds are left out (an object's own
// solid cannot cull its bounds).
#include "bench/aimed_rays.h"
#include "bench/bench_util.h"
#include "core/context.h"
#include "core/error.h"
#include "core/object_parts.h"
#include "core/random.h"
#include "io/bake_file.h"
#include "io/gltf_loader.h"
#include "occluders/panels.h"
#include "occluders/ranking.h"
#include "occluders/slanted_panels.h"
#include "rays/ray_scene.h"
#include "rays/surface_points.h"
#include "runtime/pvsr.h"

#include <omp.h>
#include <pmmintrin.h>
#include <xmmintrin.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

using pvs::bench::median;
using pvs::bench::seconds_since;

// Does the segment from e to kSegmentEnd of the way to x cross an opaque triangle of the world, in double
// (Moller-Trumbore on the float vertices, a relative tolerance of 1e-12)? The slow reference that tells a
// wrong cull from a float artifact of the ray tracer: a sight line that Embree lets through within a few
// float rounding steps of an edge that closes it.
bool segment_blocked_exactly(const pvs::World& world, glm::dvec3 e, glm::dvec3 x) {
    const glm::dvec3 d = (x - e) * double(pvs::bench::kSegmentEnd);
    for (size_t t = 0; t < world.triangles.size(); ++t) {
        if (!world.triangle_opaque[t]) continue;
        const glm::dvec3 a(world.positions[world.triangles[t].v[0]]),
            b(world.positions[world.triangles[t].v[1]]), c(world.positions[world.triangles[t].v[2]]);
        const glm::dvec3 e1 = b - a, e2 = c - a, pv = glm::cross(d, e2);
        const double det = glm::dot(e1, pv);
        if (std::abs(det) < 1e-300) continue;
        const glm::dvec3 tv = e - a;
        const double u = glm::dot(tv, pv) / det;
        if (u < 1e-12 || u > 1.0 - 1e-12) continue;
        const glm::dvec3 qv = glm::cross(tv, e1);
        const double v = glm::dot(d, qv) / det;
        if (v < 1e-12 || u + v > 1.0 - 1e-12) continue;
        const double s = glm::dot(e2, qv) / det;
        if (s > 1e-12 && s < 1.0 - 1e-12) return true;
    }
    return false;
}

constexpr uint32_t kEyeDraws = 256;  // draws of a point in a cell's box before another cell is drawn
constexpr uint32_t kOracleRays = 64;  // segments per object for the waste classes

// Boxes as an Embree scene of their faces: does a segment meet one of them (those sharing volume with a given
// box left out: an object's own solid cannot cull the object by its bounds)?
class BoxScene {
public:
    explicit BoxScene(const std::vector<pvs::Aabb>& boxes) : boxes_(boxes) {
        device_ = rtcNewDevice(nullptr);
        scene_ = rtcNewScene(device_);
        rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
        RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        const size_t n = std::max<size_t>(1, boxes.size());
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                              RTC_FORMAT_FLOAT3, 3 * sizeof(float), 8 * n));
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 12 * n));
        static const unsigned kFaces[12][3] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5},
                                               {0, 4, 5}, {0, 5, 1}, {2, 3, 7}, {2, 7, 6},
                                               {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
        for (size_t b = 0; b < n; ++b) {
            const pvs::Aabb box =
                b < boxes.size() ? boxes[b] : pvs::Aabb::of(glm::vec3(1e30f), glm::vec3(1e30f));
            for (int c = 0; c < 8; ++c) {
                v[24 * b + 3 * c + 0] = c & 4 ? box.max.x : box.min.x;
                v[24 * b + 3 * c + 1] = c & 2 ? box.max.y : box.min.y;
                v[24 * b + 3 * c + 2] = c & 1 ? box.max.z : box.min.z;
            }
            for (int f = 0; f < 12; ++f)
                for (int c = 0; c < 3; ++c) idx[36 * b + 3 * f + c] = unsigned(8 * b + kFaces[f][c]);
        }
        rtcSetGeometryOccludedFilterFunction(geom, skip_excluded);
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene_, geom);
        rtcReleaseGeometry(geom);
        rtcCommitScene(scene_);
    }
    ~BoxScene() {
        rtcReleaseScene(scene_);
        rtcReleaseDevice(device_);
    }
    BoxScene(const BoxScene&) = delete;
    BoxScene& operator=(const BoxScene&) = delete;

    // Whether every segment eye -> points[i] meets a box that does not meet `excluded`.
    // Whether the segment eye -> p meets a box that does not meet `excluded`.
    bool blocked(glm::vec3 eye, glm::vec3 p, const pvs::Aabb& excluded) const {
        return all_blocked(eye, std::vector<glm::vec3>{p}, excluded);
    }

    bool all_blocked(glm::vec3 eye, const std::vector<glm::vec3>& points, const pvs::Aabb& excluded) const {
        ExcludeContext c;
        c.boxes = &boxes_;
        c.excluded = excluded;
        for (const glm::vec3& p : points) {
            RTCRay r{};
            r.org_x = eye.x;
            r.org_y = eye.y;
            r.org_z = eye.z;
            const glm::vec3 d = p - eye;
            r.dir_x = d.x;
            r.dir_y = d.y;
            r.dir_z = d.z;
            r.tnear = 0.0f;
            r.tfar = pvs::bench::kSegmentEnd;
            r.mask = 0xffffffffu;
            rtcInitIntersectContext(&c.rtc);
            rtcOccluded1(scene_, &c.rtc, &r);
            if (r.tfar >= 0.0f) return false;
        }
        return true;
    }

    // The box the segment eye -> p meets first, or -1.
    int64_t first_hit(glm::vec3 eye, glm::vec3 p) const {
        RTCRayHit rh{};
        rh.ray.org_x = eye.x;
        rh.ray.org_y = eye.y;
        rh.ray.org_z = eye.z;
        const glm::vec3 d = p - eye;
        rh.ray.dir_x = d.x;
        rh.ray.dir_y = d.y;
        rh.ray.dir_z = d.z;
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = pvs::bench::kSegmentEnd;
        rh.ray.mask = 0xffffffffu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        ExcludeContext c;
        c.boxes = &boxes_;
        c.excluded = pvs::Aabb::empty();
        rtcInitIntersectContext(&c.rtc);
        rtcIntersect1(scene_, &c.rtc, &rh);
        return rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? -1 : int64_t(rh.hit.primID / 12);
    }

private:
    struct ExcludeContext {
        RTCIntersectContext rtc;  // first: Embree hands the filter this pointer
        const std::vector<pvs::Aabb>* boxes = nullptr;
        pvs::Aabb excluded;
    };
    static void skip_excluded(const RTCFilterFunctionNArguments* args) {
        const auto* c = reinterpret_cast<const ExcludeContext*>(args->context);
        for (unsigned i = 0; i < args->N; ++i) {
            if (args->valid[i] != -1) continue;
            const unsigned box = RTCHitN_primID(args->hit, args->N, i) / 12;
            if (box >= c->boxes->size()) continue;
            const pvs::Aabb& b = (*c->boxes)[box];
            const bool shares_volume = b.min.x < c->excluded.max.x && c->excluded.min.x < b.max.x &&
                                       b.min.y < c->excluded.max.y && c->excluded.min.y < b.max.y &&
                                       b.min.z < c->excluded.max.z && c->excluded.min.z < b.max.z;
            if (shares_volume) args->valid[i] = 0;
        }
    }
    std::vector<pvs::Aabb> boxes_;
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
};

// The boxes of up to `parts` parts of the object, as the bake cuts them (core/object_parts.h).
std::vector<pvs::Aabb> part_boxes(const pvs::World& world, uint32_t object, uint32_t parts) {
    return pvs::object_part_boxes(world, object, std::max(1u, parts));
}

struct Frame {
    uint32_t cell = 0;
    glm::vec3 eye{0.0f};
    std::vector<uint32_t> listed, drawn;
    std::vector<float> boxes;  // the occluder boxes the frame began with
    double frame_us = 0.0, walk_us = 0.0, horizon_us = 0.0;
    double build_us = 0.0, setup_us = 0.0,
           drawn_walk_us = 0.0;  // the game's frame in parts (--horizon-lists file)
    uint32_t horizon_culled = 0, horizon_used = 0, horizon_pieces = 0;
    uint32_t occluders = 0;  // boxes and polygons given
    uint32_t polygons = 0;   // of them polygons (the cell's, pvsr_culler_begin_cell)
    bool full = true;  // truth for every listed object; else for the culled ones only
};

[[noreturn]] void bad_option(const std::string& message) {
    throw pvs::bad_input("bench_frame: " + message);
}

uint64_t parse_count(const char* option, const char* text, uint64_t min, uint64_t max) {
    return pvs::bench::parse_count("bench_frame", option, text, min, max);
}

double micros(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
    return std::chrono::duration<double, std::micro>(b - a).count();
}

// The 90th percentile (nearest rank); 0 when empty.
double percentile90(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(0.9 * double(v.size())))];
}

}  // namespace

int main(int argc, char** argv) {
    const char* usage =
        "usage: bench_frame WORLD.glb LEVEL.pvsr [--frames F] [--check-frames C] [--rays R] [--occluders K]\n"
        "                   [--resolution N] [--seed S] [--split M] [--bake BAKE.h5] [--eye-occluders E]\n"
        "                   [--eye-panels 0|1] [--eye-select solid-angle|first-hit] [--parts 0|1]\n"
        "                   [--eye-polygons P] [--horizon N]\n"
        "                   [--horizon-cell-eyes K]\n"
        "                   [--horizon-exact-polygons 0|1|2] [--horizon-list-cells B]\n"
        "                   [--horizon-record FILE] [--horizon-min-uses U] [--horizon-lists file|bench]\n";
    if (argc < 3 || argv[1][0] == '-' || argv[2][0] == '-') {
        std::fputs(usage, stderr);
        return 2;
    }
    const auto t_start = std::chrono::steady_clock::now();
    const std::string world_path = argv[1], level_path = argv[2];
    uint32_t n_frames = 200, n_check = 0, n_rays = 4096, max_occluders = PVSR_CULLER_MAX_OCCLUDERS,
             n_split = 8;
    uint32_t eye_occluders = 0, eye_polygons = 0, horizon_columns = 0, horizon_cell_eyes = 0,
             horizon_exact_polygons = 0, horizon_list_cells = 1, horizon_min_uses = 1;
    bool parts_drawn = false, eye_panels = false, eye_select_first_hit = false, horizon_file_lists = false;
    std::string bake_path, horizon_record;
    int resolution = 32;
    uint64_t seed = 1;
    try {
        for (int a = 3; a < argc; ++a) {
            const std::string k = argv[a];
            if (k != "--frames" && k != "--check-frames" && k != "--rays" && k != "--occluders" &&
                k != "--resolution" && k != "--seed" && k != "--split" && k != "--bake" &&
                k != "--eye-occluders" && k != "--parts" && k != "--eye-panels" && k != "--eye-select" &&
                k != "--eye-polygons" && k != "--horizon" && k != "--horizon-cell-eyes" &&
                k != "--horizon-exact-polygons" && k != "--horizon-list-cells" && k != "--horizon-record" &&
                k != "--horizon-min-uses" && k != "--horizon-lists")
                bad_option("unknown option " + k + " (run it with no arguments for the usage)");
            if (a + 1 >= argc) bad_option(k + " wants a value");
            const char* v = argv[++a];
            if (k == "--frames")
                n_frames = uint32_t(parse_count("--frames", v, 1, 10'000'000));
            else if (k == "--check-frames")
                n_check = uint32_t(parse_count("--check-frames", v, 0, 100'000'000));
            else if (k == "--rays")
                n_rays = uint32_t(parse_count("--rays", v, 1, 100'000'000));
            else if (k == "--occluders")
                max_occluders = uint32_t(parse_count("--occluders", v, 0, PVSR_CULLER_MAX_OCCLUDERS));
            else if (k == "--resolution")
                resolution = int(parse_count("--resolution", v, 0, PVSR_CULLER_MAX_RESOLUTION));
            else if (k == "--split")
                n_split = uint32_t(parse_count("--split", v, 1, pvs::kMaxObjectParts));
            else if (k == "--bake")
                bake_path = v;
            else if (k == "--horizon-record")
                horizon_record = v;
            else if (k == "--horizon-lists") {
                if (std::string(v) != "file" && std::string(v) != "bench")
                    bad_option(std::string("--horizon-lists ") + v + ": wants file or bench");
                horizon_file_lists = std::string(v) == "file";
            } else if (k == "--eye-occluders")
                eye_occluders = uint32_t(parse_count("--eye-occluders", v, 0, PVSR_CULLER_MAX_OCCLUDERS));
            else if (k == "--eye-polygons")
                eye_polygons = uint32_t(parse_count("--eye-polygons", v, 0, PVSR_CULLER_MAX_POLYGONS));
            else if (k == "--horizon")
                horizon_columns = uint32_t(parse_count("--horizon", v, 0, 65536));
            else if (k == "--horizon-min-uses")
                horizon_min_uses = uint32_t(parse_count("--horizon-min-uses", v, 1, 255));
            else if (k == "--horizon-list-cells")
                horizon_list_cells = uint32_t(parse_count("--horizon-list-cells", v, 1, 64));
            else if (k == "--horizon-exact-polygons")
                horizon_exact_polygons = uint32_t(parse_count("--horizon-exact-polygons", v, 0, 2));
            else if (k == "--horizon-cell-eyes")
                horizon_cell_eyes = uint32_t(parse_count("--horizon-cell-eyes", v, 0, 4096));
            else if (k == "--parts")
                parts_drawn = parse_count("--parts", v, 0, 1) == 1;
            else if (k == "--eye-panels")
                eye_panels = parse_count("--eye-panels", v, 0, 1) == 1;
            else if (k == "--eye-select") {
                if (std::string(v) != "solid-angle" && std::string(v) != "first-hit")
                    bad_option(std::string("--eye-select ") + v + ": wants solid-angle or first-hit");
                eye_select_first_hit = std::string(v) == "first-hit";
            } else
                seed = parse_count("--seed", v, 0, std::numeric_limits<uint64_t>::max());
        }
    } catch (const pvs::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }

    try {
        pvs::Context ctx(pvs::Context::Options{pvs::LogLevel::kWarning, false, stderr});
        std::fprintf(stderr, "bench_frame: loading %s and %s\n", world_path.c_str(), level_path.c_str());
        const pvs::World world = pvs::load_world(ctx, world_path);
        std::vector<uint64_t> bytes;  // 8-byte aligned, as pvsr_open wants
        size_t size = 0;
        {
            std::ifstream in(level_path, std::ios::binary);
            if (!in) throw pvs::bad_input(level_path + ": cannot read the runtime file");
            const std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
            size = s.size();
            bytes.resize((size + 7) / 8 + 1);
            std::copy(s.begin(), s.end(), reinterpret_cast<char*>(bytes.data()));
        }
        pvsr_level level;
        char message[256];
        if (pvsr_open(&level, bytes.data(), size, message, sizeof message) != PVSR_OK)
            throw pvs::bad_input(level_path + ": not a runtime file pvsr_open accepts: " + message);
        const uint32_t n_objects = pvsr_object_count(&level), n_cells = pvsr_cell_count(&level);
        bool same_objects = n_objects == world.objects.size();
        for (uint32_t o = 0; same_objects && o < n_objects; ++o)
            same_objects = pvsr_object_triangles(&level, o) == world.objects[o].triangle_count;
        if (!same_objects)
            throw pvs::bad_input(level_path + ": was not baked from " + world_path +
                                 " (its objects or their triangle counts differ)");
        if (n_cells == 0) throw pvs::bad_input(level_path + ": the level has no cells");
        const double world_triangles = double(pvsr_total_triangles(&level));

        // Frames: eyes and the game's per-frame calls, one thread.
        std::vector<float> culler_memory(pvsr_culler_memory_bytes(resolution) / sizeof(float) + 1);
        pvsr_culler culler;
        if (!pvsr_culler_init(&culler, resolution, culler_memory.data(),
                              culler_memory.size() * sizeof(float)))
            throw pvs::internal_error("bench_frame: the culler did not take its memory");
        std::vector<Frame> frames(size_t(n_frames) + n_check);
        std::vector<uint32_t> scratch(n_objects + 1);
        // Measurement only: the bake's proven boxes and the objects' part boxes.
        std::vector<pvs::Aabb> proven;
        std::vector<pvs::OccluderPolygon> polygons;
        if (!bake_path.empty()) {
            const pvs::BakeData bake = pvs::read_bake_file(bake_path);
            for (const pvs::Occluder& o : bake.occluders)
                if (o.proven) proven.push_back(o.box);
            polygons = bake.polygons;
        }
        if (eye_occluders > 0 && bake_path.empty()) bad_option("--eye-occluders wants --bake");
        if (eye_polygons > 0 && bake_path.empty()) bad_option("--eye-polygons wants --bake");
        if (horizon_columns > 0 && bake_path.empty() && !horizon_file_lists)
            bad_option("--horizon wants --bake (or --horizon-lists file)");
        if (horizon_file_lists && (horizon_columns == 0 || horizon_cell_eyes > 0 || !horizon_record.empty()))
            bad_option(
                "--horizon-lists file wants --horizon, and neither --horizon-cell-eyes nor --horizon-record");
        if (horizon_file_lists && pvsr_horizon_occluder_count(&level) == 0)
            bad_option("--horizon-lists file: " + level_path + " holds no horizon lists");
        if (!horizon_record.empty() && horizon_columns == 0) bad_option("--horizon-record wants --horizon");
        std::vector<char> record;  // --horizon-record: the bytes of bench_horizon's input
        const auto put = [&record](const void* p, size_t n) {
            record.insert(record.end(), static_cast<const char*>(p), static_cast<const char*>(p) + n);
        };
        const auto put_u32 = [&put](uint32_t x) { put(&x, 4); };
        if (!horizon_record.empty()) {
            put("PVHZ", 4);
            put_u32(2);
            put_u32(n_frames + n_check);
        }
        // --horizon: every proven box of the bake, every panel and slanted panel of the world, around the
        // eye.
        std::vector<pvs::Aabb> horizon_boxes, horizon_panels;
        std::vector<pvs::SlantedPanel> horizon_slanted;
        if (horizon_columns > 0 && !horizon_file_lists) {
            horizon_boxes = proven;
            horizon_panels = pvs::find_panels(world);
            horizon_slanted = pvs::find_slanted_panels(world, 1e-4, 0.25);
            std::fprintf(stderr, "bench_frame: horizon of %zu boxes, %zu panels, %zu slanted panels\n",
                         horizon_boxes.size(), horizon_panels.size(), horizon_slanted.size());
        }
        std::vector<std::optional<pvs::OccluderPolygon>> horizon_polygons;
        for (const pvs::SlantedPanel& sp : horizon_slanted) {
            if (horizon_exact_polygons == 2) {  // tiles: the panels whole (occluders/slanted_panels.h)
                const std::vector<pvs::OccluderPolygon> q = pvs::runtime_tiles({sp}, 0.0);
                horizon_polygons.push_back(q.empty() ? std::nullopt : std::optional(q.front()));
                continue;
            }
            if (horizon_exact_polygons) {  // as found, only rounded to floats: what polygons that tile give
                pvs::OccluderPolygon q;
                q.normal = glm::vec3(sp.normal);
                q.offset = float(sp.offset);
                q.thickness = float(sp.thickness);
                for (const glm::dvec3& c : sp.corners) q.corners.push_back(glm::vec3(c));
                horizon_polygons.push_back(q.corners.size() <= PVSR_HORIZON_MAX_CORNERS ? std::optional(q)
                                                                                        : std::nullopt);
                continue;
            }
            std::vector<pvs::OccluderPolygon> q = pvs::runtime_polygons({sp}, 0.0);
            horizon_polygons.push_back(q.empty() ? std::nullopt : std::optional(q.front()));
        }
        constexpr size_t kHorizonPieces = size_t(1) << 20;
        const int runtime_columns = int(std::max<uint32_t>(horizon_columns, 1));
        std::vector<uint64_t> horizon_memory(
            horizon_columns > 0 ? pvsr_horizon_memory_bytes(runtime_columns, kHorizonPieces) / 8 + 1 : 1);
        pvsr_horizon runtime_horizon, select_horizon;  // the frame's; the one that chooses the lists
        std::vector<uint64_t> select_memory(horizon_cell_eyes > 0 ? horizon_memory.size() : 1);
        if (horizon_columns > 0 &&
            (!pvsr_horizon_init(&runtime_horizon, runtime_columns, kHorizonPieces, horizon_memory.data(),
                                horizon_memory.size() * 8) ||
             (horizon_cell_eyes > 0 && !pvsr_horizon_init(&select_horizon, runtime_columns, kHorizonPieces,
                                                          select_memory.data(), select_memory.size() * 8))))
            throw pvs::internal_error("bench_frame: the horizon did not take its memory");
        // Every occluder the horizon takes (only those `only` marks, when given), with its source index
        // (boxes, then panels, then polygons): box(source, float[6]), polygon(source, plane[5], polygon).
        const auto visit_occluders = [&](const std::vector<uint8_t>* only, const auto& box,
                                         const auto& polygon) {
            uint32_t source = 0;
            for (const std::vector<pvs::Aabb>* set : {&horizon_boxes, &horizon_panels})
                for (const pvs::Aabb& b : *set) {
                    if (!only || (*only)[source]) {
                        const float fb[6] = {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z};
                        box(source, fb);
                    }
                    ++source;
                }
            for (const std::optional<pvs::OccluderPolygon>& q : horizon_polygons) {
                if (q && (!only || (*only)[source])) {
                    const float plane[5] = {q->normal.x, q->normal.y, q->normal.z, q->offset, q->thickness};
                    polygon(source, plane, *q);
                }
                ++source;
            }
        };
        // A frame of a horizon at the eye, each occluder tagged with its source index.
        const auto build_horizon = [&](pvsr_horizon* hz, const float eye[3],
                                       const std::vector<uint8_t>* only) {
            pvsr_horizon_begin(hz, eye);
            visit_occluders(
                only,
                [&](uint32_t source, const float fb[6]) {
                    pvsr_horizon_set_tag(hz, source);
                    pvsr_horizon_add_box(hz, fb);
                },
                [&](uint32_t source, const float plane[5], const pvs::OccluderPolygon& q) {
                    pvsr_horizon_set_tag(hz, source);
                    (q.tile ? pvsr_horizon_add_tile : pvsr_horizon_add_polygon)(hz, plane, &q.corners[0].x,
                                                                                uint32_t(q.corners.size()));
                });
            pvsr_horizon_end(hz);
        };
        // --eye-polygons: up to P of the bake's polygons with the largest solid angle from the eye (area
        // times the cosine over the squared distance, at the centre), added to the cell's occluders.
        const auto add_eye_polygons = [&](const glm::vec3& eye) {
            std::vector<std::pair<double, uint32_t>> by_angle;
            for (uint32_t i = 0; i < polygons.size(); ++i) {
                const pvs::OccluderPolygon& p = polygons[i];
                glm::dvec3 c(0.0), area(0.0);
                for (size_t k = 0; k < p.corners.size(); ++k) {
                    c += glm::dvec3(p.corners[k]);
                    area += glm::cross(glm::dvec3(p.corners[k]),
                                       glm::dvec3(p.corners[(k + 1) % p.corners.size()]));
                }
                c /= double(p.corners.size());
                const glm::dvec3 d = c - glm::dvec3(eye);
                const double len = glm::length(d);
                if (len > 0.0)
                    by_angle.push_back({-std::abs(glm::dot(0.5 * area, d)) / (len * len * len), i});
            }
            const size_t k = std::min<size_t>(eye_polygons, by_angle.size());
            std::partial_sort(by_angle.begin(), by_angle.begin() + long(k), by_angle.end());
            for (size_t r = 0; r < k; ++r) {
                const pvs::OccluderPolygon& p = polygons[by_angle[r].second];
                const float plane[5] = {p.normal.x, p.normal.y, p.normal.z, p.offset, p.thickness};
                pvsr_culler_add_polygon(&culler, plane, &p.corners[0].x, uint32_t(p.corners.size()));
            }
        };
        const size_t proven_boxes = proven.size();
        if (eye_panels) {
            const std::vector<pvs::Aabb> panels = pvs::find_panels(world);
            proven.insert(proven.end(), panels.begin(), panels.end());
        }
        const std::vector<double> cum_area = pvs::cumulative_areas(world);
        std::unique_ptr<BoxScene> blocking_scene;
        if (eye_select_first_hit) blocking_scene = std::make_unique<BoxScene>(proven);
        std::vector<std::vector<pvs::Aabb>> parts(n_objects);
        if (parts_drawn)
            for (uint32_t o = 0; o < n_objects; ++o) parts[o] = part_boxes(world, o, n_split);
        pvs::Rng rng(seed, 0x4652414d45ULL);
        uint64_t cell_draws = 0;
        for (size_t i = 0; i < frames.size(); ++i) {
            Frame& f = frames[i];
            f.full = i < n_frames;
            for (bool found = false; !found;) {
                if (++cell_draws > 1000 * (uint64_t(frames.size()) + 1000))
                    throw pvs::bad_input(level_path + ": too few cells have eye space to draw eyes in");
                f.cell = rng.below(n_cells);
                float box[6];
                pvsr_cell_bounds(&level, f.cell, box);
                for (uint32_t d = 0; d < kEyeDraws && !found; ++d) {
                    const glm::vec3 p(box[0] + rng.uniform() * (box[3] - box[0]),
                                      box[1] + rng.uniform() * (box[4] - box[1]),
                                      box[2] + rng.uniform() * (box[5] - box[2]));
                    if (pvsr_in_eye_space(&level, p.x, p.y, p.z) &&
                        pvsr_find_cell(&level, p.x, p.y, p.z) == int32_t(f.cell)) {
                        f.eye = p;
                        found = true;
                    }
                }
            }
            const float eye[3] = {f.eye.x, f.eye.y, f.eye.z};
            const auto t0 = std::chrono::steady_clock::now();
            const uint32_t listed = pvsr_visible_objects(&level, f.cell, scratch.data(), scratch.size());
            const auto t1 = std::chrono::steady_clock::now();
            f.listed.assign(scratch.begin(), scratch.begin() + listed);
            if (eye_occluders == 0 && !parts_drawn) {  // the game's calls
                f.occluders = pvsr_culler_begin_cell(&culler, &level, f.cell, eye, max_occluders);
                const size_t cell_polygons = culler.polygon_count;
                if (eye_polygons > 0) add_eye_polygons(f.eye);
                f.occluders += uint32_t(culler.polygon_count - cell_polygons);
                const uint32_t drawn =
                    pvsr_drawn_objects(&level, f.cell, &culler, scratch.data(), scratch.size());
                const auto t2 = std::chrono::steady_clock::now();
                f.walk_us = micros(t0, t1);
                f.frame_us = micros(t1, t2);
                f.polygons = uint32_t(culler.polygon_count);
                f.boxes.resize(6 * size_t(f.occluders - f.polygons));
                pvsr_occluder_boxes(&level, f.cell, f.boxes.data(), f.occluders - f.polygons);
                f.drawn.assign(scratch.begin(), scratch.begin() + drawn);
            } else {  // measurement only: the eye's own best proven boxes, objects by their parts
                std::vector<std::pair<double, uint32_t>> ranked;
                if (blocking_scene &&
                    eye_occluders > 0) {  // by the segments to listed objects they stop first
                    std::vector<double> hits(proven.size(), 0.0);
                    pvs::Rng point_rng(seed ^ 0x424c4f434bULL, i);
                    for (const uint32_t o : f.listed) {
                        const pvs::WorldObject& obj = world.objects[o];
                        if (obj.triangle_count == 0 ||
                            !(cum_area[obj.first_triangle + obj.triangle_count - 1] > 0.0))
                            continue;
                        for (int k = 0; k < 32; ++k) {
                            glm::vec3 q;
                            pvs::bench::random_point_on(world, cum_area, o, point_rng, q);
                            const int64_t hit = blocking_scene->first_hit(f.eye, q);
                            if (hit >= 0) hits[size_t(hit)] += 1.0;
                        }
                    }
                    for (uint32_t b = 0; b < proven.size(); ++b)
                        if (hits[b] > 0.0) ranked.push_back({-hits[b], b});
                }
                for (uint32_t b = 0; b < proven.size() && eye_occluders > 0 && !blocking_scene; ++b) {
                    const pvs::Aabb& box = proven[b];
                    if (glm::all(glm::lessThanEqual(box.min, f.eye)) &&
                        glm::all(glm::lessThanEqual(f.eye, box.max)))
                        continue;
                    ranked.push_back({-pvs::box_solid_angle_sr(box, f.eye), b});
                }
                const size_t k = std::min<size_t>(eye_occluders, ranked.size());
                std::partial_sort(ranked.begin(), ranked.begin() + long(k), ranked.end());
                for (size_t r = 0; r < k; ++r) {
                    const pvs::Aabb& box = proven[ranked[r].second];
                    f.boxes.insert(f.boxes.end(),
                                   {box.min.x, box.min.y, box.min.z, box.max.x, box.max.y, box.max.z});
                }
                f.occluders = uint32_t(k);
                if (eye_occluders == 0) {
                    f.boxes.resize(6 * size_t(PVSR_CULLER_MAX_OCCLUDERS));
                    f.occluders = pvsr_occluder_boxes(&level, f.cell, f.boxes.data(), max_occluders);
                    f.boxes.resize(6 * size_t(f.occluders));
                }
                const auto t2 = std::chrono::steady_clock::now();
                pvsr_culler_begin_frame(&culler, eye, f.boxes.data(), f.occluders);
                for (const uint32_t o : f.listed) {
                    float box[6];
                    pvsr_object_bounds(&level, o, box);
                    bool hidden = (pvsr_object_flags(&level, o) & PVSR_OBJECT_ALWAYS_VISIBLE) == 0 &&
                                  pvsr_culler_is_hidden(&culler, box);
                    if (!hidden && parts_drawn &&
                        (pvsr_object_flags(&level, o) & PVSR_OBJECT_ALWAYS_VISIBLE) == 0) {
                        hidden = !parts[o].empty();
                        for (const pvs::Aabb& b : parts[o]) {
                            const float pb[6] = {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z};
                            if (!pvsr_culler_is_hidden(&culler, pb)) {
                                hidden = false;
                                break;
                            }
                        }
                    }
                    if (!hidden) f.drawn.push_back(o);
                }
                const auto t3 = std::chrono::steady_clock::now();
                f.walk_us = micros(t0, t1);
                f.frame_us = micros(t2, t3);
            }
        }

        if (horizon_columns > 0)  // measurement only: the horizon culls what the culler drew
            for (Frame& f : frames) {
                const uint32_t cell_eyes = horizon_cell_eyes;
                std::vector<uint8_t> used;
                if (cell_eyes > 0) {  // only the occluders that the horizons of other eyes of the cell used
                    used.assign(horizon_boxes.size() + horizon_panels.size() + horizon_slanted.size(), 0);
                    pvs::Rng erng(seed ^ 0x43454c4cULL, uint64_t(&f - frames.data()));
                    float box[6];
                    pvsr_cell_bounds(&level, f.cell, box);
                    if (horizon_list_cells > 1) {  // the block of B x B x B grid positions holding the cell
                        const float edge = level.cell_size_m * float(horizon_list_cells);
                        for (int a = 0; a < 3; ++a) {
                            const float c = 0.5f * (box[a] + box[3 + a]);
                            const float lo = level.origin[a] + edge * std::floor((c - level.origin[a]) / edge);
                            box[a] = lo;
                            box[3 + a] = lo + edge;
                        }
                    }
                    uint32_t got = 0;
                    for (uint32_t d = 0; d < 4096 && got < cell_eyes; ++d) {
                        const glm::vec3 p(box[0] + erng.uniform() * (box[3] - box[0]),
                                          box[1] + erng.uniform() * (box[4] - box[1]),
                                          box[2] + erng.uniform() * (box[5] - box[2]));
                        if (!pvsr_in_eye_space(&level, p.x, p.y, p.z) ||
                            (horizon_list_cells <= 1 && pvsr_find_cell(&level, p.x, p.y, p.z) != int32_t(f.cell)))
                            continue;
                        ++got;
                        const float pe[3] = {p.x, p.y, p.z};
                        build_horizon(&select_horizon, pe, nullptr);
                        const pvsr_horizon_use_fn count = [](void* user, uint32_t tag) {
                            uint8_t& u = (*static_cast<std::vector<uint8_t>*>(user))[tag];
                            u = uint8_t(std::min(255, u + 1));
                        };
                        for (const uint32_t o : f.listed) {
                            float b[6];
                            pvsr_object_bounds(&level, o, b);
                            if (!pvsr_horizon_hidden_by(&select_horizon, b, count, &used) && parts_drawn)
                                for (const pvs::Aabb& part : parts[o]) {
                                    const float pb[6] = {part.min.x, part.min.y, part.min.z,
                                                         part.max.x, part.max.y, part.max.z};
                                    pvsr_horizon_hidden_by(&select_horizon, pb, count, &used);
                                }
                        }
                    }
                    for (uint8_t& u : used) u = u >= horizon_min_uses ? 1 : 0;  // --horizon-min-uses
                    f.horizon_used = uint32_t(std::count(used.begin(), used.end(), uint8_t(1)));
                }
                const std::vector<uint8_t>* only = cell_eyes > 0 ? &used : nullptr;
                const float eye[3] = {f.eye.x, f.eye.y, f.eye.z};
                if (!horizon_record.empty()) {  // the same inputs in the same order as build_horizon's
                    std::vector<float> boxes;
                    std::vector<const pvs::OccluderPolygon*> polys;
                    visit_occluders(
                        only, [&](uint32_t, const float fb[6]) { boxes.insert(boxes.end(), fb, fb + 6); },
                        [&](uint32_t, const float*, const pvs::OccluderPolygon& q) { polys.push_back(&q); });
                    put(eye, sizeof eye);
                    put_u32(uint32_t(boxes.size() / 6));
                    put(boxes.data(), boxes.size() * sizeof(float));
                    put_u32(uint32_t(polys.size()));
                    for (const pvs::OccluderPolygon* q : polys) {
                        const float plane[5] = {q->normal.x, q->normal.y, q->normal.z, q->offset,
                                                q->thickness};
                        put(plane, sizeof plane);
                        put_u32(q->tile ? 1u : 0u);
                        put_u32(uint32_t(q->corners.size()));
                        put(&q->corners[0].x, q->corners.size() * sizeof(glm::vec3));
                    }
                    uint32_t tested = 0;
                    for (const uint32_t o : f.drawn)
                        tested += (pvsr_object_flags(&level, o) & PVSR_OBJECT_ALWAYS_VISIBLE) == 0;
                    put_u32(tested);
                    for (const uint32_t o : f.drawn) {
                        if (pvsr_object_flags(&level, o) & PVSR_OBJECT_ALWAYS_VISIBLE) continue;
                        float b[6];
                        pvsr_object_bounds(&level, o, b);
                        put(b, sizeof b);
                    }
                }
                const auto h0 = std::chrono::steady_clock::now();
                if (horizon_file_lists && eye_occluders == 0 && !parts_drawn) {
                    // The game's frame: the cell's culler and its horizon list from the file, then the walk
                    // culled by both (bounds, then the file's object parts)
                    const size_t before = f.drawn.size();
                    f.horizon_used = pvsr_horizon_begin_cell(&runtime_horizon, &level, f.cell, eye);
                    const auto h1 = std::chrono::steady_clock::now();
                    if (max_occluders > 0)
                        pvsr_culler_begin_cell(&culler, &level, f.cell, eye, max_occluders);
                    const auto h2 = std::chrono::steady_clock::now();
                    const uint32_t drawn =
                        pvsr_drawn_objects_horizon(&level, f.cell, max_occluders > 0 ? &culler : nullptr,
                                                   &runtime_horizon, scratch.data(), scratch.size());
                    const auto h3 = std::chrono::steady_clock::now();
                    f.horizon_us = micros(h0, h3);
                    f.build_us = micros(h0, h1);
                    f.setup_us = micros(h1, h2);
                    f.drawn_walk_us = micros(h2, h3);
                    f.horizon_pieces = uint32_t(runtime_horizon.count);
                    f.drawn.assign(scratch.begin(), scratch.begin() + drawn);
                    f.horizon_culled = uint32_t(before - std::min(before, f.drawn.size()));
                    continue;
                }
                if (horizon_file_lists)  // the cell's list from the file, as a game builds its frame
                    f.horizon_used = pvsr_horizon_begin_cell(&runtime_horizon, &level, f.cell, eye);
                else
                    build_horizon(&runtime_horizon, eye, only);
                f.horizon_pieces = uint32_t(runtime_horizon.count);
                std::vector<uint32_t> kept;
                for (const uint32_t o : f.drawn) {
                    float b[6];
                    pvsr_object_bounds(&level, o, b);
                    bool hidden = (pvsr_object_flags(&level, o) & PVSR_OBJECT_ALWAYS_VISIBLE) == 0 &&
                                  pvsr_horizon_is_hidden(&runtime_horizon, b);
                    if (!hidden && parts_drawn && !parts[o].empty() &&
                        (pvsr_object_flags(&level, o) & PVSR_OBJECT_ALWAYS_VISIBLE) == 0)
                        hidden = std::all_of(parts[o].begin(), parts[o].end(), [&](const pvs::Aabb& part) {
                            const float pb[6] = {part.min.x, part.min.y, part.min.z,
                                                 part.max.x, part.max.y, part.max.z};
                            return pvsr_horizon_is_hidden(&runtime_horizon, pb) != 0;
                        });
                    if (hidden)
                        ++f.horizon_culled;
                    else
                        kept.push_back(o);
                }
                f.drawn = std::move(kept);
                f.horizon_us = micros(h0, std::chrono::steady_clock::now());
            }

        if (!horizon_record.empty()) {
            std::ofstream out(horizon_record, std::ios::binary);
            out.write(record.data(), std::streamsize(record.size()));
            if (!out) throw pvs::bad_input(horizon_record + ": cannot write the horizon record");
        }

        // Truth: rays from each frame's eye at its listed objects (the culled ones only in check frames).
        struct Pair {
            uint32_t frame, object;
            bool drawn;
        };
        std::vector<Pair> pairs;
        for (uint32_t i = 0; i < frames.size(); ++i) {
            const Frame& f = frames[i];
            size_t d = 0;
            for (const uint32_t o : f.listed) {
                while (d < f.drawn.size() && f.drawn[d] < o) ++d;
                const bool drawn = d < f.drawn.size() && f.drawn[d] == o;
                const pvs::WorldObject& obj = world.objects[o];
                if (obj.triangle_count == 0 || !(cum_area[obj.first_triangle + obj.triangle_count - 1] > 0.0))
                    continue;  // nothing to see
                if (f.full || !drawn) pairs.push_back({i, o, drawn});
            }
        }
        const auto t_build = std::chrono::steady_clock::now();
        const pvs::bench::OpaqueScene scene(world);
        const double build_seconds = seconds_since(t_build);
        std::vector<uint8_t> visible(pairs.size(), 0);
        uint64_t rays_traced = 0;
        std::fprintf(stderr,
                     "bench_frame: %zu frames, %zu (frame, object) pairs to trace, up to %u rays each\n",
                     frames.size(), pairs.size(), n_rays);
        const auto t_rays = std::chrono::steady_clock::now();
        ctx.progress_begin("aimed rays", pairs.size(), "pairs");
#pragma omp parallel reduction(+ : rays_traced)
        {
            const unsigned csr = _mm_getcsr();  // denormals flushed while tracing, as Embree advises
            _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
            _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
            pvs::bench::AimScratch aim_scratch;
#pragma omp for schedule(dynamic, 16)
            for (int64_t p = 0; p < int64_t(pairs.size()); ++p) {
                const Pair& pair = pairs[size_t(p)];
                pvs::Rng pair_rng(pvs::mix64(seed ^ 0x4652414d45524159ULL),
                                  (uint64_t(pair.frame) << 32) | pair.object);
                const pvs::bench::Aim aim =
                    pvs::bench::aim_at_object(scene, world, cum_area, pair.object, &frames[pair.frame].eye, 1,
                                              0, n_rays, pair_rng, aim_scratch);
                visible[size_t(p)] = aim.first_reaching >= 0;
                rays_traced += aim.rays;
                ctx.progress_advance();
            }
            _mm_setcsr(csr);
        }
        ctx.progress_end();
        const double ray_seconds = seconds_since(t_rays);

        // Where the drawn but invisible triangles go (measurement only).
        const auto t_waste = std::chrono::steady_clock::now();
        std::unique_ptr<BoxScene> all_boxes, with_panels;
        std::unique_ptr<pvs::RayScene> slanted_scene;  // the slanted panels (as the bake finds them), opaque
        pvs::World slanted_world;
        if (!bake_path.empty()) {
            for (const pvs::SlantedPanel& sp : pvs::find_slanted_panels(world, 1e-4, 0.25)) {
                pvs::WorldObject o;
                o.name = "slanted" + std::to_string(slanted_world.objects.size());
                o.first_triangle = uint32_t(slanted_world.triangles.size());
                o.flags = pvs::kObjectHasOpaque;
                const uint32_t base = uint32_t(slanted_world.positions.size());
                for (const glm::dvec3& c : sp.corners) {
                    slanted_world.positions.push_back(glm::vec3(c));
                    o.bounds.extend(glm::vec3(c));
                }
                for (uint32_t k = 1; k + 1 < sp.corners.size(); ++k)
                    slanted_world.triangles.push_back(pvs::Triangle{{base, base + k, base + k + 1}});
                o.triangle_count = uint32_t(slanted_world.triangles.size()) - o.first_triangle;
                slanted_world.bounds.extend(o.bounds);
                slanted_world.objects.push_back(o);
            }
            slanted_world.triangle_opaque.assign(slanted_world.triangles.size(), 1);
            slanted_world.triangle_double_sided.assign(slanted_world.triangles.size(), 1);
            if (!slanted_world.triangles.empty())
                slanted_scene =
                    std::make_unique<pvs::RayScene>(ctx, slanted_world, pvs::BuildQuality::kMedium);
            all_boxes = std::make_unique<BoxScene>(
                std::vector<pvs::Aabb>(proven.begin(), proven.begin() + long(proven_boxes)));
            std::vector<pvs::Aabb> both(proven.begin(), proven.begin() + long(proven_boxes));
            const std::vector<pvs::Aabb> panels = pvs::find_panels(world);
            both.insert(both.end(), panels.begin(), panels.end());
            with_panels = std::make_unique<BoxScene>(both);
        }
        double waste_tri = 0, split_tri = 0, given_tri = 0, all_tri = 0, none_tri = 0, panels_tri = 0,
               slanted_tri = 0;
        {
            size_t p = 0;
            for (uint32_t i = 0; i < n_frames; ++i) {
                const Frame& f = frames[i];
                const float eye[3] = {f.eye.x, f.eye.y, f.eye.z};
                if (eye_occluders == 0 && !parts_drawn) {  // the cell's ranked boxes and polygons
                    pvsr_culler_begin_cell(&culler, &level, f.cell, eye, max_occluders);
                    if (eye_polygons > 0) add_eye_polygons(f.eye);
                } else
                    pvsr_culler_begin_frame(&culler, eye, f.boxes.data(), f.occluders);
                std::vector<pvs::Aabb> given;
                for (uint32_t k = 0; k < f.occluders - f.polygons; ++k)
                    given.push_back(
                        pvs::Aabb::of({f.boxes[6 * k], f.boxes[6 * k + 1], f.boxes[6 * k + 2]},
                                      {f.boxes[6 * k + 3], f.boxes[6 * k + 4], f.boxes[6 * k + 5]}));
                const BoxScene given_scene(given);
                for (; p < pairs.size() && pairs[p].frame == i; ++p) {
                    if (!pairs[p].drawn || visible[p]) continue;
                    const uint32_t o = pairs[p].object;
                    const double t = double(world.objects[o].triangle_count);
                    waste_tri += t;
                    bool split_hidden = true;
                    for (const pvs::Aabb& b : part_boxes(world, o, n_split)) {
                        const float box[6] = {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z};
                        if (!pvsr_culler_is_hidden(&culler, box)) {
                            split_hidden = false;
                            break;
                        }
                    }
                    split_tri += split_hidden ? t : 0.0;
                    pvs::Rng point_rng(pvs::mix64(seed ^ 0x4f5241434c45ULL), (uint64_t(i) << 32) | o);
                    std::vector<glm::vec3> points(kOracleRays);
                    for (glm::vec3& q : points) pvs::bench::random_point_on(world, cum_area, o, point_rng, q);
                    const bool by_given = given_scene.all_blocked(f.eye, points, world.objects[o].bounds);
                    const bool by_all =
                        all_boxes && all_boxes->all_blocked(f.eye, points, world.objects[o].bounds);
                    given_tri += by_given ? t : 0.0;
                    panels_tri +=
                        with_panels && with_panels->all_blocked(f.eye, points, world.objects[o].bounds) ? t
                                                                                                        : 0.0;
                    all_tri += by_all ? t : 0.0;
                    if (with_panels) {  // each segment: a box or panel, else a slanted panel over 1 cm before
                        std::vector<glm::vec3> from, dirs;
                        std::vector<float> ends;
                        bool open = false;
                        for (const glm::vec3& q : points) {
                            if (with_panels->blocked(f.eye, q, world.objects[o].bounds)) continue;
                            const float len = glm::length(q - f.eye);
                            if (!slanted_scene || !(len > 0.02f)) {
                                open = true;
                                break;
                            }
                            from.push_back(f.eye);
                            dirs.push_back((q - f.eye) / len);
                            ends.push_back(len - 0.01f);
                        }
                        if (!open && !from.empty()) {
                            std::vector<uint8_t> hit(from.size());
                            slanted_scene->occluded_opaque(from.data(), dirs.data(), ends.data(),
                                                           uint32_t(from.size()), hit.data());
                            open = std::find(hit.begin(), hit.end(), uint8_t(0)) != hit.end();
                        }
                        slanted_tri += open ? 0.0 : t;
                    }
                    none_tri += !by_given && !by_all ? t : 0.0;
                }
            }
        }
        const double waste_seconds = seconds_since(t_waste);

        // Figures.
        double pvs_tri = 0, drawn_tri = 0, visible_tri = 0, invisible_tri = 0, culled_invisible_tri = 0;
        uint64_t listed_objects = 0, drawn_objects = 0, visible_objects = 0, wrong_culls = 0,
                 culled_objects = 0, float_artifacts = 0;
        uint64_t occluders_given = 0, polygons_given = 0;
        std::vector<double> frame_us, walk_us, horizon_us, build_us, setup_us, drawn_walk_us;
        double horizon_culled = 0.0, horizon_used_sum = 0.0, horizon_pieces_sum = 0.0;
        nlohmann::ordered_json wrong = nlohmann::ordered_json::array();
        for (size_t p = 0; p < pairs.size(); ++p) {
            const Pair& pair = pairs[p];
            const Frame& f = frames[pair.frame];
            if (!pair.drawn && visible[p]) {
                // Again with the same points, each ray Embree lets through checked in double: a wrong cull
                // stands when one of them crosses no triangle (float_artifact otherwise).
                pvs::Rng pair_rng(pvs::mix64(seed ^ 0x4652414d45524159ULL),
                                  (uint64_t(pair.frame) << 32) | pair.object);
                bool open = false;
                uint32_t embree_open = 0;
                for (uint32_t k = 0; k < n_rays && !open; ++k) {
                    glm::vec3 point;
                    const uint32_t tri =
                        pvs::bench::random_point_on(world, cum_area, pair.object, pair_rng, point);
                    if (point == f.eye) {  // a point at the eye is reached, as aim_at_object says
                        open = true;
                        break;
                    }
                    RTCRay r = pvs::bench::segment_ray(f.eye, point - f.eye, pvs::bench::kSegmentEnd, 0);
                    uint32_t target = scene.prim_of(tri);
                    scene.occluded(&r, &target, 1);
                    if (!(r.tfar >= 0.0f)) continue;
                    ++embree_open;
                    open = !segment_blocked_exactly(world, glm::dvec3(f.eye), glm::dvec3(point));
                }
                (open ? wrong_culls : float_artifacts) += 1;
                if (wrong.size() < 20)
                    wrong.push_back({{"frame", pair.frame},
                                     {"cell", f.cell},
                                     {"eye", {f.eye.x, f.eye.y, f.eye.z}},
                                     {"object", pair.object},
                                     {"name", world.objects[pair.object].name},
                                     {"rays_through_in_float", embree_open},
                                     {"open_in_double", open}});
            }
            if (!f.full) continue;
            const double t = double(world.objects[pair.object].triangle_count);
            if (visible[p]) {
                visible_tri += t;
                ++visible_objects;
            } else {
                invisible_tri += t;
                if (!pair.drawn) culled_invisible_tri += t;
            }
        }
        for (const Frame& f : frames) {
            culled_objects += f.listed.size() - f.drawn.size();
            if (!f.full) continue;
            frame_us.push_back(f.frame_us);
            walk_us.push_back(f.walk_us);
            horizon_us.push_back(f.horizon_us);
            build_us.push_back(f.build_us);
            setup_us.push_back(f.setup_us);
            drawn_walk_us.push_back(f.drawn_walk_us);
            horizon_culled += f.horizon_culled;
            horizon_used_sum += f.horizon_used;
            horizon_pieces_sum += f.horizon_pieces;
            listed_objects += f.listed.size();
            drawn_objects += f.drawn.size();
            occluders_given += f.occluders;
            polygons_given += f.polygons;
            for (const uint32_t o : f.listed) pvs_tri += double(world.objects[o].triangle_count);
            for (const uint32_t o : f.drawn) drawn_tri += double(world.objects[o].triangle_count);
        }
        auto ratio = [](double a, double b) { return b > 0.0 ? a / b : 0.0; };
        const double frames_d = double(n_frames);
        nlohmann::ordered_json out;
        out["bench"] = "frame";
        out["world"] = world_path;
        out["level"] = level_path;
        out["pvs_kind"] = pvsr_mode_label(&level);
        out["cells_kind"] = pvsr_cell_kind(&level) == 1 ? "octree" : "grid";
        out["level_bytes"] = size;
        out["cells"] = n_cells;
        out["objects"] = n_objects;
        out["world_triangles"] = world_triangles;
        out["seed"] = seed;
        out["frames"] = n_frames;
        out["check_frames"] = n_check;
        out["rays_per_object"] = n_rays;
        out["max_occluders"] = max_occluders;
        out["culler_resolution"] = resolution;
        out["threads"] = omp_get_max_threads();
        out["occluders_given_mean"] = ratio(double(occluders_given), frames_d);
        out["polygons_given_mean"] = ratio(double(polygons_given), frames_d);
        out["pvs_triangle_share_mean"] = pvs_tri / frames_d / world_triangles;
        out["drawn_triangle_share_mean"] = drawn_tri / frames_d / world_triangles;
        out["visible_triangle_share_mean"] = visible_tri / frames_d / world_triangles;
        out["drawn_over_visible_triangles"] = ratio(drawn_tri, visible_tri);
        out["pvs_over_visible_triangles"] = ratio(pvs_tri, visible_tri);
        out["culled_share_of_pvs_triangles"] = ratio(pvs_tri - drawn_tri, pvs_tri);
        out["culled_share_of_invisible_pvs_triangles"] = ratio(culled_invisible_tri, invisible_tri);
        out["pvs_objects_mean"] = double(listed_objects) / frames_d;
        out["drawn_objects_mean"] = double(drawn_objects) / frames_d;
        out["visible_objects_mean"] = double(visible_objects) / frames_d;
        out["frame_us_median"] = median(frame_us);
        out["frame_us_p90"] = percentile90(frame_us);
        out["walk_us_median"] = median(walk_us);
        if (horizon_columns > 0) {
            out["horizon_columns"] = horizon_columns;
            out["horizon_cell_eyes"] = horizon_cell_eyes;
            out["horizon_lists"] = horizon_file_lists ? "file" : "bench";
            out["horizon_us_median"] = median(horizon_us);
            if (horizon_file_lists && eye_occluders == 0 && !parts_drawn) {  // the game's frame, in parts
                out["horizon_build_us_median"] = median(build_us);
                out["culler_setup_us_median"] = median(setup_us);
                out["drawn_walk_us_median"] = median(drawn_walk_us);
            }
            out["horizon_culled_objects_mean"] = horizon_culled / double(frame_us.size());
            out["horizon_used_mean"] = horizon_used_sum / double(frame_us.size());
            out["horizon_pieces_mean"] = horizon_pieces_sum / double(frame_us.size());
        }
        out["culled_objects_all_frames"] = culled_objects;
        out["wrong_culls"] = wrong_culls;
        out["wrong_culls_float_artifacts"] = float_artifacts;
        out["wrong_cull_examples"] = wrong;
        nlohmann::ordered_json waste;
        waste["drawn_invisible_triangle_share_mean"] = waste_tri / frames_d / world_triangles;
        waste["split_parts"] = n_split;
        waste["split_culls_share"] = ratio(split_tri, waste_tri);
        waste["given_boxes_hide_share"] = ratio(given_tri, waste_tri);
        waste["all_proven_boxes_hide_share"] =
            all_boxes ? nlohmann::ordered_json(ratio(all_tri, waste_tri)) : nullptr;
        waste["all_proven_boxes_and_panels_hide_share"] =
            with_panels ? nlohmann::ordered_json(ratio(panels_tri, waste_tri)) : nullptr;
        waste["all_proven_boxes_panels_and_slanted_panels_hide_share"] =
            with_panels ? nlohmann::ordered_json(ratio(slanted_tri, waste_tri)) : nullptr;
        waste["no_box_set_hides_share"] = ratio(none_tri, waste_tri);
        waste["segments_per_object"] = kOracleRays;
        out["waste"] = waste;
        out["rays_traced"] = rays_traced;
        out["cell_draws"] = cell_draws;
        out["seconds"] = {{"scene_build", build_seconds},
                          {"rays", ray_seconds},
                          {"waste", waste_seconds},
                          {"total", seconds_since(t_start)}};
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
