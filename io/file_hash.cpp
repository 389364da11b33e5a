// SPDX-License-Identifier: MIT
// Content hash of a file with xxHash's XXH3 (64 bits): fast enough to hash every world at every bake.
#include "io/file_hash.h"

#include "core/error.h"

#include <fmt/format.h>
#include <xxhash.h>

#include <cstdio>
#include <memory>
#include <vector>

namespace pvs {

std::string hash_file_hex(const std::string& path) {
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
    if (!f) throw bad_input(fmt::format("{}: cannot read the file to hash it", path));
    std::unique_ptr<XXH3_state_t, XXH_errorcode (*)(XXH3_state_t*)> state(XXH3_createState(),
                                                                          &XXH3_freeState);
    if (!state || XXH3_64bits_reset(state.get()) != XXH_OK)
        throw internal_error("hash_file_hex: xxHash failed");
    std::vector<char> buf(1 << 20);
    size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), f.get())) > 0)
        XXH3_64bits_update(state.get(), buf.data(), n);
    if (std::ferror(f.get())) throw bad_input(fmt::format("{}: read error while hashing", path));
    return fmt::format("{:016x}", XXH3_64bits_digest(state.get()));
}

}  // namespace pvs
