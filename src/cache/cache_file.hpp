// SPDX-License-Identifier: MIT
// The framing the render's small cache files share (pieces_cache.hpp, hull_cache.hpp): 8 bytes of
// magic, a body of little-endian values, and the FNV-1a (u64) of all before it, written
// atomically. Internal to strike_scene.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>

#include "strike/core/result.hpp"

namespace strike::cache_file {

/// "<dir>/<16 hex digits of key><extension>", the cache's names.
std::string path(const std::string& dir, uint64_t key, const char* extension);

/// A file's bytes, checked: its body is [8, body_end).
struct Checked {
  std::string bytes;
  size_t body_end = 0;
  size_t at = 8;  ///< where get() reads next

  /// The next value of the body; false past its end.
  template <typename T>
  bool get(T& value) {
    if (body_end - at < sizeof(T)) return false;
    std::memcpy(&value, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return true;
  }
};

/// Reads `path` whole (at most max_bytes) and checks its magic and checksum, and that the body
/// holds at least min_body bytes. The error names the file: "PATH: damaged KIND file (WHY)".
Result<Checked> read(const std::string& path, const char (&magic)[8], const char* kind, uint64_t max_bytes,
                     size_t min_body);

/// The damaged-file error read() gives, for what the caller finds wrong in the body.
Error damaged(const std::string& path, const char* kind, const std::string& why);

/// Appends a value to a file being built (the project's targets are little-endian).
template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

/// Appends the checksum to `out` (magic and body) and writes it atomically.
Status write(const std::string& path, std::string out);

}  // namespace strike::cache_file
