// SPDX-License-Identifier: MIT
// Private helper of src/audio: temporary names beside an output, so that rename() is atomic
// (same directory, same file system). strike_sndfile and strike_fftw each link one dependency
// only, so they do not link strike_bank's writeFileAtomically; this is the same scheme
// ("<path>.tmp-<pid>-<counter>").
#pragma once

#include <unistd.h>

#include <atomic>
#include <string>

namespace strike::detail {

inline std::string audioTemporaryPathFor(const std::string& path) {
  static std::atomic<unsigned> counter{0};  // distinct names for several writes in one process
  return path + ".tmp-" + std::to_string(static_cast<long>(getpid())) + "-" + std::to_string(counter.fetch_add(1));
}

}  // namespace strike::detail
