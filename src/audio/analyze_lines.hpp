// SPDX-License-Identifier: MIT
// Private to strike_fftw: what analyzeAudio (analyze.cpp) shares with its spectrum
// (analyze_spectrum.cpp: the whole-signal spectrum, its peaks and the closed-form line shape) and
// its decay fits (analyze_decay.cpp: frames demodulated at a line, their log-line and pair fits).
#pragma once

#include <cstddef>
#include <vector>

#include "strike/audio/audio.hpp"

namespace strike::detail {

/// One channel to analyse: the mean of the channels, the first sample over the onset threshold.
struct Mono {
  std::vector<double> x;
  size_t onset = 0;
  double peak = 0.0;
};

/// |X_k| scaled so that a stationary sinusoid of amplitude a peaks at a (2 |X| / sum w).
struct Spectrum {
  std::vector<double> amplitude;
  double bin_hz = 0.0;
  double window_sum = 0.0;  ///< sum of the window over the signal: a line's |X| is A sum(w) / 2
};

struct Candidate {
  double freq_hz = 0.0;
  double amplitude = 0.0;
  double half_width_hz = 0.0;      ///< half width at -3 dB, for the first guess of the decay
  double skirt_decay_per_s = 0.0;  ///< decay used to model this line's leakage onto others
};

struct DecayFit {
  double decay_per_s = -1.0;  ///< < 0: too few usable frames
  double freq_hz = 0.0;       ///< from the phase slope of the same frames
  double amplitude = 0.0;     ///< A of A e^{-d t} cos(...) at the onset, from the line's intercept
};

/// The spectrum of mono.x from mono.onset on, zero-padded to a power of two, with `window`.
Spectrum wholeSpectrum(const Mono& mono, SpectrumWindow window, double rate_hz);
/// The window's response to one decaying line offset_hz away, in closed form.
double lineShape(double offset_hz, double decay_per_s, size_t length, double rate_hz, SpectrumWindow window);
/// The decay whose model line is as wide as the measured one.
double decayFromHalfWidth(double half_width_hz, size_t length, double rate_hz, SpectrumWindow window);
/// The peak at bin k, interpolated.
Candidate interpolatePeak(const Spectrum& spectrum, size_t k);
/// The -3 dB half width of a peak.
double halfWidthHz(const Spectrum& spectrum, const Candidate& candidate);
/// A line's decay, frequency and amplitude from frames demodulated at it.
DecayFit fitDecay(const Mono& mono, double rate_hz, const Candidate& peak, double nearest_df_hz);

}  // namespace strike::detail
