// SPDX-License-Identifier: MIT
// Rays aimed from an eye at points of an object, against the world's opaque triangles, for the benches that
// measure what is really visible (bench_truth, bench_frame): Embree and the world's triangles alone, nothing
// of the solver (pvs/) decides. A point is reached when no opaque triangle, other than the one the point
// lies on, meets the segment from the eye to kSegmentEnd of the way to it (see-through triangles never
// block; docs/ALGORITHMS.md#words).
#pragma once

#include "core/error.h"
#include "core/random.h"
#include "core/world.h"
#include "rays/surface_points.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace pvs::bench {

constexpr float kSegmentEnd = 1.0f - 1e-5f;  // the segment stops this far along to its point
constexpr uint32_t kNoTarget = UINT32_MAX;

// The world's OPAQUE triangles as an Embree scene (see-through ones never block, so they are left out).
// An occlusion query skips the one triangle its ray aims at (its primID in the context's target[ray.id]).
class OpaqueScene {
public:
    explicit OpaqueScene(const World& world) : prim_of_triangle_(world.triangles.size(), kNoTarget) {
        device_ = rtcNewDevice(nullptr);
        if (!device_) throw internal_error("aimed rays: cannot create an Embree device");
        scene_ = rtcNewScene(device_);
        rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
        size_t count = 0;
        for (size_t t = 0; t < world.triangles.size(); ++t) count += world.triangle_opaque[t] != 0;
        RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH);
        auto* verts =
            static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), std::max<size_t>(1, 3 * count)));
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), count));
        uint32_t k = 0;
        for (size_t t = 0; t < world.triangles.size(); ++t) {
            if (!world.triangle_opaque[t]) continue;
            for (int c = 0; c < 3; ++c) {
                const glm::vec3 p = world.positions[world.triangles[t].v[c]];
                verts[9 * size_t(k) + 3 * c + 0] = p.x;
                verts[9 * size_t(k) + 3 * c + 1] = p.y;
                verts[9 * size_t(k) + 3 * c + 2] = p.z;
                idx[3 * size_t(k) + c] = unsigned(3 * k + c);
            }
            prim_of_triangle_[t] = k++;
        }
        rtcSetGeometryOccludedFilterFunction(geom, skip_target);
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene_, geom);
        rtcReleaseGeometry(geom);
        rtcCommitScene(scene_);
        if (rtcGetDeviceError(device_) != RTC_ERROR_NONE)
            throw internal_error("aimed rays: the Embree scene build failed");
    }
    ~OpaqueScene() {
        rtcReleaseScene(scene_);
        rtcReleaseDevice(device_);
    }
    OpaqueScene(const OpaqueScene&) = delete;
    OpaqueScene& operator=(const OpaqueScene&) = delete;

    // The primID of world triangle t, or kNoTarget when it is see-through (not in the scene).
    uint32_t prim_of(uint32_t t) const { return prim_of_triangle_[t]; }

    // rays[i] (ids 0..n-1) aims at primID target[i]: sets tfar < 0 on the rays some OTHER opaque triangle
    // blocks. Thread-safe.
    void occluded(RTCRay* rays, const uint32_t* target, uint32_t n) const {
        AimContext c;
        rtcInitIntersectContext(&c.rtc);
        c.target = target;
        rtcOccluded1M(scene_, &c.rtc, rays, n, sizeof(RTCRay));
    }

private:
    struct AimContext {
        RTCIntersectContext rtc;  // first: Embree hands the filter this pointer
        const uint32_t* target = nullptr;
    };
    static void skip_target(const RTCFilterFunctionNArguments* args) {
        const auto* c = reinterpret_cast<const AimContext*>(args->context);
        for (unsigned i = 0; i < args->N; ++i) {
            if (args->valid[i] != -1) continue;
            if (RTCHitN_primID(args->hit, args->N, i) == c->target[RTCRayN_id(args->ray, args->N, i)])
                args->valid[i] = 0;  // the aimed-at triangle itself: not a blocker
        }
    }

    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
    std::vector<uint32_t> prim_of_triangle_;
};

// A triangle of `object` picked by area and a uniform point in it, in double (rays/surface_points.h).
using pvs::random_point_on;

// Reused buffers of aim_at_object (one per thread).
// The ray from `eye` along `d` (unnormalized: t in [0, 1] spans the segment) up to t = tfar, with id `id`,
// for OpaqueScene::occluded().
inline RTCRay segment_ray(glm::vec3 eye, glm::vec3 d, float tfar, uint32_t id) {
    RTCRay r{};
    r.org_x = eye.x;
    r.org_y = eye.y;
    r.org_z = eye.z;
    r.dir_x = d.x;
    r.dir_y = d.y;
    r.dir_z = d.z;
    r.tnear = 0.0f;
    r.tfar = tfar;
    r.time = 0.0f;
    r.mask = 0xffffffffu;
    r.id = id;
    r.flags = 0;
    return r;
}

struct AimScratch {
    static constexpr uint32_t kFirstBatch = 32, kMaxBatch = 2048;  // rays per Embree stream, doubling
    std::vector<RTCRay> rays = std::vector<RTCRay>(kMaxBatch);
    std::vector<uint32_t> target = std::vector<uint32_t>(kMaxBatch);
};

struct Aim {
    int64_t first_reaching = -1;  // the index of the first ray that reached its point, or -1
    uint32_t rays = 0;            // rays traced
};

// Up to n_rays rays at random points of `object` (random_point_on, from rng), ray k from
// eyes[(first_eye + k) % eye_count], in batches that double, stopping at the first batch where one reaches.
// A point at its eye is reached (nothing lies between). Thread-safe with a scratch per thread.
inline Aim aim_at_object(const OpaqueScene& scene, const World& world, const std::vector<double>& cum_area,
                         uint32_t object, const glm::vec3* eyes, size_t eye_count, uint32_t first_eye,
                         uint32_t n_rays, Rng& rng, AimScratch& scratch) {
    Aim aim;
    uint32_t batch = AimScratch::kFirstBatch;
    while (aim.rays < n_rays && aim.first_reaching < 0) {
        const uint32_t done = aim.rays, n = std::min(batch, n_rays - done);
        int64_t at_eye = -1;
        for (uint32_t k = 0; k < n; ++k) {
            const glm::vec3 eye = eyes[(first_eye + uint64_t(done) + k) % eye_count];
            glm::vec3 point;
            const uint32_t t = random_point_on(world, cum_area, object, rng, point);
            const glm::vec3 d = point - eye;
            if (at_eye < 0 && d == glm::vec3(0.0f)) at_eye = done + k;
            // Unnormalized: t in [0, 1]; a point at the eye is marked by a ray that never runs.
            scratch.rays[k] = segment_ray(eye, d, d == glm::vec3(0.0f) ? -1.0f : kSegmentEnd, k);
            scratch.target[k] = scene.prim_of(t);
        }
        scene.occluded(scratch.rays.data(), scratch.target.data(), n);
        for (uint32_t k = 0; k < n && aim.first_reaching < 0; ++k)
            if (scratch.rays[k].tfar >= 0.0f) aim.first_reaching = done + k;
        if (at_eye >= 0 && (aim.first_reaching < 0 || at_eye < aim.first_reaching))
            aim.first_reaching = at_eye;
        aim.rays += n;
        batch = std::min(batch * 2, AimScratch::kMaxBatch);
    }
    return aim;
}

}  // namespace pvs::bench
