// SPDX-License-Identifier: MIT
// The band a render plays: defined once here, so the synthesizer, the modes a render computes and
// the modes the precompute gives an acoustic transfer all follow the same rule, and the
// precompute needs no synthesizer to know it.
#pragma once

#include <algorithm>

namespace strike {

/// A render's sample rate and the top of the band asked for, when nothing else is said.
constexpr double kDefaultSampleRateHz = 48000.0;
constexpr double kDefaultMaxFreqHz = 20000.0;

/// The top of the band a render synthesizes, as a fraction of its sample rate (a margin below
/// Nyquist, 0.5). The one definition of it: the oscillator bank's band, the modes a render
/// computes, and the modes that get an acoustic transfer all follow it.
constexpr double kBandTopOfSampleRate = 0.45;

/// The highest frequency a render at `sample_rate_hz` synthesizes with `max_freq_hz` asked for:
/// min(max_freq_hz, 0.45 fs). A mode at or below it is played (OscillatorBank), above it never.
inline double synthesizedTopHz(double max_freq_hz, double sample_rate_hz) {
  return std::min(max_freq_hz, kBandTopOfSampleRate * sample_rate_hz);
}

}  // namespace strike
