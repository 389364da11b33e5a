// SPDX-License-Identifier: MIT
// Resumable bakes (docs/ALGORITHMS.md#resume): the journal of finished rows, its checkpoint chunks, and
// bakes of the real pvsbake binary killed with SIGKILL and run again, which must write the file an
// uninterrupted bake writes (the same outside /run, docs/FORMAT.md).
#include "core/error.h"
#include "core/row_journal.h"
#include "io/checkpoint.h"
#include "io/gltf_writer.h"
#include "samples/crack_set.h"
#include "samples/random_world.h"
#include "samples/world_edit.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

namespace pvs {
namespace {

namespace fs = std::filesystem;

RowChunk::Table table(const std::string& name, uint32_t words, std::vector<uint64_t> keys) {
    RowChunk::Table t{name, words, keys, {}};
    for (uint64_t k : keys)
        for (uint32_t w = 0; w < words; ++w) t.words.push_back(k * 1000 + w);
    return t;
}

CheckpointIdentity identity() {
    return CheckpointIdentity{
        "1.2.3", "00ff00ff00ff00ff", {{"mode", "conservative"}, {"cells.cell_size_m", "2"}}};
}

TEST(RowJournal, RowsGoToTheSinkInChunksAndComeBackFromACheckpoint) {
    std::vector<RowChunk> chunks;
    RowJournal journal([&](const RowChunk& c) { return chunks.push_back(c), true; }, 0.0);
    const std::vector<uint64_t> a{1, 2}, b{3, 4, 5};
    journal.record("face", 7, a.data(), 2);
    journal.record("face", 9, b.data(), 2);
    journal.record("shaft", 7, b.data(), 3);
    EXPECT_TRUE(chunks.empty()) << "no interval: only flush() writes";
    journal.flush();
    journal.flush();  // nothing new: no chunk
    ASSERT_EQ(chunks.size(), 1u);
    EXPECT_EQ(chunks[0].row_count(), 3u);

    test::TempDir dir;
    const std::string folder = dir.file("out.h5.checkpoint");
    write_checkpoint_chunk(folder, 1, identity(), chunks[0]);
    write_checkpoint_chunk(folder, 2, identity(), RowChunk{{table("box", 1, {100, 101})}});
    const Checkpoint read = read_checkpoint(folder, identity());
    ASSERT_EQ(read.chunks.size(), 2u);
    EXPECT_EQ(read.next_index, 3u);
    RowJournal again(nullptr, 0.0);
    for (const RowChunk& c : read.chunks) again.load(c);
    EXPECT_EQ(again.loaded_rows(), 5u);
    std::vector<uint64_t> row(3, 0);
    ASSERT_TRUE(again.find("face", 9, row.data(), 2));
    EXPECT_EQ(row[0], 3u);
    EXPECT_EQ(row[1], 4u);
    ASSERT_TRUE(again.find("shaft", 7, row.data(), 3));
    EXPECT_EQ(row, b);
    ASSERT_TRUE(again.find("box", 101, row.data(), 1));
    EXPECT_EQ(row[0], 101000u);
    EXPECT_FALSE(again.find("face", 8, row.data(), 2));
    EXPECT_FALSE(again.find("hidden", 7, row.data(), 2));
    EXPECT_THROW(again.find("face", 9, row.data(), 3), Error) << "a row of another width is a bug";
}

TEST(RowJournal, RowsASinkCouldNotWriteWaitForTheNextChunk) {
    int calls = 0;
    std::vector<RowChunk> written;
    RowJournal journal(
        [&](const RowChunk& c) {
            if (++calls == 1) return false;  // a full disk, say
            written.push_back(c);
            return true;
        },
        0.0);
    const std::vector<uint64_t> a{1};
    journal.record("face", 1, a.data(), 1);
    journal.flush();
    EXPECT_TRUE(written.empty());
    journal.record("face", 2, a.data(), 1);
    journal.flush();
    ASSERT_EQ(written.size(), 1u);
    EXPECT_EQ(written[0].row_count(), 2u) << "the row of the failed chunk comes with the next";
}

TEST(RowJournal, AnIntervalWritesChunksWhileRowsAreRecorded) {
    size_t chunks = 0;
    RowJournal journal([&](const RowChunk&) { return ++chunks, true; }, 1e-9);
    const std::vector<uint64_t> a{1};
    for (uint64_t k = 0; k < 5; ++k) journal.record("box", k, a.data(), 1);
    EXPECT_EQ(chunks, 5u);
    EXPECT_EQ(journal.recorded_rows(), 5u);
}

void expect_refused(const std::string& folder, const CheckpointIdentity& id, const std::string& naming) {
    try {
        read_checkpoint(folder, id);
        ADD_FAILURE() << "a checkpoint of another bake was read";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
        EXPECT_NE(std::string(e.what()).find(naming), std::string::npos) << e.what();
    }
}

TEST(Checkpoint, ChunksOfAnotherBakeOrDamagedAreRefusedAndHalfWrittenOnesIgnored) {
    test::TempDir dir;
    const std::string folder = dir.file("x.h5.checkpoint");
    EXPECT_FALSE(checkpoint_exists(folder));
    EXPECT_TRUE(read_checkpoint(folder, identity()).chunks.empty());
    write_checkpoint_chunk(folder, 1, identity(), RowChunk{{table("face", 2, {1, 2, 3})}});
    EXPECT_TRUE(checkpoint_exists(folder));
    // What a write killed before its rename leaves: never read.
    test::write_file(folder + "/rows-000002.h5.tmp-123-0", "half a file");
    EXPECT_EQ(read_checkpoint(folder, identity()).chunks.size(), 1u);
    EXPECT_EQ(read_checkpoint(folder, identity()).next_index, 2u);

    CheckpointIdentity other = identity();
    other.parameters[1].second = "4";
    expect_refused(folder, other, "cells.cell_size_m = 2");
    other = identity();
    other.world_hash = "1111111111111111";
    expect_refused(folder, other, "another world");
    other = identity();
    other.tool_version = "9.9.9";
    expect_refused(folder, other, "pvsbake 1.2.3");
    other = identity();
    other.parameters.emplace_back("conservative.shaft_budget", "0");
    expect_refused(folder, other, "conservative.shaft_budget");

    test::write_file(folder + "/rows-000003.h5", "not an HDF5 file");
    expect_refused(folder, identity(), "rows-000003.h5");
    test::write_file(folder + "/notes.txt", "the user's");
    EXPECT_TRUE(remove_checkpoint(folder));
    EXPECT_FALSE(checkpoint_exists(folder));
    EXPECT_TRUE(fs::exists(folder + "/notes.txt")) << "only the checkpoint's files are removed";
    fs::remove(folder + "/notes.txt");
    EXPECT_TRUE(remove_checkpoint(folder));
    EXPECT_FALSE(fs::exists(folder));
}

// ---------------------------------------------------------------------------------------------------------
// The real binary, killed.

// Starts `program` (pvsbake by default) with `args`, its output and log going to `log`, in a process group
// of its own (so that an mpirun and its ranks can be killed together).
pid_t spawn(const std::vector<std::string>& args, const std::string& log,
            const std::vector<std::string>& program = {PVSBAKE_BINARY}) {
    std::vector<std::string> all = args;
    all.insert(all.begin(), program.begin(), program.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::setpgid(0, 0);
        const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
        if (fd >= 0) {
            ::dup2(fd, 1);
            ::dup2(fd, 2);
        }
        ::execv(argv[0], argv.data());
        ::_exit(127);
    }
    ::setpgid(pid, pid);
    return pid;
}

// The exit status, or 128 + the signal that ended it.
int wait_for(pid_t pid) {
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

bool exited(pid_t pid, int& status) {
    int s = 0;
    if (::waitpid(pid, &s, WNOHANG) != pid) return false;
    status = WIFEXITED(s) ? WEXITSTATUS(s) : 128 + WTERMSIG(s);
    return true;
}

// Waits until the process ends (true, its status in `status`) or the deadline passes (false).
bool exited_by(pid_t pid, std::chrono::steady_clock::time_point deadline, int& status) {
    while (!exited(pid, status)) {
        if (std::chrono::steady_clock::now() >= deadline) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return true;
}

size_t chunk_files(const std::string& folder) {
    std::error_code ec;
    size_t n = 0;
    for (const auto& e : fs::directory_iterator(folder, ec)) {
        const std::string name = e.path().filename().string();
        n += name.rfind("rows-", 0) == 0 && name.size() > 3 && name.substr(name.size() - 3) == ".h5";
    }
    return n;
}

// Waits until the folder holds `chunks` chunk files or the process ends; returns false if it ended.
bool wait_for_chunks(pid_t pid, const std::string& folder, size_t chunks, int& status) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
    while (std::chrono::steady_clock::now() < deadline) {
        if (exited(pid, status)) return false;
        if (chunk_files(folder) >= chunks) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    ::kill(pid, SIGKILL);
    status = wait_for(pid);
    ADD_FAILURE() << "no chunk in 5 minutes";
    return false;
}

bool log_has(const std::string& log, const std::string& text) {
    return test::read_file(log).find(text) != std::string::npos;
}

// A bake of the sample world whose conservative PVS takes seconds on two threads (unless `extra` says
// --threads), after cheap occluders.
std::vector<std::string> bake_args(const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> a = {"bake",
                                  test::sample_world(),
                                  "-o",
                                  out,
                                  "--eyes",
                                  "2",
                                  "--rays",
                                  "64",
                                  "-q",
                                  "--no-verify",
                                  "--occluder-probe-eyes",
                                  "64",
                                  "--occluder-gap-lines",
                                  "0",
                                  "--occluder-seal-rays",
                                  "0"};
    if (std::find(extra.begin(), extra.end(), "--threads") == extra.end())
        a.insert(a.end(), {"--threads", "2"});
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
}

// Bakes once uninterrupted, then again killed with SIGKILL after a random number of new checkpoint chunks
// (and a random few milliseconds more, so that some kills land inside a chunk's write), run again, killed
// again..., and finally run to its end: the two files must be the same outside /run.
// `program`: what runs the killed bakes (pvsbake, or mpirun and its ranks).
void kill_and_resume(const std::vector<std::string>& extra, uint32_t seed,
                     const std::vector<std::string>& program = {PVSBAKE_BINARY}) {
    test::TempDir dir;
    const std::string reference = dir.file("reference.h5"), out = dir.file("resumed.h5");
    const std::string folder = out + ".checkpoint", log = dir.file("log.txt");
    std::vector<std::string> plain = extra;
    plain.insert(plain.end(), {"--checkpoint-interval", "0"});
    ASSERT_EQ(wait_for(spawn(bake_args(reference, plain), log)), 0) << test::read_file(log);
    EXPECT_FALSE(fs::exists(reference + ".checkpoint")) << "--checkpoint-interval 0 writes no checkpoint";

    std::vector<std::string> often = extra;
    often.insert(often.end(), {"--checkpoint-interval", "0.05"});
    std::mt19937 rng(seed);
    int kills = 0, status = -1;
    for (int attempt = 0; attempt < 4; ++attempt) {
        const pid_t pid = spawn(bake_args(out, often), log, program);
        const size_t target = chunk_files(folder) + 1 + rng() % 6;
        if (!wait_for_chunks(pid, folder, target, status)) break;  // it finished first
        std::this_thread::sleep_for(std::chrono::milliseconds(rng() % 40));
        ::kill(-pid, SIGKILL);
        wait_for(pid);
        ++kills;
        ASSERT_FALSE(fs::exists(out)) << "a killed bake wrote its output";
    }
    ASSERT_GE(kills, 2) << "the bake ended before it could be killed twice: make it longer\n"
                        << test::read_file(log);
    const std::string final_log = dir.file("final.txt");
    std::vector<std::string> last = bake_args(out, often);
    last.erase(std::find(last.begin(), last.end(), "-q"));
    ASSERT_EQ(wait_for(spawn(last, final_log, program)), 0) << test::read_file(final_log);
    EXPECT_TRUE(log_has(final_log, "resuming from the checkpoint")) << test::read_file(final_log);
    EXPECT_FALSE(fs::exists(folder)) << "the checkpoint outlived the bake it served";
    const std::string diff = dir.file("h5diff.txt");
    EXPECT_EQ(test::h5diff_outside_run(reference, out, diff), 0) << test::read_file(diff);
}

TEST(Resume, AGridBakeKilledAtRandomPointsAndResumedWritesTheSameFile) {
    // Every table of the grid: the single-occluder pass, the faces with their seen rows, the shaft pass
    // (by blocks of cells, whose rows are taken from the journal only all together; the blocks' proofs
    // before the faces, with their roots' failures; nodes giving up where both witnesses fail).
    kill_and_resume({"--shaft-budget", "16", "--shaft-block", "2", "--shaft-early", "--shaft-give-up", "1"},
                    1);
}

TEST(Resume, AnOctreeBakeKilledAtRandomPointsAndResumedWritesTheSameFile) {
    kill_and_resume({"--cells", "octree"}, 2);
}

// A node killed at any moment, twenty times (docs/RESULTS.md, "Faults"): each run of the same command is
// killed with SIGKILL after a random time (drawn over the whole of an undisturbed bake, so that kills land
// in the stages before the PVS, in the PVS and in the writes), and every run that finishes before its kill
// must write the undisturbed bake's file; so must the run after the last kill. A random test world (a bake
// of a second or two) keeps twenty kills within the test command's time.
TEST(Resume, ABakeKilledTwentyTimesAtRandomMomentsAndRunAgainWritesTheSameFile) {
    test::TempDir dir;
    const std::string world = dir.file("world.glb"), reference = dir.file("reference.h5"),
                      out = dir.file("out.h5"), log = dir.file("log.txt");
    write_glb(edited_world(make_random_world(3, 0).world, {}), world);
    const auto args = [&](const std::string& file) {
        std::vector<std::string> a = bake_args(file, {"--checkpoint-interval", "0.02"});
        a[1] = world;
        return a;
    };
    const auto start = std::chrono::steady_clock::now();
    ASSERT_EQ(wait_for(spawn(args(reference), log)), 0) << test::read_file(log);
    const double whole_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::mt19937 rng(63);
    std::uniform_real_distribution<double> moment(0.0, whole_s);
    int kills = 0, finished = 0;
    for (int run = 0; kills < 20 && run < 60; ++run) {
        const pid_t pid = spawn(args(out), log);
        const auto deadline = std::chrono::steady_clock::now() +
                              std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                  std::chrono::duration<double>(moment(rng)));
        int status = -1;
        if (!exited_by(pid, deadline, status)) {
            ::kill(-pid, SIGKILL);
            wait_for(pid);
            ++kills;
            continue;
        }
        ASSERT_EQ(status, 0) << test::read_file(log);
        ++finished;
        const std::string diff = dir.file("h5diff.txt");
        ASSERT_EQ(test::h5diff_outside_run(reference, out, diff), 0) << test::read_file(diff);
        fs::remove(out);
    }
    ASSERT_EQ(kills, 20) << finished << " runs finished first";
    ASSERT_EQ(wait_for(spawn(args(out), log)), 0) << test::read_file(log);
    const std::string diff = dir.file("h5diff.txt");
    EXPECT_EQ(test::h5diff_outside_run(reference, out, diff), 0) << test::read_file(diff);
    EXPECT_FALSE(fs::exists(out + ".checkpoint"));
    for (const auto& e : fs::directory_iterator(dir.path()))
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST(Resume, ACheckpointOfOtherParametersIsRefusedAndRestartStartsOver) {
    test::TempDir dir;
    const std::string out = dir.file("x.h5"), folder = out + ".checkpoint", log = dir.file("log.txt");
    int status = -1;
    const pid_t pid = spawn(bake_args(out, {"--checkpoint-interval", "0.01"}), log);
    ASSERT_TRUE(wait_for_chunks(pid, folder, 1, status)) << test::read_file(log);
    ::kill(pid, SIGKILL);
    wait_for(pid);

    const std::string other = dir.file("other.txt");
    EXPECT_EQ(wait_for(spawn(bake_args(out, {"--cell-size", "3"}), other)), 2);
    EXPECT_TRUE(log_has(other, "cells.cell_size_m")) << test::read_file(other);
    EXPECT_TRUE(log_has(other, "--restart")) << test::read_file(other);
    EXPECT_FALSE(fs::exists(out));
    EXPECT_TRUE(checkpoint_exists(folder)) << "a refused checkpoint is left as it was";

    const std::string restart = dir.file("restart.txt");
    EXPECT_EQ(wait_for(spawn(bake_args(out, {"--cell-size", "3", "--restart"}), restart)), 0)
        << test::read_file(restart);
    EXPECT_TRUE(fs::exists(out));
    EXPECT_FALSE(fs::exists(folder));

    const std::string none = dir.file("none.txt");
    EXPECT_EQ(wait_for(spawn(bake_args(dir.file("y.h5"), {"--resume"}), none)), 2);
    EXPECT_TRUE(log_has(none, "no checkpoint")) << test::read_file(none);
}

TEST(Resume, AnOutputThatCannotBeWrittenAtTheEndKeepsTheRowsAndTheNextRunFinishes) {
    test::TempDir dir;
    const std::string reference = dir.file("reference.h5"), out = dir.file("x.h5"),
                      folder = out + ".checkpoint";
    const std::string log = dir.file("log.txt");
    ASSERT_EQ(wait_for(spawn(bake_args(reference, {"--checkpoint-interval", "0"}), log)), 0)
        << test::read_file(log);
    int status = -1;
    const pid_t pid = spawn(bake_args(out, {"--checkpoint-interval", "0.01"}), log);
    ASSERT_TRUE(wait_for_chunks(pid, folder, 1, status)) << test::read_file(log);
    // After the check before the first stage, the output's name is taken by a folder: the last rename fails.
    fs::create_directory(out);
    test::write_file(out + "/in_the_way", "");
    EXPECT_EQ(wait_for(pid), 1) << test::read_file(log);
    EXPECT_TRUE(log_has(log, "the finished rows are kept in " + folder)) << test::read_file(log);
    ASSERT_TRUE(checkpoint_exists(folder));

    fs::remove_all(out);
    const std::string again = dir.file("again.txt");
    std::vector<std::string> args = bake_args(out, {"--checkpoint-interval", "0.01", "--resume"});
    args.erase(std::find(args.begin(), args.end(), "-q"));
    ASSERT_EQ(wait_for(spawn(args, again)), 0) << test::read_file(again);
    EXPECT_TRUE(log_has(again, "resuming from the checkpoint")) << test::read_file(again);
    const std::string diff = dir.file("h5diff.txt");
    EXPECT_EQ(test::h5diff_outside_run(reference, out, diff), 0) << test::read_file(diff);
}

#ifdef PVSBAKE_MPI
// ---------------------------------------------------------------------------------------------------------
// Several processes (docs/ALGORITHMS.md#processes): 2 ranks of one thread under mpirun write the file one
// process of two threads writes.

std::vector<std::string> mpirun(int ranks) {
    // OpenMPI refuses to run as root unless told; the test's machines run as root. Only these children see
    // it.
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    return {"/usr/bin/mpirun", "--oversubscribe", "-np", std::to_string(ranks), PVSBAKE_BINARY};
}

void expect_same_under_mpirun(const std::vector<std::string>& extra, int ranks = 2) {
    test::TempDir dir;
    const std::string one = dir.file("one.h5"), two = dir.file("two.h5"), log = dir.file("log.txt");
    ASSERT_EQ(wait_for(spawn(bake_args(one, extra), log)), 0) << test::read_file(log);
    std::vector<std::string> one_thread = extra;
    one_thread.insert(one_thread.end(), {"--threads", "1"});
    const std::vector<std::string> args = bake_args(two, one_thread);
    ASSERT_EQ(wait_for(spawn(args, log, mpirun(ranks))), 0) << test::read_file(log);
    EXPECT_FALSE(fs::exists(two + ".checkpoint"));
    const std::string diff = dir.file("h5diff.txt");
    EXPECT_EQ(test::h5diff_outside_run(one, two, diff), 0) << test::read_file(diff);
}

TEST(Processes, TwoRanksBakeTheGridOneProcessBakes) {
    expect_same_under_mpirun({"--shaft-budget", "16"});
}

TEST(Processes, ThreeRanksBakeTheGridOneProcessBakes) {
    // The shaft pass by blocks of cells: a block is dealt whole, in the blocks' proofs before the faces too.
    expect_same_under_mpirun(
        {"--shaft-budget", "16", "--shaft-block", "2", "--shaft-early", "--shaft-give-up", "1"}, 3);
}

// A command that shares no work starts no MPI under mpirun either (driver/processes.h), and only rank 0
// speaks: the ranks' output holds the file's summary once.
TEST(Processes, UnderMpirunACommandThatSharesNoWorkSpeaksOnce) {
    test::TempDir dir;
    const std::string out = dir.file("x.h5"), log = dir.file("log.txt"), info = dir.file("info.txt");
    ASSERT_EQ(wait_for(spawn(bake_args(out, {}), log)), 0) << test::read_file(log);
    ASSERT_EQ(wait_for(spawn({"info", out}, info, mpirun(3))), 0) << test::read_file(info);
    const std::string text = test::read_file(info);
    const size_t first = text.find("pvs_objects_mean");
    ASSERT_NE(first, std::string::npos) << text;
    EXPECT_EQ(text.find("pvs_objects_mean", first + 1), std::string::npos) << "more than one rank spoke:\n" << text;
}

// The stages before the PVS dealt between the ranks (docs/ALGORITHMS.md#processes): a world with cracks
// that the sight, gap and seal probes find, baked with every probe on by one process of two threads and by
// three ranks of one: the same file (its figures hold each probe's counts and what it removed).
TEST(Processes, ThreeRanksDealTheProbesAndTheShrunkLevelsAsOneProcessComputesThem) {
    test::TempDir dir;
    CrackSetSpec spec;
    spec.widths_m = {0.002f, 0.01f, 0.05f};
    spec.cases_per_width = 5;  // each kind once per width
    const std::string world = dir.file("cracks.glb");
    write_glb(make_crack_set(spec).scene, world);
    const std::string one = dir.file("one.h5"), three = dir.file("three.h5"), log = dir.file("log.txt"),
                      report = dir.file("one.json");
    const auto args = [&](const std::string& out, const char* threads) {
        return std::vector<std::string>{"bake", world, "-o", out, "--eyes", "2", "--rays", "64", "-q",
                                        "--no-verify", "--threads", threads, "--report", out + ".json"};
    };
    ASSERT_EQ(wait_for(spawn(args(one, "2"), log)), 0) << test::read_file(log);
    ASSERT_EQ(wait_for(spawn(args(three, "1"), log, mpirun(3))), 0) << test::read_file(log);
    const std::string diff = dir.file("h5diff.txt");
    EXPECT_EQ(test::h5diff_outside_run(one, three, diff), 0) << test::read_file(diff);
    // The probes found openings, so their united finds are what the files compare.
    const auto j = nlohmann::json::parse(test::read_file(one + ".json"));
    EXPECT_GT(j["figures"]["occluder_gap_removed_voxels"].get<double>() +
                  j["figures"]["occluder_seal_removed_voxels"].get<double>(),
              0.0)
        << j["figures"].dump(1);
}

// The verification dealt between the ranks (docs/ALGORITHMS.md#dealt-verification): a sampled bake (which
// misses objects, so misses, witnesses and neighbour passes all cross between the ranks) verified by one
// process of two threads and by three ranks of one writes the same verification into the file.
TEST(Processes, ThreeRanksVerifyAsOneProcessVerifies) {
    test::TempDir dir;
    const std::string baked = dir.file("sampled.h5"), one = dir.file("one.h5"), three = dir.file("three.h5"),
                      log = dir.file("log.txt");
    ASSERT_EQ(wait_for(spawn(bake_args(baked, {"--mode", "sampled"}), log)), 0) << test::read_file(log);
    fs::copy_file(baked, one);
    fs::copy_file(baked, three);
    const auto args = [&](const std::string& file, const char* threads) {
        return std::vector<std::string>{"verify",        test::sample_world(), file,      "-q",
                                        "--threads",     threads,              "--report", file + ".json",
                                        "--verify-eyes", "4",                  "--verify-rays-per-eye", "256"};
    };
    // Exit 3: the sampled bake misses objects.
    ASSERT_EQ(wait_for(spawn(args(one, "2"), log)), 3) << test::read_file(log);
    ASSERT_EQ(wait_for(spawn(args(three, "1"), log, mpirun(3))), 3) << test::read_file(log);
    const std::string diff = dir.file("h5diff.txt");
    EXPECT_EQ(test::h5diff_outside_run(one, three, diff), 0) << test::read_file(diff);
    const auto j = nlohmann::json::parse(test::read_file(one + ".json"));
    const auto& f = j["verification"]["figures"];
    EXPECT_GT(f["missed_pairs"].get<double>(), 0.0) << f.dump(1);
    EXPECT_GT(f["neighbour_passes"].get<double>(), 0.0) << f.dump(1);
}

TEST(Processes, TwoRanksBakeTheOctreeOneProcessBakes) {
    expect_same_under_mpirun({"--cells", "octree"});
}

TEST(Processes, TwoRanksKilledTogetherAndRunAgainWriteTheSameFile) {
    kill_and_resume({"--threads", "1"}, 4, mpirun(2));
}

// The pid of the rank `rank` among the children of `parent` (mpirun starts its ranks itself), or -1.
pid_t rank_pid(pid_t parent, int rank) {
    const std::string wanted = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
    for (const auto& e : fs::directory_iterator("/proc")) {
        const std::string name = e.path().filename().string();
        if (name.find_first_not_of("0123456789") != std::string::npos) continue;
        std::string stat, env;
        try {
            stat = test::read_file(e.path().string() + "/stat");
            env = test::read_file(e.path().string() + "/environ");
        } catch (const std::runtime_error&) {
            continue;  // ended meanwhile
        }
        // "pid (comm) state ppid ...": the comm may hold spaces, so read after its closing parenthesis.
        const size_t close = stat.rfind(')');
        if (close == std::string::npos) continue;
        char state = 0;
        int ppid = 0;
        if (std::sscanf(stat.c_str() + close + 1, " %c %d", &state, &ppid) != 2 || ppid != parent) continue;
        size_t at = 0;
        for (size_t end; (end = env.find('\0', at)) != std::string::npos; at = end + 1)
            if (env.compare(at, end - at, wanted) == 0) return pid_t(std::stol(name));
    }
    return -1;
}

// One rank of three killed in the middle of the PVS: the job ends (no rank waits for it for ever) with a
// message naming the dead rank, and the same job run again resumes from the rows every rank had
// checkpointed and writes the file one process writes.
TEST(Processes, ARankKilledMidPvsEndsTheJobAndTheJobRunAgainResumes) {
    test::TempDir dir;
    const std::string reference = dir.file("reference.h5"), out = dir.file("out.h5"), log = dir.file("log.txt");
    const std::string folder = out + ".checkpoint";
    ASSERT_EQ(wait_for(spawn(bake_args(reference, {"--checkpoint-interval", "0"}), log)), 0)
        << test::read_file(log);
    const std::vector<std::string> extra = {"--threads", "1", "--checkpoint-interval", "0.05"};
    const pid_t pid = spawn(bake_args(out, extra), log, mpirun(3));
    int status = -1;
    ASSERT_TRUE(wait_for_chunks(pid, folder, 6, status)) << test::read_file(log);
    const pid_t victim = rank_pid(pid, 1);
    ASSERT_GT(victim, 0) << "rank 1 not found";
    ::kill(victim, SIGKILL);
    if (!exited_by(pid, std::chrono::steady_clock::now() + std::chrono::minutes(2), status)) {
        ::kill(-pid, SIGKILL);
        wait_for(pid);
        FAIL() << "the job hung for two minutes after a rank died\n" << test::read_file(log);
    }
    EXPECT_NE(status, 0);
    EXPECT_TRUE(log_has(log, "rank 1")) << test::read_file(log);
    EXPECT_FALSE(fs::exists(out));
    ASSERT_TRUE(checkpoint_exists(folder));

    const std::string again = dir.file("again.txt");
    std::vector<std::string> args = bake_args(out, extra);
    args.erase(std::find(args.begin(), args.end(), "-q"));
    ASSERT_EQ(wait_for(spawn(args, again, mpirun(3))), 0) << test::read_file(again);
    EXPECT_TRUE(log_has(again, "resuming from the checkpoint")) << test::read_file(again);
    const std::string diff = dir.file("h5diff.txt");
    EXPECT_EQ(test::h5diff_outside_run(reference, out, diff), 0) << test::read_file(diff);
}

TEST(Processes, AMissingWorldEndsEveryRankWithAMessage) {
    // Every rank fails before the first stage; none may wait for the others.
    test::TempDir dir;
    const std::string log = dir.file("log.txt");
    EXPECT_NE(wait_for(spawn({"bake", dir.file("missing.glb"), "-o", dir.file("x.h5")}, log, mpirun(2))), 0);
    EXPECT_TRUE(log_has(log, "missing.glb")) << test::read_file(log);
}
#endif

}  // namespace
}  // namespace pvs
