// SPDX-License-Identifier: MIT
#include "core/row_journal.h"

#include "core/error.h"

#include <fmt/format.h>

#include <algorithm>

namespace pvs {

size_t RowChunk::row_count() const {
    size_t n = 0;
    for (const Table& t : tables) n += t.keys.size();
    return n;
}

RowJournal::RowJournal(Sink sink, double interval_s)
    : sink_(std::move(sink)), interval_(interval_s), last_(std::chrono::steady_clock::now()) {}

void RowJournal::load(const RowChunk& chunk) {
    for (const RowChunk::Table& t : chunk.tables) {
        Loaded& l = loaded_[t.name];
        if (l.at.empty() && l.words.empty()) l.words_per_row = t.words_per_row;
        if (l.words_per_row != t.words_per_row || t.words.size() != t.keys.size() * size_t(t.words_per_row)) {
            throw internal_error(fmt::format("journal table {}: rows of {} words after rows of {}", t.name,
                                             t.words_per_row, l.words_per_row));
        }
        for (size_t i = 0; i < t.keys.size(); ++i) {
            const auto [it, fresh] = l.at.emplace(t.keys[i], l.words.size());
            if (!fresh) continue;  // the same deterministic row twice: keep the first
            l.words.insert(l.words.end(), t.words.begin() + ptrdiff_t(i * t.words_per_row),
                           t.words.begin() + ptrdiff_t((i + 1) * t.words_per_row));
            ++loaded_rows_;
        }
    }
}

bool RowJournal::find(const std::string& table, uint64_t key, uint64_t* row, uint32_t words_per_row) const {
    // `loaded_` changes only in load(), outside parallel regions: no lock.
    const auto t = loaded_.find(table);
    if (t == loaded_.end()) return false;
    const auto at = t->second.at.find(key);
    if (at == t->second.at.end()) return false;
    if (t->second.words_per_row != words_per_row) {
        throw internal_error(fmt::format("journal table {}: asked for rows of {} words, holds rows of {}",
                                         table, words_per_row, t->second.words_per_row));
    }
    std::copy_n(t->second.words.data() + at->second, words_per_row, row);
    return true;
}

void RowJournal::record(const std::string& table, uint64_t key, const uint64_t* row, uint32_t words_per_row) {
    std::lock_guard<std::mutex> lock(mutex_);
    RowChunk::Table& t = pending_[table];
    if (t.keys.empty()) {
        t.name = table;
        t.words_per_row = words_per_row;
    }
    t.keys.push_back(key);
    t.words.insert(t.words.end(), row, row + words_per_row);
    ++recorded_;
    if (interval_.count() > 0.0 && std::chrono::steady_clock::now() - last_ >= interval_) flush_locked();
}

void RowJournal::flush() {
    std::lock_guard<std::mutex> lock(mutex_);
    flush_locked();
}

size_t RowJournal::recorded_rows() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return recorded_;
}

void RowJournal::flush_locked() {
    last_ = std::chrono::steady_clock::now();
    if (pending_.empty()) return;
    RowChunk chunk;
    for (auto& [name, t] : pending_) chunk.tables.push_back(std::move(t));
    pending_.clear();
    if (!sink_ || sink_(chunk)) return;
    for (RowChunk::Table& t : chunk.tables) pending_[t.name] = std::move(t);
}

}  // namespace pvs
