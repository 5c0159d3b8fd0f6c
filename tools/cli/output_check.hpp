// SPDX-License-Identifier: MIT
// Output paths are checked before any work: a render that simulates for 20 s and solves an
// eigenproblem must not then fail on a typo in -o.
#pragma once

#include <string>
#include <vector>

#include "strike/core/result.hpp"

namespace strike::cli {

/// Checks that `path` (given with `option`, e.g. "-o") can be written: its extension is one of
/// `extensions` (lower case, with the dot; empty list: any), its folder exists and accepts a new
/// file (probed by creating and removing the temporary file the atomic write would use), and it
/// is not itself a folder. The error names the option, the path and what is wrong.
Status checkOutputFile(const std::string& option, const std::string& path, const std::vector<std::string>& extensions);

/// Creates the output folder `dir` (and its parents) if missing, then checks that it is a folder
/// that accepts new files.
Status prepareOutputDir(const std::string& option, const std::string& dir);

}  // namespace strike::cli
