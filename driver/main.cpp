// pvsbake: bake, verify and inspect potentially-visible sets of glTF worlds. See README.md.
#include "driver/cli.h"

#include <iostream>

int main(int argc, char** argv) {
    return pvs::run_cli(argc, argv, std::cout, stderr);
}
