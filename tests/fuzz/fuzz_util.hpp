// SPDX-License-Identifier: MIT
// Shared by the libFuzzer targets: the path-based readers get the input through a file in a
// per-process scratch folder (tmpfs when available).
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "strike/bank.hpp"

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

/// A copy of a mode bank file with its header's payload size and FNV-1a checksum made to match
/// the payload (docs/bank-format.md: 32-byte header, u64 size at 16, u64 checksum at 24), so that
/// mutations reach the chunk decoder instead of stopping at the checksum.
inline std::vector<uint8_t> withValidChecksum(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes(data, data + size);
  if (bytes.size() < 32) return bytes;
  const uint64_t payload_size = bytes.size() - 32;
  uint32_t version = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  const uint64_t hash = strike::bankPayloadChecksum(version, bytes.data() + 32, payload_size);
  std::memcpy(bytes.data() + 16, &payload_size, 8);
  std::memcpy(bytes.data() + 24, &hash, 8);
  return bytes;
}

}  // namespace strike::fuzz
