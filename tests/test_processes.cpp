// SPDX-License-Identifier: MIT
// The processes of a bake (driver/processes.h): MPI starts only for a bake or a verification that an MPI
// launcher started; every other command, and a bake run alone, starts no MPI runtime.
#include "driver/processes.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

namespace pvs {
namespace {

// The launcher's variables set (or cleared) for the scope of a test.
struct LauncherEnv {
    static constexpr const char* kNames[] = {"OMPI_COMM_WORLD_SIZE", "OMPI_COMM_WORLD_RANK", "PMIX_RANK",
                                             "PMI_RANK", "PMI_SIZE"};
    LauncherEnv(const char* size, const char* rank) {
        for (const char* n : kNames) unsetenv(n);
        if (size) setenv("OMPI_COMM_WORLD_SIZE", size, 1);
        if (rank) setenv("OMPI_COMM_WORLD_RANK", rank, 1);
    }
    ~LauncherEnv() {
        for (const char* n : kNames) unsetenv(n);
    }
};

void start(const char* command) {
    std::vector<std::string> words{"pvsbake", command};
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    int argc = int(words.size());
    char** p = argv.data();
    start_processes(argc, p);
}

TEST(Processes, NoCommandRunAloneStartsMpi) {
    const LauncherEnv none(nullptr, nullptr);
    for (const char* command : {"bake", "verify", "occluders", "info", "query", "--version", "--help"}) {
        start(command);
        EXPECT_FALSE(processes_started()) << command;
        EXPECT_EQ(process_rank(), 0);
        EXPECT_EQ(process_count(), 1);
        end_processes();
    }
}

// Under mpirun, a command that shares no work starts no MPI either, and only the launcher's rank 0 speaks
// (the others see their rank and leave, as with MPI).
TEST(Processes, UnderALauncherACommandThatSharesNoWorkStartsNoMpi) {
    const LauncherEnv rank2("3", "2");
    for (const char* command : {"info", "query", "occluders", "--version"}) {
        start(command);
        EXPECT_FALSE(processes_started()) << command;
#ifdef PVSBAKE_MPI
        EXPECT_EQ(process_rank(), 2) << command;
#else
        EXPECT_EQ(process_rank(), 0) << command;
#endif
        EXPECT_EQ(process_count(), 1) << command;
        end_processes();
    }
}

}  // namespace
}  // namespace pvs
