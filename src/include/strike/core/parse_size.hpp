// SPDX-License-Identifier: MIT
// Sizes and ages as the command line takes them (`--max-memory`, `--cache-max-size`,
// `strike cache --older-than`): one spelling for every option.
#pragma once

#include <cstdint>
#include <string>

#include "strike/core/result.hpp"

namespace strike {

/// Parses a size such as "500M", "2G", "1.5GiB", "800000" (bytes; K/M/G/T are powers of 1024).
Result<uint64_t> parseByteSize(const std::string& text, const std::string& what);
/// Parses an age such as "30d", "12h", "90m", "45s" (a bare number is days).
Result<double> parseAgeSeconds(const std::string& text, const std::string& what);

}  // namespace strike
