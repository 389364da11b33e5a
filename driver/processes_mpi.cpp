// SPDX-License-Identifier: MIT
// pvsbake driver: the ranks of an MPI job (built with PVSBAKE_MPI=ON; OpenMPI from Debian). Items are dealt
// by one counter on rank 0 that every rank's threads advance with MPI_Fetch_and_op, a batch at a time
// (docs/ALGORITHMS.md#processes); unite() is an MPI_Allreduce with MPI_BOR.
#include "driver/processes.h"

#include "core/error.h"

#include <fmt/format.h>
// The C API only: OpenMPI's mpi.h otherwise pulls in the deprecated C++ bindings, which need libmpi_cxx.
#define OMPI_SKIP_MPICXX 1
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>

namespace pvs {
namespace {

bool g_started = false;

void check(int status, const char* what) {
    if (status != MPI_SUCCESS) throw internal_error(fmt::format("MPI: {} failed ({})", what, status));
}

class MpiShare final : public WorkShare {
public:
    explicit MpiShare(Context& ctx) : ctx_(ctx) {
        MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
        MPI_Comm_size(MPI_COMM_WORLD, &size_);
        const MPI_Aint bytes = rank_ == 0 ? MPI_Aint(sizeof(uint64_t)) : 0;
        check(MPI_Win_allocate(bytes, sizeof(uint64_t), MPI_INFO_NULL, MPI_COMM_WORLD, &counter_, &window_),
              "MPI_Win_allocate");
        open_ = true;
    }
    ~MpiShare() override { close(); }

    int rank() const override { return rank_; }
    int processes() const override { return size_; }

    void begin(uint64_t count) override {
        // Every rank has left the previous pass (its unite() was collective) before the counter restarts.
        check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
        if (rank_ == 0) {
            MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, window_);
            *counter_ = 0;
            MPI_Win_unlock(0, window_);
        }
        check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
        count_ = count;
        shown_ = 0;
    }

    uint64_t next(uint64_t batch, uint64_t& first) override {
        std::lock_guard<std::mutex> lock(mutex_);  // MPI_THREAD_SERIALIZED: one thread in MPI at a time
        MPI_Win_lock(MPI_LOCK_SHARED, 0, 0, window_);
        check(MPI_Fetch_and_op(&batch, &first, MPI_UINT64_T, 0, 0, MPI_SUM, window_), "MPI_Fetch_and_op");
        MPI_Win_unlock(0, window_);
        // Rank 0 shows the whole job's progress: what the counter has dealt to every rank.
        if (rank_ == 0 && first > shown_) {
            const uint64_t reached = std::min(first, count_);
            ctx_.progress_advance(reached - shown_);
            shown_ = reached;
        }
        return first >= count_ ? 0 : (first + batch > count_ ? count_ - first : batch);
    }

    void advance(Context&, uint64_t) override {}  // next() keeps rank 0's progress

    void unite(uint64_t* words, size_t n) override {
        for (size_t at = 0; at < n;) {
            const int part = int(std::min<size_t>(n - at, size_t(1) << 26));
            check(MPI_Allreduce(MPI_IN_PLACE, words + at, part, MPI_UINT64_T, MPI_BOR, MPI_COMM_WORLD),
                  "MPI_Allreduce");
            at += size_t(part);
        }
    }

    void add(uint64_t* values, size_t n) override {
        check(MPI_Allreduce(MPI_IN_PLACE, values, int(n), MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD),
              "MPI_Allreduce");
    }

    void barrier() override { check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier"); }

    void close() override {
        if (!open_) return;
        open_ = false;
        MPI_Win_free(&window_);
    }

private:
    Context& ctx_;
    int rank_ = 0, size_ = 1;
    MPI_Win window_ = MPI_WIN_NULL;
    uint64_t* counter_ = nullptr;
    bool open_ = false;
    uint64_t count_ = 0, shown_ = 0;
    std::mutex mutex_;
};

// The rank an MPI launcher gave this process, or -1 when none started it.
int launcher_rank() {
    for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"}) {
        const char* value = std::getenv(name);
        if (value && *value) return std::max(0, std::atoi(value));
    }
    return std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMI_SIZE") ? 0 : -1;
}

}  // namespace

void start_processes(int& argc, char**& argv) {
    const bool shared = argc >= 2 && (std::strcmp(argv[1], "bake") == 0 || std::strcmp(argv[1], "verify") == 0);
    if (!shared || launcher_rank() < 0) return;
    int provided = 0;
    if (MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS) return;
    g_started = true;
    if (provided < MPI_THREAD_SERIALIZED) {
        std::fprintf(stderr, "error: MPI gives no MPI_THREAD_SERIALIZED support\n");
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
}

void end_processes() {
    if (g_started) MPI_Finalize();
    g_started = false;
}

bool processes_started() {
    return g_started;
}

int process_rank() {
    if (!g_started) return std::max(0, launcher_rank());
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
}

int process_count() {
    int size = 1;
    if (g_started) MPI_Comm_size(MPI_COMM_WORLD, &size);
    return size;
}

std::unique_ptr<WorkShare> make_work_share(Context& ctx) {
    if (process_count() <= 1) return nullptr;
    return std::make_unique<MpiShare>(ctx);
}

void abort_processes(int status) {
    if (g_started && process_count() > 1) MPI_Abort(MPI_COMM_WORLD, status);
}

}  // namespace pvs
