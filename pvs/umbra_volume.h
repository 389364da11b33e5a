// SPDX-License-Identifier: MIT
// pvsbake solver: the space hidden from a whole eye region, grown front to back, where space already
// proven hidden joins the occluders (after G. Schaufler, J. Dorsey, X. Decoret, F. Sillion, "Conservative
// Volumetric Visibility with Occluder Fusion", SIGGRAPH 2000). A first pass of the conservative solver
// (pvs/conservative.h), beside the single-occluder pass: what it proves for a cell's region, no face tests.
//
// Contract: UmbraHider::hide() sets an object's bit only if every segment from an eye of `region` (the
// region holds them all: cells/eyes.h, eye_region) to a point of the object's triangles meets an opaque
// triangle before its end. It keeps, per region, a set of HIDDEN blocks (cubes of block_voxels voxels of the
// proven solid's grid, and aligned groups of them): a block is marked only when one blocker hides it whole
// from the region, exactly (the 64 corner segments in double, as pvs/region_hiding.h). A blocker is a panel,
// a slanted panel, or a box of voxels each in the proven solid or in a hidden block, grown from a box of
// the solid through both; its blocks hidden earlier are as good as the solid, so occluders fuse through the
// space behind them. An object is hidden when every block its triangles touch is. The argument, by
// induction over the marks: docs/ALGORITHMS.md#umbra-volume.
#pragma once

#include "core/context.h"
#include "core/occluder.h"
#include "core/world.h"

#include <cstdint>
#include <vector>

namespace pvs {

struct UmbraFigures {
    uint64_t regions = 0;       // hide() calls with a region
    uint64_t blockers = 0;      // blockers cast
    uint64_t node_tests = 0;    // exact tests of a node of blocks against a blocker
    uint64_t nodes_hidden = 0;  // nodes marked hidden
    uint64_t hidden = 0;        // objects it proved hidden
    double seconds = 0.0;       // thread seconds in hide()

    UmbraFigures& operator+=(const UmbraFigures& o) {
        regions += o.regions;
        blockers += o.blockers;
        node_tests += o.node_tests;
        nodes_hidden += o.nodes_hidden;
        hidden += o.hidden;
        seconds += o.seconds;
        return *this;
    }
};

class UmbraHider {
public:
    // The proven solid, panels, slanted panels and floor-epsilon boxes of `set`, and the blocks each
    // object's triangles touch. `block_voxels`: the edge of a block, in voxels of the solid's grid (>= 1).
    UmbraHider(Context& ctx, const World& world, const ShrunkOccluders& set, int block_voxels = 4);

    // Sets the bit in `hidden` (a row of one bit per object) of every object of `objects` whose triangles
    // lie in space hidden from every eye of `region`; returns how many it set. Objects with empty bounds,
    // bounds meeting the region, or a bit already set are skipped. Thread-safe.
    uint32_t hide(const World& world, const Aabb& region, const std::vector<uint32_t>& objects,
                  uint64_t* hidden, UmbraFigures* figures = nullptr) const;

    // For tests: the blocks hidden from `region` (one flag per block, x fastest) and the block grid.
    std::vector<uint8_t> hidden_blocks(const Aabb& region) const;
    glm::ivec3 block_dims() const { return bdims_; }
    // The closed box of block b (coordinates), clipped to the solid's grid, in double.
    void block_box(glm::ivec3 b, glm::dvec3& lo, glm::dvec3& hi) const;

private:
    struct Seed {
        int kind = 0;   // 0: a box of the solid (voxels [vlo, vhi)), 1: a panel, 2: a slanted panel
        int index = 0;  // into panels_ / slanted
        int axis = -1;  // a panel's flat axis
        glm::ivec3 vlo{0}, vhi{0};
        glm::dvec3 lo{0.0}, hi{0.0};  // bounds
    };
    struct Scratch;
    void run(const Aabb& region, Scratch& s, UmbraFigures& f) const;
    bool block_hidden(const Scratch& s, glm::ivec3 b) const;
    size_t flag_index(int level, glm::ivec3 n) const;
    void mark(Scratch& s, int level, glm::ivec3 n) const;
    bool range_hidden(Scratch& s, glm::ivec3 b0, glm::ivec3 b1) const;
    bool voxel_blocked(const Scratch& s, glm::ivec3 v) const;
    void grow(const Scratch& s, glm::ivec3& lo, glm::ivec3& hi, int axis, int side,
              bool through_hidden) const;

    const ShrunkOccluders& set_;
    glm::dvec3 origin_{0.0};
    double h_ = 0.0;
    glm::ivec3 vdims_{0};
    int b_ = 4;
    glm::ivec3 bdims_{0};
    std::vector<glm::ivec3> ldims_;  // per level of the block pyramid (0: blocks)
    std::vector<size_t> loffset_;    // first flag of each level
    size_t flags_ = 0;
    std::vector<Seed> seeds_;
    std::vector<Aabb> panels_;
    std::vector<uint64_t> relevant_;  // per node of the pyramid: holds an object's or a solid rim's block
    std::vector<uint32_t> object_offset_;  // objects + 1
    std::vector<uint32_t> object_blocks_;  // block indices each object's triangles touch, ascending
};

}  // namespace pvs
