// SPDX-License-Identifier: MIT
// Reading a whole input file with a size cap, so a hostile path cannot exhaust memory.
#pragma once

#include <cstdint>
#include <string>

#include "strike/core/result.hpp"

namespace strike {

/// Reads a whole file; refuses directories and files larger than max_bytes (naming the cap).
Result<std::string> readWholeFile(const std::string& path, uint64_t max_bytes);

}  // namespace strike
