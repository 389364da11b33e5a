// SPDX-License-Identifier: MIT
// pvsbake core: the Context every stage receives: logs, progress and timers (after Recast's rcContext).
//
// A Context is passed in, never global. It is thread-safe: stages may log and advance progress from
// OpenMP threads. Progress goes to stderr: a live line when stderr is a terminal, a plain line every
// few seconds otherwise, nothing when quiet. Stage timings are kept in order for the report.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace pvs {

enum class LogLevel { kError = 0, kWarning = 1, kInfo = 2, kDebug = 3 };

class Context {
public:
    struct Options {
        LogLevel level = LogLevel::kInfo;
        bool quiet = false;        // no info, no progress (warnings and errors still print)
        std::FILE* sink = stderr;  // where logs and progress go; nullptr = nowhere (tests)
    };

    Context();
    explicit Context(Options options);

    void log(LogLevel level, const std::string& message);
    void error(const std::string& m) { log(LogLevel::kError, m); }
    void warn(const std::string& m) { log(LogLevel::kWarning, m); }
    void info(const std::string& m) { log(LogLevel::kInfo, m); }
    void debug(const std::string& m) { log(LogLevel::kDebug, m); }

    // Warnings given so far (for the report).
    std::vector<std::string> warnings() const;

    // Progress of one stage. begin() then advance() from any thread, then end().
    void progress_begin(const std::string& stage, uint64_t total, const std::string& unit);
    void progress_advance(uint64_t n = 1);
    void progress_end();
    // How far the current (or last) stage has advanced, and its total (0: not known).
    uint64_t progress_done() const { return done_.load(std::memory_order_relaxed); }
    uint64_t progress_total() const { return total_; }

    // Stage timings, in the order stages finished: seconds of wall time and, when measured (cpu_seconds >= 0),
    // CPU seconds of the whole process (every thread) over the same span, so that a stage that leaves the
    // threads idle shows itself (docs/USAGE.md, "Report").
    void add_timing(const std::string& stage, double seconds, double cpu_seconds = -1.0);
    std::vector<std::pair<std::string, double>> timings() const;
    std::vector<std::pair<std::string, double>> cpu_timings() const;  // the stages with CPU seconds

    bool quiet() const { return options_.quiet; }

private:
    void print_progress(bool final_line);

    Options options_;
    bool tty_ = false;
    mutable std::mutex mutex_;
    std::vector<std::string> warnings_;
    std::vector<std::pair<std::string, double>> timings_, cpu_timings_;

    std::string stage_;
    std::string unit_;
    uint64_t total_ = 0;
    std::atomic<uint64_t> done_{0};
    std::chrono::steady_clock::time_point stage_start_;
    std::chrono::steady_clock::time_point last_print_;
    std::mutex progress_mutex_;
};

// CPU seconds the process (all its threads) has used so far.
double process_cpu_seconds();

// Times a stage from construction to destruction, wall and process CPU, and records it in the context.
class ScopedTimer {
public:
    ScopedTimer(Context& ctx, std::string stage)
        : ctx_(ctx),
          stage_(std::move(stage)),
          start_(std::chrono::steady_clock::now()),
          cpu_start_(process_cpu_seconds()) {}
    ~ScopedTimer() { ctx_.add_timing(stage_, seconds(), process_cpu_seconds() - cpu_start_); }
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }
    ScopedTimer(const ScopedTimer&) = delete;
    ScopedTimer& operator=(const ScopedTimer&) = delete;

private:
    Context& ctx_;
    std::string stage_;
    std::chrono::steady_clock::time_point start_;
    double cpu_start_;
};

}  // namespace pvs
