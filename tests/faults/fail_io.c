// SPDX-License-Identifier: MIT
/* A preloaded library (LD_PRELOAD) that makes a chosen write-side call of a process fail, in the manner of
 * SQLite's I/O error tests: tests/faults/inject.py runs a command once to count its calls, then once for every
 * N, failing the Nth.
 *
 * Counted ("a write"): open, openat, creat that create or truncate, or open an existing file for writing; write, pwrite, writev,
 * pwritev, ftruncate, fsync, fdatasync and close on a descriptor that is neither a terminal nor a pipe nor
 * one of 0, 1 and 2 (the logs); rename, renameat, renameat2, mkdir, mkdirat, link, symlink. Reads and removals
 * are never counted, so a failure cannot hide what a run had already written.
 *
 * Environment:
 *   PVSBAKE_FAIL_AT=N        the Nth counted call fails (1-based; unset or 0: none fails)
 *   PVSBAKE_FAIL_STICKY=1    every counted call from the Nth on fails (a disk that stays full)
 *   PVSBAKE_FAIL_ERRNO=E     the errno a failing call sets: ENOSPC (default), EIO, EDQUOT, EROFS, EACCES
 *   PVSBAKE_FAIL_TRACE=PATH  appends "N call target" for every counted call, and "fail" on those made to fail
 *   PVSBAKE_FAIL_PATH=TEXT   only calls on paths holding TEXT are counted (the others neither count nor fail)
 *   PVSBAKE_DENY_READ=TEXT   every open for reading of a path holding TEXT fails with EACCES (a file the
 *                            process may not read, which root cannot otherwise see)
 *
 * A close made to fail still closes its descriptor (as Linux does when close reports an error). The library is
 * a test tool: nothing of pvsbake links it. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

static atomic_long calls;

static long env_long(const char* name) {
    const char* v = getenv(name);
    return v ? strtol(v, NULL, 10) : 0;
}

static int fail_errno(void) {
    const char* v = getenv("PVSBAKE_FAIL_ERRNO");
    if (!v || !strcmp(v, "ENOSPC")) return ENOSPC;
    if (!strcmp(v, "EIO")) return EIO;
    if (!strcmp(v, "EDQUOT")) return EDQUOT;
    if (!strcmp(v, "EROFS")) return EROFS;
    if (!strcmp(v, "EACCES")) return EACCES;
    return atoi(v) > 0 ? atoi(v) : ENOSPC;
}

static void* real(const char* name) {
    void* f = dlsym(RTLD_NEXT, name);
    if (!f) abort();
    return f;
}

/* The target of a descriptor, for the trace. */
static void fd_target(int fd, char* out, size_t size) {
    char link[64];
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    const ssize_t n = readlink(link, out, size - 1);
    out[n > 0 ? (size_t)n : 0] = '\0';
}

static void trace(long n, const char* call, const char* target, int failed) {
    const char* path = getenv("PVSBAKE_FAIL_TRACE");
    if (!path) return;
    static int (*real_open)(const char*, int, ...);
    static ssize_t (*real_write)(int, const void*, size_t);
    static int (*real_close)(int);
    if (!real_open) {
        real_open = (int (*)(const char*, int, ...))real("open");
        real_write = (ssize_t(*)(int, const void*, size_t))real("write");
        real_close = (int (*)(int))real("close");
    }
    char line[PATH_MAX + 96];
    const int len = snprintf(line, sizeof line, "%ld %s %s%s\n", n, call, target, failed ? " fail" : "");
    const int fd = real_open(path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd < 0) return;
    if (len > 0) real_write(fd, line, (size_t)len < sizeof line ? (size_t)len : sizeof line - 1);
    real_close(fd);
}

/* Counts one call; returns 1 when it is to fail (errno is then set). */
static int counted(const char* call, const char* target) {
    const char* only = getenv("PVSBAKE_FAIL_PATH");
    if (only && *only && (!target || !strstr(target, only))) return 0;
    const long n = atomic_fetch_add(&calls, 1) + 1;
    const long at = env_long("PVSBAKE_FAIL_AT");
    const int fail = at > 0 && (n == at || (n > at && env_long("PVSBAKE_FAIL_STICKY") == 1));
    trace(n, call, target, fail);
    if (fail) errno = fail_errno();
    return fail;
}

/* A descriptor whose writes count: not the logs, a terminal or a pipe. */
static int counts(int fd) {
    if (fd <= 2) return 0;
    struct stat st;
    if (fstat(fd, &st) != 0) return 0;
    return S_ISREG(st.st_mode) || S_ISDIR(st.st_mode) || S_ISBLK(st.st_mode);
}

static int counted_fd(const char* call, int fd) {
    if (!counts(fd)) return 0;
    char target[PATH_MAX];
    fd_target(fd, target, sizeof target);
    return counted(call, target);
}

#define MODE_ARG(flags, mode)                 \
    mode_t mode = 0;                          \
    if ((flags) & (O_CREAT | __O_TMPFILE)) {  \
        va_list ap;                           \
        va_start(ap, flags);                  \
        mode = va_arg(ap, mode_t);            \
        va_end(ap);                           \
    }

/* An open that creates or truncates counts before it runs; one that only opens an existing file for writing
 * counts once it succeeded (HDF5 tries such opens of names that need not exist). */
static int open_result(int fd, int flags, const char* call, const char* path) {
    if (fd < 0 || (flags & (O_CREAT | O_TRUNC)) || (flags & O_ACCMODE) == O_RDONLY) return fd;
    if (counted(call, path)) {
        const int saved = errno;
        ((int (*)(int))real("close"))(fd);
        errno = saved;
        return -1;
    }
    return fd;
}

static int creates(int flags) {
    return (flags & (O_CREAT | O_TRUNC)) != 0;
}

/* A read-only open that PVSBAKE_DENY_READ refuses. */
static int denied(const char* path, int flags) {
    const char* deny = getenv("PVSBAKE_DENY_READ");
    if (!deny || !*deny || (flags & O_ACCMODE) != O_RDONLY || !path || !strstr(path, deny)) return 0;
    errno = EACCES;
    return 1;
}

int open(const char* path, int flags, ...) {
    MODE_ARG(flags, mode);
    if (creates(flags) && counted("open", path)) return -1;
    if (denied(path, flags)) return -1;
    return open_result(((int (*)(const char*, int, ...))real("open"))(path, flags, mode), flags, "open", path);
}
int open64(const char* path, int flags, ...) {
    MODE_ARG(flags, mode);
    if (creates(flags) && counted("open", path)) return -1;
    if (denied(path, flags)) return -1;
    return open_result(((int (*)(const char*, int, ...))real("open64"))(path, flags, mode), flags, "open", path);
}
int openat(int dir, const char* path, int flags, ...) {
    MODE_ARG(flags, mode);
    if (creates(flags) && counted("openat", path)) return -1;
    if (denied(path, flags)) return -1;
    return open_result(((int (*)(int, const char*, int, ...))real("openat"))(dir, path, flags, mode), flags,
                       "openat", path);
}
int openat64(int dir, const char* path, int flags, ...) {
    MODE_ARG(flags, mode);
    if (creates(flags) && counted("openat", path)) return -1;
    if (denied(path, flags)) return -1;
    return open_result(((int (*)(int, const char*, int, ...))real("openat64"))(dir, path, flags, mode), flags,
                       "openat", path);
}
int creat(const char* path, mode_t mode) {
    if (counted("creat", path)) return -1;
    return ((int (*)(const char*, mode_t))real("creat"))(path, mode);
}
int creat64(const char* path, mode_t mode) {
    if (counted("creat", path)) return -1;
    return ((int (*)(const char*, mode_t))real("creat64"))(path, mode);
}

ssize_t write(int fd, const void* buf, size_t n) {
    if (counted_fd("write", fd)) return -1;
    return ((ssize_t(*)(int, const void*, size_t))real("write"))(fd, buf, n);
}
ssize_t pwrite(int fd, const void* buf, size_t n, off_t at) {
    if (counted_fd("pwrite", fd)) return -1;
    return ((ssize_t(*)(int, const void*, size_t, off_t))real("pwrite"))(fd, buf, n, at);
}
ssize_t pwrite64(int fd, const void* buf, size_t n, off_t at) {
    if (counted_fd("pwrite", fd)) return -1;
    return ((ssize_t(*)(int, const void*, size_t, off_t))real("pwrite64"))(fd, buf, n, at);
}
ssize_t writev(int fd, const struct iovec* iov, int count) {
    if (counted_fd("writev", fd)) return -1;
    return ((ssize_t(*)(int, const struct iovec*, int))real("writev"))(fd, iov, count);
}
ssize_t pwritev(int fd, const struct iovec* iov, int count, off_t at) {
    if (counted_fd("pwritev", fd)) return -1;
    return ((ssize_t(*)(int, const struct iovec*, int, off_t))real("pwritev"))(fd, iov, count, at);
}
int ftruncate(int fd, off_t length) {
    if (counted_fd("ftruncate", fd)) return -1;
    return ((int (*)(int, off_t))real("ftruncate"))(fd, length);
}
int ftruncate64(int fd, off_t length) {
    if (counted_fd("ftruncate", fd)) return -1;
    return ((int (*)(int, off_t))real("ftruncate64"))(fd, length);
}
int fsync(int fd) {
    if (counted_fd("fsync", fd)) return -1;
    return ((int (*)(int))real("fsync"))(fd);
}
int fdatasync(int fd) {
    if (counted_fd("fdatasync", fd)) return -1;
    return ((int (*)(int))real("fdatasync"))(fd);
}
int close(int fd) {
    int wrote = 0;
    if (counts(fd)) {
        const int flags = fcntl(fd, F_GETFL);
        wrote = flags >= 0 && (flags & O_ACCMODE) != O_RDONLY;
    }
    const int fail = wrote && counted_fd("close", fd);
    const int saved = errno;
    const int r = ((int (*)(int))real("close"))(fd);
    if (fail) {
        errno = saved;
        return -1;
    }
    return r;
}

int rename(const char* from, const char* to) {
    if (counted("rename", to)) return -1;
    return ((int (*)(const char*, const char*))real("rename"))(from, to);
}
int renameat(int fd_from, const char* from, int fd_to, const char* to) {
    if (counted("renameat", to)) return -1;
    return ((int (*)(int, const char*, int, const char*))real("renameat"))(fd_from, from, fd_to, to);
}
int renameat2(int fd_from, const char* from, int fd_to, const char* to, unsigned flags) {
    if (counted("renameat2", to)) return -1;
    return ((int (*)(int, const char*, int, const char*, unsigned))real("renameat2"))(fd_from, from, fd_to, to,
                                                                                        flags);
}
int mkdir(const char* path, mode_t mode) {
    if (counted("mkdir", path)) return -1;
    return ((int (*)(const char*, mode_t))real("mkdir"))(path, mode);
}
int mkdirat(int dir, const char* path, mode_t mode) {
    if (counted("mkdirat", path)) return -1;
    return ((int (*)(int, const char*, mode_t))real("mkdirat"))(dir, path, mode);
}
int link(const char* from, const char* to) {
    if (counted("link", to)) return -1;
    return ((int (*)(const char*, const char*))real("link"))(from, to);
}
int symlink(const char* from, const char* to) {
    if (counted("symlink", to)) return -1;
    return ((int (*)(const char*, const char*))real("symlink"))(from, to);
}
