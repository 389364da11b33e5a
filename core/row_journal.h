// SPDX-License-Identifier: MIT
// pvsbake core: the journal of finished rows, what makes a long stage resumable
// (docs/ALGORITHMS.md#resume).
//
// A stage whose rows are deterministic functions of the world, the parameters and rows finished before them
// (the conservative solver's face rows, an octree box's row) records each row once it is final, under a
// table name and a key that identify it in every run (a face index, an octree node's stream). Rows recorded
// are handed to a sink in chunks: every `interval_s` seconds (by the thread that records a row then) and at
// flush(), which stages call at their ends. A later run loads the chunks a killed run left and looks each
// row up before computing it: what it finds is the row an uninterrupted run computes, so the output is the
// same.
//
// Thread-safe: find() and record() may be called from any thread; load() and flush() from one thread
// outside parallel regions. The sink runs under the journal's lock.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

namespace pvs {

// Rows of some tables, as written to and read from a checkpoint (io/checkpoint.h).
struct RowChunk {
    struct Table {
        std::string name;
        uint32_t words_per_row = 0;
        std::vector<uint64_t> keys;
        std::vector<uint64_t> words;  // keys.size() * words_per_row
    };
    std::vector<Table> tables;
    size_t row_count() const;
};

class RowJournal {
public:
    // Writes a chunk; returns false when it could not (the rows stay for the next chunk). Must not throw.
    using Sink = std::function<bool(const RowChunk&)>;
    // interval_s <= 0: chunks go to the sink only at flush().
    RowJournal(Sink sink, double interval_s);

    // Adds the rows of a chunk an earlier run wrote. Throws pvs::Error (internal) when a table's row width
    // differs from one loaded before.
    void load(const RowChunk& chunk);
    size_t loaded_rows() const { return loaded_rows_; }

    // Copies the row of (table, key) into `row` (words_per_row words) and returns true, if a run recorded it.
    bool find(const std::string& table, uint64_t key, uint64_t* row, uint32_t words_per_row) const;

    // Records a finished row; the sink gets it with the next chunk.
    void record(const std::string& table, uint64_t key, const uint64_t* row, uint32_t words_per_row);

    // Hands every row recorded since the last chunk to the sink (nothing when there is none).
    void flush();

    size_t recorded_rows() const;

private:
    struct Loaded {
        uint32_t words_per_row = 0;
        std::unordered_map<uint64_t, size_t> at;  // key -> offset in words
        std::vector<uint64_t> words;
    };
    void flush_locked();

    Sink sink_;
    std::chrono::duration<double> interval_;
    std::chrono::steady_clock::time_point last_;
    std::map<std::string, Loaded> loaded_;
    size_t loaded_rows_ = 0;
    mutable std::mutex mutex_;
    std::map<std::string, RowChunk::Table> pending_;
    size_t recorded_ = 0;
};

}  // namespace pvs
