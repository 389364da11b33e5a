// SPDX-License-Identifier: MIT
// pvsbake core: the one exception type thrown at boundaries (files, glTF, Embree, HDF5, config).
//
// Rule (CONTRIBUTING.md): a message says what is wrong, where (file, node, accessor, option) and, when
// it helps, what to do. The top level catches pvs::Error, prints its message on one line and exits
// with exit_status(kind): 2 for bad input, 1 for everything else.
#pragma once

#include <stdexcept>
#include <string>

namespace pvs {

enum class ErrorKind {
    kBadInput,  // the user's file, option or world is wrong: exit status 2
    kIo,        // reading or writing failed for reasons outside the input (disk full, permissions)
    kInternal,  // a library failed or an invariant broke: a bug to report
};

class Error : public std::runtime_error {
public:
    Error(ErrorKind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
    ErrorKind kind() const { return kind_; }

private:
    ErrorKind kind_;
};

inline Error bad_input(const std::string& message) {
    return Error(ErrorKind::kBadInput, message);
}
inline Error io_error(const std::string& message) {
    return Error(ErrorKind::kIo, message);
}
inline Error internal_error(const std::string& message) {
    return Error(ErrorKind::kInternal, message);
}

inline int exit_status(ErrorKind kind) {
    return kind == ErrorKind::kBadInput ? 2 : 1;
}

}  // namespace pvs
