// SPDX-License-Identifier: MIT
// Verification of a PVS against Embree rays: misses, sampled visible sets, overestimation.
// Aimed rays after Wonka et al., "Guided visibility sampling" (SIGGRAPH 2006): rays from random eye points
// to random points on the objects uniform sampling did not touch.
#include "driver/verify.h"

#include "cells/eyes.h"
#include "core/random.h"
#include "rays/clearance.h"
#include "rays/ray_sampler.h"
#include "rays/surface_points.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <type_traits>
#include <cmath>
#include <limits>

namespace pvs {

namespace {

struct Stats {
    double mean = 0, median = 0, max = 0;
};

Stats stats_of(std::vector<double> v) {
    Stats s;
    if (v.empty()) return s;
    double sum = 0;
    for (double x : v) {
        sum += x;
        s.max = std::max(s.max, x);
    }
    s.mean = sum / double(v.size());
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    s.median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    return s;
}

uint64_t row_triangles(const World& world, const PvsSet& set, uint32_t cell) {
    uint64_t tris = 0;
    const uint64_t* row = set.row(cell);
    for (uint32_t w = 0; w < set.words_per_row; ++w) {
        uint64_t bits = row[w];
        while (bits) {
            const uint32_t o = w * 64 + uint32_t(__builtin_ctzll(bits));
            bits &= bits - 1;
            tris += world.objects[o].triangle_count;
        }
    }
    return tris;
}

// Random streams of the aimed rays, apart from the uniform ones (whose eye stream is the cell index and
// whose direction stream is (cell << 20) ^ eye).
constexpr uint64_t kAimedEyeStream = uint64_t(0x41494d) << 40;         // | cell (no budget), ^ (cell, batch)
constexpr uint64_t kAimedSubsetStream = uint64_t(0x535542) << 40;      // ^ (cell, round): which candidates
constexpr uint64_t kAimedPointStream = uint64_t(0x505453) << 40;       // ^ (cell << 20) ^ eye: target points
constexpr uint64_t kNeighbourEyeStream = uint64_t(0x4e4559) << 40;     // ^ (cell, 0): fallback eyes
constexpr uint64_t kNeighbourSubsetStream = uint64_t(0x4e5342) << 40;  // ^ (cell, round): which witnesses
constexpr float kMinAimDistanceM = 1e-4f;                              // closer targets give no direction
constexpr uint32_t kMaxNeighbourPasses = 8;
constexpr float kNeighbourEyeInsetM = 1e-3f;  // a witness's eye moved into a cell stays this far inside
// The eye points of the aimed rounds of a cell come in batches of 16, stratified over the cell's eye region
// and taken in bit-reversed order, so the first 2, 4, 8 rounds of a batch already spread over the region.
constexpr uint32_t kRoundEyesPerBatch = 16;
constexpr uint8_t kRoundEyeOrder[kRoundEyesPerBatch] = {0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15};

// A stream of (cell, index), one per pair, for a purpose tagged by `tag`.
uint64_t cell_stream(uint64_t tag, uint32_t cell, uint32_t index) {
    return tag ^ mix64((uint64_t(cell) << 32) | index);
}

// The aimed rays of one cell. Without a budget eye e's rays are [first[e], first[e + 1]) in `directions`;
// with one, a round has one eye and its rays are all of `directions`.
struct AimedRays {
    std::vector<uint32_t> listed;    // candidates the PVS lists, increasing
    std::vector<uint32_t> left_out;  // candidates the PVS leaves out, increasing
    std::vector<uint32_t> targets;   // of a round (or every candidate without a budget), increasing
    std::vector<glm::vec3> eyes;
    std::vector<uint32_t> first;
    std::vector<glm::vec3> directions;
    std::vector<RayTouch> touches;      // ray = index into directions
    std::vector<glm::vec3> batch_eyes;  // the eye points of batch `batch` of the rounds
    uint32_t batch = UINT32_MAX;
    std::vector<uint64_t> cell_voxels;  // the eye voxels of cell `voxels_of` (eye_voxels_in), drawn from
    uint32_t voxels_of = UINT32_MAX;    // by every batch of the cell's rounds
};

// Appends one ray per object of `targets` from `eye` at a random point on the object (none for an object
// closer than kMinAimDistanceM).
void aim_from(const World& world, const std::vector<double>& cum_area, const glm::vec3& eye,
              const std::vector<uint32_t>& targets, Rng& rng, std::vector<glm::vec3>& directions) {
    for (uint32_t o : targets) {
        const glm::vec3 d = random_point_on(world, cum_area, o, rng) - eye;
        const float len = glm::length(d);
        if (len < kMinAimDistanceM) continue;
        directions.push_back(d / len);
    }
}

// Without a budget: `eye_count` eye points each aim one ray at a random point on every object of `targets`.
void trace_aimed(const RayScene& scene, const World& world, const std::vector<double>& cum_area,
                 const CellSet& cells, uint32_t c, uint32_t eye_count, uint64_t seed, AimedRays& out) {
    out.eyes.clear();
    out.first.assign(1, 0);
    out.directions.clear();
    out.touches.clear();
    sample_eye_points_in(cells, cells.cells[c].bounds, kAimedEyeStream | c, eye_count, seed, out.eyes);
    for (uint32_t e = 0; e < out.eyes.size(); ++e) {
        Rng rng(seed, kAimedPointStream ^ (uint64_t(c) << 20) ^ e);
        const uint32_t begin = uint32_t(out.directions.size());
        aim_from(world, cum_area, out.eyes[e], out.targets, rng, out.directions);
        const uint32_t count = uint32_t(out.directions.size()) - begin;
        out.first.push_back(begin + count);
        const size_t t0 = out.touches.size();
        scene.trace(out.eyes[e], out.directions.data() + begin, count, out.touches);
        for (size_t i = t0; i < out.touches.size(); ++i) out.touches[i].ray += begin;
    }
}

// Round `round` of cell c: one eye point (from its batch) aims one ray at every object of `out.targets`.
// False when the cell has no eye point (no eye voxel in it): nothing traced.
bool trace_round(const RayScene& scene, const World& world, const std::vector<double>& cum_area,
                 const CellSet& cells, uint32_t c, uint32_t round, uint64_t seed, AimedRays& out) {
    const uint32_t batch = round / kRoundEyesPerBatch, slot = kRoundEyeOrder[round % kRoundEyesPerBatch];
    if (batch != out.batch) {
        out.batch = batch;
        out.batch_eyes.clear();
        if (out.voxels_of != c) {
            out.voxels_of = c;
            out.cell_voxels = eye_voxels_in(cells, cells.cells[c].bounds);
        }
        sample_eye_points_from(cells, cells.cells[c].bounds, out.cell_voxels,
                               cell_stream(kAimedEyeStream, c, batch), kRoundEyesPerBatch, seed,
                               out.batch_eyes);
    }
    out.eyes.clear();
    out.directions.clear();
    out.touches.clear();
    if (slot >= out.batch_eyes.size()) return false;
    out.eyes.push_back(out.batch_eyes[slot]);
    Rng rng(seed, cell_stream(kAimedPointStream, c, round));
    aim_from(world, cum_area, out.eyes[0], out.targets, rng, out.directions);
    scene.trace(out.eyes[0], out.directions.data(), uint32_t(out.directions.size()), out.touches);
    return true;
}

// Where a ray of a cell first touched an object: the neighbour pass aims at these points from the cells
// around.
struct Witness {
    uint32_t object = 0;
    glm::vec3 eye{0.0f};
    glm::vec3 point{0.0f};
};

// A thread's counters, summed at the end.
struct Counts {
    uint64_t rays = 0, aimed_rays = 0, aimed_listed_rays = 0, aimed_candidates = 0,
             aimed_listed_candidates = 0, aimed_targets = 0, aimed_new = 0, aimed_listed_new = 0,
             aimed_missed = 0, aimed_rounds = 0, neighbour_rays = 0, neighbour_targets = 0, neighbour_new = 0,
             neighbour_listed_new = 0, neighbour_missed = 0;
    void add(const Counts& o) {
        rays += o.rays;
        aimed_rays += o.aimed_rays;
        aimed_listed_rays += o.aimed_listed_rays;
        aimed_candidates += o.aimed_candidates;
        aimed_listed_candidates += o.aimed_listed_candidates;
        aimed_targets += o.aimed_targets;
        aimed_new += o.aimed_new;
        aimed_listed_new += o.aimed_listed_new;
        aimed_missed += o.aimed_missed;
        aimed_rounds += o.aimed_rounds;
        neighbour_rays += o.neighbour_rays;
        neighbour_targets += o.neighbour_targets;
        neighbour_new += o.neighbour_new;
        neighbour_listed_new += o.neighbour_listed_new;
        neighbour_missed += o.neighbour_missed;
    }
};

// Per cell, the other cells whose closed boxes meet its own (by a face, an edge or a corner), increasing.
// A sweep over the cells sorted by min x: a grid cell meets only the cells of its own and the next slab.
std::vector<std::vector<uint32_t>> touching_cells(const CellSet& cells) {
    const uint32_t n = uint32_t(cells.size());
    std::vector<uint32_t> order(n);
    for (uint32_t i = 0; i < n; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        const float xa = cells.cells[a].bounds.min.x, xb = cells.cells[b].bounds.min.x;
        return xa < xb || (xa == xb && a < b);
    });
    constexpr float kTouchToleranceM = 1e-4f;
    std::vector<std::vector<uint32_t>> out(n);
    for (uint32_t i = 0; i < n; ++i) {
        const Aabb& a = cells.cells[order[i]].bounds;
        for (uint32_t j = i + 1; j < n; ++j) {
            const Aabb& b = cells.cells[order[j]].bounds;
            if (b.min.x > a.max.x + kTouchToleranceM) break;
            bool meet = true;
            for (int k = 1; k < 3 && meet; ++k)
                meet = b.min[k] <= a.max[k] + kTouchToleranceM && a.min[k] <= b.max[k] + kTouchToleranceM;
            if (!meet) continue;
            out[order[i]].push_back(order[j]);
            out[order[j]].push_back(order[i]);
        }
    }
    for (std::vector<uint32_t>& v : out) std::sort(v.begin(), v.end());
    return out;
}

// The rays of one cell, pass by pass; one per thread. Writes only the cell's own row of `sampled`, its
// misses and its witnesses, so cells run in parallel with the same result for any thread count.
class CellVerifier {
public:
    struct Shared {
        const VerifyConfig& config;
        const World& world;
        const RayScene& scene;
        const CellSet& cells;
        const PvsSet& pvs;
        const std::vector<double>& cum_area;
        PvsSet& sampled;
        std::vector<std::vector<Miss>> cell_misses;
        std::vector<uint64_t> cell_missed_rays;
        bool aim_capped = false;
        PvsSet aimed_at;                              // per cell: the objects an aimed round aimed at
        std::vector<uint32_t> rounds_of;              // per cell: aimed rounds of the first pass
        std::vector<std::vector<Witness>> witnesses;  // per cell: first touches of the last pass (or none)
    };

    Counts counts;

    explicit CellVerifier(Shared& shared) : s_(shared), n_objects_(uint32_t(shared.world.objects.size())) {}

    // Uniform rays, then `budget` aimed rays in rounds (or every candidate from eyes_per_cell eyes without
    // a budget). Records the cell's witnesses when the neighbour pass will need them.
    void first_pass(uint32_t c, uint32_t rays_per_eye, bool aim, uint64_t budget) {
        begin_cell(c, s_.witnesses.empty() ? nullptr : &s_.witnesses[c]);
        trace_cell(s_.scene, s_.cells, c, s_.config.rays, rays_per_eye, rays_);
        counts.rays += uint64_t(rays_.eyes.size()) * rays_.rays_per_eye;
        for (const RayTouch& t : rays_.touches)
            see(t, rays_.eyes[t.ray / rays_.rays_per_eye], rays_.directions[t.ray]);
        if (!aim) return;
        collect_candidates();
        counts.aimed_candidates += aimed_.listed.size() + aimed_.left_out.size();
        counts.aimed_listed_candidates += aimed_.listed.size();
        if (!s_.aim_capped) {
            // No budget: eyes_per_cell eye points aim at every candidate.
            aimed_.targets.resize(aimed_.listed.size() + aimed_.left_out.size());
            std::merge(aimed_.listed.begin(), aimed_.listed.end(), aimed_.left_out.begin(),
                       aimed_.left_out.end(), aimed_.targets.begin());
            if (aimed_.targets.empty()) return;
            trace_aimed(s_.scene, s_.world, s_.cum_area, s_.cells, c, s_.config.rays.eyes_per_cell,
                        s_.config.rays.seed, aimed_);
            if (!aimed_.eyes.empty()) counts.aimed_targets += aimed_.targets.size();
            counts.aimed_rounds += aimed_.eyes.size();
            counts.aimed_rays += aimed_.directions.size();
            counts.rays += aimed_.directions.size();
            for (const RayTouch& t : aimed_.touches) {
                const uint32_t eye =
                    uint32_t(std::upper_bound(aimed_.first.begin(), aimed_.first.end(), t.ray) -
                             aimed_.first.begin() - 1);
                see_aimed(t, aimed_.eyes[eye]);
            }
            return;
        }
        round_ = 0;
        aimed_.batch = UINT32_MAX;
        spend_rounds(budget);
        s_.rounds_of[c] = round_;
        counts.aimed_rounds += round_;
    }

    // A neighbour pass: from this cell, one ray at each point where a ray of the last pass in a cell around
    // first touched an object this cell's rays have not (in round k the k-th such witness of every such
    // object), from the point of this cell nearest the witness's eye. Spends at most `budget` rays (no cap
    // without a budget); returns what it spent. This cell's own first touches become `found`.
    uint64_t neighbour_pass(uint32_t c, const std::vector<uint32_t>& touching,
                            const std::vector<std::vector<Witness>>& last, std::vector<Witness>& found,
                            uint64_t budget) {
        resume_cell(c, &found);
        want_.assign(n_objects_, 0);
        for (uint32_t o : aimed_.listed) want_[o] = 1;
        for (uint32_t o : aimed_.left_out) want_[o] = 1;
        pairs_.clear();
        for (uint32_t n : touching)
            for (const Witness& w : last[n])
                if (want_[w.object]) pairs_.push_back(&w);
        if (pairs_.empty()) return 0;
        std::stable_sort(pairs_.begin(), pairs_.end(),
                         [](const Witness* a, const Witness* b) { return a->object < b->object; });
        // Eye points of the cell, for witnesses whose nearest point in the cell is not eye space.
        near_eyes_.clear();
        sample_eye_points_in(s_.cells, s_.cells.cells[c].bounds, cell_stream(kNeighbourEyeStream, c, 0),
                             kRoundEyesPerBatch, s_.config.rays.seed, near_eyes_);
        uint64_t spent = 0;
        for (uint32_t k = 0;; ++k) {
            const uint64_t left = s_.aim_capped ? budget - spent : UINT64_MAX;
            if (left == 0) break;
            picks_.clear();
            for (size_t i = 0; i < pairs_.size();) {
                size_t j = i;
                while (j < pairs_.size() && pairs_[j]->object == pairs_[i]->object) ++j;
                if (i + k < j && !s_.sampled.test(c, pairs_[i]->object)) picks_.push_back(pairs_[i + k]);
                i = j;
            }
            if (picks_.empty()) break;
            if (picks_.size() > left) {
                Rng rng(s_.config.rays.seed,
                        cell_stream(kNeighbourSubsetStream ^ (uint64_t(pass_) << 32), c, k));
                for (uint64_t i = 0; i < left; ++i)
                    std::swap(picks_[i], picks_[i + rng.below(uint32_t(picks_.size() - i))]);
                picks_.resize(left);
            }
            origins_.clear();
            aimed_.directions.clear();
            for (const Witness* w : picks_) {
                glm::vec3 eye;
                if (!eye_near(c, w->eye, eye)) continue;
                const glm::vec3 d = w->point - eye;
                const float len = glm::length(d);
                if (len < kMinAimDistanceM) continue;
                origins_.push_back(eye);
                aimed_.directions.push_back(d / len);
            }
            spent += picks_.size();
            counts.neighbour_targets += picks_.size();
            aimed_.touches.clear();
            s_.scene.trace_from(origins_.data(), aimed_.directions.data(), uint32_t(origins_.size()),
                                aimed_.touches);
            counts.neighbour_rays += origins_.size();
            counts.rays += origins_.size();
            for (const RayTouch& t : aimed_.touches) {
                const See r = see(t, origins_[t.ray], aimed_.directions[t.ray]);
                counts.neighbour_new += r.first;
                counts.neighbour_listed_new += r.first && r.listed;
                counts.neighbour_missed += r.missed;
            }
        }
        return spent;
    }

    // After the neighbour passes: `budget` more aimed rounds, as in the first pass.
    void spare_rounds(uint32_t c, uint64_t budget) {
        resume_cell(c, nullptr);
        round_ = s_.rounds_of[c];
        aimed_.batch = UINT32_MAX;
        spend_rounds(budget);
        counts.aimed_rounds += round_ - s_.rounds_of[c];
    }

    // The neighbour pass this verifier runs (1, 2, ...): its random subsets draw their own streams.
    uint32_t pass_ = 0;

private:
    struct See {
        bool first = false;   // the cell's rays had not touched the object before
        bool listed = false;  // the PVS lists it
        bool missed = false;  // a new missed pair (not listed, first report for the cell)
    };

    void begin_cell(uint32_t c, std::vector<Witness>* witnesses) {
        c_ = c;
        witnesses_ = witnesses;
        reported_.assign(n_objects_, 0);
    }

    // Back to cell c after an earlier pass: the misses it found stay reported, and its candidates are what
    // its rays have not touched yet.
    void resume_cell(uint32_t c, std::vector<Witness>* witnesses) {
        begin_cell(c, witnesses);
        for (const Miss& m : s_.cell_misses[c]) reported_[m.object] = 1;
        collect_candidates();
    }

    // One touch of any ray of the cell: the object is seen; a witness when first; a miss when unlisted.
    See see(const RayTouch& t, const glm::vec3& eye, const glm::vec3& direction) {
        See r;
        r.first = !s_.sampled.test(c_, t.object);
        r.listed = s_.pvs.test(c_, t.object);
        if (r.first) {
            s_.sampled.set(c_, t.object);
            if (witnesses_) witnesses_->push_back(Witness{t.object, eye, eye + direction * t.t});
        }
        if (r.listed) return r;
        ++s_.cell_missed_rays[c_];
        if (reported_[t.object]) return r;
        reported_[t.object] = 1;
        s_.cell_misses[c_].push_back(Miss{c_, t.object, eye, direction, t.t});
        r.missed = true;
        return r;
    }

    void see_aimed(const RayTouch& t, const glm::vec3& eye) {
        const See r = see(t, eye, aimed_.directions[t.ray]);
        counts.aimed_new += r.first;
        counts.aimed_listed_new += r.first && r.listed;
        counts.aimed_missed += r.missed;
    }

    // Candidates: what the cell's rays have not touched, but for listed objects every PVS lists; split into
    // those the PVS lists and those it leaves out.
    void collect_candidates() {
        aimed_.listed.clear();
        aimed_.left_out.clear();
        const Aabb& cell_box = s_.cells.cells[c_].bounds;
        for (uint32_t o = 0; o < n_objects_; ++o) {
            const WorldObject& obj = s_.world.objects[o];
            if (s_.sampled.test(c_, o) || obj.triangle_count == 0) continue;
            if (s_.cum_area[obj.first_triangle + obj.triangle_count - 1] <= 0.0) continue;
            if (!s_.pvs.test(c_, o)) {
                aimed_.left_out.push_back(o);
            } else if (!(obj.flags & kObjectAlwaysVisible) && !cell_box.overlaps(obj.bounds)) {
                aimed_.listed.push_back(o);
            }
        }
    }

    // The point of the cell's eye space nearest `eye`: the eye moved into the cell (a millimetre inside, so
    // it is in the cell's own voxels) when that is eye space, else the nearest of the cell's near_eyes_.
    bool eye_near(uint32_t c, const glm::vec3& eye, glm::vec3& out) const {
        const Aabb& box = s_.cells.cells[c].bounds;
        const glm::vec3 inset = glm::min(glm::vec3(kNeighbourEyeInsetM), 0.25f * box.size());
        out = glm::clamp(eye, box.min + inset, box.max - inset);
        if (s_.cells.eyes.empty() || s_.cells.eyes.contains(out)) return true;
        float best = std::numeric_limits<float>::max();
        for (const glm::vec3& p : near_eyes_) {
            const float d = glm::dot(p - eye, p - eye);
            if (d < best) {
                best = d;
                out = p;
            }
        }
        return !near_eyes_.empty();
    }

    // Rounds: one fresh eye point aims at every object of the group not seen yet (the last round, short of
    // rays, at a seeded random subset). Each round charges the group one ray per target. Returns the rays
    // charged: 0 when nothing of the group is left unseen.
    uint64_t aim_round(const std::vector<uint32_t>& group, bool listed, uint64_t rays_left) {
        aimed_.targets.clear();
        for (uint32_t o : group)
            if (!s_.sampled.test(c_, o)) aimed_.targets.push_back(o);
        const uint64_t k = aimed_.targets.size();
        if (k == 0 || rays_left == 0) return 0;
        if (k > rays_left) {
            Rng rng(s_.config.rays.seed, cell_stream(kAimedSubsetStream, c_, round_));
            for (uint64_t i = 0; i < rays_left; ++i)
                std::swap(aimed_.targets[i], aimed_.targets[i + rng.below(uint32_t(k - i))]);
            aimed_.targets.resize(rays_left);
            std::sort(aimed_.targets.begin(), aimed_.targets.end());
        }
        if (!trace_round(s_.scene, s_.world, s_.cum_area, s_.cells, c_, round_, s_.config.rays.seed, aimed_))
            return 0;
        ++round_;
        for (uint32_t o : aimed_.targets) {
            counts.aimed_targets += !s_.aimed_at.test(c_, o);
            s_.aimed_at.set(c_, o);
        }
        counts.aimed_rays += aimed_.directions.size();
        counts.rays += aimed_.directions.size();
        if (listed) counts.aimed_listed_rays += aimed_.directions.size();
        for (const RayTouch& t : aimed_.touches) see_aimed(t, aimed_.eyes[0]);
        return aimed_.targets.size();
    }

    uint64_t aim_group(const std::vector<uint32_t>& group, bool listed, uint64_t budget) {
        uint64_t spent = 0;
        while (spent < budget) {
            const uint64_t rays = aim_round(group, listed, budget - spent);
            if (rays == 0) break;
            spent += rays;
        }
        return spent;
    }

    // The listed group's share first, then the left-out group gets the rest, then the listed group what the
    // left-out one could not use (its objects all seen: misses).
    void spend_rounds(uint64_t budget) {
        const uint64_t listed_budget =
            aimed_.left_out.empty()
                ? budget
                : std::min(budget, uint64_t(double(budget) * s_.config.aimed_listed_share));
        uint64_t spent = aim_group(aimed_.listed, true, listed_budget);
        spent += aim_group(aimed_.left_out, false, budget - spent);
        aim_group(aimed_.listed, true, budget - spent);
    }

    Shared& s_;
    const uint32_t n_objects_;
    uint32_t c_ = 0;
    uint32_t round_ = 0;
    std::vector<Witness>* witnesses_ = nullptr;
    CellRays rays_;
    AimedRays aimed_;
    std::vector<uint8_t> reported_;
    std::vector<uint8_t> want_;
    std::vector<const Witness*> pairs_;
    std::vector<const Witness*> picks_;
    std::vector<glm::vec3> origins_;
    std::vector<glm::vec3> near_eyes_;
};

}  // namespace

NamedValues VerifyResult::run_figures() const {
    return {
        {"verify_seconds", seconds},
        {"verify_rays_per_second", seconds > 0 ? double(rays) / seconds : 0.0},
        {"verify_width_seconds", width_seconds},
    };
}

NamedValues VerifyResult::figures() const {
    return {
        {"rays", double(rays)},
        {"rays_per_eye", double(rays_per_eye)},
        {"missed_pairs", double(missed_pairs)},
        {"missed_rays", double(missed_rays)},
        {"cells_with_misses", double(cells_with_misses)},
        {"aimed_rays", double(aimed_rays)},
        {"aimed_listed_rays", double(aimed_listed_rays)},
        {"aimed_rays_per_cell", double(aimed_rays_per_cell)},
        {"aimed_candidates", double(aimed_candidates)},
        {"aimed_listed_candidates", double(aimed_listed_candidates)},
        {"aimed_targets", double(aimed_targets)},
        {"aimed_rounds", double(aimed_rounds)},
        {"aimed_rounds_mean",
         cell_sampled_visible.empty() ? 0.0 : double(aimed_rounds) / double(cell_sampled_visible.size())},
        {"aimed_new_pairs", double(aimed_new_pairs)},
        {"aimed_listed_new_pairs", double(aimed_listed_new_pairs)},
        {"aimed_missed_pairs", double(aimed_missed_pairs)},
        {"neighbour_passes", double(neighbour_passes)},
        {"neighbour_rays", double(neighbour_rays)},
        {"neighbour_targets", double(neighbour_targets)},
        {"neighbour_new_pairs", double(neighbour_new_pairs)},
        {"neighbour_listed_new_pairs", double(neighbour_listed_new_pairs)},
        {"neighbour_missed_pairs", double(neighbour_missed_pairs)},
        {"wide_missed_pairs", double(wide_missed_pairs)},
        {"narrow_missed_pairs", double(narrow_missed_pairs)},
        {"narrow_width_max_m", double(narrow_width_max_m)},
        {"overestimation_mean", overestimation_mean},
        {"overestimation_median", overestimation_median},
        {"overestimation_max", overestimation_max},
        {"overestimation_triangles_mean", overestimation_tri_mean},
        {"overestimation_triangles_median", overestimation_tri_median},
        {"overestimation_triangles_max", overestimation_tri_max},
        {"pvs_triangle_share_mean", pvs_triangle_share_mean},
        {"sampled_triangle_share_mean", sampled_triangle_share_mean},
        {"cells_with_empty_sample", double(cells_with_empty_sample)},
    };
}

namespace {

// Lines tried near each reported miss's ray when measuring its opening (docs/ALGORITHMS.md#miss-widths).
constexpr uint32_t kWidthTries = 1024;

// Measures the opening of every reported miss and splits the missed pairs into narrow and wide.
// Records of trivially copyable type as whole words, and back.
template <class T>
void put_record(std::vector<uint64_t>& out, const T& r) {
    static_assert(std::is_trivially_copyable_v<T>);
    const size_t at = out.size();
    out.resize(at + (sizeof(T) + 7) / 8, 0);
    std::memcpy(&out[at], &r, sizeof(T));
}
template <class T>
T get_record(const uint64_t*& in) {
    T r;
    std::memcpy(static_cast<void*>(&r), in, sizeof(T));
    in += (sizeof(T) + 7) / 8;
    return r;
}

// After a dealt pass, every process takes what the others wrote of the cells they were dealt
// (docs/ALGORITHMS.md#dealt-verification): the rows of objects seen and aimed at (united), and per cell its
// misses, missed rays, aimed rounds, neighbour rays spent and the witnesses of this pass (`found`), as the
// process that verified the cell holds them. `mine`: the cells this process verified in the pass.
void share_cells(WorkShare& share, const std::vector<uint8_t>& mine, CellVerifier::Shared& s,
                 std::vector<uint64_t>* spent, std::vector<std::vector<Witness>>* found) {
    if (share.processes() == 1) return;
    share.unite(s.sampled.words.data(), s.sampled.words.size());
    share.unite(s.aimed_at.words.data(), s.aimed_at.words.size());
    std::vector<uint64_t> own;
    for (uint32_t c = 0; c < uint32_t(mine.size()); ++c) {
        if (!mine[c]) continue;
        const std::vector<Witness>* w = found ? &(*found)[c] : nullptr;
        own.insert(own.end(), {uint64_t(c), s.cell_missed_rays[c], s.rounds_of[c], spent ? (*spent)[c] : 0,
                               uint64_t(s.cell_misses[c].size()), uint64_t(w ? w->size() : 0)});
        for (const Miss& m : s.cell_misses[c]) put_record(own, m);
        if (w)
            for (const Witness& x : *w) put_record(own, x);
    }
    const std::vector<uint64_t> all = gather_all(share, own);
    for (const uint64_t* in = all.data(); in < all.data() + all.size();) {
        const uint32_t c = uint32_t(in[0]);
        s.cell_missed_rays[c] = in[1];
        s.rounds_of[c] = uint32_t(in[2]);
        if (spent) (*spent)[c] = in[3];
        const uint64_t n_misses = in[4], n_witnesses = in[5];
        in += 6;
        s.cell_misses[c].clear();
        for (uint64_t k = 0; k < n_misses; ++k) s.cell_misses[c].push_back(get_record<Miss>(in));
        if (found) (*found)[c].clear();
        for (uint64_t k = 0; k < n_witnesses; ++k) {
            const Witness x = get_record<Witness>(in);
            if (found) (*found)[c].push_back(x);
        }
    }
}

// A pass's counts summed over the processes.
void share_counts(WorkShare& share, Counts& c) {
    static_assert(sizeof(Counts) % sizeof(uint64_t) == 0 && std::is_trivially_copyable_v<Counts>);
    uint64_t words[sizeof(Counts) / sizeof(uint64_t)];
    std::memcpy(words, &c, sizeof c);
    share.add(words, sizeof(Counts) / sizeof(uint64_t));
    std::memcpy(&c, words, sizeof c);
}

// One pass over the cells, dealt between the threads and the processes: fn(verifier, cell) for each cell
// dealt to this process (marked in `mine`, cleared first). Returns the pass's counts summed over every
// process; the caller then passes the cells' records on (share_cells()).
template <class Fn>
Counts dealt_pass(Context& ctx, WorkShare& deal, CellVerifier::Shared& shared, std::vector<uint8_t>& mine,
                  const std::string& label, uint32_t pass, Fn&& fn) {
    std::fill(mine.begin(), mine.end(), 0);
    ctx.progress_begin(label, mine.size(), "cells");
    deal.begin(mine.size());
    Counts counts;
#pragma omp parallel
    {
        CellVerifier v(shared);
        v.pass_ = pass;
        for_each_dealt(deal, ctx, 4, [&](uint64_t c) {
            mine[c] = 1;
            fn(v, uint32_t(c));
        });
#pragma omp critical
        counts.add(v.counts);
    }
    ctx.progress_end();
    share_counts(deal, counts);
    return counts;
}

void measure_miss_widths(Context& ctx, const VerifyConfig& config, const RayScene& scene,
                         const CellSet& cells, VerifyResult& result) {
    result.gap_tolerance_m = config.gap_tolerance_m;
    if (result.misses.empty()) {
        result.wide_missed_pairs = result.missed_pairs;
        return;
    }
    ScopedTimer timer(ctx, "verify_miss_widths");
    const auto start = std::chrono::steady_clock::now();
    const float tolerance = float(config.gap_tolerance_m);
    std::vector<Miss>& misses = result.misses;
#pragma omp parallel for schedule(dynamic, 1)
    for (int64_t i = 0; i < int64_t(misses.size()); ++i) {
        Miss& m = misses[size_t(i)];
        const Aabb box = cells.cells[m.cell].bounds;
        // Other lines must start from eyes of the same cell: in the cell, in its eye space.
        const auto eye_allowed = [&](glm::vec3 p) {
            return box.contains(p) && (cells.eyes.empty() || cells.eyes.contains(p));
        };
        const SightLine line =
            widest_sight_line_near(scene, m.object, m.eye, m.direction, m.distance_m, tolerance, eye_allowed,
                                   kWidthTries, config.rays.seed ^ (uint64_t(m.cell) << 32));
        m.opening_width_m = line.width_m;
    }
    for (const Miss& m : misses) {
        if (result.is_narrow(m)) {
            ++result.narrow_missed_pairs;
            result.narrow_width_max_m = std::max(result.narrow_width_max_m, m.opening_width_m);
        }
    }
    result.wide_missed_pairs = result.missed_pairs - result.narrow_missed_pairs;
    result.width_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

VerifyResult verify_pvs(Context& ctx, const VerifyConfig& config, const World& world, const RayScene& scene,
                        const CellSet& cells, const PvsSet& pvs, WorkShare* share) {
    ScopedTimer timer(ctx, "verify");
    WorkShare alone;
    WorkShare& deal = share ? *share : alone;
    std::vector<uint8_t> mine(cells.size(), 0);  // the cells this process verified in the current pass
    const auto start = std::chrono::steady_clock::now();
    VerifyResult result;
    const uint32_t n_cells = uint32_t(cells.size());
    const uint32_t n_objects = uint32_t(world.objects.size());
    result.sampled = PvsSet::make(n_cells, n_objects);
    // The uniform rays fit in what the aimed ones leave of the budget (all of it when aimed_share = 0: the
    // uniform rays alone).
    const bool aim = config.aimed_share > 0.0;
    const uint64_t aimed_budget =
        aim ? std::min(config.rays.ray_budget, uint64_t(double(config.rays.ray_budget) * config.aimed_share))
            : 0;
    SampleConfig uniform = config.rays;
    uniform.ray_budget -= aimed_budget;
    result.rays_per_eye = rays_per_eye_within_budget(uniform, n_cells);
    result.aimed_rays_per_cell = n_cells > 0 ? aimed_budget / n_cells : 0;
    const bool aim_capped = config.rays.ray_budget > 0;
    const uint64_t rays_per_cell = uint64_t(config.rays.eyes_per_cell) * result.rays_per_eye;
    ctx.info(fmt::format("verify: {} cells x {} eyes x {} rays = {:.1f} M uniform rays (seed {})", n_cells,
                         config.rays.eyes_per_cell, result.rays_per_eye,
                         double(rays_per_cell) * double(n_cells) * 1e-6, config.rays.seed));
    if (aim && aim_capped) {
        ctx.info(
            fmt::format("verify: aimed rays: {} per cell ({:.1f} M, {:.0f}% of the budget) at the objects "
                        "the uniform rays did not touch, {:.0f}% of them at those the PVS lists",
                        result.aimed_rays_per_cell, double(result.aimed_rays_per_cell * n_cells) * 1e-6,
                        100.0 * config.aimed_share, 100.0 * config.aimed_listed_share));
    } else if (aim) {
        ctx.info(
            fmt::format("verify: aimed rays: from {} eye points per cell at every object the uniform rays "
                        "did not touch (no ray budget)",
                        config.rays.eyes_per_cell));
    }
    const std::vector<double> cum_area = aim ? cumulative_areas(world) : std::vector<double>();

    // The neighbour pass's share of each cell's aimed rays (all of what it finds without a budget).
    const bool neighbours = aim && config.neighbour_share > 0.0;
    const uint64_t neighbour_budget =
        neighbours && aim_capped ? uint64_t(double(result.aimed_rays_per_cell) * config.neighbour_share) : 0;
    if (neighbours) {
        ctx.info(
            fmt::format("verify: neighbour pass: {} aimed rays per cell at the points where the rays of "
                        "the cells around saw objects the cell's own rays did not",
                        aim_capped ? fmt::format("{}", neighbour_budget) : std::string("all")));
    }
    CellVerifier::Shared shared{config, world, scene,      cells, pvs, cum_area, result.sampled,
                                {},     {},    aim_capped, {},    {},  {}};
    shared.cell_misses.resize(n_cells);
    shared.cell_missed_rays.assign(n_cells, 0);
    shared.rounds_of.assign(n_cells, 0);
    if (aim && aim_capped) shared.aimed_at = PvsSet::make(n_cells, n_objects);
    if (neighbours) shared.witnesses.resize(n_cells);
    Counts counts;
    const uint64_t first_budget = result.aimed_rays_per_cell - neighbour_budget;
    counts.add(dealt_pass(ctx, deal, shared, mine, "verify", 0, [&](CellVerifier& v, uint32_t c) {
        v.first_pass(c, result.rays_per_eye, aim, first_budget);
    }));
    share_cells(deal, mine, shared, nullptr, neighbours ? &shared.witnesses : nullptr);
    if (neighbours) {
        // Neighbour passes until one finds nothing new (or kMaxNeighbourPasses): each aims at what the last
        // one found in the cells around (the first at all the first pass found).
        const std::vector<std::vector<uint32_t>> touching = touching_cells(cells);
        std::vector<uint64_t> spent(n_cells, 0);
        std::vector<std::vector<Witness>> found(n_cells);
        for (uint32_t pass = 1; pass <= kMaxNeighbourPasses; ++pass) {
            const uint64_t before = counts.neighbour_new;
            counts.add(dealt_pass(ctx, deal, shared, mine, fmt::format("verify neighbours {}", pass), pass,
                                  [&](CellVerifier& v, uint32_t c) {
                                      found[c].clear();
                                      const uint64_t left =
                                          aim_capped ? neighbour_budget - spent[c] : UINT64_MAX;
                                      spent[c] += v.neighbour_pass(c, touching[c], shared.witnesses,
                                                                   found[c], left);
                                  }));
            share_cells(deal, mine, shared, &spent, &found);
            ++result.neighbour_passes;
            std::swap(shared.witnesses, found);
            if (counts.neighbour_new == before) break;
        }
        if (aim_capped) {
            counts.add(dealt_pass(ctx, deal, shared, mine, "verify spare rounds", 0,
                                  [&](CellVerifier& v, uint32_t c) {
                                      if (spent[c] < neighbour_budget)
                                          v.spare_rounds(c, neighbour_budget - spent[c]);
                                  }));
            share_cells(deal, mine, shared, &spent, nullptr);
        }
    }
    std::vector<std::vector<Miss>>& cell_misses = shared.cell_misses;
    for (std::vector<Miss>& m : cell_misses)
        std::sort(m.begin(), m.end(), [](const Miss& a, const Miss& b) { return a.object < b.object; });

    result.aimed_rays = counts.aimed_rays;
    result.aimed_listed_rays = counts.aimed_listed_rays;
    result.aimed_candidates = counts.aimed_candidates;
    result.aimed_listed_candidates = counts.aimed_listed_candidates;
    result.aimed_listed_new_pairs = counts.aimed_listed_new;
    result.aimed_rounds = counts.aimed_rounds;
    result.aimed_targets = counts.aimed_targets;
    result.aimed_new_pairs = counts.aimed_new;
    result.aimed_missed_pairs = counts.aimed_missed;
    result.neighbour_rays = counts.neighbour_rays;
    result.neighbour_targets = counts.neighbour_targets;
    result.neighbour_new_pairs = counts.neighbour_new;
    result.neighbour_listed_new_pairs = counts.neighbour_listed_new;
    result.neighbour_missed_pairs = counts.neighbour_missed;
    result.rays = counts.rays;
    result.cell_sampled_visible.resize(n_cells);
    std::vector<double> over, over_tri, pvs_share, sampled_share;
    const double world_tris = std::max<double>(1.0, double(world.triangles.size()));
    for (uint32_t c = 0; c < n_cells; ++c) {
        result.missed_rays += shared.cell_missed_rays[c];
        result.missed_pairs += cell_misses[c].size();
        result.cells_with_misses += !cell_misses[c].empty();
        for (const Miss& m : cell_misses[c]) {
            if (result.misses.size() >= config.max_misses_reported) break;
            result.misses.push_back(m);
        }
        const uint32_t seen = result.sampled.count(c);
        result.cell_sampled_visible[c] = seen;
        const uint64_t pvs_tris = row_triangles(world, pvs, c);
        pvs_share.push_back(double(pvs_tris) / world_tris);
        if (seen == 0) {
            ++result.cells_with_empty_sample;
            sampled_share.push_back(0.0);
            continue;
        }
        const uint64_t seen_tris = row_triangles(world, result.sampled, c);
        sampled_share.push_back(double(seen_tris) / world_tris);
        over.push_back(double(pvs.count(c)) / double(seen));
        over_tri.push_back(seen_tris ? double(pvs_tris) / double(seen_tris) : 1.0);
    }
    measure_miss_widths(ctx, config, scene, cells, result);
    const Stats o = stats_of(over), ot = stats_of(over_tri);
    result.overestimation_mean = o.mean;
    result.overestimation_median = o.median;
    result.overestimation_max = o.max;
    result.overestimation_tri_mean = ot.mean;
    result.overestimation_tri_median = ot.median;
    result.overestimation_tri_max = ot.max;
    result.pvs_triangle_share_mean = stats_of(pvs_share).mean;
    result.sampled_triangle_share_mean = stats_of(sampled_share).mean;
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

void log_verify_summary(Context& ctx, const VerifyResult& r, const World& world) {
    ctx.info(fmt::format("verify: {:.1f} M rays in {:.1f} s ({:.2f} M rays/s)", double(r.rays) * 1e-6,
                         r.seconds, r.seconds > 0 ? double(r.rays) * 1e-6 / r.seconds : 0.0));
    if (r.aimed_rays > 0 || r.aimed_candidates > 0) {
        ctx.info(fmt::format(
            "verify: aimed rays {:.1f} M ({:.1f} M at listed objects, {:.1f} eye points per cell) at {} of "
            "{} "
            "untouched (cell, object) pairs ({} listed): {} pairs seen only by them ({} listed), {} missed "
            "pairs found only by them",
            double(r.aimed_rays) * 1e-6, double(r.aimed_listed_rays) * 1e-6,
            r.cell_sampled_visible.empty() ? 0.0
                                           : double(r.aimed_rounds) / double(r.cell_sampled_visible.size()),
            r.aimed_targets, r.aimed_candidates, r.aimed_listed_candidates, r.aimed_new_pairs,
            r.aimed_listed_new_pairs, r.aimed_missed_pairs));
    }
    if (r.neighbour_targets > 0) {
        ctx.info(fmt::format(
            "verify: {} neighbour passes: {:.2f} M rays at {} witness points of the cells around: "
            "{} pairs seen only by them ({} listed), {} missed pairs found only by them",
            r.neighbour_passes, double(r.neighbour_rays) * 1e-6, r.neighbour_targets, r.neighbour_new_pairs,
            r.neighbour_listed_new_pairs, r.neighbour_missed_pairs));
    }
    ctx.info(
        fmt::format("verify: overestimation |PVS|/|sampled| mean {:.2f}, median {:.2f}, max {:.2f}; "
                    "by triangles mean {:.2f}, median {:.2f}, max {:.2f}",
                    r.overestimation_mean, r.overestimation_median, r.overestimation_max,
                    r.overestimation_tri_mean, r.overestimation_tri_median, r.overestimation_tri_max));
    ctx.info(
        fmt::format("verify: the PVS lets through {:.1f}% of the triangles on average; the rays saw {:.1f}%",
                    100.0 * r.pvs_triangle_share_mean, 100.0 * r.sampled_triangle_share_mean));
    if (r.missed_pairs == 0) {
        ctx.info("verify: no misses");
        return;
    }
    const auto show_miss = [&](const Miss& m) {
        return fmt::format(
            "cell {} object {} '{}' from eye ({:.3f}, {:.3f}, {:.3f}) direction ({:.4f}, {:.4f}, {:.4f}) at "
            "{:.3f} m, {}",
            m.cell, m.object, world.objects[m.object].name, m.eye.x, m.eye.y, m.eye.z, m.direction.x,
            m.direction.y, m.direction.z, m.distance_m,
            m.opening_width_m < 0.0f ? std::string("opening not measured")
                                     : fmt::format("widest line found {:.3g} mm", 1e3 * m.opening_width_m));
    };
    if (r.narrow_missed_pairs > 0) {
        ctx.info(
            fmt::format("verify: {} misses through openings narrower than the gap tolerance (widest line "
                        "found {:.3g} mm): "
                        "outside the promise, they do not fail the verification",
                        r.narrow_missed_pairs, 1e3 * r.narrow_width_max_m));
        size_t shown = 0;
        for (const Miss& m : r.misses) {
            if (shown >= 3) break;
            if (!r.is_narrow(m)) continue;
            ctx.info("  narrow miss: " + show_miss(m));
            ++shown;
        }
    }
    if (r.wide_missed_pairs == 0) return;
    ctx.warn(
        fmt::format("verify: {} MISSES: {} (cell, object) pairs in {} cells, {} rays saw an unlisted object",
                    r.wide_missed_pairs, r.missed_pairs, r.cells_with_misses, r.missed_rays));
    size_t shown = 0;
    for (const Miss& m : r.misses) {
        if (shown >= 10) break;
        if (r.is_narrow(m)) continue;
        ctx.warn("  miss: " + show_miss(m));
        ++shown;
    }
    if (r.wide_missed_pairs > shown)
        ctx.warn(fmt::format("  ... and {} more (see the report)", r.wide_missed_pairs - shown));
}

}  // namespace pvs
