// SPDX-License-Identifier: MIT
// pvsbake solver: objects that ONE occluder hides from a whole eye region, proven exactly: no shrinking, no
// pixels, no patches. A first pass of the conservative solver (pvs/conservative.h): what it proves for a
// cell's region, no face of the cell tests.
//
// Contract: panel_hides() and box_hides() are true only if EVERY segment from the region box to the object
// box meets the occluder (shrunk by kHideToleranceM on every side, so float rounding of the inputs cannot
// turn a grazing segment into a hit). They check exactly the 64 segments between the corners of the two
// boxes, in double: the occluder is convex, so these decide for all segments. Sight that crosses a panel
// (covered by opaque triangles) or meets a box of the proven solid (the occluders shrunk by epsilon_0) is
// stopped, so what RegionHider::hide() proves is hidden from every eye of the region (the region holds them
// all: cells/eyes.h, eye_region). The proof: docs/ALGORITHMS.md#single-occluder.
//
// Which occluders are tried: those the segment between the centres of the region and the object meets
// (every segment from region to object must meet a hider, that one too), found by tracing that segment
// through an Embree scene of the occluders. One occluder at a time: no fusion (the solver's depth cubes
// fuse); what it adds is the occluders' full size, where the solver loses their shrunk margins, panel insets
// and pixel edges.
#pragma once

#include "core/context.h"
#include "core/occluder.h"
#include "core/world.h"
#include "rays/ray_scene.h"

#include <array>
#include <memory>
#include <vector>

namespace pvs {

constexpr double kHideToleranceM = 1e-4;

// The 8 corners of the box grown by `grow` on every side, in double (corner i takes max on x for bit 1, on
// y for bit 2, on z for bit 4).
std::array<glm::dvec3, 8> box_corners(const Aabb& b, double grow = 0.0);

// Box meshes (a flat panel is a box of zero thickness) as a world to trace rays against: one object per
// box, `boxes` first, then `flat`, then each slanted panel as a fan of its corners; every triangle opaque,
// or every one see-through (a ray then reports each occluder it passes).
World box_world(const std::vector<Aabb>& boxes, const std::vector<Aabb>& flat, bool opaque = true,
                const std::vector<SlantedPanel>& slanted = {});

// Does every segment from the box `region` to the box `object` cross the flat rectangle `panel` (flat along
// `axis`, shrunk by kHideToleranceM)? Both boxes must lie strictly on opposite sides of its plane.
bool panel_hides(const Aabb& region, const Aabb& object, const Aabb& panel, int axis);

// Does every segment from the box `region` to the box `object` meet the box `box` shrunk by
// kHideToleranceM?
bool box_hides(const Aabb& region, const Aabb& object, const Aabb& box);

// Does every segment from the box `region` to the box `object` meet the triangles of the slanted panel?
// True only if the two boxes lie strictly on opposite sides of its slab (|n.x - offset| <= thickness, grown
// by kHideToleranceM) and each of the 64 corner segments crosses both faces of the slab inside the polygon
// shrunk by kHideToleranceM: then every segment's part in the slab lies over the polygon, where the
// triangles form a continuous surface across the slab (docs/ALGORITHMS.md#slanted-panels).
bool slanted_hides(const Aabb& region, const Aabb& object, const SlantedPanel& panel);

// The occluders of one set (ShrunkOccluders: its panels, and its boxes at the floor epsilon), ready to
// prove objects hidden from regions.
class RegionHider {
public:
    RegionHider(Context& ctx, const ShrunkOccluders& set);
    ~RegionHider();
    RegionHider(const RegionHider&) = delete;
    RegionHider& operator=(const RegionHider&) = delete;

    // Sets the bit in `hidden` (a row of one bit per object) of every object of `objects` that one
    // occluder hides from all of `region`; returns how many it set. Objects with empty bounds or bounds
    // meeting the region are never hidden. Thread-safe.
    uint32_t hide(const World& world, const Aabb& region, const std::vector<uint32_t>& objects,
                  uint64_t* hidden) const;
    // The same answer, slowly: every occluder each ray touches (RayScene::trace_reference), tested in turn.
    // For tests.
    uint32_t hide_reference(const World& world, const Aabb& region, const std::vector<uint32_t>& objects,
                            uint64_t* hidden) const;

private:
    // Does occluder k (boxes_, then panels_, then slanted_) hide the box `object` from all of `region`?
    bool occluder_hides(const Aabb& region, const Aabb& object, uint32_t k) const;

    std::vector<Aabb> boxes_, panels_;
    std::vector<int> panel_axis_;
    std::vector<SlantedPanel> slanted_;
    std::unique_ptr<RayScene> scene_;  // boxes_, panels_, then slanted_, every triangle see-through
};

// A RegionHider for every set of a ShrunkOccluders (the global one and each block's), built once.
class RegionHiders {
public:
    RegionHiders(Context& ctx, const ShrunkOccluders& occluders);
    // The hider of ShrunkOccluders::set(i) (i < 0: the global set).
    const RegionHider& of(int32_t i) const { return *hiders_[size_t(i + 1)]; }

private:
    std::vector<std::unique_ptr<RegionHider>> hiders_;
};

}  // namespace pvs
