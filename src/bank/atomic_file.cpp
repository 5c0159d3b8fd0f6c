// SPDX-License-Identifier: MIT
#include "strike/atomic_file.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "strike/interrupt_cleanup.hpp"

namespace strike {

std::string temporaryPathFor(const std::string& path) {
  static std::atomic<unsigned> counter{0};  // distinct names for several writes in one process
  return path + ".tmp-" + std::to_string(static_cast<long>(getpid())) + "-" +
         std::to_string(counter.fetch_add(1));
}

Status writeFileAtomically(const std::string& path, const void* data, size_t size) {
  const std::string temp = temporaryPathFor(path);
  // Registered before it exists, so an interrupt at any point removes it (unlink of a missing
  // file is harmless); unregistered after the rename or the removal.
  TemporaryRegistration registration(temp);
  std::FILE* file = std::fopen(temp.c_str(), "wb");
  if (!file) return badInput(path + ": error: cannot create output file: " + std::strerror(errno));
  const bool written = size == 0 || std::fwrite(data, 1, size, file) == size;
  const int write_errno = errno;
  // fclose reports delayed write errors (a full disk) that fwrite may not.
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) {
    std::remove(temp.c_str());
    return badInput(path + ": error: writing failed: " + std::strerror(written ? errno : write_errno));
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const int rename_errno = errno;
    std::remove(temp.c_str());
    return badInput(path + ": error: cannot move the output into place: " + std::strerror(rename_errno));
  }
  return {};
}

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
