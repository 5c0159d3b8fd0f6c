// SPDX-License-Identifier: MIT
// A delay line read at a fractional position (private to src/synth): what a moving source's
// paths are heard through (moving_source.cpp).
//
// The interpolator is a Kaiser-windowed sinc of kTaps taps (beta 8) [Laakso, Valimaki, Karjalainen
// & Laine 1996, "Splitting the unit delay", IEEE Signal Processing Magazine 13(1), sec. on
// windowed sinc], tabulated at kPhases fractions and interpolated linearly between them, each
// fraction's taps scaled to sum to 1 (a constant passes unchanged). Its error against the ideal
// delay e^{-i omega f}, the worst over the fraction f, at 48 kHz (docs/listener.md): below
// -88 dB up to 16 kHz, -79 dB at 18 kHz, -77 dB at 20 kHz; a 4-point Lagrange interpolator would
// be -55 dB at 4 kHz and -4 dB at 20 kHz.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace strike {

class FractionalDelay {
 public:
  static constexpr int kTaps = 32;
  static constexpr int kPhases = 1024;
  /// Samples the line must hold after a read position: taps kTaps / 2 ahead of floor(x).
  static constexpr int kLookahead = kTaps / 2;
  FractionalDelay();
  /// The line's sample at fractional index x (x >= kTaps / 2 - 1 samples after the oldest one
  /// kept, x + kLookahead < the newest written): `ring` holds sample j at j & mask.
  float read(const float* ring, uint64_t mask, double x) const;

 private:
  std::vector<float> table_;  ///< (kPhases + 1) x kTaps: taps for fraction p / kPhases
};

}  // namespace strike
