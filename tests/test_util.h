// SPDX-License-Identifier: MIT
// Helpers shared by the tests: temporary folders, the real worlds when present, CI sizing.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

namespace pvs::test {

// A fresh folder under the system temp dir, removed when the object dies.
class TempDir {
public:
    TempDir();
    ~TempDir();
    const std::filesystem::path& path() const { return path_; }
    std::string file(const std::string& name) const { return (path_ / name).string(); }

private:
    std::filesystem::path path_;
};

// ../shared/worlds/<name> when it exists, else "" (tests then GTEST_SKIP: the folder is optional).
std::string shared_world(const std::string& name);

// The committed sample world (samples/rooms.glb).
std::string sample_world();

// A file of the source tree, by its path from the top ("tests/install/game.c").
std::string source_file(const std::string& relative);

// True under CI (CI=true): long checks run smaller there and full size in bench/.
bool in_ci();

// Mutants a fuzz test makes: PVSBAKE_FUZZ_ITERATIONS when set, else `ci` under CI and `full` otherwise.
int fuzz_iterations(int full, int ci);

std::string read_file(const std::string& path);
// The comparison docs/FORMAT.md gives: `h5diff --exclude-path /run A B`, its output in `log`; its exit
// status (0: the two bakes are the same outside the run's own record).
int h5diff_outside_run(const std::string& a, const std::string& b, const std::string& log);
void write_file(const std::string& path, const std::string& bytes);

}  // namespace pvs::test
