// SPDX-License-Identifier: MIT
#include "strike/core/read_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace strike {

Result<std::string> readWholeFile(const std::string& path, uint64_t max_bytes) {
  struct stat info {};
  if (stat(path.c_str(), &info) != 0) return badInput(path + ": error: cannot open: " + std::strerror(errno));
  if (S_ISDIR(info.st_mode)) return badInput(path + ": error: is a directory, expected a file");
  if (static_cast<uint64_t>(info.st_size) > max_bytes)
    return badInput(path + ": error: file is " + std::to_string(info.st_size) + " bytes, larger than the limit of " +
                    std::to_string(max_bytes) + " bytes");
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) return badInput(path + ": error: cannot open: " + std::strerror(errno));
  std::string bytes;
  bytes.reserve(static_cast<size_t>(info.st_size));  // no regrowth copies of a 17 MB bank
  char buffer[1 << 16];
  size_t got = 0;
  while ((got = std::fread(buffer, 1, sizeof buffer, file)) > 0) {
    bytes.append(buffer, got);
    if (bytes.size() > max_bytes) break;  // the file grew while we read it
  }
  const bool failed = std::ferror(file) != 0;
  std::fclose(file);
  if (failed) return badInput(path + ": error: read failed");
  if (bytes.size() > max_bytes)
    return badInput(path + ": error: file is larger than the limit of " + std::to_string(max_bytes) + " bytes");
  return bytes;
}

}  // namespace strike
