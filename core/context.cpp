// SPDX-License-Identifier: MIT
#include "core/context.h"

#include <ctime>

#include <fmt/format.h>
#include <unistd.h>

namespace pvs {

namespace {
const char* level_prefix(LogLevel level) {
    switch (level) {
        case LogLevel::kError:
            return "error: ";
        case LogLevel::kWarning:
            return "warning: ";
        case LogLevel::kInfo:
            return "";
        case LogLevel::kDebug:
            return "debug: ";
    }
    return "";
}
constexpr double kPlainProgressIntervalS = 5.0;
constexpr double kTtyProgressIntervalS = 0.2;
}  // namespace

Context::Context() : Context(Options{}) {}

Context::Context(Options options) : options_(options) {
    tty_ = options_.sink != nullptr && isatty(fileno(options_.sink));
}

void Context::log(LogLevel level, const std::string& message) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (level == LogLevel::kWarning) warnings_.push_back(message);
    if (options_.sink == nullptr) return;
    if (level > options_.level) return;
    if (options_.quiet && level > LogLevel::kWarning) return;
    if (tty_ && !stage_.empty()) std::fputs("\r\033[K", options_.sink);  // clear a live progress line
    std::fprintf(options_.sink, "%s%s\n", level_prefix(level), message.c_str());
    std::fflush(options_.sink);
}

std::vector<std::string> Context::warnings() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return warnings_;
}

void Context::progress_begin(const std::string& stage, uint64_t total, const std::string& unit) {
    std::lock_guard<std::mutex> lock(progress_mutex_);
    stage_ = stage;
    unit_ = unit;
    total_ = total;
    done_ = 0;
    stage_start_ = last_print_ = std::chrono::steady_clock::now();
}

void Context::progress_advance(uint64_t n) {
    done_.fetch_add(n, std::memory_order_relaxed);
    if (options_.quiet || options_.sink == nullptr) return;
    std::unique_lock<std::mutex> lock(progress_mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    const auto now = std::chrono::steady_clock::now();
    const double since = std::chrono::duration<double>(now - last_print_).count();
    if (since < (tty_ ? kTtyProgressIntervalS : kPlainProgressIntervalS)) return;
    last_print_ = now;
    print_progress(false);
}

void Context::progress_end() {
    std::lock_guard<std::mutex> lock(progress_mutex_);
    if (!options_.quiet && options_.sink != nullptr && tty_) std::fputs("\r\033[K", options_.sink);
    stage_.clear();
}

void Context::print_progress(bool /*final_line*/) {
    const uint64_t done = done_.load(std::memory_order_relaxed);
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - stage_start_).count();
    const double rate = elapsed > 0 ? double(done) / elapsed : 0.0;
    const double left = rate > 0 && total_ > done ? double(total_ - done) / rate : 0.0;
    const double pct = total_ ? 100.0 * double(done) / double(total_) : 100.0;
    const std::string line = total_ ? fmt::format("{}: {}/{} {} ({:.1f}%), {:.1f} {}/s, {:.0f} s left",
                                                  stage_, done, total_, unit_, pct, rate, unit_, left)
                                    : fmt::format("{}: {} {}, {:.1f} {}/s", stage_, done, unit_, rate, unit_);
    std::lock_guard<std::mutex> lock(mutex_);
    if (tty_) {
        std::fprintf(options_.sink, "\r\033[K%s", line.c_str());
    } else {
        std::fprintf(options_.sink, "%s\n", line.c_str());
    }
    std::fflush(options_.sink);
}

void Context::add_timing(const std::string& stage, double seconds, double cpu_seconds) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        timings_.emplace_back(stage, seconds);
        if (cpu_seconds >= 0.0) cpu_timings_.emplace_back(stage, cpu_seconds);
    }
    debug(cpu_seconds >= 0.0 ? fmt::format("stage {} took {:.3f} s ({:.3f} CPU s)", stage, seconds, cpu_seconds)
                             : fmt::format("stage {} took {:.3f} s", stage, seconds));
}

std::vector<std::pair<std::string, double>> Context::timings() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return timings_;
}

std::vector<std::pair<std::string, double>> Context::cpu_timings() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return cpu_timings_;
}

double process_cpu_seconds() {
    timespec t{};
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t) != 0) return 0.0;
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

}  // namespace pvs
