// SPDX-License-Identifier: MIT
// pvsbake io: checkpoint chunks, written with io/hdf5_writer.h and read with the loader's validating
// Reader (io/loader/hdf5_reader.h).
#include "io/checkpoint.h"

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/hdf5_file.h"
#include "io/loader/bake_reader.h"

#include <fmt/format.h>
#include <hdf5.h>

#include <algorithm>
#include <filesystem>
#include <system_error>

namespace pvs {
namespace {

namespace fs = std::filesystem;
using pvsbake::detail::Handle;
using pvsbake::detail::QuietHdf5;
using pvsbake::detail::Reader;

constexpr const char* kCheckpointFormat = "pvsbake-checkpoint";
constexpr int32_t kCheckpointVersion = 1;
constexpr const char* kChunkPrefix = "rows-";
constexpr const char* kChunkSuffix = ".h5";

// "rows-000007.h5"; under MPI each rank writes its own, rank r > 0 "rows-000007-r3.h5".
std::string chunk_name(uint32_t index, int rank) {
    return rank > 0 ? fmt::format("{}{:06}-r{}{}", kChunkPrefix, index, rank, kChunkSuffix)
                    : fmt::format("{}{:06}{}", kChunkPrefix, index, kChunkSuffix);
}

bool all_digits(const std::string& s) {
    return !s.empty() && s.size() <= 9 &&
           std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// The number of a chunk's file name, or 0 when it is not one (temporary files of a killed write included).
uint32_t chunk_index(const std::string& name) {
    const std::string prefix = kChunkPrefix, suffix = kChunkSuffix;
    if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
        return 0;
    const std::string middle = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    const size_t dash = middle.find("-r");
    const std::string digits = middle.substr(0, dash);
    if (!all_digits(digits) || (dash != std::string::npos && !all_digits(middle.substr(dash + 2)))) return 0;
    return uint32_t(std::stoul(digits));
}

// What differs between the identity a chunk holds and the one expected, or "" when nothing does.
std::string difference(const CheckpointIdentity& found, const CheckpointIdentity& expected) {
    if (found.tool_version != expected.tool_version)
        return fmt::format("it was made by pvsbake {}, this is {}", found.tool_version,
                           expected.tool_version);
    if (found.world_hash != expected.world_hash) {
        return fmt::format("it was made from another world (content hash {}, this world's is {})",
                           found.world_hash, expected.world_hash);
    }
    for (const auto& [key, value] : expected.parameters) {
        const auto it = std::find_if(found.parameters.begin(), found.parameters.end(),
                                     [&](const auto& p) { return p.first == key; });
        if (it == found.parameters.end()) return fmt::format("it has no parameter {}", key);
        if (it->second != value)
            return fmt::format("it was made with {} = {}, this bake has {}", key, it->second, value);
    }
    if (found.parameters.size() != expected.parameters.size())
        return fmt::format("it has {} parameters, this bake {}", found.parameters.size(),
                           expected.parameters.size());
    return {};
}

RowChunk read_chunk(const std::string& path, const CheckpointIdentity& expected) {
    return h5::read_file(path, [&](const Reader& r, hid_t root) {
        if (!r.has_attr(root, "format") || r.string_attr(root, "/", "format") != kCheckpointFormat)
            r.fail("not a pvsbake checkpoint chunk");
        if (r.int_attr(root, "/", "version") != kCheckpointVersion)
            r.fail(fmt::format("a checkpoint of another layout (this pvsbake reads version {})",
                               kCheckpointVersion));
        CheckpointIdentity found;
        found.tool_version = r.string_attr(root, "/", "tool_version");
        found.world_hash = r.string_attr(root, "/", "world_hash");
        found.parameters = pvsbake::detail::read_string_pairs(r, root, "/parameters");
        const std::string diff = difference(found, expected);
        if (!diff.empty()) throw bad_input(fmt::format("{}: not this bake's checkpoint: {}", path, diff));

        RowChunk chunk;
        Handle tables = r.open_group(root, "/tables");
        for (const std::string& name : r.string_dataset(root, "/", "table_names", -1)) {
            const std::string where = "/tables/" + name;
            Handle g = r.open_group(tables.get(), where);
            RowChunk::Table t;
            t.name = name;
            t.words_per_row = uint32_t(r.int_attr(g.get(), where, "words_per_row"));
            std::vector<int64_t> n{-1};
            t.keys = r.numeric_dataset<uint64_t>(g.get(), where, "keys", H5T_NATIVE_UINT64, n, H5T_INTEGER);
            std::vector<int64_t> shape{int64_t(t.keys.size()), int64_t(t.words_per_row)};
            t.words =
                r.numeric_dataset<uint64_t>(g.get(), where, "rows", H5T_NATIVE_UINT64, shape, H5T_INTEGER);
            chunk.tables.push_back(std::move(t));
        }
        return chunk;
    });
}

}  // namespace

std::string checkpoint_folder(const std::string& output_path) {
    return output_path + ".checkpoint";
}

bool checkpoint_exists(const std::string& folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return false;
    for (const fs::directory_entry& e : fs::directory_iterator(folder, ec))
        if (chunk_index(e.path().filename().string()) > 0) return true;
    return false;
}

Checkpoint read_checkpoint(const std::string& folder, const CheckpointIdentity& expected) {
    Checkpoint out;
    std::error_code ec;
    if (!fs::exists(folder, ec)) return out;
    if (!fs::is_directory(folder, ec))
        throw bad_input(fmt::format("the checkpoint {} is not a folder", folder));
    std::vector<std::pair<uint32_t, std::string>> files;
    for (const fs::directory_entry& e : fs::directory_iterator(folder, ec)) {
        const uint32_t index = chunk_index(e.path().filename().string());
        if (index > 0) files.emplace_back(index, e.path().string());
    }
    if (ec) throw bad_input(fmt::format("the checkpoint {}: cannot list it: {}", folder, ec.message()));
    std::sort(files.begin(), files.end());
    for (const auto& [index, path] : files) {
        out.chunks.push_back(read_chunk(path, expected));
        out.next_index = std::max(out.next_index, index + 1);
    }
    return out;
}

void write_checkpoint_chunk(const std::string& folder, uint32_t index, const CheckpointIdentity& id,
                            const RowChunk& chunk, int rank) {
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) throw write_error(folder, ec.value(), "the checkpoint", "creating the folder of");
    const std::string path = (fs::path(folder) / chunk_name(index, rank)).string();
    QuietHdf5 quiet;
    std::string bytes;
    {
        const h5::Site site(path, ErrorKind::kIo, "cannot write the checkpoint: ");
        Handle file = h5::create_memory_file(site);
        {
            h5::Writer w(site);
            Handle root = site.handle(H5Gopen2(file.get(), "/", H5P_DEFAULT), H5Gclose, "cannot open /");
            w.string_attr(root.get(), "format", kCheckpointFormat);
            w.int_attr(root.get(), "version", kCheckpointVersion);
            w.string_attr(root.get(), "tool_version", id.tool_version);
            w.string_attr(root.get(), "world_hash", id.world_hash);
            h5::write_string_pairs(w, root.get(), "/", "parameters", id.parameters);
            std::vector<std::string> names;
            for (const RowChunk::Table& t : chunk.tables) names.push_back(t.name);
            w.string_dataset(root.get(), "/", "table_names", names);
            Handle tables = w.group(root.get(), "/", "tables");
            for (const RowChunk::Table& t : chunk.tables) {
                const std::string where = "/tables/" + t.name;
                Handle g = w.group(tables.get(), "/tables", t.name);
                w.u32_attr(g.get(), "words_per_row", t.words_per_row);
                w.dataset(g.get(), where, "keys", H5T_STD_U64LE, H5T_NATIVE_UINT64, {t.keys.size()},
                          t.keys.data(), true);
                w.dataset(g.get(), where, "rows", H5T_STD_U64LE, H5T_NATIVE_UINT64,
                          {t.keys.size(), t.words_per_row}, t.words.data(), true);
            }
        }
        bytes = h5::take_file_image(site, file);
    }
    write_file_atomically(path, bytes, "the checkpoint");
}

bool remove_checkpoint(const std::string& folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return true;
    bool ok = true;
    for (const fs::directory_entry& e : fs::directory_iterator(folder, ec)) {
        const std::string name = e.path().filename().string();
        if (name.rfind(kChunkPrefix, 0) != 0) continue;  // not ours: left in place
        std::error_code rm;
        fs::remove(e.path(), rm);
        ok = ok && !rm;
    }
    std::error_code rm;
    if (fs::is_empty(folder, rm)) fs::remove(folder, rm);
    return ok && !rm && !ec;
}

}  // namespace pvs
