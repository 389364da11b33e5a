// SPDX-License-Identifier: MIT
// The pvsbake command line: options declared once (core/config.h visit_options) drive parsing, --help,
// validation and the parameters stored in the bake.
#include "driver/cli.h"

#include "cells/view_volume.h"
#include "core/error.h"
#include "driver/bake.h"
#include "driver/processes.h"
#include "driver/report.h"
#include "driver/verify.h"
#include "io/atomic_file.h"
#include "io/bake_file.h"
#include "io/checkpoint.h"
#include "io/file_hash.h"
#include "io/gltf_loader.h"
#include "io/gltf_writer.h"
#include "io/runtime_file.h"
#include "occluders/synthesis.h"
#include "rays/ray_scene.h"

#include <fmt/format.h>
#include <omp.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string_view>
#include <type_traits>

#include <unistd.h>

namespace pvs {

namespace {

// Peak resident memory of this process (VmHWM), MiB; 0 when unknown.
double peak_memory_mb() {
    std::FILE* f = std::fopen("/proc/self/status", "r");
    if (!f) return 0.0;
    char line[256];
    double kb = 0.0;
    while (std::fgets(line, sizeof line, f)) {
        if (std::strncmp(line, "VmHWM:", 6) == 0) kb = std::strtod(line + 6, nullptr);
    }
    std::fclose(f);
    return kb / 1024.0;
}

// Binds the declared options whose key starts with one of `prefixes` to CLI11 options of `app`, group by
// group in the order of kOptionGroups (so --help lists them grouped); before each group's declared options,
// `extra` adds the command's own options of that group (with `group_title` as their group).
using ExtraOptions = std::function<void(OptionGroup group, const std::string& group_title)>;
void bind_options(CLI::App& app, BakeConfig& config, std::initializer_list<std::string_view> prefixes,
                  const ExtraOptions& extra = {}) {
    for (const OptionGroup group : kOptionGroups) {
        const std::string title = to_string(group);
        if (extra) extra(group, title);
        visit_options(config, [&](const OptionSpec& spec, auto& field) {
            if (spec.group != group) return;
            const std::string_view key(spec.key);
            bool wanted = false;
            for (std::string_view p : prefixes) wanted |= key.substr(0, p.size()) == p;
            if (!wanted) return;
            std::string help = spec.help;
            if (*spec.units) help += fmt::format(" [{}]", spec.units);
            // A declared boolean that is off by default is a flag (`--slanted-cubes`).
            if constexpr (std::is_same_v<std::decay_t<decltype(field)>, bool>) {
                if (!field) {
                    app.add_flag(spec.flag, field, help)->group(title);
                    return;
                }
            }
            CLI::Option* opt = app.add_option(spec.flag, field, help)->capture_default_str()->group(title);
            if (std::isfinite(spec.min) && std::isfinite(spec.max)) {
                opt->check(CLI::Range(spec.min, spec.max));
            } else if (std::isfinite(spec.min)) {
                opt->check(CLI::Range(spec.min, 1.8e19));
            }
        });
    }
}

// "1.5,2,-3" -> {1.5, 2, -3}; exactly `count` finite numbers or a bad-input error naming the option.
std::vector<double> parse_numbers(const std::string& text, size_t count, const char* option) {
    std::vector<double> out;
    size_t at = 0;
    while (at <= text.size()) {
        const size_t comma = std::min(text.find(',', at), text.size());
        const std::string item = text.substr(at, comma - at);
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(v)) {
            throw bad_input(fmt::format("{} {}: '{}' is not a number", option, text, item));
        }
        out.push_back(v);
        at = comma + 1;
    }
    if (out.size() != count) {
        throw bad_input(
            fmt::format("{} {}: wants {} comma-separated numbers, got {}", option, text, count, out.size()));
    }
    return out;
}

// The view volume options, shared by bake and occluders.
struct ViewArgs {
    std::vector<std::string> boxes, seeds;
    bool no_world_seeds = false, no_world_boxes = false;
};

void add_view_options(CLI::App& app, ViewArgs& args, const std::string& group) {
    app.add_option("--view-box", args.boxes,
                   "a box where eyes can be: minx,miny,minz,maxx,maxy,maxz [m]; repeat for more")
        ->type_name("BOX")
        ->group(group);
    app.add_option("--view-seed", args.seeds, "a point in the playable space: x,y,z [m]; repeat for more")
        ->type_name("POINT")
        ->group(group);
    app.add_flag("--no-world-seeds", args.no_world_seeds, "ignore the world's pvs_view_seed nodes")
        ->group(group);
    app.add_flag("--no-world-boxes", args.no_world_boxes, "ignore the world's pvs_view_volume nodes")
        ->group(group);
}

void apply_view_args(const ViewArgs& args, ViewVolumeConfig& view) {
    for (const std::string& text : args.boxes) {
        const std::vector<double> v = parse_numbers(text, 6, "--view-box");
        view.boxes.push_back(Aabb::of(glm::vec3(v[0], v[1], v[2]), glm::vec3(v[3], v[4], v[5])));
        if (view.boxes.back().is_empty())
            throw bad_input(fmt::format("--view-box {}: min must not exceed max", text));
    }
    for (const std::string& text : args.seeds) {
        const std::vector<double> v = parse_numbers(text, 3, "--view-seed");
        view.seeds.emplace_back(v[0], v[1], v[2]);
    }
    view.use_world_seeds = !args.no_world_seeds;
    view.use_world_boxes = !args.no_world_boxes;
}

struct CommonOptions {
    bool quiet = false;
    bool verbose = false;
    std::string report_path;
};

void add_common(CLI::App& app, CommonOptions& common, const std::string& group) {
    app.add_flag("-q,--quiet", common.quiet,
                 "no progress and no info lines (warnings and errors still print)")
        ->group(group);
    app.add_flag("-v,--verbose", common.verbose, "debug lines, stage timings")->group(group);
}

Context make_context(const CommonOptions& common, std::FILE* log) {
    Context::Options o;
    o.quiet = common.quiet;
    o.level = common.verbose ? LogLevel::kDebug : LogLevel::kInfo;
    o.sink = log;
    return Context(o);
}

void set_threads(int threads) {
    if (threads > 0) omp_set_num_threads(threads);
}

// The CPU seconds of each stage (process-wide, every thread) and the threads the run had, as run figures:
// the report divides them into each stage's thread utilisation (driver/report.h).
void add_cpu_figures(const Context& ctx, RunRecord& run) {
    run.figures.emplace_back("threads", double(omp_get_max_threads()));
    for (const auto& [stage, cpu] : ctx.cpu_timings()) run.figures.emplace_back("cpu_seconds_" + stage, cpu);
}

void write_report(const std::string& path, const BakeData& bake, const Context& ctx) {
    if (path.empty()) return;
    write_file_atomically(path, bake_report_json(bake, ctx.warnings()), "the report");
}

// occluders WORLD -o boxes.glb
int run_occluders(Context& ctx, const BakeConfig& config, const std::string& world_path,
                  const std::string& out_path, const std::string& report_path) {
    ScopedTimer total(ctx, "total");
    check_output_writable(out_path, "the output");
    if (!report_path.empty()) check_output_writable(report_path, "the report");
    set_threads(config.run.threads);
    const World world = load_world(ctx, world_path);
    const ViewVolume view = build_view_volume(ctx, config.view, world);
    RayScene scene(ctx, world, BuildQuality::kMedium, config.run.threads);
    OccluderFigures figures;
    OccluderConfig occluders = config.occluders;
    occluders.gap_tolerance_m = config.gap.tolerance_m;
    const std::vector<Occluder> boxes = synthesize_occluders(ctx, occluders, world, view, scene, figures);
    SceneDesc glb;
    glb.materials.push_back(
        SceneMaterial{"occluder", {0.9f, 0.3f, 0.2f, 0.5f}, SceneMaterial::Alpha::kBlend, true});
    uint32_t written = 0;
    for (size_t i = 0; i < boxes.size(); ++i) {
        if (!boxes[i].proven) continue;
        glb.nodes.push_back(make_box_node(fmt::format("occluder_{}", i), boxes[i].box, 0));
        ++written;
    }
    if (!view.leak_path.empty()) {
        write_file_atomically(out_path + ".leak.obj", leak_path_obj(view.leak_path), "the leak path");
    }
    if (glb.nodes.empty()) {
        ctx.warn("occluders: no box passed; writing an empty scene");
        SceneNode marker;
        marker.name = "no_occluders";
        glb.nodes.push_back(marker);
    }
    write_glb(glb, out_path);
    if (!report_path.empty()) {
        nlohmann::ordered_json j;
        j["tool"] = "pvsbake";
        j["version"] = tool_version();
        j["world"] = world_path;
        j["objects"] = world.objects.size();
        j["triangles"] = world.triangles.size();
        j["view_voxel_size_m"] = view.voxelized ? view.grid.voxel_size_m : 0.0f;
        j["solid_m3"] = figures.solid_m3;
        j["boxes_grown"] = figures.grown;
        j["boxes_kept"] = figures.kept;
        j["boxes_rejected_by_ray_check"] = figures.rejected_by_rays;
        j["boxes_written"] = written;
        j["covered_m3"] = figures.covered_m3;
        j["covered_share_of_solid"] = figures.solid_m3 > 0 ? figures.covered_m3 / figures.solid_m3 : 0.0;
        j["solid_near_view_m3"] = figures.near_m3;
        j["covered_share_of_solid_near_view"] =
            figures.near_m3 > 0 ? figures.near_covered_m3 / figures.near_m3 : 0.0;
        j["check_rays"] = figures.check_rays;
        j["probe_rays"] = figures.probe_rays;
        j["probe_rays_into_solid"] = figures.probe_rays_into_solid;
        j["probe_rays_narrow"] = figures.probe_rays_narrow;
        j["probe_carved_voxels"] = figures.probe_carved_voxels;
        j["gap_voxels"] = figures.gap_voxels;
        j["gap_gaps"] = figures.gap_gaps;
        j["gap_lines"] = figures.gap_lines;
        j["gap_leaks"] = figures.gap_leaks;
        j["gap_removed_voxels"] = figures.gap_removed_voxels;
        j["seal_frontier_voxels"] = figures.seal_frontier_voxels;
        j["seal_rays"] = figures.seal_rays;
        j["seal_leaks"] = figures.seal_leaks;
        j["seal_narrow"] = figures.seal_narrow;
        j["seal_removed_voxels"] = figures.seal_removed_voxels;
        nlohmann::ordered_json t = nlohmann::ordered_json::object();
        for (const auto& [k, v] : ctx.timings()) t[k] = v;
        j["timings_s"] = t;
        j["peak_memory_mb"] = peak_memory_mb();
        nlohmann::ordered_json arr = nlohmann::ordered_json::array();
        for (const Occluder& o : boxes) {
            arr.push_back({{"min", {o.box.min.x, o.box.min.y, o.box.min.z}},
                           {"max", {o.box.max.x, o.box.max.y, o.box.max.z}},
                           {"voxel_size_m", o.voxel_size_m},
                           {"proven", o.proven},
                           {"objects", o.objects}});
        }
        j["boxes"] = arr;
        j["warnings"] = ctx.warnings();
        write_file_atomically(report_path, j.dump(2) + "\n", "the report");
    }
    ctx.info(fmt::format("wrote {} ({} boxes)", out_path, written));
    return kExitOk;
}

double figure_or(const NamedValues& values, const std::string& key, double fallback) {
    for (const auto& [k, v] : values)
        if (k == key) return v;
    return fallback;
}

// What a bake does with the checkpoint beside its output (docs/ALGORITHMS.md#resume).
enum class ResumeMode {
    kAuto,     // resume from a checkpoint of this bake, refuse one of another
    kResume,   // --resume: as kAuto, and a checkpoint must exist
    kRestart,  // --restart: remove any checkpoint first
};

// What writing the checkpoint cost a run (its run figures checkpoint_*).
struct CheckpointCost {
    uint64_t chunks = 0, rows = 0, failures = 0;
    double seconds = 0.0;
};

// The journal of a conservative bake's finished rows, loaded from the checkpoint in `folder` and writing
// its chunks there (adding to `cost`); none when checkpoints are off or the mode has none (sampled). Under
// MPI (`share`) every rank reads the whole checkpoint and writes chunks of its own.
std::unique_ptr<RowJournal> open_journal(Context& ctx, const BakeConfig& config, const std::string& folder,
                                         const CheckpointIdentity& id, ResumeMode resume,
                                         CheckpointCost& cost, WorkShare* share) {
    const int rank = share ? share->rank() : 0;
    const bool on = config.run.checkpoint_interval_s > 0.0 && config.mode == BakeMode::kConservative;
    if (!on) {
        if (resume == ResumeMode::kResume) {
            throw bad_input(config.mode == BakeMode::kConservative
                                ? "--resume: checkpoints are off (--checkpoint-interval 0)"
                                : "--resume: only conservative bakes keep checkpoints");
        }
        if (checkpoint_exists(folder))
            ctx.warn(fmt::format("the checkpoint {} is not used by this bake; it is left as it is", folder));
        return nullptr;
    }
    if (resume == ResumeMode::kRestart && rank == 0 && checkpoint_exists(folder)) {
        if (!remove_checkpoint(folder))
            throw bad_input(fmt::format("--restart: cannot remove the checkpoint {}", folder));
        ctx.info(fmt::format("removed the checkpoint {}", folder));
    }
    if (share) share->barrier();  // no rank reads what rank 0 is removing
    Checkpoint checkpoint;
    try {
        checkpoint = read_checkpoint(folder, id);
    } catch (const Error& e) {
        if (e.kind() == ErrorKind::kIo)
            throw io_error(fmt::format("{}; the checkpoint {} cannot be read: let this process read it, or bake "
                                       "with --restart to start again from zero",
                                       e.what(), folder));
        throw bad_input(fmt::format("{}; the checkpoint {} is not this bake's or is damaged: remove it, or bake "
                                    "with --restart to start again from zero",
                                    e.what(), folder));
    }
    if (resume == ResumeMode::kResume && checkpoint.chunks.empty())
        throw bad_input(fmt::format("--resume: there is no checkpoint at {}", folder));
    // The sink runs under the journal's lock, so the chunk numbers follow the chunks. A chunk that cannot be
    // written is no reason to lose the bake: the rows wait for the next chunk, and the first failure alone is
    // said (a full disk would otherwise repeat it at every chunk).
    auto sink = [&ctx, &cost, folder, id, rank, next = checkpoint.next_index](const RowChunk& chunk) mutable {
        const auto start = std::chrono::steady_clock::now();
        try {
            write_checkpoint_chunk(folder, next, id, chunk, rank);
            ++next;
            ++cost.chunks;
            cost.rows += chunk.row_count();
            cost.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            return true;
        } catch (const Error& e) {
            if (cost.failures++ == 0)
                ctx.warn(fmt::format("{}; the bake goes on, and its rows wait for the next chunk", e.what()));
            return false;
        } catch (const std::bad_alloc&) {
            if (cost.failures++ == 0)
                ctx.warn(fmt::format("{}: out of memory while writing the checkpoint; the bake goes on", folder));
            return false;
        }
    };
    auto journal = std::make_unique<RowJournal>(std::move(sink), config.run.checkpoint_interval_s);
    for (const RowChunk& chunk : checkpoint.chunks) journal->load(chunk);
    if (journal->loaded_rows() > 0) {
        ctx.info(fmt::format("resuming from the checkpoint {}: {} finished rows in {} chunks", folder,
                             journal->loaded_rows(), checkpoint.chunks.size()));
    }
    return journal;
}

// While alive, a bake stopped by SIGTERM, SIGINT or SIGHUP (a scheduler's time limit, Ctrl-C, mpirun ending
// the job because one of its ranks died) says in one line where its checkpoint is before it ends; the
// signal then ends the process as it would have (docs/ALGORITHMS.md#faults). A signal the process ignored
// when it started (nohup, a background job) stays ignored. A signal handler can reach only what is set
// before it runs: the line lives in a static buffer, written with write(2) alone.
class StopNotice {
public:
    explicit StopNotice(const std::string& folder) {
        std::string line = fmt::format(
            "error: the bake was stopped by a signal; run the same command again to resume from the rows "
            "checkpointed in {}/",
            folder);
        line = line.substr(0, sizeof(line_) - 1) + "\n";
        length_ = line.size();
        std::memcpy(line_, line.data(), length_);
        struct sigaction action {};
        action.sa_handler = &StopNotice::on_signal;
        sigemptyset(&action.sa_mask);
        for (size_t i = 0; i < kSignals.size(); ++i) {
            struct sigaction before {};
            if (::sigaction(kSignals[i], nullptr, &before) != 0 || before.sa_handler == SIG_IGN) continue;
            installed_[i] = ::sigaction(kSignals[i], &action, &previous_[i]) == 0;
        }
    }
    ~StopNotice() {
        for (size_t i = 0; i < kSignals.size(); ++i)
            if (installed_[i]) ::sigaction(kSignals[i], &previous_[i], nullptr);
    }
    StopNotice(const StopNotice&) = delete;
    StopNotice& operator=(const StopNotice&) = delete;

private:
    static constexpr std::array<int, 3> kSignals = {SIGTERM, SIGINT, SIGHUP};
    static void on_signal(int sig) {
        // One line even when two signals come at once: the first takes the line.
        if (!said_.test_and_set()) {
            [[maybe_unused]] const ssize_t n = ::write(2, line_, length_);
        }
        ::signal(sig, SIG_DFL);
        ::raise(sig);
    }
    static inline char line_[1024];
    static inline size_t length_ = 0;
    static inline std::atomic_flag said_ = ATOMIC_FLAG_INIT;
    std::array<struct sigaction, 3> previous_{};
    std::array<bool, 3> installed_{};
};

// The runtime file of the bake at bake_path (io/runtime_file.h), and a line saying what it holds.
void write_runtime_file(Context& ctx, const std::string& bake_path, const std::string& runtime_path,
                        const RuntimeFileOptions& options = {}) {
    ScopedTimer t(ctx, "export");
    const RuntimeFileFigures f = export_runtime_file(bake_path, runtime_path, options);
    std::string parts;
    for (const auto& [tag, bytes] : f.sections) parts += fmt::format("{}{} {}", parts.empty() ? "" : ", ", tag, bytes);
    ctx.info(fmt::format("wrote {} ({} bytes: {})", runtime_path, f.file_bytes, parts));
}

// export BAKE.h5 -o LEVEL.pvsr
int run_export(Context& ctx, const std::string& bake_path, const std::string& runtime_path,
               const RuntimeFileOptions& options) {
    check_output_writable(runtime_path, "the runtime file");
    write_runtime_file(ctx, bake_path, runtime_path, options);
    return kExitOk;
}

// bake WORLD -o OUT.h5
int run_bake(Context& ctx, const BakeConfig& config, const std::string& world_path,
             const std::string& out_path, const std::string& report_path, ResumeMode resume,
             const std::string& reuse_path, const std::string& runtime_path) {
    ScopedTimer total(ctx, "total");
    // Before any stage: a bad output path must not cost a night's bake.
    check_output_writable(out_path, "the output");
    if (!runtime_path.empty()) check_output_writable(runtime_path, "the runtime file");
    if (!report_path.empty()) check_output_writable(report_path, "the report");
    remove_stale_temporaries(out_path + ".leak.obj");
    set_threads(config.run.threads);
    const std::string hash = hash_file_hex(world_path);
    CheckpointIdentity id{tool_version(), hash, {}};
    for (auto& p : resolved_parameters(config))
        if (!is_run_parameter(p.first)) id.parameters.push_back(std::move(p));
    // --reuse: the old bake is read and checked before any stage too (docs/ALGORITHMS.md#reuse). A
    // checkpoint's rows were computed beside the old bake's, so it belongs to that old bake alone.
    std::optional<BakeData> reuse;
    if (!reuse_path.empty()) {
        reuse = read_bake_file(reuse_path);
        check_reuse(config, *reuse, reuse_path);
        if (config.mode != BakeMode::kConservative)
            throw bad_input("--reuse: only a conservative bake reuses an old one");
        id.parameters.emplace_back("reuse", hash_file_hex(reuse_path));
    }
    const std::string folder = checkpoint_folder(out_path);
    // Several processes (mpirun): each runs this; rank 0 alone writes (driver/processes.h).
    const std::unique_ptr<WorkShare> share = make_work_share(ctx);
    CheckpointCost cost;
    std::unique_ptr<RowJournal> journal = open_journal(ctx, config, folder, id, resume, cost, share.get());
    const size_t resumed_rows = journal ? journal->loaded_rows() : 0;
    std::optional<StopNotice> stop_notice;
    if (journal && (!share || share->rank() == 0)) stop_notice.emplace(folder);
    const World world = load_world(ctx, world_path);
    BakeData bake = bake_world(ctx, config, world, world_path, hash, journal.get(), share.get(),
                               reuse ? &*reuse : nullptr);
    if (share && share->rank() != 0) return kExitOk;
    if (reuse) bake.run.parameters.emplace_back("reuse", reuse_path);
    bake.run.timings_s = ctx.timings();
    add_cpu_figures(ctx, bake.run);
    bake.run.figures.emplace_back("peak_memory_mb", peak_memory_mb());
    if (journal) {
        // Writing a chunk holds the journal's lock, so its seconds bound what checkpoints cost the bake.
        bake.run.figures.emplace_back("checkpoint_chunks", double(cost.chunks));
        bake.run.figures.emplace_back("checkpoint_rows", double(cost.rows));
        bake.run.figures.emplace_back("checkpoint_seconds", cost.seconds);
        bake.run.figures.emplace_back("checkpoint_failures", double(cost.failures));
        bake.run.figures.emplace_back("resumed_rows", double(resumed_rows));
    }
    // Every output before the checkpoint goes: a failure of any of them keeps the rows for the next run.
    try {
        {
            ScopedTimer t(ctx, "write");
            write_bake_file(out_path, bake);
        }
        if (!bake.leak_path.empty()) {
            const std::string leak_file = out_path + ".leak.obj";
            write_file_atomically(leak_file, leak_path_obj(bake.leak_path), "the leak path");
            ctx.warn(fmt::format("the leak path is in {} (load it over the world in a viewer)", leak_file));
        }
        write_report(report_path, bake, ctx);
        ctx.info(fmt::format("wrote {} ({}, {} cells, mean PVS {:.1f} of {} objects)", out_path, pvs_kind(bake),
                             bake.cells.size(), figure_or(bake.figures, "pvs_objects_mean", 0.0),
                             bake.objects.size()));
        if (!runtime_path.empty()) write_runtime_file(ctx, out_path, runtime_path);
    } catch (const Error& e) {
        if (!journal) throw;
        if (!checkpoint_exists(folder)) {
            remove_checkpoint(folder);  // a folder no chunk could be written to
            throw;
        }
        throw Error(e.kind(), fmt::format("{}; the finished rows are kept in {}/: run the same command again to "
                                          "resume",
                                          e.what(), folder));
    } catch (const std::bad_alloc&) {
        if (!journal || !checkpoint_exists(folder)) throw;
        throw io_error(fmt::format("out of memory while writing the outputs; the finished rows are kept in {}/: "
                                   "run the same command again to resume",
                                   folder));
    }
    stop_notice.reset();
    if (journal && !remove_checkpoint(folder))
        ctx.warn(
            fmt::format("cannot remove the checkpoint {} (the bake is written; remove it by hand)", folder));
    // Misses through openings narrower than the gap tolerance are outside the promise (reported, no failure).
    const double wide =
        bake.verification.ran ? figure_or(bake.verification.figures, "wide_missed_pairs", 0.0) : 0.0;
    const double seen_into =
        bake.verification.ran ? figure_or(bake.verification.figures, "ranked_boxes_seen_into", 0.0) : 0.0;
    return (wide > 0.0 || seen_into > 0.0) && bake.conservative ? kExitMisses : kExitOk;
}

// verify WORLD BAKE.h5
// `tolerance_given`: --gap-tolerance was on the command line; otherwise the bake's own tolerance (the
// default for bakes made before it was recorded) decides which misses fail.
int run_verify(Context& ctx, BakeConfig config, const std::string& world_path, const std::string& bake_path,
               const std::string& report_path, bool write_back, bool tolerance_given) {
    if (write_back) check_output_writable(bake_path, "the bake");
    if (!report_path.empty()) check_output_writable(report_path, "the report");
    set_threads(config.run.threads);
    BakeData bake = read_bake_file(bake_path);
    if (!tolerance_given) config.gap.tolerance_m = gap_tolerance_of(bake);
    config.verify.gap_tolerance_m = config.gap.tolerance_m;
    const World world = load_world(ctx, world_path);
    const std::string hash = hash_file_hex(world_path);
    check_bake_matches_world(ctx, bake, world, hash);
    ctx.info(fmt::format("verifying {} ({}) against {}", bake_path, pvs_kind(bake), world_path));
    RayScene scene(ctx, world, BuildQuality::kMedium, config.run.threads);
    // Several processes (mpirun): the passes are dealt; rank 0 alone writes (driver/processes.h).
    const std::unique_ptr<WorkShare> share = make_work_share(ctx);
    const VerifyResult result = verify_pvs(ctx, config.verify, world, scene, bake.cells, bake.pvs, share.get());
    if (share) {
        share->close();
        if (share->rank() != 0) return kExitOk;
    }
    log_verify_summary(ctx, result, world);
    store_verification(result, bake);
    verify_ranked_boxes(ctx, scene, config.verify.rays.seed, bake);
    if (write_back) write_bake_file(bake_path, bake);
    write_report(report_path, bake, ctx);
    const bool seen_into = figure_or(bake.verification.figures, "ranked_boxes_seen_into", 0.0) > 0.0;
    return result.wide_missed_pairs > 0 || seen_into ? kExitMisses : kExitOk;
}

// The ranked occluders of a bake in a few lines (format 1.2; older files and bakes without occluders have
// none).
std::string ranked_summary(const BakeData& bake) {
    uint32_t proven = 0;
    for (const Occluder& o : bake.occluders) proven += o.proven ? 1 : 0;
    std::string text = fmt::format("occluders   {} boxes, {} proven; {} polygons\n", bake.occluders.size(),
                                   proven, bake.polygons.size());
    const RankedOccluders& r = bake.ranked;
    if (r.empty()) {
        return text + (bake.format_minor < 2 && bake.format_major == 1
                           ? "ranked      none (format older than 1.2)\n"
                           : "ranked      none (ranking off, or no occluders)\n");
    }
    const size_t cells = bake.cells.size();
    uint32_t most = 0, none = 0;
    double score = 0.0, solid = 0.0, hidden = 0.0, share = 0.0, best_share = 0.0;
    std::vector<uint32_t> uses(bake.occluders.size() + bake.polygons.size(), 0);
    for (uint32_t c = 0; c < cells; ++c) {
        const uint32_t n = r.count(c);
        most = std::max(most, n);
        none += n == 0 ? 1 : 0;
        if (n > 0) best_share += r.entries[r.offsets[c]].hidden_triangle_share;
    }
    for (const RankedOccluder& e : r.entries) {
        score += e.score;
        solid += e.solid_angle_sr;
        hidden += e.hidden_objects;
        share += e.hidden_triangle_share;
        ++uses[e.box];
    }
    const double n = std::max<double>(1.0, double(r.entries.size()));
    const size_t distinct = size_t(std::count_if(uses.begin(), uses.end(), [](uint32_t u) { return u > 0; }));
    text += fmt::format("ranked      {:.2f} per cell (most {}, {} cells with none), {} distinct occluders\n",
                        cells ? double(r.entries.size()) / double(cells) : 0.0, most, none, distinct);
    text += fmt::format(
        "            mean of the kept: score {:.3f}, solid angle {:.3f} sr, hides {:.1f} objects and {:.1f}% "
        "of "
        "the triangles; the best of a cell hides {:.1f}% of the triangles on average\n",
        score / n, solid / n, hidden / n, 100.0 * share / n,
        cells > none ? 100.0 * best_share / double(cells - none) : 0.0);
    return text;
}

int run_info(const std::string& bake_path, bool json, std::ostream& out) {
    const BakeData bake = read_bake_file(bake_path);
    if (json) {
        out << bake_report_json(bake, {});
        return kExitOk;
    }
    out << fmt::format("bake file   {} (format {}.{}, pvsbake {})\n", bake_path, bake.format_major,
                       bake.format_minor, bake.tool_version);
    out << fmt::format("world       {} (hash {})\n", bake.world_path, bake.world_hash);
    out << fmt::format("PVS         {}\n", pvs_kind(bake));
    out << fmt::format("objects     {}, triangles {}\n", bake.objects.size(),
                       uint64_t(figure_or(bake.figures, "triangles", 0)));
    const CellSet& cells = bake.cells;
    out << fmt::format("cells       {} ({} {} x {} x {} of {} m from ({:.2f}, {:.2f}, {:.2f}))\n",
                       cells.size(), cells.kind == CellSet::Kind::kGrid ? "grid" : "octree", cells.dims.x,
                       cells.dims.y, cells.dims.z, cells.cell_size_m, cells.origin.x, cells.origin.y,
                       cells.origin.z);
    out << ranked_summary(bake);
    out << "parameters\n";
    for (const auto& [k, v] : bake.parameters) out << fmt::format("  {:<32} {}\n", k, v);
    out << "figures\n";
    for (const auto& [k, v] : bake.figures) out << fmt::format("  {:<32} {:g}\n", k, v);
    if (bake.verification.ran) {
        out << "verification\n";
        for (const auto& [k, v] : bake.verification.figures) out << fmt::format("  {:<32} {:g}\n", k, v);
        constexpr size_t kMissesShown = 20;
        const double tolerance = gap_tolerance_of(bake);
        for (size_t i = 0; i < bake.verification.misses.size() && i < kMissesShown; ++i) {
            const Miss& m = bake.verification.misses[i];
            const bool narrow = is_narrow_miss(m, tolerance);
            out << fmt::format(
                "  {}: cell {} object '{}' eye ({:.3f}, {:.3f}, {:.3f}) dir ({:.4f}, {:.4f}, {:.4f}) "
                "at {:.3f} m{}\n",
                narrow ? "narrow miss" : "miss", m.cell, bake.objects[m.object].name, m.eye.x, m.eye.y,
                m.eye.z, m.direction.x, m.direction.y, m.direction.z, m.distance_m,
                m.opening_width_m < 0.0f
                    ? std::string()
                    : fmt::format(", widest line found {:.3g} mm", 1e3 * m.opening_width_m));
        }
        if (bake.verification.misses.size() > kMissesShown) {
            out << fmt::format("  ... {} more misses stored (pvsbake info --json lists them)\n",
                               bake.verification.misses.size() - kMissesShown);
        }
    } else {
        out << "verification: not run (pvsbake verify WORLD BAKE.h5)\n";
    }
    out << "run (what differs between runs of the same bake)\n";
    for (const auto& [k, v] : bake.run.parameters) out << fmt::format("  {:<32} {}\n", k, v);
    for (const auto& [k, v] : bake.run.figures) out << fmt::format("  {:<32} {:g}\n", k, v);
    out << "run timings (s)\n";
    for (const auto& [k, v] : bake.run.timings_s) out << fmt::format("  {:<32} {:.3f}\n", k, v);
    return kExitOk;
}

int run_query(const std::string& bake_path, const std::vector<double>& xyz, bool json, std::ostream& out) {
    const BakeData bake = read_bake_file(bake_path);
    const glm::vec3 p{static_cast<float>(xyz[0]), static_cast<float>(xyz[1]), static_cast<float>(xyz[2])};
    if (!is_finite(p)) throw bad_input("query: the point must be three finite numbers");
    const int32_t cell = bake.cells.find(p);
    std::vector<uint32_t> visible;
    if (cell >= 0) {
        for (uint32_t o = 0; o < bake.objects.size(); ++o)
            if (bake.pvs.test(uint32_t(cell), o)) visible.push_back(o);
    }
    if (json) {
        nlohmann::ordered_json j;
        j["point"] = {p.x, p.y, p.z};
        j["pvs_kind"] = pvs_kind(bake);
        if (cell < 0) {
            j["cell"] = nullptr;
        } else {
            const Aabb& b = bake.cells.cells[cell].bounds;
            j["cell"] = cell;
            j["cell_bounds"] = {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z};
            j["visible_count"] = visible.size();
            nlohmann::ordered_json names = nlohmann::ordered_json::array();
            for (uint32_t o : visible) names.push_back(bake.objects[o].name);
            j["visible"] = names;
        }
        out << j.dump(2) << "\n";
        return kExitOk;
    }
    if (cell < 0) {
        out << fmt::format("no cell holds ({}, {}, {})\n", p.x, p.y, p.z);
        return kExitOk;
    }
    const Aabb& b = bake.cells.cells[cell].bounds;
    out << fmt::format(
        "cell {} ({:.2f}, {:.2f}, {:.2f}) - ({:.2f}, {:.2f}, {:.2f}) sees {} of {} objects ({})\n", cell,
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z, visible.size(), bake.objects.size(),
        pvs_kind(bake));
    for (uint32_t o : visible) out << bake.objects[o].name << "\n";
    return kExitOk;
}

}  // namespace

int run_cli(int argc, const char* const* argv, std::ostream& out, std::FILE* log) {
    CLI::App app{
        "pvsbake: bake, verify and inspect potentially-visible sets (PVS) of glTF 2.0 worlds.\n"
        "Units are metres; axes are glTF's (+Y up)."};
    app.require_subcommand(1);
    app.set_version_flag("--version", tool_version());

    BakeConfig config;
    CommonOptions common;
    std::string world_path, out_path, bake_path, mode = "conservative";
    bool no_verify = false, no_write = false, json = false, resume = false, restart = false;
    std::string reuse_path, runtime_path;
    std::vector<double> point;

    CLI::App* bake =
        app.add_subcommand("bake", "bake the PVS of a world into an HDF5 bake file, then verify it");
    bake->add_option("world", world_path, "the world, glTF 2.0 (.gltf or .glb)")->required();
    bool no_occluders = false;
    std::string cells_kind = "grid";
    ViewArgs view_args;
    bind_options(
        *bake, config,
        {"run.", "gap.", "view.", "cells.", "occluders.", "ranking.", "conservative.", "sampled.", "verify."},
        [&](OptionGroup group, const std::string& title) {
            switch (group) {
                case OptionGroup::kGeneral:
                    bake->add_option("--mode", mode,
                                     "conservative (the default): every object any eye may see, proven with "
                                     "shrunk occluders (occluder fusion); sampled: the union of what sample "
                                     "rays saw (AGGRESSIVE: may miss small or grazing objects)")
                        ->check(CLI::IsMember({"conservative", "sampled"}))
                        ->capture_default_str()
                        ->group(title);
                    add_common(*bake, common, title);
                    break;
                case OptionGroup::kOutput:
                    bake->add_option("-o,--output", out_path, "the bake file to write (HDF5)")
                        ->required()
                        ->group(title);
                    bake->add_option("--report", common.report_path, "also write a JSON report here")
                        ->group(title);
                    bake->add_option("--runtime-output", runtime_path,
                                     "also write the runtime file a game ships (.pvsr, as pvsbake export "
                                     "writes it)")
                        ->group(title);
                    bake->add_flag("--resume", resume,
                                   "continue from the checkpoint OUT.checkpoint/ of a killed bake (a bake "
                                   "also resumes without it when the checkpoint is its own); fail if there "
                                   "is none")
                        ->group(title);
                    bake->add_flag(
                            "--restart", restart,
                            "remove the checkpoint OUT.checkpoint/ and bake from zero (a checkpoint of "
                            "another world or other parameters is refused otherwise)")
                        ->excludes("--resume")
                        ->group(title);
                    bake->add_option(
                            "--reuse", reuse_path,
                            "OLD.h5, a conservative grid bake of this world before an edit, with the "
                            "same parameters: keep its rows where the edit cannot change them and "
                            "compute the rest (the same file as a full bake)")
                        ->group(title);
                    break;
                case OptionGroup::kViewVolume:
                    add_view_options(*bake, view_args, title);
                    break;
                case OptionGroup::kCells:
                    bake->add_option("--cells", cells_kind,
                                     "grid: uniform cells of --cell-size; octree: split where visibility "
                                     "changes, down to --min-cell-size")
                        ->check(CLI::IsMember({"grid", "octree"}))
                        ->capture_default_str()
                        ->group(title);
                    break;
                case OptionGroup::kOccluders:
                    bake->add_flag("--no-occluders", no_occluders,
                                   "sampled mode: skip occluder synthesis (the conservative mode needs it)")
                        ->group(title);
                    break;
                case OptionGroup::kVerification:
                    bake->add_flag("--no-verify", no_verify, "skip verification by ray sampling")
                        ->group(title);
                    break;
                default:
                    break;
            }
        });

    CLI::App* verify = app.add_subcommand(
        "verify",
        "check a bake against its world with Embree rays: exit 3 and the misses when a ray sees an "
        "object the PVS leaves out");
    verify->add_option("world", world_path, "the world the bake was made from")->required();
    verify->add_option("bake", bake_path, "the bake file; its verification group is updated")->required();
    bind_options(
        *verify, config, {"run.threads", "gap.", "verify."},
        [&](OptionGroup group, const std::string& title) {
            if (group == OptionGroup::kGeneral) add_common(*verify, common, title);
            if (group == OptionGroup::kOutput) {
                verify->add_option("--report", common.report_path, "also write a JSON report here")
                    ->group(title);
                verify->add_flag("--no-write", no_write, "leave the bake file as it is")->group(title);
            }
        });

    CLI::App* occ = app.add_subcommand(
        "occluders",
        "synthesize occluder boxes inside the world's opaque solid and write them as glTF (.glb)");
    occ->add_option("world", world_path, "the world, glTF 2.0 (.gltf or .glb)")->required();
    ViewArgs occ_view_args;
    bind_options(*occ, config, {"run.threads", "gap.", "view.", "occluders."},
                 [&](OptionGroup group, const std::string& title) {
                     if (group == OptionGroup::kGeneral) add_common(*occ, common, title);
                     if (group == OptionGroup::kOutput) {
                         occ->add_option("-o,--output", out_path,
                                         "the boxes, as a .glb to open over the world")
                             ->required()
                             ->group(title);
                         occ->add_option("--report", common.report_path, "also write a JSON report here")
                             ->group(title);
                     }
                     if (group == OptionGroup::kViewVolume) add_view_options(*occ, occ_view_args, title);
                 });

    CLI::App* info = app.add_subcommand("info", "what a bake file holds: world, counts, parameters, figures");
    info->add_option("bake", bake_path, "the bake file")->required();
    info->add_flag("--json", json, "print JSON (the same shape as the bake report)");

    CLI::App* exporter = app.add_subcommand(
        "export", "write the runtime file a game ships (.pvsr: docs/FORMAT.md) from a bake file");
    exporter->add_option("bake", bake_path, "the bake file")->required();
    exporter->add_option("-o,--output", runtime_path, "the runtime file to write (.pvsr)")->required();
    RuntimeFileOptions runtime_options;
    exporter->add_flag("--occluder-measures", runtime_options.occluder_measures,
                       "also each ranked occluder's score, solid angle and hidden shares (16 bytes an entry; a "
                       "culler needs only the boxes, in rank order)");
    exporter
        ->add_option(
            "--max-chain", runtime_options.max_chain,
            "rows XORed to decode one PVS row: longer chains make the file smaller and a walk slower "
            "(1: every row whole)")
        ->check(CLI::Range(1, 16))
        ->capture_default_str();
    exporter->add_option("--merge-cells", runtime_options.merge_cells,
                         "K > 1 (grid bakes): each cell lists what its block of K x K x K cells lists, so the block "
                         "shares one row: a smaller file, more drawn, still conservative (1: off)")
        ->check(CLI::Range(1, 16))
        ->capture_default_str();
    add_common(*exporter, common, "Options");

    CLI::App* query = app.add_subcommand("query", "the cell holding a point and the objects its PVS lists");
    query->add_option("bake", bake_path, "the bake file")->required();
    query->add_option("point", point, "X Y Z in metres")->expected(3)->required();
    query->add_flag("--json", json, "print JSON");

    if (argc >= 2 && argv[1][0] != '-') {
        bool known = false;
        for (const CLI::App* sub : app.get_subcommands({})) known |= sub->get_name() == argv[1];
        if (!known) {
            if (log)
                std::fprintf(log,
                             "error: unknown subcommand '%s' (use bake, verify, occluders, export, info or query; "
                             "see pvsbake --help)\n",
                             argv[1]);
            return kExitBadInput;
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        out << app.help(e.get_name().empty() ? "" : "", CLI::AppFormatMode::Normal);
        return kExitOk;
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) {
            std::ostringstream o, err;
            app.exit(e, o, err);
            out << o.str();
            return kExitOk;
        }
        if (log)
            std::fprintf(
                log, "error: %s (see pvsbake %s--help)\n", e.what(),
                app.get_subcommands().empty() ? "" : (app.get_subcommands()[0]->get_name() + " ").c_str());
        return kExitBadInput;
    }

    // Under mpirun rank 0 speaks for the job (driver/processes.h), and only bake and verify are shared between
    // ranks: the other commands run on rank 0 alone.
    if (process_rank() > 0 && !bake->parsed() && !verify->parsed()) return kExitOk;
    if (process_rank() > 0) common.quiet = true;
    Context ctx = make_context(common, log);
    try {
        config.verify.enabled = !no_verify;
        if (bake->parsed()) {
            config.cells.kind = cells_kind == "octree" ? CellKind::kOctree : CellKind::kGrid;
            config.mode = mode == "conservative" ? BakeMode::kConservative : BakeMode::kSampled;
            apply_view_args(view_args, config.view);
            config.occluders.enabled = !no_occluders;
            validate(config);
            return run_bake(ctx, config, world_path, out_path, common.report_path,
                            resume    ? ResumeMode::kResume
                            : restart ? ResumeMode::kRestart
                                      : ResumeMode::kAuto,
                            reuse_path, runtime_path);
        }
        if (verify->parsed()) {
            validate(config);
            return run_verify(ctx, config, world_path, bake_path, common.report_path, !no_write,
                              verify->count("--gap-tolerance") > 0);
        }
        if (occ->parsed()) {
            apply_view_args(occ_view_args, config.view);
            validate(config);
            return run_occluders(ctx, config, world_path, out_path, common.report_path);
        }
        if (info->parsed()) return run_info(bake_path, json, out);
        if (query->parsed()) return run_query(bake_path, point, json, out);
        if (exporter->parsed()) return run_export(ctx, bake_path, runtime_path, runtime_options);
    } catch (const Error& e) {
        ctx.error(e.what());
        abort_processes(exit_status(e.kind()));
        return exit_status(e.kind());
    } catch (const std::bad_alloc&) {
        ctx.error("out of memory (try a larger --cell-size or fewer rays)");
        abort_processes(kExitFailure);
        return kExitFailure;
    } catch (const std::exception& e) {
        ctx.error(fmt::format("internal error: {}", e.what()));
        abort_processes(kExitFailure);
        return kExitFailure;
    }
    return kExitFailure;
}

}  // namespace pvs
