// SPDX-License-Identifier: MIT
// bench_horizon: the runtime's occlusion horizon (pvsr_horizon, runtime/pvsr.h) alone, on frames recorded by
// bench_frame --horizon-record, so that its cost is measured apart from the rays and the bench's own model.
//
//   bench_horizon RECORD [--columns N] [--repeats R] [--pieces P]
//
// RECORD (little-endian): "PVHZ", uint32 version 2, uint32 frames; per frame: float eye[3]; uint32 boxes,
// float box[6] each; uint32 polygons, each float plane[5], uint32 tile (1: added as a tile), uint32
// corners, float corner[3] each; uint32 tests, float bounds[6] each (the objects the frame's culler drew).
// Per frame, R times (default 5), on one thread: begin, every box and polygon added, end (the build), then
// every test box (the tests); a frame's time is the median of its R. Figures: medians and 90th percentiles
// over frames of the build (and the median of its end alone), the tests and both, in microseconds; pieces a
// frame (mean); boxes hidden in all. N columns a side frame (default 256), memory for P pieces (default
// 2^20). Prints JSON on stdout; exit status 2 on a bad record or option.
#include "pvsr.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Polygon {
    float plane[5];
    uint32_t tile = 0;
    std::vector<float> corners;
};

struct Frame {
    float eye[3];
    std::vector<float> boxes, tests;  // 6 floats each
    std::vector<Polygon> polygons;
};

class Reader {
public:
    explicit Reader(std::vector<char> bytes) : bytes_(std::move(bytes)) {}
    void get(void* p, size_t n) {
        if (n > bytes_.size() - at_) throw std::runtime_error("the record ends early");
        std::memcpy(p, bytes_.data() + at_, n);
        at_ += n;
    }
    uint32_t u32(uint32_t limit) {
        uint32_t x = 0;
        get(&x, 4);
        if (x > limit) throw std::runtime_error("a count past its limit (" + std::to_string(x) + ")");
        return x;
    }
    void floats(std::vector<float>& v, size_t n) {
        if (n > (bytes_.size() - at_) / 4) throw std::runtime_error("the record ends early");
        v.resize(n);
        get(v.data(), n * 4);
    }
    bool done() const { return at_ == bytes_.size(); }

private:
    std::vector<char> bytes_;
    size_t at_ = 0;
};

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

double p90(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, v.size() * 9 / 10)];
}

long parse(const std::string& option, const char* v, long lo, long hi) {
    char* end = nullptr;
    const long x = std::strtol(v, &end, 10);
    if (end == v || *end != '\0' || x < lo || x > hi)
        throw std::invalid_argument(option + " " + v + ": wants a whole number in [" + std::to_string(lo) +
                                    ", " + std::to_string(hi) + "]");
    return x;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fputs("usage: bench_horizon RECORD [--columns N] [--repeats R] [--pieces P]\n", stderr);
        return 2;
    }
    int columns = 256, repeats = 5;
    long pieces = 1L << 20;
    std::vector<Frame> frames;
    try {
        for (int a = 2; a < argc; a += 2) {
            const std::string k = argv[a];
            if (a + 1 >= argc) throw std::invalid_argument(k + " wants a value");
            if (k == "--columns")
                columns = int(parse(k, argv[a + 1], PVSR_HORIZON_MIN_COLUMNS, PVSR_HORIZON_MAX_COLUMNS));
            else if (k == "--repeats")
                repeats = int(parse(k, argv[a + 1], 1, 1000));
            else if (k == "--pieces")
                pieces = parse(k, argv[a + 1], 1, 1L << 26);
            else
                throw std::invalid_argument("unknown option " + k);
        }
        std::ifstream in(argv[1], std::ios::binary);
        if (!in) throw std::invalid_argument(std::string(argv[1]) + ": cannot read it");
        Reader r(std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()));
        char magic[4];
        r.get(magic, 4);
        if (std::memcmp(magic, "PVHZ", 4) != 0 || r.u32(2) != 2)
            throw std::runtime_error("not a horizon record of version 2");
        frames.resize(r.u32(1u << 24));
        for (Frame& f : frames) {
            r.get(f.eye, sizeof f.eye);
            r.floats(f.boxes, 6 * size_t(r.u32(1u << 24)));
            f.polygons.resize(r.u32(1u << 24));
            for (Polygon& p : f.polygons) {
                r.get(p.plane, sizeof p.plane);
                p.tile = r.u32(1);
                r.floats(p.corners, 3 * size_t(r.u32(PVSR_HORIZON_MAX_CORNERS)));
            }
            r.floats(f.tests, 6 * size_t(r.u32(1u << 24)));
        }
        if (!r.done()) throw std::runtime_error("bytes after the last frame");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s: %s\n", argv[1], e.what());
        return 2;
    }

    std::vector<uint64_t> memory(pvsr_horizon_memory_bytes(columns, size_t(pieces)) / 8 + 1);
    pvsr_horizon h;
    if (!pvsr_horizon_init(&h, columns, size_t(pieces), memory.data(), memory.size() * 8)) {
        std::fputs("error: the horizon did not take its memory\n", stderr);
        return 2;
    }
    using Clock = std::chrono::steady_clock;
    const auto us = [](Clock::time_point a, Clock::time_point b) {
        return std::chrono::duration<double, std::micro>(b - a).count();
    };
    std::vector<double> build_us, end_us, test_us, total_us;
    double pieces_sum = 0.0;
    uint64_t hidden = 0, tests = 0, dropped = 0;
    for (const Frame& f : frames) {
        std::vector<double> b(static_cast<size_t>(repeats)), t(static_cast<size_t>(repeats)),
            e(static_cast<size_t>(repeats));
        uint32_t frame_hidden = 0;
        for (int k = 0; k < repeats; ++k) {
            const auto t0 = Clock::now();
            pvsr_horizon_begin(&h, f.eye);
            for (size_t i = 0; i < f.boxes.size(); i += 6) pvsr_horizon_add_box(&h, &f.boxes[i]);
            for (const Polygon& p : f.polygons)
                (p.tile ? pvsr_horizon_add_tile : pvsr_horizon_add_polygon)(&h, p.plane, p.corners.data(),
                                                                            uint32_t(p.corners.size() / 3));
            const auto te = Clock::now();
            pvsr_horizon_end(&h);
            const auto t1 = Clock::now();
            frame_hidden = 0;
            for (size_t i = 0; i < f.tests.size(); i += 6)
                frame_hidden += uint32_t(pvsr_horizon_is_hidden(&h, &f.tests[i]));
            const auto t2 = Clock::now();
            b[size_t(k)] = us(t0, t1);
            e[size_t(k)] = us(te, t1);
            t[size_t(k)] = us(t1, t2);
        }
        build_us.push_back(median(b));
        end_us.push_back(median(e));
        test_us.push_back(median(t));
        total_us.push_back(build_us.back() + test_us.back());
        pieces_sum += double(h.count);
        dropped += h.dropped;
        hidden += frame_hidden;
        tests += f.tests.size() / 6;
    }
    std::printf(
        "{\n  \"bench\": \"horizon\",\n  \"record\": \"%s\",\n  \"frames\": %zu,\n  \"columns\": %d,\n"
        "  \"repeats\": %d,\n  \"pieces_mean\": %.2f,\n  \"pieces_dropped\": %llu,\n  \"tests\": %llu,\n"
        "  \"hidden\": %llu,\n  \"build_us_median\": %.3f,\n  \"build_us_p90\": %.3f,\n"
        "  \"end_us_median\": %.3f,\n"
        "  \"test_us_median\": %.3f,\n  \"test_us_p90\": %.3f,\n  \"frame_us_median\": %.3f,\n"
        "  \"frame_us_p90\": %.3f\n}\n",
        argv[1], frames.size(), columns, repeats, frames.empty() ? 0.0 : pieces_sum / double(frames.size()),
        static_cast<unsigned long long>(dropped), static_cast<unsigned long long>(tests),
        static_cast<unsigned long long>(hidden), median(build_us), p90(build_us), median(end_us),
        median(test_us), p90(test_us), median(total_us), p90(total_us));
    return 0;
}
