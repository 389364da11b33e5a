// SPDX-License-Identifier: MIT
// pvsbake rays: the world as an Embree scene, for tracing sight rays (verification and sampled PVS).
//
// Conventions: glTF axes, metres. A ray from `origin` along unit `direction` sees, in order, every
// see-through triangle (BLEND, MASK, or of an object that never occludes) until it reaches the first
// opaque triangle, which it also sees and which stops it. Both sides of every triangle are hit: a
// one-sided wall still blocks sight from behind (as map compilers treat solid), which is the
// conservative choice for verification only where eyes stay in playable space (docs/ALGORITHMS.md#words).
// Embree types stay in ray_scene.cpp (pimpl). One device and one committed scene per RayScene;
// trace() may be called from many threads at once.
#pragma once

#include "core/context.h"
#include "core/world.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace pvs {

// One object touched by one ray.
struct RayTouch {
    uint32_t ray = 0;     // index of the ray in the batch passed to trace()
    uint32_t object = 0;  // World object index
    float t = 0.0f;       // distance from the origin, metres
    bool stops = false;   // an opaque triangle: the ray ends here
};

// A triangle as its three corners, and the object it belongs to.
struct TriangleCorners {
    glm::vec3 a, b, c;
    uint32_t object = 0;
};

enum class BuildQuality { kLow, kMedium, kHigh };

class RayScene {
public:
    // threads: Embree's build threads, 0 = every core.
    RayScene(Context& ctx, const World& world, BuildQuality quality = BuildQuality::kMedium, int threads = 0);
    ~RayScene();
    RayScene(const RayScene&) = delete;
    RayScene& operator=(const RayScene&) = delete;

    // Traces `count` rays from one origin (bundled as coherent streams) and appends every object each
    // ray touches to `touches` (an object may appear more than once per ray). Thread-safe.
    void trace(glm::vec3 origin, const glm::vec3* directions, uint32_t count,
               std::vector<RayTouch>& touches) const;
    // The same, ray i ending at tfar[i] (nothing beyond is touched).
    void trace_until(glm::vec3 origin, const glm::vec3* directions, const float* tfar, uint32_t count,
                     std::vector<RayTouch>& touches) const;

    // The same for rays with an origin each (origins[i] for directions[i]), traced as incoherent streams.
    void trace_from(const glm::vec3* origins, const glm::vec3* directions, uint32_t count,
                    std::vector<RayTouch>& touches) const;

    // Reference path for tests and benchmarks: the same answer, one rtcIntersect1 at a time.
    void trace_reference(glm::vec3 origin, const glm::vec3* directions, uint32_t count,
                         std::vector<RayTouch>& touches) const;

    // The alternative to the filter, for the benchmark: one rtcIntersect1 per surface, restarting past each
    // see-through hit until an opaque one (or nothing) is hit. Same answer.
    void trace_repeated(glm::vec3 origin, const glm::vec3* directions, uint32_t count,
                        std::vector<RayTouch>& touches) const;

    // Does ray i (from `origin`, t in [0, tfar[i]]) touch an opaque triangle, or a see-through triangle of an
    // object o with test(user, i, o) true? Writes 1 or 0 into found[i]. The test is called on the touches
    // in no set order (each see-through triangle touched at most once per ray, until one is accepted), so
    // found[] does not depend on it: the answer of trace_until() followed by the test on every touch.
    // Thread-safe if the test is.
    using TouchTest = bool (*)(void* user, uint32_t ray, uint32_t object);
    void touches_any(glm::vec3 origin, const glm::vec3* directions, const float* tfar, uint32_t count,
                     TouchTest test, void* user, uint8_t* found) const;

    // Is each segment origins[i] + t * directions[i], t in [0, tfar[i]], blocked by an OPAQUE triangle?
    // (See-through triangles never block.) Writes 1 (blocked) or 0 into blocked[i]. Thread-safe.
    void occluded_opaque(const glm::vec3* origins, const glm::vec3* directions, const float* tfar,
                         uint32_t count, uint8_t* blocked) const;

    // Appends to `out` every opaque triangle within `radius_m` of the segment [p, q], and maybe a few more
    // (those whose bounds come that near); none twice. Embree point queries at points spaced along the
    // segment, each with a radius that covers the capsule around its piece. Thread-safe.
    void opaque_triangles_near(glm::vec3 p, glm::vec3 q, float radius_m,
                               std::vector<TriangleCorners>& out) const;

    // Benchmark baseline: plain rtcOccluded1 per ray (is any opaque triangle hit?). Returns the
    // number of rays that hit something.
    uint64_t occluded_baseline(glm::vec3 origin, const glm::vec3* directions, uint32_t count) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace pvs
