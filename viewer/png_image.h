// SPDX-License-Identifier: MIT
// pvsbake viewer: read a PNG back as plain RGB pixels (the screenshot tests look at pixels).
//
// Conventions: row 0 is the top of the image (as the picture is seen), 3 bytes per pixel.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace pvs::viewer {

struct RgbImage {
    int width = 0;
    int height = 0;
    std::vector<uint8_t> rgb;  // width * height * 3, top row first

    std::array<uint8_t, 3> at(int x, int y) const {
        const size_t i = (size_t(y) * size_t(width) + size_t(x)) * 3;
        return {rgb[i], rgb[i + 1], rgb[i + 2]};
    }
};

// Throws pvs::Error (kBadInput) naming the file when it is missing or not a PNG.
RgbImage read_png(const std::string& path);

}  // namespace pvs::viewer
