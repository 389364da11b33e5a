// SPDX-License-Identifier: MIT
// Tests io/atomic_file: commit publishes the bytes, no commit leaves nothing, the temporary file sits next
// to the final one, and failures throw pvs::Error (kIo) naming the paths.
#include "io/atomic_file.h"

#include "core/error.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace pvs {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> folder_entries(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(folder)) names.push_back(e.path().filename().string());
    return names;
}

TEST(AtomicFile, CommitCreatesTheFileWithTheBytes) {
    test::TempDir dir;
    const std::string path = dir.file("out.bin");
    {
        AtomicOutput out(path);
        test::write_file(out.temp_path(), std::string("abc\0def", 7));
        EXPECT_FALSE(fs::exists(path));
        out.commit();
    }
    EXPECT_EQ(test::read_file(path), std::string("abc\0def", 7));
    EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"out.bin"});
}

TEST(AtomicFile, DestructorWithoutCommitLeavesNothing) {
    test::TempDir dir;
    const std::string path = dir.file("out.bin");
    std::string temp;
    {
        AtomicOutput out(path);
        temp = out.temp_path();
        test::write_file(temp, "half written");
        EXPECT_TRUE(fs::exists(temp));
    }
    EXPECT_FALSE(fs::exists(temp));
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(AtomicFile, DestructorWithoutTempFileDoesNotThrow) {
    test::TempDir dir;
    EXPECT_NO_THROW({ AtomicOutput out(dir.file("never_written.bin")); });
    EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(AtomicFile, TempFileIsInTheSameFolderAndUnique) {
    test::TempDir dir;
    const std::string path = dir.file("bake.h5");
    AtomicOutput a(path);
    AtomicOutput b(path);
    EXPECT_EQ(a.final_path(), path);
    EXPECT_EQ(fs::path(a.temp_path()).parent_path(), dir.path());
    EXPECT_EQ(fs::path(a.temp_path()).filename().string().rfind("bake.h5.tmp-", 0), 0u) << a.temp_path();
    EXPECT_NE(a.temp_path(), b.temp_path());
}

TEST(AtomicFile, CommitReplacesAnExistingFile) {
    test::TempDir dir;
    const std::string path = dir.file("out.txt");
    test::write_file(path, "old");
    write_file_atomically(path, "new contents", "the test file");
    EXPECT_EQ(test::read_file(path), "new contents");
    EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, WriteFileAtomicallyWritesEmptyAndBinaryBytes) {
    test::TempDir dir;
    write_file_atomically(dir.file("empty"), "", "the test file");
    EXPECT_TRUE(fs::exists(dir.file("empty")));
    EXPECT_EQ(fs::file_size(dir.file("empty")), 0u);
    std::string bytes;
    for (int i = 0; i < 70000; ++i) bytes.push_back(char(i * 31));
    write_file_atomically(dir.file("binary"), bytes, "the test file");
    EXPECT_EQ(test::read_file(dir.file("binary")), bytes);
}

TEST(AtomicFile, MissingFolderThrowsIoErrorAndLeavesNothing) {
    test::TempDir dir;
    const std::string path = dir.file("no_such_folder/out.txt");
    try {
        write_file_atomically(path, "x", "the test file");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kIo);
        const std::string msg = e.what();
        EXPECT_EQ(msg, path + ": the folder does not exist (any more) while writing the test file");
    }
    EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(AtomicFile, FailedCommitNamesBothPathsAndKeepsTheTarget) {
    test::TempDir dir;
    // The final path is a folder holding a file: the rename must fail and leave both untouched.
    const std::string path = dir.file("target");
    fs::create_directory(path);
    test::write_file(path + "/keep.txt", "keep");
    std::string temp;
    try {
        AtomicOutput out(path);
        temp = out.temp_path();
        test::write_file(temp, "new");
        out.commit();
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kIo);
        const std::string msg = e.what();
        EXPECT_NE(msg.find(temp), std::string::npos) << msg;
        EXPECT_NE(msg.find(path), std::string::npos) << msg;
    }
    EXPECT_FALSE(fs::exists(temp));
    EXPECT_TRUE(fs::is_directory(path));
    EXPECT_EQ(test::read_file(path + "/keep.txt"), "keep");
    EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"target"});
}

TEST(AtomicFile, WriteFileAtomicallyOverAFolderThrowsAndLeavesNoTempFile) {
    test::TempDir dir;
    const std::string path = dir.file("target");
    fs::create_directory(path);
    EXPECT_THROW(write_file_atomically(path, "x", "the test file"), Error);
    EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"target"});
}

}  // namespace
}  // namespace pvs
