// SPDX-License-Identifier: MIT
// Shared by the libFuzzer targets: the path-based readers get the input through a file in a
// per-process scratch folder (tmpfs when available).
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace strike::fuzz {

inline std::string scratchPath(const char* name) {
  const char* base = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
  return std::string(base) + "/strike-fuzz-" + std::to_string(static_cast<long>(getpid())) + "-" + name;
}

/// Writes the bytes to `path`; false if the file cannot be written (then the input is skipped).
inline bool writeBytes(const std::string& path, const uint8_t* data, size_t size) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) return false;
  const bool ok = size == 0 || std::fwrite(data, 1, size, file) == size;
  return std::fclose(file) == 0 && ok;
}

}  // namespace strike::fuzz
