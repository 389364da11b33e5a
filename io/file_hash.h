// SPDX-License-Identifier: MIT
// pvsbake io: content hash of a file (XXH3, 64 bits, as 16 hex digits), to tie a bake to its world.
#pragma once

#include <string>

namespace pvs {

// Throws pvs::Error (bad input) when the file cannot be read.
std::string hash_file_hex(const std::string& path);

}  // namespace pvs
