// SPDX-License-Identifier: MIT
// Audio files (target strike_sndfile, libsndfile) and spectral analysis (target strike_fftw,
// FFTW: GPL, used by the tool and tests only, never by the runtime library).
#pragma once

#include <cstddef>
#include <cstdint>
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

// ---- files: target strike_sndfile ------------------------------------------------------------

/// Writes WAV or FLAC (chosen by the extension, .wav or .flac, case-insensitive) atomically
/// (temporary file "<path>.tmp-<pid>-<n>" in the same directory, then rename; on failure the
/// temporary is removed and `path` is untouched). Any channel count >= 1 and any whole sample
/// rate libsndfile accepts. FLAC is PCM only (Float32 to .flac is BadInput).
/// PCM: sample x is stored as clamp(round_half_even(x * 2^(bits-1)), -2^(bits-1), 2^(bits-1)-1),
/// so values at or beyond +-1 saturate (never wrap) and readAudio returns q / 2^(bits-1): a round
/// trip is exact to half an LSB below full scale. NaN is written as 0. The caller reports
/// clipping (see AudioAnalysis::clipped_samples). Deterministic: the same input gives the same
/// bytes (float WAV is written without libsndfile's time-stamped PEAK chunk).
Status writeAudio(const std::string& path, const AudioBuffer& audio, SampleEncoding encoding);

/// Reads any format libsndfile reads, as interleaved float (PCM scaled by 1/2^(bits-1)).
/// Errors name the path and libsndfile's message.
Result<AudioBuffer> readAudio(const std::string& path);

// ---- analysis: target strike_fftw (GPL) ------------------------------------------------------
// Thread safety: FFTW's planner is not thread-safe. analyzeAudio and writeSpectrogramPng
// serialise their own plan creation and destruction with one internal mutex, so they may be
// called from several threads at once; but any other code in the process that calls
// fftw_plan_* / fftw_destroy_plan concurrently with them is a data race. Plans are made with
// FFTW_ESTIMATE (deterministic, no wisdom files are read or written).

struct SpectralPeak {
  double freq_hz = 0.0;      ///< interpolated (sub-bin) peak frequency
  double level_db = 0.0;     ///< dB relative to the strongest peak (0 dB)
  double decay_per_s = -1.0; ///< fitted amplitude decay rate d of A e^(-d t), or < 0 if not fitted
  double level_dbfs = 0.0;   ///< 20 log10(a) of the stationary sinusoid of amplitude a that gives this spectral peak
};

/// Window for the whole-signal spectrum.
enum class SpectrumWindow {
  /// Default. w = cos^2(pi t / 2T) from the onset (w = 1) to the end of the signal (w = 0):
  /// an impact is a real onset, not a truncation, so only the end is tapered. A symmetric window
  /// would weight a mode that decays at 200/s in a 2 s file by ~1e-6 (-120 dB); this one keeps
  /// it at its natural level. A step at the onset leaks as a monotone 1/f tail (no sidelobe
  /// lobes to mistake for peaks), -6 dB/octave, about 20 log10(1 / (pi df T)) dB at df Hz.
  OnsetHalfHann,
  /// Symmetric Hann over the whole signal: lowest near leakage for stationary tones.
  Hann,
};

struct AnalyzeOptions {
  int max_peaks = 20;        ///< strongest peaks to report
  double floor_db = -60.0;   ///< ignore peaks below this, relative to the strongest
  bool fit_decay = true;
  SpectrumWindow window = SpectrumWindow::OnsetHalfHann;
  /// Peaks closer than this many bins of the unpadded DFT (1/T Hz each) to a stronger one are
  /// not reported (main-lobe shoulders, noise ripple).
  double min_separation_bins = 2.0;
};

struct AudioAnalysis {
  double sample_rate_hz = 0.0;
  double duration_s = 0.0;
  double peak_amplitude = 0.0;  ///< max |sample| over all channels (clipping happens per channel)
  double rms = 0.0;             ///< over all samples of all channels
  int clipped_samples = 0;      ///< samples (any channel) with |sample| >= 1
  int non_finite_samples = 0;   ///< NaN or infinite samples (treated as 0 everywhere else)
  double onset_s = 0.0;         ///< first mixdown sample above 1e-3 of its peak (-60 dB)
  std::vector<SpectralPeak> peaks;  ///< by decreasing level
};

/// Analyses the mixdown (mean of channels).
/// Spectrum: the whole signal from the onset, windowed (AnalyzeOptions::window), zero-padded to
/// a power of two >= 2N; local maxima of |X| above floor_db, located by quadratic interpolation
/// of log|X| over three bins (Smith, Spectral Audio Signal Processing, "Quadratic Interpolation
/// of Spectral Peaks"). Peaks closer than min_separation_bins to a stronger one, and (Hann)
/// peaks under twice a stronger peak's sidelobe envelope, are dropped.
/// Decay: for each peak, the magnitude of a Blackman-Harris-windowed frame demodulated at the
/// peak frequency, slid over the signal from the onset; for A e^(-dt) its log is exactly linear
/// in the frame start with slope -d, whatever the frame length, so a least-squares line over the
/// range above the noise floor (down to 10 dB above it, at most 60 dB) gives d. The frame
/// length adapts to the nearest other peak (5/df s, so it falls in the -92 dB sidelobes), the
/// negative-frequency image (2.5/f s) and the decay (<= 8/d s). When the fit succeeds, freq_hz
/// is refined from the slope of the same frames' phase (|Y|^2-weighted), which a wide line's
/// negative-frequency image does not pull.
/// Measured (tests/unit/audio/analyze_test.cpp, 48 kHz float signals):
///   stationary 440 / 1234.5 / 5000 Hz at 0 / -20 / -40 dB, 1 s: frequency within 3e-6
///   (0.006 bin), level within 0.02 dB (OnsetHalfHann) or 0.004 dB (Hann);
///   d = 1..200 /s at 150, 1000, 7000 Hz, 2 s: d within 0.001 %, frequency within 2e-8;
///   five struck-bar modes (d 2..180 /s): d within 0.03 %; two equal peaks 7 Hz apart
///   (d 3 and 9 /s): within 0.03 %; white noise 74 dB below the start: within 0.7 %;
///   16-bit quantized with silence before the onset: within 0.01 %.
/// Cost: one FFT of 2N plus, per peak, ~50-100 frames of the chosen length (10 s of 192 kHz
/// stereo with 30 modes: 0.35 s).
AudioAnalysis analyzeAudio(const AudioBuffer& audio, const AnalyzeOptions& options);

// ---- spectrogram picture: target strike_fftw -------------------------------------------------

struct SpectrogramOptions {
  int width_px = 1024;        ///< whole image, including the axis margins
  int height_px = 512;
  int fft_size = 4096;        ///< samples per Hann-windowed frame (a power of two is fastest)
  bool log_frequency = true;  ///< log axis from min_freq_hz; else linear from 0 Hz
  double min_freq_hz = 20.0;  ///< bottom of a log axis
  double max_freq_hz = 0.0;   ///< top of the axis; 0 = Nyquist
  double range_db = 100.0;    ///< colours span [loudest - range_db, loudest]
  bool axis_labels = true;    ///< tick marks and labels (Hz, s) in margins, when the image is >= 160x100
};

/// Renders the mixdown's spectrogram (time on x, frequency on y, dB in the magma colour map)
/// and writes it as an RGB PNG atomically (temporary file beside `path`, then rename).
Status writeSpectrogramPng(const std::string& path, const AudioBuffer& audio, const SpectrogramOptions& options);

/// Encodes 8-bit RGB pixels (row-major, top row first, width * height * 3 bytes) as a PNG:
/// signature, IHDR, one IDAT holding a zlib stream of stored (uncompressed) deflate blocks with
/// its Adler-32, IEND; every chunk with its CRC-32 (ISO/IEC 15948, RFC 1950, RFC 1951).
/// Returns an empty string if the sizes do not match or are not positive.
std::string encodePngRgb(int width, int height, const std::vector<uint8_t>& rgb);

}  // namespace strike
