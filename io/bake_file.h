// SPDX-License-Identifier: MIT
// pvsbake io: the bake file (HDF5), format version 1.5. docs/FORMAT.md documents every group, dataset and
// attribute; this header is the in-memory form.
//
// Conventions: glTF axes (right-handed, +Y up), metres. Grid index order x fastest (core/cell_set.h).
// PVS rows: object i is bit (i % 8) of byte (i / 8). Identical rows are stored once; each cell points
// to its row. A bake whose mode is not conservative is labelled aggressive in the file.
// write_bake_file() writes the file whole or not at all. read_bake_file() validates everything it reads
// (sizes consistent, indices in range) and throws pvs::Error (kBadInput) naming the file and the
// dataset when something is wrong; it refuses a newer major format version.
#pragma once

#include "core/cell_set.h"
#include "core/geometry_print.h"
#include "core/math.h"
#include "core/object_parts.h"
#include "core/occluder.h"
#include "core/pvs_set.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace pvs {

constexpr int kBakeFormatMajor = 1;
constexpr int kBakeFormatMinor = 10;  // 1.1 added the PVS code (/pvs/code), 1.2 ranked occluders per cell,
                                      // 1.3 the opening width of each verification miss, 1.4 the voxel
                                      // masks as bricks, 1.5 the run's own record (/run), 1.6 the geometry
                                      // print (/reuse), 1.7 polygon occluders ranked per cell,
                                      // 1.8 the run-time horizon's occluders and lists (/horizon),
                                      // 1.9 the objects' part boxes (/objects/part_*), 1.10 the objects
                                      // each cell's frames test (/horizon/test_*)

struct ObjectRecord {
    std::string name;
    Aabb bounds;
    uint32_t triangle_count = 0;
    uint32_t flags = 0;  // core/world.h ObjectFlags
};

// A ray that saw an object the PVS of its cell does not list.
struct Miss {
    uint32_t cell = 0;
    uint32_t object = 0;
    glm::vec3 eye{0.0f};
    glm::vec3 direction{0.0f};  // unit
    float distance_m = 0.0f;    // from eye to where the ray touched the object
    // The widest sight line the verifier found to the object near this ray (docs/ALGORITHMS.md#openings),
    // metres; a width at or above the bake's gap tolerance makes the miss fail verification. -1: not
    // measured (format 1.2 and older, or beyond the misses measured).
    float opening_width_m = -1.0f;
};

// A measured miss through an opening narrower than the gap tolerance: outside the promise, it does not fail
// verification (docs/ALGORITHMS.md#miss-widths). Unmeasured misses are never narrow.
inline bool is_narrow_miss(const Miss& m, double gap_tolerance_m) {
    return m.opening_width_m >= 0.0f && double(m.opening_width_m) < gap_tolerance_m;
}

struct VerificationRecord {
    bool ran = false;
    std::vector<std::pair<std::string, double>> figures;  // rays, misses, overestimation ...
    std::vector<uint32_t> cell_sampled_visible;           // per cell: objects the rays saw (empty if not ran)
    std::vector<Miss> misses;                             // the first max_misses_reported
};

using NamedValues = std::vector<std::pair<std::string, double>>;
using NamedStrings = std::vector<std::pair<std::string, std::string>>;

// What differs between two runs of one bake (same world, same parameters): the options that cannot change
// a row (threads ...), seconds, memory, and the counts of work done in this run, which depend on the
// schedule and on what a resumed run took from its checkpoint. Everything else in the file is a function
// of the world and the parameters alone (docs/FORMAT.md, "/run").
struct RunRecord {
    NamedStrings parameters;  // the run.* options (core/config.h is_run_parameter)
    NamedValues figures;      // work done in this run: seconds, rates, memory, tests, samples
    NamedValues timings_s;    // seconds per stage
};

struct BakeData {
    int format_major = kBakeFormatMajor;
    int format_minor = kBakeFormatMinor;
    std::string tool_version;
    std::string world_path;     // as given on the command line
    std::string world_hash;     // content hash of the world file (hex)
    std::string mode;           // "sampled" or "conservative"
    bool conservative = false;  // false = aggressive: may miss visible objects
    NamedStrings parameters;    // every resolved option that can change a row (core/config.h
                                // resolved_parameters); the others are in run.parameters
    std::vector<ObjectRecord> objects;
    CellSet cells;
    PvsSet pvs;                        // cells.size() rows of objects.size() bits
    NamedValues figures;               // counts and figures of the result (the run's own: run.figures)
    std::vector<glm::vec3> leak_path;  // view volume flood: seed to outside, when the level leaks
    std::vector<Occluder> occluders;   // synthesized boxes (only proven ones may occlude)
    std::vector<OccluderPolygon> polygons;  // 1.7: the polygon occluders the ranking may name
    RankedOccluders
        ranked;  // per cell, indices into `occluders`, then `polygons` (empty: none, or a file < 1.2)
    HorizonLists horizon;  // 1.8: the run-time horizon's occluders and lists (empty: none, or a file < 1.8)
    ObjectParts object_parts;  // 1.9: the objects' part boxes (core/object_parts.h; empty: none, or < 1.9)
    VerificationRecord verification;
    GeometryPrint print;  // conservative bakes from 1.6: what a re-bake after an edit compares (/reuse)
    RunRecord run;
};

void write_bake_file(const std::string& path, const BakeData& bake);
BakeData read_bake_file(const std::string& path);

}  // namespace pvs
