// Helpers shared by the benchmarks: medians and means of repeats, and wall-clock seconds.
// Every benchmark prints one JSON document on stdout; figures are medians of repeats and ratios taken
// within one run (the machines are shared and noisy). The commands are in docs/RESULTS.md.
#pragma once

#include <algorithm>
#include <chrono>
#include <numeric>
#include <vector>

namespace pvs::bench {

// The median (the mean of the two middle values when there is an even number of them); 0 when empty.
inline double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The arithmetic mean; 0 when empty.
inline double mean(const std::vector<double>& v) {
    return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
}

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace pvs::bench
