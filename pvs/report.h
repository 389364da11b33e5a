// pvsbake pvs: the JSON report of a bake (and of `pvsbake info --json`).
//
// Keys: tool, version, world, world_hash, mode, pvs_kind ("conservative" or "aggressive"), objects,
// triangles, cells, parameters{}, timings_s{}, figures{}, verification{ran, figures..., misses[]},
// warnings[]. Numbers are plain JSON numbers; misses carry the object's name.
#pragma once

#include "io/bake_file.h"

#include <string>
#include <vector>

namespace pvs {

std::string bake_report_json(const BakeData& bake, const std::vector<std::string>& warnings);

// "conservative" or "aggressive (sampled: may miss visible objects)".
std::string pvs_kind(const BakeData& bake);

}  // namespace pvs
