// SPDX-License-Identifier: MIT
// Allocations that fail in the writers (docs/ALGORITHMS.md#faults), in the manner of SQLite's malloc tests:
// the Nth allocation of a write throws std::bad_alloc, for every N until a write needs no more. Each failed
// write must end in an exception (std::bad_alloc or pvs::Error), leave no file, temporary or final, and leave
// the libraries fit for the next write, which must give the undisturbed bytes. The writes' own failing I/O
// calls are tests/faults/inject.py's. This binary replaces the global operator new: keep it alone in its
// file.
#include "core/error.h"
#include "io/atomic_file.h"
#include "io/bake_file.h"
#include "io/checkpoint.h"
#include "io/runtime_file.h"
#include "tests/bake_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <new>
#include <string>
#include <vector>

namespace {

// 0: no allocation fails; N > 0: the Nth allocation counted from arm() throws.
std::atomic<long> g_fail_at{0};
std::atomic<long> g_count{0};

void* counted_alloc(std::size_t n) {
    const long at = g_fail_at.load(std::memory_order_relaxed);
    if (at > 0 && g_count.fetch_add(1, std::memory_order_relaxed) + 1 == at) throw std::bad_alloc();
    void* p = std::malloc(n == 0 ? 1 : n);
    if (p == nullptr) throw std::bad_alloc();
    return p;
}

}  // namespace

void* operator new(std::size_t n) {
    return counted_alloc(n);
}
void* operator new[](std::size_t n) {
    return counted_alloc(n);
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    std::free(p);
}

namespace pvs {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> entries(const std::string& folder) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(folder)) names.push_back(e.path().filename().string());
    return names;
}

// Runs `write` (which writes `output` in `folder`) with its Nth allocation failing, for N = 1, 2, ... until
// it succeeds; checks every failure and that the success gives `expected`. Returns the failures seen.
int fail_each_allocation(const std::string& folder, const std::string& output, const std::string& expected,
                         const std::function<void()>& write) {
    int failures = 0;
    for (long n = 1; n < 1'000'000; ++n) {
        SCOPED_TRACE(testing::Message() << "allocation " << n << " of " << output << " fails");
        const std::vector<std::string> before = entries(folder);
        bool failed = false;
        g_count = 0;
        g_fail_at = n;
        try {
            write();
        } catch (const std::bad_alloc&) {
            failed = true;
        } catch (const Error&) {
            failed = true;
        }
        g_fail_at = 0;
        if (!failed) {
            EXPECT_EQ(test::read_file(folder + "/" + output), expected);
            return failures;
        }
        ++failures;
        EXPECT_EQ(entries(folder), before) << "a failed write left a file";
        if (testing::Test::HasFailure()) return failures;
    }
    ADD_FAILURE() << "the write never succeeded";
    return failures;
}

TEST(WriteFaults, EveryAllocationOfABakeFileWriteFailsCleanly) {
    test::TempDir dir;
    const BakeData bake = test::coherent_bake(40, {4, 2, 3}, false, true, 5);
    const std::string expected_path = dir.file("expected.h5");
    write_bake_file(expected_path, bake);
    const std::string expected = test::read_file(expected_path);
    fs::remove(expected_path);
    const int failures =
        fail_each_allocation(dir.path(), "b.h5", expected, [&] { write_bake_file(dir.file("b.h5"), bake); });
    EXPECT_GT(failures, 50) << "the write allocates less than expected: is the counter armed?";
    testing::Test::RecordProperty("failed_allocations", failures);
    EXPECT_EQ(read_bake_file(dir.file("b.h5")).pvs.words, bake.pvs.words);
}

TEST(WriteFaults, EveryAllocationOfACheckpointChunkFailsCleanly) {
    test::TempDir dir;
    const std::string folder = dir.file("x.h5.checkpoint");
    const CheckpointIdentity id{"pvsbake test", "00ff", {{"mode", "conservative"}}};
    RowChunk chunk;
    chunk.tables.push_back(RowChunk::Table{"face", 2, {1, 5, 9}, {1, 2, 3, 4, 5, 6}});
    write_checkpoint_chunk(folder, 1, id, chunk, 0);
    const std::string expected = test::read_file(folder + "/rows-000001.h5");
    fs::remove_all(folder);
    fs::create_directory(folder);
    const int failures = fail_each_allocation(folder, "rows-000001.h5", expected,
                                              [&] { write_checkpoint_chunk(folder, 1, id, chunk, 0); });
    EXPECT_GT(failures, 20);
    testing::Test::RecordProperty("failed_allocations", failures);
    EXPECT_EQ(read_checkpoint(folder, id).chunks.size(), 1u);
}

TEST(WriteFaults, EveryAllocationOfARuntimeFileExportFailsCleanly) {
    test::TempDir dir;
    const std::string bake_path = dir.file("in.h5");
    write_bake_file(bake_path, test::coherent_bake(40, {4, 2, 3}, false, true, 6));
    const std::string out = dir.file("out");
    fs::create_directory(out);
    export_runtime_file(bake_path, out + "/expected.pvsr");
    const std::string expected = test::read_file(out + "/expected.pvsr");
    fs::remove(out + "/expected.pvsr");
    const int failures = fail_each_allocation(out, "l.pvsr", expected,
                                              [&] { export_runtime_file(bake_path, out + "/l.pvsr"); });
    EXPECT_GT(failures, 20);
    testing::Test::RecordProperty("failed_allocations", failures);
}

}  // namespace
}  // namespace pvs
