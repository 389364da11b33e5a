// SPDX-License-Identifier: MIT
// pvsview: the VTK viewer of pvsbake's bakes. See viewer/README.md and viewer/pvsview.h.
#include "viewer/pvsview.h"

int main(int argc, char** argv) {
    return pvs::viewer::run_pvsview(argc, argv, stderr);
}
