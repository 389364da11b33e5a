// SPDX-License-Identifier: MIT
// The world as an Embree 3 scene: two triangle geometries (opaque, see-through). See-through hits are
// recorded and rejected by an intersection filter so the ray carries on to the first opaque hit.
#include "rays/ray_scene.h"

#include "core/error.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pvs {

namespace {

constexpr unsigned kOpaqueGeom = 0;
constexpr unsigned kSeeThroughGeom = 1;
constexpr unsigned kStreamSize = 256;  // rays per rtcIntersect1M call

// The intersect context carries where the filter writes its see-through touches.
struct TraceContext {
    RTCIntersectContext rtc;
    std::vector<RayTouch>* touches;
    const uint32_t* see_through_object;  // primID -> object
    uint32_t ray_base;
    bool pass_through = true;  // false: accept see-through hits like opaque ones (trace_repeated)
};

void see_through_filter(const RTCFilterFunctionNArguments* args) {
    const auto* tc = reinterpret_cast<const TraceContext*>(args->context);
    if (!tc->pass_through) return;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        const float t = RTCRayN_tfar(args->ray, args->N, i);  // the candidate hit's distance
        const unsigned id = RTCRayN_id(args->ray, args->N, i);
        tc->touches->push_back(RayTouch{tc->ray_base + id, tc->see_through_object[prim], t, false});
        args->valid[i] = 0;  // reject: sight goes on through
    }
}

// The occlusion context: with a test, a see-through touch ends the ray when the test accepts it.
struct OccludedContext {
    RTCIntersectContext rtc;
    RayScene::TouchTest test = nullptr;
    void* user = nullptr;
    const uint32_t* see_through_object = nullptr;  // primID -> object
    uint32_t ray_base = 0;
};

// See-through triangles never block an occlusion query, unless its test accepts them.
void see_through_occluded_filter(const RTCFilterFunctionNArguments* args) {
    const auto* oc = reinterpret_cast<const OccludedContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        if (oc->test != nullptr) {
            const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
            const unsigned id = RTCRayN_id(args->ray, args->N, i);
            if (oc->test(oc->user, oc->ray_base + id, oc->see_through_object[prim])) continue;  // stop
        }
        args->valid[i] = 0;
    }
}

void embree_error(void* user, RTCError code, const char* message) {
    auto* ctx = static_cast<Context*>(user);
    ctx->error(fmt::format("Embree error {}: {}", int(code), message ? message : ""));
}

void init_ray(RTCRay& r, glm::vec3 origin, glm::vec3 direction, float tnear, float tfar, unsigned id) {
    r.org_x = origin.x;
    r.org_y = origin.y;
    r.org_z = origin.z;
    r.dir_x = direction.x;
    r.dir_y = direction.y;
    r.dir_z = direction.z;
    r.tnear = tnear;
    r.tfar = tfar;
    r.time = 0.0f;
    r.mask = 0xffffffffu;
    r.id = id;
    r.flags = 0;
}

void init_rayhit(RTCRayHit& rh, glm::vec3 origin, glm::vec3 direction, float tnear, unsigned id,
                 float tfar = std::numeric_limits<float>::infinity()) {
    init_ray(rh.ray, origin, direction, tnear, tfar, id);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

struct ScopedFtz {
    ScopedFtz() : csr_(_mm_getcsr()) {
        _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
        _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    }
    ~ScopedFtz() { _mm_setcsr(csr_); }
    unsigned csr_;
};

}  // namespace

struct RayScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<uint32_t> object_of[2];     // per geometry: primID -> object
    const float* opaque_corners = nullptr;  // the opaque geometry's vertex buffer: 9 floats per primID

    ~Impl() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }

    // Ray i starts at origins[i * origin_step] (step 0: one origin for all).
    void trace_streams(const glm::vec3* origins, uint32_t origin_step, const glm::vec3* directions,
                       uint32_t count, RTCIntersectContextFlags flags, std::vector<RayTouch>& touches,
                       const float* tfar = nullptr) const {
        ScopedFtz ftz;
        RTCRayHit rays[kStreamSize];
        for (uint32_t base = 0; base < count; base += kStreamSize) {
            const uint32_t n = std::min(kStreamSize, count - base);
            for (uint32_t i = 0; i < n; ++i)
                init_rayhit(rays[i], origins[size_t(base + i) * origin_step], directions[base + i], 0.0f, i,
                            tfar ? tfar[base + i] : std::numeric_limits<float>::infinity());
            TraceContext tc;
            rtcInitIntersectContext(&tc.rtc);
            tc.rtc.flags = flags;
            tc.touches = &touches;
            tc.see_through_object = object_of[kSeeThroughGeom].data();
            tc.ray_base = base;
            const size_t first = touches.size();
            rtcIntersect1M(scene, &tc.rtc, rays, n, sizeof(RTCRayHit));
            finish(rays, n, base, first, touches);
        }
    }

    // Keeps see-through touches before the opaque hit and adds the opaque hit itself.
    void finish(const RTCRayHit* rays, uint32_t n, uint32_t ray_base, size_t first_touch,
                std::vector<RayTouch>& touches) const {
        size_t w = first_touch;
        for (size_t r = first_touch; r < touches.size(); ++r) {
            const RayTouch& t = touches[r];
            if (t.t <= rays[t.ray - ray_base].ray.tfar) touches[w++] = t;
        }
        touches.resize(w);
        for (uint32_t i = 0; i < n; ++i) {
            if (rays[i].hit.geomID == kOpaqueGeom) {
                touches.push_back(RayTouch{ray_base + i, object_of[kOpaqueGeom][rays[i].hit.primID],
                                           rays[i].ray.tfar, true});
            }
        }
    }
};

RayScene::RayScene(Context& ctx, const World& world, BuildQuality quality, int threads)
    : impl_(std::make_unique<Impl>()) {
    ScopedTimer timer(ctx, "embree_build");
    const std::string device_config = threads > 0 ? fmt::format("threads={}", threads) : std::string();
    impl_->device = rtcNewDevice(device_config.empty() ? nullptr : device_config.c_str());
    if (!impl_->device) {
        throw internal_error(fmt::format("RayScene: cannot create an Embree device (error {})",
                                         int(rtcGetDeviceError(nullptr))));
    }
    rtcSetDeviceErrorFunction(impl_->device, embree_error, &ctx);
    impl_->scene = rtcNewScene(impl_->device);
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
    const RTCBuildQuality q = quality == BuildQuality::kLow    ? RTC_BUILD_QUALITY_LOW
                              : quality == BuildQuality::kHigh ? RTC_BUILD_QUALITY_HIGH
                                                               : RTC_BUILD_QUALITY_MEDIUM;
    rtcSetSceneBuildQuality(impl_->scene, q);

    for (unsigned g = 0; g < 2; ++g) {
        const bool want_opaque = g == kOpaqueGeom;
        std::vector<uint32_t>& owner = impl_->object_of[g];
        size_t count = 0;
        for (size_t t = 0; t < world.triangles.size(); ++t)
            count += (world.triangle_opaque[t] != 0) == want_opaque;
        RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryBuildQuality(geom, q);
        // Each geometry gets its own copy of the vertices it needs: simple, and worlds are small
        // next to memory (tens of MB for millions of triangles).
        auto* verts =
            static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), std::max<size_t>(1, 3 * count)));
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), count));
        owner.reserve(count);
        size_t k = 0;
        for (uint32_t o = 0; o < world.objects.size(); ++o) {
            const WorldObject& obj = world.objects[o];
            for (uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count; ++t) {
                if ((world.triangle_opaque[t] != 0) != want_opaque) continue;
                for (int c = 0; c < 3; ++c) {
                    const glm::vec3 p = world.positions[world.triangles[t].v[c]];
                    verts[9 * k + 3 * c + 0] = p.x;
                    verts[9 * k + 3 * c + 1] = p.y;
                    verts[9 * k + 3 * c + 2] = p.z;
                    idx[3 * k + c] = unsigned(3 * k + c);
                }
                owner.push_back(o);
                ++k;
            }
        }
        if (want_opaque) impl_->opaque_corners = verts;
        if (!want_opaque) {
            rtcSetGeometryIntersectFilterFunction(geom, see_through_filter);
            rtcSetGeometryOccludedFilterFunction(geom, see_through_occluded_filter);
        }
        rtcCommitGeometry(geom);
        const unsigned id = rtcAttachGeometry(impl_->scene, geom);
        rtcReleaseGeometry(geom);
        if (id != g) throw internal_error("RayScene: unexpected Embree geometry id");
    }
    rtcCommitScene(impl_->scene);
    const RTCError err = rtcGetDeviceError(impl_->device);
    if (err != RTC_ERROR_NONE)
        throw internal_error(fmt::format("RayScene: Embree scene build failed (error {})", int(err)));
    ctx.debug(fmt::format("embree: {} opaque and {} see-through triangles", impl_->object_of[0].size(),
                          impl_->object_of[1].size()));
}

RayScene::~RayScene() = default;

void RayScene::trace(glm::vec3 origin, const glm::vec3* directions, uint32_t count,
                     std::vector<RayTouch>& touches) const {
    impl_->trace_streams(&origin, 0, directions, count, RTC_INTERSECT_CONTEXT_FLAG_COHERENT, touches);
}

void RayScene::trace_until(glm::vec3 origin, const glm::vec3* directions, const float* tfar, uint32_t count,
                           std::vector<RayTouch>& touches) const {
    impl_->trace_streams(&origin, 0, directions, count, RTC_INTERSECT_CONTEXT_FLAG_COHERENT, touches, tfar);
}

void RayScene::trace_from(const glm::vec3* origins, const glm::vec3* directions, uint32_t count,
                          std::vector<RayTouch>& touches) const {
    impl_->trace_streams(origins, 1, directions, count, RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT, touches);
}

void RayScene::trace_reference(glm::vec3 origin, const glm::vec3* directions, uint32_t count,
                               std::vector<RayTouch>& touches) const {
    ScopedFtz ftz;
    for (uint32_t i = 0; i < count; ++i) {
        RTCRayHit rh;
        init_rayhit(rh, origin, directions[i], 0.0f, 0);
        TraceContext tc;
        rtcInitIntersectContext(&tc.rtc);
        tc.touches = &touches;
        tc.see_through_object = impl_->object_of[kSeeThroughGeom].data();
        tc.ray_base = i;
        const size_t first = touches.size();
        rtcIntersect1(impl_->scene, &tc.rtc, &rh);
        impl_->finish(&rh, 1, i, first, touches);
    }
}

void RayScene::trace_repeated(glm::vec3 origin, const glm::vec3* directions, uint32_t count,
                              std::vector<RayTouch>& touches) const {
    ScopedFtz ftz;
    for (uint32_t i = 0; i < count; ++i) {
        float tnear = 0.0f;
        for (int surfaces = 0; surfaces < 1024; ++surfaces) {
            RTCRayHit rh;
            init_rayhit(rh, origin, directions[i], tnear, 0);
            TraceContext tc;
            rtcInitIntersectContext(&tc.rtc);
            tc.touches = nullptr;
            tc.see_through_object = nullptr;
            tc.ray_base = 0;
            tc.pass_through = false;  // the filter accepts: every surface stops this query
            rtcIntersect1(impl_->scene, &tc.rtc, &rh);
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
            const bool opaque = rh.hit.geomID == kOpaqueGeom;
            touches.push_back(
                RayTouch{i, impl_->object_of[rh.hit.geomID][rh.hit.primID], rh.ray.tfar, opaque});
            if (opaque) break;
            tnear = std::nextafter(rh.ray.tfar, std::numeric_limits<float>::infinity());
        }
    }
}

void RayScene::occluded_opaque(const glm::vec3* origins, const glm::vec3* directions, const float* tfar,
                               uint32_t count, uint8_t* blocked) const {
    ScopedFtz ftz;
    RTCRay rays[kStreamSize];
    for (uint32_t base = 0; base < count; base += kStreamSize) {
        const uint32_t n = std::min(kStreamSize, count - base);
        for (uint32_t i = 0; i < n; ++i)
            init_ray(rays[i], origins[base + i], directions[base + i], 0.0f, tfar[base + i], i);
        OccludedContext oc;
        rtcInitIntersectContext(&oc.rtc);
        rtcOccluded1M(impl_->scene, &oc.rtc, rays, n, sizeof(RTCRay));
        for (uint32_t i = 0; i < n; ++i) blocked[base + i] = rays[i].tfar < 0.0f ? 1 : 0;
    }
}

void RayScene::touches_any(glm::vec3 origin, const glm::vec3* directions, const float* tfar, uint32_t count,
                           TouchTest test, void* user, uint8_t* found) const {
    ScopedFtz ftz;
    RTCRay rays[kStreamSize];
    for (uint32_t base = 0; base < count; base += kStreamSize) {
        const uint32_t n = std::min(kStreamSize, count - base);
        for (uint32_t i = 0; i < n; ++i)
            init_ray(rays[i], origin, directions[base + i], 0.0f, tfar[base + i], i);
        OccludedContext oc;
        rtcInitIntersectContext(&oc.rtc);
        oc.rtc.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        oc.test = test;
        oc.user = user;
        oc.see_through_object = impl_->object_of[kSeeThroughGeom].data();
        oc.ray_base = base;
        rtcOccluded1M(impl_->scene, &oc.rtc, rays, n, sizeof(RTCRay));
        for (uint32_t i = 0; i < n; ++i) found[base + i] = rays[i].tfar < 0.0f ? 1 : 0;
    }
}

uint64_t RayScene::occluded_baseline(glm::vec3 origin, const glm::vec3* directions, uint32_t count) const {
    ScopedFtz ftz;
    uint64_t hits = 0;
    OccludedContext oc;
    rtcInitIntersectContext(&oc.rtc);
    for (uint32_t i = 0; i < count; ++i) {
        RTCRay r;
        init_ray(r, origin, directions[i], 0.0f, std::numeric_limits<float>::infinity(), 0);
        rtcOccluded1(impl_->scene, &oc.rtc, &r);
        hits += r.tfar < 0.0f;
    }
    return hits;
}

namespace {

// Collects the opaque primitives a point query's sphere meets (by their bounds).
bool collect_opaque(RTCPointQueryFunctionArguments* args) {
    if (args->geomID == kOpaqueGeom)
        static_cast<std::vector<uint32_t>*>(args->userPtr)->push_back(args->primID);
    return false;  // the radius is not changed
}

}  // namespace

void RayScene::opaque_triangles_near(glm::vec3 p, glm::vec3 q, float radius_m,
                                     std::vector<TriangleCorners>& out) const {
    // Sample points p + k s (q - p) / |q - p| with both ends included and spacing s: every point within r of
    // the segment is within r + s / 2 of a sample point. The spacing trades queries against their size.
    const float length = glm::length(q - p);
    const float spacing = std::max({radius_m, length / 256.0f, 1e-4f});
    const int steps = std::max(1, int(std::ceil(length / spacing)));
    const float query_radius = radius_m + 0.5f * (length / float(steps)) + 1e-5f;
    std::vector<uint32_t> prims;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    for (int k = 0; k <= steps; ++k) {
        const glm::vec3 c = p + (q - p) * (float(k) / float(steps));
        RTCPointQuery query;
        query.x = c.x;
        query.y = c.y;
        query.z = c.z;
        query.time = 0.0f;
        query.radius = query_radius;
        rtcPointQuery(impl_->scene, &query, &context, collect_opaque, &prims);
    }
    std::sort(prims.begin(), prims.end());
    prims.erase(std::unique(prims.begin(), prims.end()), prims.end());
    const float* v = impl_->opaque_corners;
    for (uint32_t prim : prims) {
        const float* t = v + size_t(prim) * 9;
        out.push_back(TriangleCorners{glm::vec3(t[0], t[1], t[2]), glm::vec3(t[3], t[4], t[5]),
                                      glm::vec3(t[6], t[7], t[8]), impl_->object_of[kOpaqueGeom][prim]});
    }
}

}  // namespace pvs
