// SPDX-License-Identifier: MIT
// pvsbake core: how the items of a pass (grid faces, cells, octree boxes) are shared between the processes
// of a bake (docs/ALGORITHMS.md#processes).
//
// A pass deals its items in batches: every thread of every process asks next() for the next batch until none
// is left, so a process whose items are costly simply takes fewer (items differ in cost by orders of
// magnitude). What one item computes depends only on the item and on what earlier passes computed, so the
// result does not depend on who computed what. At the pass's end every process calls unite() on each array
// the pass wrote: it ORs the array over all processes, and every process then holds the union. An item's
// output is written only by the process that computed it, and is zero elsewhere.
//
// One process (this class): every item is its own and unite() does nothing. Under MPI, driver/mpi_share.h.
// begin() and unite() are collective: every process calls them, in the same order, from one thread.
#pragma once

#include "core/context.h"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pvs {

class WorkShare {
public:
    virtual ~WorkShare() = default;
    virtual int rank() const { return 0; }
    virtual int processes() const { return 1; }

    // Starts a pass over `count` items.
    virtual void begin(uint64_t count) {
        count_ = count;
        next_.store(0, std::memory_order_relaxed);
    }
    // The next batch of at most `batch` items, [first, first + n); returns n, 0 when none is left.
    // Thread-safe.
    virtual uint64_t next(uint64_t batch, uint64_t& first) {
        first = next_.fetch_add(batch, std::memory_order_relaxed);
        return first >= count_ ? 0 : (first + batch > count_ ? count_ - first : batch);
    }
    // Advances the progress by `n` items this process finished (under MPI, rank 0 shows the whole job's).
    virtual void advance(Context& ctx, uint64_t n) { ctx.progress_advance(n); }
    // ORs words[0, n) over every process.
    virtual void unite(uint64_t* /*words*/, size_t /*n*/) {}
    // Sums values[0, n) over every process (the counts of a dealt pass; each process counts its own items).
    virtual void add(uint64_t* /*values*/, size_t /*n*/) {}
    // Waits until every process calls it.
    virtual void barrier() {}
    // Ends the sharing (frees what the processes share); collective. No pass may begin after it.
    virtual void close() {}

private:
    uint64_t count_ = 0;
    std::atomic<uint64_t> next_{0};
};

// Calls fn(i) for every item the share deals this thread, `batch` at a time; from every thread of a parallel
// region, between begin() and unite().
template <class Fn>
void for_each_dealt(WorkShare& share, Context& ctx, uint64_t batch, Fn&& fn) {
    uint64_t first = 0;
    while (const uint64_t n = share.next(batch, first)) {
        for (uint64_t i = first; i < first + n; ++i) fn(i);
        share.advance(ctx, n);
    }
}

// Every process's `words`, one after another in rank order, on every process. Collective.
inline std::vector<uint64_t> gather_all(WorkShare& share, const std::vector<uint64_t>& words) {
    const size_t processes = size_t(share.processes()), rank = size_t(share.rank());
    if (processes == 1) return words;
    std::vector<uint64_t> sizes(processes, 0);
    sizes[rank] = words.size();
    share.unite(sizes.data(), sizes.size());
    size_t at = 0, total = 0;
    for (size_t p = 0; p < processes; ++p) {
        if (p == rank) at = total;
        total += size_t(sizes[p]);
    }
    std::vector<uint64_t> all(total, 0);
    std::copy(words.begin(), words.end(), all.begin() + std::ptrdiff_t(at));
    share.unite(all.data(), all.size());
    return all;
}

// Gives every process `words` as process `owner` holds them (the others' are replaced, whatever their size):
// for a result one process computed alone. Collective.
inline void take_from(WorkShare& share, int owner, std::vector<uint64_t>& words) {
    if (share.processes() == 1) return;
    uint64_t n = share.rank() == owner ? uint64_t(words.size()) : 0;
    share.unite(&n, 1);
    if (share.rank() != owner) words.assign(size_t(n), 0);
    share.unite(words.data(), words.size());
}

}  // namespace pvs
