// SPDX-License-Identifier: MIT
// pvsbake viewer: read a PNG back as plain RGB pixels, with VTK's PNG reader. See png_image.h.
#include "viewer/png_image.h"

#include "core/error.h"

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>

#include <filesystem>

namespace pvs::viewer {

RgbImage read_png(const std::string& path) {
    vtkNew<vtkPNGReader> reader;
    if (!std::filesystem::exists(path) || !reader->CanReadFile(path.c_str())) {
        throw bad_input(path + ": missing or not a PNG file");
    }
    reader->SetFileName(path.c_str());
    reader->Update();
    vtkImageData* data = reader->GetOutput();
    int dims[3];
    data->GetDimensions(dims);
    const int comps = data->GetNumberOfScalarComponents();
    if (dims[0] <= 0 || dims[1] <= 0 || comps < 3 || data->GetScalarType() != VTK_UNSIGNED_CHAR) {
        throw bad_input(path + ": not an 8-bit RGB or RGBA PNG");
    }
    RgbImage img;
    img.width = dims[0];
    img.height = dims[1];
    img.rgb.resize(size_t(img.width) * size_t(img.height) * 3);
    for (int y = 0; y < img.height; ++y) {
        for (int x = 0; x < img.width; ++x) {
            // VTK's image row 0 is the bottom.
            const auto* p = static_cast<const uint8_t*>(data->GetScalarPointer(x, img.height - 1 - y, 0));
            const size_t i = (size_t(y) * size_t(img.width) + size_t(x)) * 3;
            img.rgb[i] = p[0];
            img.rgb[i + 1] = p[1];
            img.rgb[i + 2] = p[2];
        }
    }
    return img;
}

}  // namespace pvs::viewer
