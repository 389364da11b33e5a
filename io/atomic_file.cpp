// SPDX-License-Identifier: MIT
// pvsbake io: AtomicOutput and write_file_atomically. Output goes to "<final>.tmp-<pid>-<counter>" in the
// final file's folder (so the rename stays on one file system and is atomic), then commit() renames it
// over the final path; an uncommitted temporary file is removed by the destructor. Plain POSIX calls, each
// checked, so that every failure keeps its errno.
#include "io/atomic_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <csignal>
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

// Makes the rename itself durable. Best effort, and it never throws: the file is in place whatever happens
// here (some file systems refuse fsync on a folder; an allocation may fail).
void sync_parent_folder(const std::string& path) noexcept {
    try {
        std::filesystem::path folder = std::filesystem::path(path).parent_path();
        if (folder.empty()) folder = ".";
        const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
        if (fd < 0) return;
        ::fsync(fd);
        ::close(fd);
    } catch (...) {
    }
}

// A failure of the disk rather than of the place the user named.
bool disk_failure(int err) {
    return err == ENOSPC || err == EDQUOT || err == EIO || err == EFBIG || err == ENOMEM;
}

}  // namespace

std::string describe_errno(int err) {
    switch (err) {
        case ENOSPC:
            return "no space left on device";
        case EDQUOT:
            return "the disk quota is exceeded";
        case EIO:
            return "the device reported an I/O error";
        case EROFS:
            return "the file system is read-only";
        case EACCES:
        case EPERM:
            return "permission denied";
        case ENOENT:
            return "the folder does not exist (any more)";
        case ENOTDIR:
            return "a part of the path is not a folder";
        case EISDIR:
            return "a folder is in the way";
        case EFBIG:
            return "the file is too large for the file system";
        case ENAMETOOLONG:
            return "the name is too long";
        default:
            break;
    }
    std::string s = std::strerror(err);
    if (!s.empty()) s[0] = char(std::tolower(static_cast<unsigned char>(s[0])));
    return s;
}

Error write_error(const std::string& path, int err, const std::string& what, const std::string& doing) {
    return io_error(fmt::format("{}: {} while {} {}", path, describe_errno(err), doing, what));
}

void remove_stale_temporaries(const std::string& final_path) noexcept {
    try {
        namespace fs = std::filesystem;
        const fs::path p(final_path);
        fs::path folder = p.parent_path();
        if (folder.empty()) folder = ".";
        const std::string prefix = p.filename().string() + ".tmp-";
        std::error_code ec;
        for (const fs::directory_entry& e : fs::directory_iterator(folder, ec)) {
            const std::string name = e.path().filename().string();
            if (name.rfind(prefix, 0) != 0) continue;
            // "<final>.tmp-<pid>-<counter>": the writer's pid.
            const std::string rest = name.substr(prefix.size());
            const size_t dash = rest.find('-');
            if (dash == 0 || dash == std::string::npos ||
                rest.find_first_not_of("0123456789") != dash)
                continue;
            const long pid = std::stol(rest.substr(0, dash));
            if (pid == long(::getpid()) || ::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;
            std::error_code rm;
            fs::remove(e.path(), rm);
        }
    } catch (...) {
    }
}

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
    remove_stale_temporaries(path);
    const std::string probe = make_temp_path(path);
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) {
        const int err = errno;
        const std::string message = fmt::format("{} {}: cannot write in the folder {}: {}", what, path,
                                                folder.string(), describe_errno(err));
        throw disk_failure(err) ? io_error(message) : bad_input(message);
    }
    ::close(fd);  // an empty probe: nothing of it needs to reach the disk
    fs::remove(probe, ec);
}

AtomicOutput::AtomicOutput(std::string final_path, std::string what)
    : final_path_(std::move(final_path)), what_(std::move(what)), temp_path_(make_temp_path(final_path_)) {}

AtomicOutput::~AtomicOutput() {
    if (committed_) return;
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);  // never throws; a missing file is fine
}

void AtomicOutput::commit() {
    if (committed_) throw internal_error(fmt::format("{}: committed twice", final_path_));
    if (::rename(temp_path_.c_str(), final_path_.c_str()) != 0) {
        const int err = errno;
        throw io_error(fmt::format("{}: {} while writing {} (renaming {} to it)", final_path_,
                                   describe_errno(err), what_, temp_path_));
    }
    committed_ = true;
    sync_parent_folder(final_path_);
}

void write_file_atomically(const std::string& path, const std::string& bytes, const std::string& what) {
    AtomicOutput out(path, what);
    const int fd = ::open(out.temp_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) throw write_error(path, errno, what);
    int err = 0;
    for (size_t done = 0; done < bytes.size();) {
        const ssize_t n =
            ::write(fd, bytes.data() + done, std::min<size_t>(bytes.size() - done, size_t(1) << 30));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            err = n < 0 ? errno : ENOSPC;  // a regular file that takes no byte is full
            break;
        }
        done += size_t(n);
    }
    if (err == 0 && ::fsync(fd) != 0) err = errno;
    if (::close(fd) != 0 && err == 0) err = errno;
    if (err != 0) throw write_error(path, err, what);
    out.commit();
}

}  // namespace pvs
