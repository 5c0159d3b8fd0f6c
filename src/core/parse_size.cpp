// SPDX-License-Identifier: MIT
#include "strike/core/parse_size.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace strike {

Result<uint64_t> parseByteSize(const std::string& text, const std::string& what) {
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  std::string unit(end ? end : "");
  for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (unit.size() > 1 && unit.back() == 'B') unit.pop_back();  // "MB", "GiB" -> "M", "Gi"
  if (unit.size() == 2 && unit[1] == 'I') unit.pop_back();
  double scale = 0;
  if (unit.empty())
    scale = 1;
  else if (unit == "K")
    scale = 1024.0;
  else if (unit == "M")
    scale = 1024.0 * 1024;
  else if (unit == "G")
    scale = 1024.0 * 1024 * 1024;
  else if (unit == "T")
    scale = 1024.0 * 1024 * 1024 * 1024;
  if (text.empty() || end == text.c_str() || scale == 0 || !std::isfinite(value) || value < 0 || errno == ERANGE ||
      value * scale > 1.8e19)
    return badInput(what + " = '" + text + "' (expected a size such as 500M, 2G or a number of bytes)");
  return static_cast<uint64_t>(std::llround(value * scale));
}

Result<double> parseAgeSeconds(const std::string& text, const std::string& what) {
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  const std::string unit(end ? end : "");
  double scale = 0;
  if (unit.empty() || unit == "d")
    scale = 86400;
  else if (unit == "h")
    scale = 3600;
  else if (unit == "m")
    scale = 60;
  else if (unit == "s")
    scale = 1;
  if (text.empty() || end == text.c_str() || scale == 0 || !std::isfinite(value) || value < 0 || errno == ERANGE)
    return badInput(what + " = '" + text + "' (expected an age such as 30d, 12h, 90m or 45s)");
  return value * scale;
}

}  // namespace strike
