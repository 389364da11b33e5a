// SPDX-License-Identifier: MIT
// pvsbake io: write a file whole or not at all, and say in plain words why a write failed.
//
// Write to temp_path(), then commit(): the temporary file is renamed over the final path (atomic on
// one file system). If commit() is never called (an error, an exception), the destructor removes the
// temporary file, so no half-written output is ever left under the final name, and what a full disk took
// is given back.
//
// Every failure is a pvs::Error (kIo) of one line that starts with the final path, says why in plain words
// and what was being written: "out/r.h5: no space left on device while writing the bake file".
#pragma once

#include "core/error.h"

#include <string>

namespace pvs {

class AtomicOutput {
public:
    // `what` names the output in messages ("the bake file", "the report").
    explicit AtomicOutput(std::string final_path, std::string what = "the output");
    ~AtomicOutput();
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;

    const std::string& temp_path() const { return temp_path_; }
    const std::string& final_path() const { return final_path_; }
    // Renames the temporary file to the final path. Throws pvs::Error (kIo) on failure.
    void commit();

private:
    std::string final_path_;
    std::string what_;
    std::string temp_path_;
    bool committed_ = false;
};

// Writes bytes to path atomically (through AtomicOutput): written, flushed to the disk (fsync), closed, then
// renamed. Throws pvs::Error (kIo) naming path and `what` on any failure.
void write_file_atomically(const std::string& path, const std::string& bytes, const std::string& what);

// Checks, before any work, that an output can be written at `path` as AtomicOutput writes it: its folder
// exists, `path` is not a folder, and a temporary file can be created in that folder (permissions, a
// read-only file system); the probe file is removed, and so are the temporary files of earlier writers of
// `path` that were killed (remove_stale_temporaries()). Throws pvs::Error naming `what` and the path otherwise:
// bad input for a wrong place (a missing folder, permissions, a read-only file system), kIo when the disk
// itself fails (full, quota, I/O error). A disk that fills up later is not foreseen.
void check_output_writable(const std::string& path, const std::string& what);

// Removes the temporary files "<final_path>.tmp-<pid>-<n>" that writers killed before their rename left
// (their process is gone from this machine). check_output_writable() calls it. Never throws.
void remove_stale_temporaries(const std::string& final_path) noexcept;

// An errno in plain words, as a clause: "no space left on device".
std::string describe_errno(int err);

// The error of a failed write: "{path}: {describe_errno(err)} while {doing} {what}" (kIo). `doing`:
// "writing", "creating", "renaming"...
Error write_error(const std::string& path, int err, const std::string& what,
                  const std::string& doing = "writing");

}  // namespace pvs
