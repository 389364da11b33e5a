// SPDX-License-Identifier: MIT
// tinygltf's implementation compiled into the world loader's fuzz target, so that its parser is
// instrumented (coverage, ASan, UBSan) like our code; the bake links Debian's libtinygltf instead. Images
// are never decoded by the loader (io/gltf_loader.cpp sets no image loader), so stb is left out.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

// The image callbacks the header's TinyGLTF constructor names when stb is in (as io/gltf_loader.cpp sees
// it); never called, since the loader replaces the image loader.
namespace tinygltf {
bool LoadImageData(Image*, const int, std::string* err, std::string*, int, int, const unsigned char*, int, void*) {
    if (err) *err += "images are not decoded";
    return false;
}
bool WriteImageData(const std::string*, const std::string*, const Image*, bool, std::string*, void*) {
    return false;
}
}  // namespace tinygltf
