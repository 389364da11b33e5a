// SPDX-License-Identifier: MIT
// pvsbake loader (internal): voxel masks as 8 x 8 x 8 bricks (docs/FORMAT.md, "Voxel masks"), the form the
// runtime loader looks masks up in and, from format 1.4, the form the file stores beside the plain bits.
//
// Brick b = bx + bdx * (by + bdy * bz), bd = ceil(dims / 8), covers voxels 8 b .. 8 b + 7 on each axis.
// index[b] is kBrickEmpty (no voxel set), kBrickFull (every voxel of the brick inside the volume set), or
// kFirstBrick + j: the brick's voxels are bytes[64 j .. 64 j + 64), voxel (x, y, z) of the brick at bit
// x of byte z * 8 + y, with the bits of voxels outside the volume zero.
#pragma once

#include <cstdint>
#include <vector>

namespace pvsbake::detail {

constexpr uint32_t kBrickEmpty = 0;
constexpr uint32_t kBrickFull = 1;
constexpr uint32_t kFirstBrick = 2;
constexpr uint32_t kBrickBytes = 64;

// Bricks along each axis for a mask of these dimensions (each >= 0).
inline uint64_t bricks_along(int32_t voxels) {
    return (uint64_t(voxels) + 7) / 8;
}

// The bricks of a mask given as bits (voxel i = x + dims[0] * (y + dims[1] * z) is bit i % 8 of byte i / 8;
// `bits` holds ceil(voxels / 8) bytes).
void make_bricks(const std::vector<uint8_t>& bits, const int32_t dims[3], std::vector<uint32_t>& index,
                 std::vector<uint8_t>& bytes);

}  // namespace pvsbake::detail
