// SPDX-License-Identifier: MIT
#include "strike/core/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "strike/core/interrupt_cleanup.hpp"

namespace strike {

std::string temporaryPathFor(const std::string& path) {
  static std::atomic<unsigned> counter{0};  // distinct names for several writes in one process
  return path + ".tmp-" + std::to_string(static_cast<long>(getpid())) + "-" + std::to_string(counter.fetch_add(1));
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

}  // namespace strike
