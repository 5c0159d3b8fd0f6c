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

#include "strike/bank/bank.hpp"

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

/// A copy of a mode bank file with its header's payload size and checksum made to match the
/// payload (docs/bank-format.md: u64 size at 16, u64 checksum at 24; format 3 has a 40-byte
/// header whose u64 head_size at 32 says how much of the payload the checksum covers), so that
/// mutations reach the chunk decoder instead of stopping at the checksum. Format 3 shape blocks
/// keep their own checksums: mutations there are refused when the block is read.
inline std::vector<uint8_t> withValidChecksum(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes(data, data + size);
  if (bytes.size() < 32) return bytes;
  uint32_t version = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  const size_t header = version >= 3 ? 40 : 32;
  if (bytes.size() < header) return bytes;
  const uint64_t payload_size = bytes.size() - header;
  uint64_t covered = payload_size;
  if (version >= 3) {
    std::memcpy(&covered, bytes.data() + 32, 8);
    covered = covered < payload_size ? covered : payload_size;
  }
  const uint64_t hash = strike::bankPayloadChecksum(version, bytes.data() + header, covered);
  std::memcpy(bytes.data() + 16, &payload_size, 8);
  std::memcpy(bytes.data() + 24, &hash, 8);
  return bytes;
}

}  // namespace strike::fuzz
