// Helpers shared by the benchmarks: medians of repeats and wall-clock seconds.
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

namespace pvs::bench {

inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace pvs::bench
