// SPDX-License-Identifier: MIT
// pvsbake viewer: pvsview, the VTK viewer of bakes (the world, cells coloured by PVS size, a picked cell's
// PVS and figures, occluders, verification misses, the leak path, the view volume), interactive or
// headless (--screenshot). VTK stays inside the .cpp files.
//
// Conventions: glTF axes (right-handed, +Y up), metres. Exit status as pvsbake's: 0 success, 2 bad input
// (file, option, a bake of another world), 1 anything else.
#pragma once

#include <cstdio>

namespace pvs::viewer {

// The whole command line of pvsview (`pvsview --help` lists it).
int run_pvsview(int argc, char** argv, std::FILE* err);

}  // namespace pvs::viewer
