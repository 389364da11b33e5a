// SPDX-License-Identifier: MIT
// The C99 runtime compiled as C++17 (a game may build it in a C++ target): built with warnings as errors,
// never linked (its symbols are pvsbake_runtime's).
#include "pvsr.c"
