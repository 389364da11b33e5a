// SPDX-License-Identifier: MIT
// pvsbake core: small, fast, seedable random numbers for sampling.
//
// Every random stream is derived from (seed, stream id), e.g. (config seed, cell index), never from
// thread ids or time, so results are identical for any thread count and any schedule.
#pragma once

#include <cstdint>

namespace pvs {

// SplitMix64 (Steele, Lea, Flood 2014): a good 64-bit mixer and a small generator.
inline uint64_t mix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

class Rng {
public:
    Rng(uint64_t seed, uint64_t stream) : state_(mix64(seed ^ mix64(stream + 0x632be59bd9b4e019ULL))) {}
    uint64_t next() {
        state_ += 0x9e3779b97f4a7c15ULL;
        uint64_t z = state_;
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        return z ^ (z >> 31);
    }
    // Uniform in [0, 1).
    float uniform() { return float(next() >> 40) * (1.0f / 16777216.0f); }
    // Uniform integer in [0, n).
    uint32_t below(uint32_t n) { return uint32_t((next() >> 32) * uint64_t(n) >> 32); }

private:
    uint64_t state_;
};

}  // namespace pvs
