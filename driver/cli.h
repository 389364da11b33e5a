// SPDX-License-Identifier: MIT
// pvsbake driver: the command line, as a function so tests run it in-process.
//
// Subcommands: bake, verify, info, query (pvsbake --help). Exit status: 0 success; 2 bad input (a file,
// an option or a world is wrong; the message names it); 3 verification found misses (verify, or a
// conservative bake); 1 anything else. Output files are written whole or not at all.
#pragma once

#include <cstdio>
#include <ostream>

namespace pvs {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitMisses = 3;

// Results (info, query) go to `out`; logs, progress and errors to `log` (nullptr = silent).
int run_cli(int argc, const char* const* argv, std::ostream& out, std::FILE* log);

}  // namespace pvs
