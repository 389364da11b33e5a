// SPDX-License-Identifier: MIT
#include "tests/test_util.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include <sys/wait.h>

namespace pvs::test {

TempDir::TempDir() {
    std::random_device rd;
    const auto base = std::filesystem::temp_directory_path();
    for (int attempt = 0; attempt < 100; ++attempt) {
        auto p = base / ("pvsbake-test-" + std::to_string(rd()) + std::to_string(attempt));
        if (std::filesystem::create_directory(p)) {
            path_ = p;
            return;
        }
    }
    throw std::runtime_error("cannot create a temporary folder");
}

TempDir::~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

std::string shared_world(const std::string& name) {
    const std::filesystem::path p = std::filesystem::path(PVSBAKE_SHARED_WORLDS) / name;
    return std::filesystem::exists(p) ? p.string() : std::string();
}

std::string sample_world() {
    return source_file("samples/rooms.glb");
}

std::string source_file(const std::string& relative) {
    return std::string(PVSBAKE_SOURCE_DIR) + "/" + relative;
}

bool in_ci() {
    const char* ci = std::getenv("CI");
    return ci != nullptr && std::string(ci) == "true";
}

int fuzz_iterations(int full, int ci) {
    if (const char* env = std::getenv("PVSBAKE_FUZZ_ITERATIONS")) return std::max(1, std::atoi(env));
    return in_ci() ? ci : full;
}

std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

void write_file(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    if (!out) throw std::runtime_error("cannot write " + path);
}

int h5diff_outside_run(const std::string& a, const std::string& b, const std::string& log) {
    const int status =
        std::system(("h5diff --exclude-path /run '" + a + "' '" + b + "' > '" + log + "' 2>&1").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace pvs::test
