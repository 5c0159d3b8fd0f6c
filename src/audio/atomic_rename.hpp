// SPDX-License-Identifier: MIT
// Private helper of src/audio: temporary names beside an output, so that rename() is atomic
// (same directory, same file system). Used by audio_file.cpp: libsndfile opens the file by name,
// and strike_sndfile links libsndfile only, not strike_bank, so it cannot use strike_bank's
// temporaryPathFor (strike/atomic_file.hpp); this makes names of the same form,
// "<path>.tmp-<pid>-<counter>". (strike_fftw does link strike_bank: its PNGs are written with
// writeFileAtomically.)
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
