// SPDX-License-Identifier: MIT
// pvsbake: bake, verify and inspect potentially-visible sets of glTF worlds. See README.md.
#include "driver/cli.h"
#include "driver/processes.h"

#include <iostream>

int main(int argc, char** argv) {
    pvs::start_processes(argc, argv);
    const int status = pvs::run_cli(argc, argv, std::cout, stderr);
    pvs::end_processes();
    return status;
}
