// SPDX-License-Identifier: MIT
// Shared helpers for the audio tests: scratch directories and synthetic signals.
#pragma once

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "strike/audio/audio.hpp"
#include "strike/core/constants.hpp"

namespace strike::test {

using strike::kPi;  // test::kPi, as the audio tests spell it

/// A fresh directory under /tmp, removed (with its files) by the destructor.
class ScratchDir {
 public:
  ScratchDir() {
    char pattern[] = "/tmp/strike-audio-test-XXXXXX";
    path_ = mkdtemp(pattern) ? pattern : "/tmp";
  }
  ~ScratchDir() {
    for (const std::string& name : list()) std::remove((path_ + "/" + name).c_str());
    rmdir(path_.c_str());
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  const std::string& path() const { return path_; }
  std::vector<std::string> list() const {
    std::vector<std::string> names;
    if (DIR* dir = opendir(path_.c_str())) {
      while (dirent* entry = readdir(dir)) {
        const std::string name = entry->d_name;
        if (name != "." && name != "..") names.push_back(name);
      }
      closedir(dir);
    }
    return names;
  }

 private:
  std::string path_;
};

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

struct Partial {
  double freq_hz;
  double amplitude;
  double decay_per_s;
  double phase = 0.0;
};

/// Mono sum of A e^{-d t} sin(2 pi f t + phase), computed in double and rounded once to float.
inline AudioBuffer partials(const std::vector<Partial>& parts, double rate_hz, double duration_s, int channels = 1) {
  AudioBuffer audio;
  audio.sample_rate_hz = rate_hz;
  audio.channels = channels;
  const auto frames = static_cast<size_t>(std::llround(duration_s * rate_hz));
  audio.samples.resize(frames * static_cast<size_t>(channels));
  for (size_t n = 0; n < frames; ++n) {
    const double t = static_cast<double>(n) / rate_hz;
    double x = 0.0;
    for (const Partial& p : parts)
      x += p.amplitude * std::exp(-p.decay_per_s * t) * std::sin(2.0 * kPi * p.freq_hz * t + p.phase);
    for (int c = 0; c < channels; ++c)
      audio.samples[n * static_cast<size_t>(channels) + static_cast<size_t>(c)] = static_cast<float>(x);
  }
  return audio;
}

}  // namespace strike::test
