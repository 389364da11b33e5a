// SPDX-License-Identifier: MIT
// The C API's opaque handles (pvsbake/loader_c.h, pvsbake/occlusion_c.h): what each wraps, shared by the
// two files that implement them.
#pragma once

#include <pvsbake/loader.h>
#include <pvsbake/occlusion.h>

struct pvsbake_bake {
    pvsbake::Bake bake;
};

struct pvsbake_culler {
    pvsbake::OcclusionCuller culler;
    explicit pvsbake_culler(int resolution) : culler(resolution) {}
};

struct pvsbake_horizon {
    pvsbake::Horizon horizon;
    pvsbake_horizon(int columns, size_t max_pieces) : horizon(columns, max_pieces) {}
};
