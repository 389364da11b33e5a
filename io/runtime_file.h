// SPDX-License-Identifier: MIT
// pvsbake io: the runtime file (.pvsr), what a game ships: cells, masks, PVS rows, objects and ranked
// occluders of a bake, flat, little-endian, checksummed, every section 64-byte aligned (docs/FORMAT.md,
// "The runtime file"), read in place by the C99 runtime runtime/pvsr.h. The HDF5 bake file stays the
// product of `pvsbake bake` and the input of every tool; this is exported from it.
#pragma once

#include "core/object_parts.h"
#include "core/world.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace pvs {

struct RuntimeFileFigures {
    uint64_t file_bytes = 0;
    std::vector<std::pair<std::string, uint64_t>> sections;  // tag, bytes (padding to 64 included)
};

struct RuntimeFileOptions {
    bool occluder_measures = false;  // also each ranked occluder's score, solid angle and hidden shares
    // Rows XORed to decode one PVS row, 1 (every row whole) to PVSR_MAX_CHAIN: longer chains code rows
    // against more similar ones (smaller) and cost more to walk. Past PVSR_STACK_OBJECTS objects, at most 2.
    uint32_t max_chain = 16;
    // 1: every cell keeps its row. K > 1 (a grid bake): each cell lists what its block of K x K x K cells
    // lists (the union of their rows): fewer distinct rows, a larger PVS, still conservative.
    uint32_t merge_cells = 1;
    // On a grid whose cells are its grid boxes, the rows in block order (io/runtime_file.cpp) before they are
    // coded: fewer key rows. False: the bake's order (measurement).
    bool block_order = true;
};

// Each part box rounded outward to the grid of its object's bounds on which the runtime file stores it
// (file 5.1, pvsr_part_encode; docs/FORMAT.md, "The grid of an object's parts"): the bake holds these, so
// that the bake file and the runtime file give every reader the same boxes. A part that is not a finite box
// inside its object's bounds drops the object's parts (they keep their promise only whole).
void round_parts_to_runtime_grid(const World& world, ObjectParts& parts);

// The runtime file of the bake file at bake_path, as bytes. Throws pvs::Error (bad input) naming the file
// and what is wrong when the bake cannot be read or does not fit the runtime format (over 2^27 objects).
std::string runtime_file_bytes(const std::string& bake_path, const RuntimeFileOptions& options = {},
                               RuntimeFileFigures* figures = nullptr);

// Writes it to out_path, whole or not at all (io/atomic_file.h).
RuntimeFileFigures export_runtime_file(const std::string& bake_path, const std::string& out_path,
                                       const RuntimeFileOptions& options = {});

}  // namespace pvs
