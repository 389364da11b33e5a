// SPDX-License-Identifier: MIT
// pvsbake loader (internal): voxel masks as bricks (mask_bricks.h).
#include "mask_bricks.h"

#include <algorithm>

namespace pvsbake::detail {

void make_bricks(const std::vector<uint8_t>& bits, const int32_t dims[3], std::vector<uint32_t>& index,
                 std::vector<uint8_t>& bytes) {
    const uint64_t dx = uint64_t(dims[0]), dy = uint64_t(dims[1]), dz = uint64_t(dims[2]);
    const uint64_t bdx = bricks_along(dims[0]), bdy = bricks_along(dims[1]), bdz = bricks_along(dims[2]);
    index.assign(size_t(bdx * bdy * bdz), kBrickEmpty);
    bytes.clear();
    uint8_t brick[kBrickBytes];
    size_t at = 0;
    for (uint64_t bz = 0; bz < bdz; ++bz) {
        for (uint64_t by = 0; by < bdy; ++by) {
            for (uint64_t bx = 0; bx < bdx; ++bx, ++at) {
                const uint64_t x0 = bx * 8;
                const uint32_t width = uint32_t(std::min<uint64_t>(8, dx - x0));
                const uint8_t valid = uint8_t((1u << width) - 1);
                bool any = false, full = true;
                for (uint64_t zz = 0; zz < 8; ++zz) {
                    for (uint64_t yy = 0; yy < 8; ++yy) {
                        const uint64_t y = by * 8 + yy, z = bz * 8 + zz;
                        uint8_t v = 0;
                        if (y < dy && z < dz) {
                            const uint64_t i = x0 + dx * (y + dy * z);
                            const size_t byte = size_t(i >> 3);
                            const unsigned shift = unsigned(i & 7);
                            unsigned w = bits[byte] >> shift;
                            if (shift != 0 && byte + 1 < bits.size())
                                w |= unsigned(bits[byte + 1]) << (8 - shift);
                            v = uint8_t(w) & valid;
                            full = full && v == valid;
                        }
                        any = any || v != 0;
                        brick[zz * 8 + yy] = v;
                    }
                }
                if (!any) continue;
                if (full) {
                    index[at] = kBrickFull;
                    continue;
                }
                index[at] = kFirstBrick + uint32_t(bytes.size() / kBrickBytes);
                bytes.insert(bytes.end(), brick, brick + kBrickBytes);
            }
        }
    }
}

}  // namespace pvsbake::detail
