// pvsbake io: write a file whole or not at all.
//
// Write to temp_path(), then commit(): the temporary file is renamed over the final path (atomic on
// one file system). If commit() is never called (an error, an exception), the destructor removes the
// temporary file, so no half-written output is ever left under the final name.
#pragma once

#include <string>

namespace pvs {

class AtomicOutput {
public:
    explicit AtomicOutput(std::string final_path);
    ~AtomicOutput();
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;

    const std::string& temp_path() const { return temp_path_; }
    const std::string& final_path() const { return final_path_; }
    // Renames the temporary file to the final path. Throws pvs::Error (kIo) on failure.
    void commit();

private:
    std::string final_path_;
    std::string temp_path_;
    bool committed_ = false;
};

// Writes bytes to path atomically (through AtomicOutput). Throws pvs::Error (kIo) on failure.
void write_file_atomically(const std::string& path, const std::string& bytes);

// Checks, before any work, that an output can be written at `path` as AtomicOutput writes it: its folder
// exists, `path` is not a folder, and a temporary file can be created in that folder (permissions, a
// read-only file system); the probe file is removed. Throws pvs::Error (kBadInput) naming `what` and the
// path otherwise. A disk that fills up later is not foreseen.
void check_output_writable(const std::string& path, const std::string& what);

}  // namespace pvs
