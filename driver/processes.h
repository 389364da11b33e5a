// SPDX-License-Identifier: MIT
// pvsbake driver: the processes of a bake. One, or the ranks of an MPI job when pvsbake is built with
// PVSBAKE_MPI=ON and started by mpirun (docs/ALGORITHMS.md#processes). Every rank runs the whole command: the
// stages before the PVS with their probes, ray check and shrunk levels dealt between the ranks
// (docs/ALGORITHMS.md#dealt-stages), the PVS with its passes dealt (core/work_share.h), and so are the
// occluder ranking and the verification; rank 0 alone writes the output.
#pragma once

#include "core/context.h"
#include "core/work_share.h"

#include <memory>

namespace pvs {

// Starts the job's processes (MPI_Init_thread under MPI); once, from main, before anything else. MPI starts
// only for a command that shares work between ranks (`bake`, `verify`: argv[1]) in a process an MPI launcher
// started (mpirun sets OMPI_COMM_WORLD_SIZE, PMIX_RANK or PMI_RANK); every other command, and a bake run
// alone, starts no MPI runtime (no orted daemon).
void start_processes(int& argc, char**& argv);
// Did start_processes() start MPI?
bool processes_started();
// Ends them (MPI_Finalize); once, from main, after everything else.
void end_processes();
// This process's rank and the number of processes: 0 and 1 without MPI. Without MPI started, a process that
// an MPI launcher started has the launcher's rank (so that only rank 0 of such a job speaks) and a count of 1.
int process_rank();
int process_count();
// A share of the PVS passes between the processes, its progress shown by rank 0 on `ctx`; null for one
// process. Collective: every process creates it.
std::unique_ptr<WorkShare> make_work_share(Context& ctx);
// Ends every process of the job with `status` (MPI_Abort: a rank that fails must not leave the others
// waiting for it forever); returns only without MPI or with one process.
void abort_processes(int status);

}  // namespace pvs
