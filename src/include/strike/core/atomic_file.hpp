// SPDX-License-Identifier: MIT
// Writing outputs so that nothing half-written is ever left where the output should be
// (strike_output; the temporaries are removed on Ctrl-C through interrupt_cleanup.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "strike/core/read_file.hpp"  // the reading side, for the callers that do both
#include "strike/core/result.hpp"

namespace strike {

/// A temporary path in the same directory as `path` (so rename() is atomic on POSIX):
/// "<path>.tmp-<pid>-<counter>".
std::string temporaryPathFor(const std::string& path);

/// Writes `size` bytes to a temporary file beside `path`, closes it, then renames it over
/// `path`. On any failure the temporary file is removed and `path` is untouched.
Status writeFileAtomically(const std::string& path, const void* data, size_t size);

}  // namespace strike
