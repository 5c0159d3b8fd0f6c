// SPDX-License-Identifier: MIT
#include "cache_file.hpp"

#include <cstdio>

#include "strike/core/atomic_file.hpp"
#include "strike/core/hash.hpp"
#include "strike/core/read_file.hpp"

namespace strike::cache_file {

std::string path(const std::string& dir, uint64_t key, const char* extension) {
  char name[24];
  std::snprintf(name, sizeof name, "%016llx", static_cast<unsigned long long>(key));
  return dir + "/" + name + extension;
}

Error damaged(const std::string& path, const char* kind, const std::string& why) {
  return badInput(path + ": damaged " + kind + " file (" + why + ")");
}

Result<Checked> read(const std::string& path, const char (&magic)[8], const char* kind, uint64_t max_bytes,
                     size_t min_body) {
  Result<std::string> bytes = readWholeFile(path, max_bytes);
  if (!bytes) return bytes.error();
  Checked file;
  file.bytes = std::move(*bytes);
  const std::string& in = file.bytes;
  if (in.size() < sizeof magic + min_body + sizeof(uint64_t) || std::memcmp(in.data(), magic, sizeof magic) != 0)
    return damaged(path, kind, "no " + std::string(magic, sizeof magic) + " header");
  file.body_end = in.size() - sizeof(uint64_t);
  uint64_t checksum = 0;
  std::memcpy(&checksum, in.data() + file.body_end, sizeof checksum);
  if (checksum != fnv1a64(in.data(), file.body_end)) return damaged(path, kind, "checksum");
  return file;
}

Status write(const std::string& path, std::string out) {
  put(out, fnv1a64(out.data(), out.size()));
  return writeFileAtomically(path, out.data(), out.size());
}

}  // namespace strike::cache_file
