// SPDX-License-Identifier: MIT
// pvsbake driver: one process (built without PVSBAKE_MPI).
#include "driver/processes.h"

namespace pvs {

void start_processes(int&, char**&) {}
bool processes_started() {
    return false;
}
void end_processes() {}
int process_rank() {
    return 0;
}
int process_count() {
    return 1;
}
std::unique_ptr<WorkShare> make_work_share(Context&) {
    return nullptr;
}
void abort_processes(int) {}

}  // namespace pvs
