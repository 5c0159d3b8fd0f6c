// SPDX-License-Identifier: MIT
// Audio files (target strike_sndfile, libsndfile) and spectral analysis (target strike_fftw,
// FFTW: GPL, used by the tool and tests only, never by the runtime library).
#pragma once

#include <string>
#include <vector>

#include "strike/result.hpp"

namespace strike {

enum class SampleEncoding { Pcm16, Pcm24, Float32 };

struct AudioBuffer {
  double sample_rate_hz = 48000.0;
  int channels = 1;
  std::vector<float> samples;  ///< interleaved, frames * channels, full scale = 1.0
  size_t frames() const { return channels > 0 ? samples.size() / static_cast<size_t>(channels) : 0; }
};

/// Writes WAV or FLAC (chosen by the extension, .wav or .flac) atomically (temporary file in
/// the same directory, then rename). PCM encodings are written without wrapping: values
/// beyond +-1 are clipped by libsndfile's clipping mode, and the caller reports clipping.
Status writeAudio(const std::string& path, const AudioBuffer& audio, SampleEncoding encoding);
Result<AudioBuffer> readAudio(const std::string& path);

struct SpectralPeak {
  double freq_hz = 0.0;      ///< interpolated (sub-bin) peak frequency
  double level_db = 0.0;     ///< dB relative to the strongest peak (0 dB)
  double decay_per_s = -1.0; ///< fitted amplitude decay rate d of A e^(-d t), or < 0 if not fitted
};

struct AnalyzeOptions {
  int max_peaks = 20;        ///< strongest peaks to report
  double floor_db = -60.0;   ///< ignore peaks below this, relative to the strongest
  bool fit_decay = true;
};

struct AudioAnalysis {
  double sample_rate_hz = 0.0;
  double duration_s = 0.0;
  double peak_amplitude = 0.0;  ///< max |sample|
  double rms = 0.0;
  int clipped_samples = 0;      ///< |sample| >= 1
  std::vector<SpectralPeak> peaks;  ///< by decreasing level
};

/// Analyses the mixdown (mean of channels): whole-signal windowed FFT with sub-bin
/// interpolation for peaks; per-peak decay from the envelope of a narrow band around the peak.
AudioAnalysis analyzeAudio(const AudioBuffer& audio, const AnalyzeOptions& options);

}  // namespace strike
