// pvsbake io: AtomicOutput and write_file_atomically. Output goes to "<final>.tmp-<pid>-<counter>" in the
// final file's folder (so the rename stays on one file system and is atomic), then commit() renames it
// over the final path; an uncommitted temporary file is removed by the destructor.
#include "io/atomic_file.h"

#include "core/error.h"

#include <fmt/format.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

namespace pvs {
namespace {

std::string make_temp_path(const std::string& final_path) {
    // Unique within the process by the counter and across processes by the pid.
    static std::atomic<uint64_t> counter{0};
    return fmt::format("{}.tmp-{}-{}", final_path, long(::getpid()), counter.fetch_add(1));
}

// Makes the rename itself durable. Best effort: some file systems refuse fsync on a folder.
void sync_parent_folder(const std::string& path) {
    std::filesystem::path folder = std::filesystem::path(path).parent_path();
    if (folder.empty()) folder = ".";
    const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;
    ::fsync(fd);
    ::close(fd);
}

}  // namespace

void check_output_writable(const std::string& path, const std::string& what) {
    namespace fs = std::filesystem;
    const fs::path p(path);
    fs::path folder = p.parent_path();
    if (folder.empty()) folder = ".";
    std::error_code ec;
    if (p.filename().empty() || fs::is_directory(p, ec)) {
        throw bad_input(fmt::format("{} {}: is a folder, not a file name", what, path));
    }
    if (!fs::is_directory(folder, ec)) {
        throw bad_input(fmt::format("{} {}: the folder {} does not exist", what, path, folder.string()));
    }
    const std::string probe = make_temp_path(path);
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) {
        const int err = errno;
        throw bad_input(fmt::format("{} {}: cannot write in the folder {}: {}", what, path, folder.string(),
                                    std::strerror(err)));
    }
    ::close(fd);
    fs::remove(probe, ec);
}

AtomicOutput::AtomicOutput(std::string final_path)
    : final_path_(std::move(final_path)), temp_path_(make_temp_path(final_path_)) {}

AtomicOutput::~AtomicOutput() {
    if (committed_) return;
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);  // never throws; a missing file is fine
}

void AtomicOutput::commit() {
    if (committed_) throw internal_error(fmt::format("{}: committed twice", final_path_));
    std::error_code ec;
    std::filesystem::rename(temp_path_, final_path_, ec);
    if (ec) {
        throw io_error(fmt::format("cannot rename {} to {}: {}", temp_path_, final_path_, ec.message()));
    }
    committed_ = true;
    sync_parent_folder(final_path_);
}

void write_file_atomically(const std::string& path, const std::string& bytes) {
    AtomicOutput out(path);
    std::FILE* f = std::fopen(out.temp_path().c_str(), "wb");
    if (f == nullptr) throw io_error(fmt::format("{}: cannot write: {}", path, std::strerror(errno)));
    bool ok = bytes.empty() || std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    ok = ok && std::fflush(f) == 0;
    ok = ok && ::fsync(::fileno(f)) == 0;
    const int saved_errno = errno;
    const bool closed = std::fclose(f) == 0;
    if (!ok || !closed) {
        throw io_error(fmt::format("{}: cannot write: {}", path, std::strerror(ok ? errno : saved_errno)));
    }
    out.commit();
}

}  // namespace pvs
