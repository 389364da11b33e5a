// SPDX-License-Identifier: MIT
// A game in C++17 over the installed runtime loader's static library (tests/test_loader_install.cpp).
// Usage: game_cxx BAKE.h5. Walks every cell's PVS with the C++ API and checks it against the C API on the
// same file; prints the line tests/install/game.c prints, so the two can be compared.
#include <pvsbake/loader.h>
#include <pvsbake/loader_c.h>

#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: game_cxx BAKE.h5\n");
        return 2;
    }
    pvsbake::Bake bake;
    if (const pvsbake::LoadResult r = bake.load(argv[1]); !r) {
        std::fprintf(stderr, "game_cxx: %s\n", r.message.c_str());
        return 1;
    }
    pvsbake_bake* handle = nullptr;
    char message[512];
    if (pvsbake_load(argv[1], &handle, message, sizeof message) != PVSBAKE_OK) {
        std::fprintf(stderr, "game_cxx: %s\n", message);
        return 1;
    }
    uint64_t visible = 0, sum = 0;
    uint32_t found = 0;
    std::vector<uint32_t> walked, listed(bake.object_count() + 1);
    for (uint32_t c = 0; c < bake.cell_count(); ++c) {
        walked.clear();
        bake.for_each_visible(c, [&](uint32_t o) { walked.push_back(o); });
        const uint32_t n = pvsbake_visible_objects(handle, c, listed.data(), listed.size());
        if (n != walked.size() || n != bake.visible_count(c)) {
            std::fprintf(stderr, "game_cxx: cell %u: the C and C++ APIs disagree on the count\n", c);
            return 1;
        }
        for (uint32_t i = 0; i < n; ++i) {
            if (listed[i] != walked[i]) {
                std::fprintf(stderr, "game_cxx: cell %u: the C and C++ APIs disagree on object %u\n", c, i);
                return 1;
            }
            sum += uint64_t(c + 1) * (walked[i] + 1);
        }
        visible += n;
        const pvsbake::Box b = bake.cell_bounds(c);
        if (bake.find_cell((b.min[0] + b.max[0]) / 2, (b.min[1] + b.max[1]) / 2, (b.min[2] + b.max[2]) / 2) ==
            int32_t(c))
            ++found;
    }
    pvsbake_free(handle);
    std::printf("cells %u objects %u visible %llu sum %llu found %u\n", bake.cell_count(),
                bake.object_count(), (unsigned long long)visible, (unsigned long long)sum, found);
    return 0;
}
