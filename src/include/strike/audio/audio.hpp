// SPDX-License-Identifier: MIT
// Audio files (target strike_sndfile, libsndfile) and spectral analysis (target strike_fftw,
// FFTW: GPL, used by the tool and tests only, never by the runtime library).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "strike/core/result.hpp"

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
  double freq_hz = 0.0;       ///< interpolated (sub-bin) peak frequency
  double level_db = 0.0;      ///< dB relative to the strongest peak (0 dB)
  double decay_per_s = -1.0;  ///< fitted amplitude decay rate d of A e^(-d t), or < 0 if not fitted
  double level_dbfs = 0.0;    ///< 20 log10(a) of the stationary sinusoid of amplitude a that gives this spectral peak
};

/// Window for the whole-signal spectrum.
enum class SpectrumWindow {
  /// Default. w = cos^2(pi t / 2T) from the onset (w = 1) to the end of the signal (w = 0):
  /// an impact is a real onset, not a truncation, so only the end is tapered. A symmetric window
  /// would weight a mode that decays at 200/s in a 2 s file by ~1e-6 (-120 dB); this one keeps
  /// it at its natural level. A step at the onset leaks as a monotone 1/f tail, -6 dB/octave,
  /// about 20 log10(1 / (pi df T)) dB at df Hz; a decaying line adds its own Lorentzian skirt,
  /// d / (2 pi df) of its peak. Where the skirts of two strong lines cross, the sum is flat to
  /// a fraction of a dB and any ripple is a local maximum: analyzeAudio's leakage test, not the
  /// window, keeps those out of the peak list.
  OnsetHalfHann,
  /// Symmetric Hann over the whole signal: lowest near leakage for stationary tones.
  Hann,
};

struct AnalyzeOptions {
  int max_peaks = 20;       ///< strongest peaks to report
  double floor_db = -60.0;  ///< ignore peaks below this, relative to the strongest
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
  /// Start of each impact found in the mixdown (the first is onset_s): a 1 ms block more than
  /// 6 dB above the largest |sample| of the 25 ms before it (impacts within 25 ms of the first
  /// are not told apart). With more than one, the peaks come from per-impact segments.
  std::vector<double> impact_onsets_s;
  std::vector<SpectralPeak> peaks;  ///< by decreasing level
};

/// Analyses the mixdown (mean of channels).
/// Several impacts (impact_onsets_s): over a window spanning two impacts a mode is the same
/// line twice, delayed by dt, i.e. multiplied by a comb of period 1/dt Hz whose teeth pass every
/// test below (four taps of a 5567 Hz mode gave 20 peaks 5558-5576 Hz and 2.45 /s for
/// 38.3 /s). Between impacts the sound is one free ring, so each segment (2 ms after an onset to
/// 1 ms before the next, at least 40 ms) is analysed as below on its own, and the lines merged:
/// a line within max(min_separation_bins, its -3 dB half width d / 2 pi) of a stronger one from
/// another segment is that line. Each is reported from the segment where it is strongest
/// (level_dbfs is its level in that segment; level_db relative to the strongest so kept).
/// One impact: the whole signal from the onset, as follows.
/// Spectrum: the whole signal from the onset, windowed (AnalyzeOptions::window), zero-padded to
/// a power of two >= 2N; local maxima of |X| above floor_db, located by quadratic interpolation
/// of log|X| over three bins (Smith, Spectral Audio Signal Processing, "Quadratic Interpolation
/// of Spectral Peaks"). Peaks closer than min_separation_bins to a stronger one, and (Hann)
/// peaks under twice a stronger peak's sidelobe envelope, are dropped.
/// Only genuine lines are reported; a local maximum must pass two tests, strongest first:
///  - leakage: it must stand 6 dB above the summed skirts of the stronger accepted peaks at its
///    frequency (and their negative-frequency images), each modelled exactly as the window's
///    response to a decaying exponential (a sum of geometric series) with the decay whose model
///    line is as wide (-3 dB) as the measured one. A merged pair looks wider, so its skirt is
///    over-estimated (the safe side). Consequence: a weak mode is reported when it rises 6 dB
///    above the skirts of the strong ones, which for a line at L dB needs df > roughly
///    (d / 2 pi + 1 / pi T) 10^(-(L + 6) / 20) Hz from a 0 dB line of decay d (e.g. a -58 dB line
///    1.5 kHz from a 0 dB line of d = 2 /s in 2 s is kept; one 40 Hz away lies under that skirt
///    and is not a local maximum at all).
///  - line: the decay frames below (which reject every other peak to -92 dB) must find at least
///    a tenth of the amplitude the spectral peak implies for a line of the fitted decay; for a
///    ripple they find only what leaks through the sidelobes. (Lenient because with several
///    impacts a real mode's single-exponential intercept can be off by 10 dB.)
/// On the rendered steel bar this removes ripples at -49.5 dB between the 9101 and 9638 Hz
/// modes; with several impacts (comb-modulated lines) the leakage test removes lobes up to
/// 1.9x the modelled skirts, i.e. the 6 dB margin is what keeps them out.
/// Decay: for each peak, the magnitude of a Blackman-Harris-windowed frame demodulated at the
/// peak frequency, slid over the signal from the onset; for A e^(-dt) its log is exactly linear
/// in the frame start with slope -d, whatever the frame length, so a least-squares line over the
/// range above the noise floor (down to 10 dB above it, at most 60 dB) gives d. The frame
/// length adapts to the nearest other peak (5/df s, so it falls in the -92 dB sidelobes), the
/// negative-frequency image (2.5/f s) and the decay (<= 8/d s); if too few frames lie above the
/// floor (a width guess made narrow by noise ripples) it retries with 4x and 16x shorter frames.
/// When the fit succeeds, freq_hz is refined from the slope of the same frames' phase
/// (|Y|^2-weighted), which a wide line's negative-frequency image does not pull.
/// Near-degenerate pairs (two modes closer than the line width, e.g. a square bar's bending
/// pairs 0.01-3 Hz apart) are reported as ONE peak. Their frames beat, which biases the log
/// line (3045 Hz pair of the bar: 1.53 /s for 2.02). When one exponential leaves > 1e-4 of the
/// frames' energy unexplained, a two-pole Prony fit with a long lag on the complex frames
/// (exact for two exponentials) replaces it if it explains 10x more and its two decays agree
/// within 2x; decay_per_s and freq_hz are then the |c|^2-weighted means of the two (the pair
/// shares its damping). A pair whose beat is much slower than the record (1135.21/1135.22 Hz
/// in 2 s) looks like one exponential and keeps the single fit (there: 1.3 % low).
/// Measured (tests/unit/audio/analyze_test.cpp, 48 kHz float signals):
///   stationary 440 / 1234.5 / 5000 Hz at 0 / -20 / -40 dB, 1 s: frequency within 3e-6
///   (0.006 bin), level within 0.02 dB (OnsetHalfHann) or 0.004 dB (Hann);
///   d = 1..200 /s at 150, 1000, 7000 Hz, 2 s: d within 0.001 %, frequency within 2e-8;
///   five struck-bar modes (d 2..180 /s): d within 0.03 %; two equal peaks 7 Hz apart
///   (d 3 and 9 /s): within 0.03 %; white noise 74 dB below the start: within 0.7 %;
///   16-bit quantized with silence before the onset: within 0.01 %;
///   bar-like spectrum (5 pairs 0.1-0.4 Hz apart, some in antiphase, 4 isolated modes, 4 weak
///   modes at -45..-51 dB, d 0.65..64 /s, 2 s): no spurious peak, every line reported, isolated
///   d within 0.001 %, pair d within 0.03 %; the rendered bar's 18 modes: 12 peaks, all modes,
///   pair decays within 0.01 %.
/// Cost: one FFT of 2N plus, per peak, ~50-100 frames of the chosen length (10 s of 192 kHz
/// stereo with 30 modes: 0.35 s).
AudioAnalysis analyzeAudio(const AudioBuffer& audio, const AnalyzeOptions& options);

// ---- spectrogram picture: target strike_fftw -------------------------------------------------

struct SpectrogramOptions {
  int width_px = 1024;        ///< whole image, including the axis margins
  int height_px = 512;        ///< of each channel's panel, margins included (see spectrogramPanelHeight)
  int fft_size = 4096;        ///< samples per Hann-windowed frame (a power of two is fastest)
  bool log_frequency = true;  ///< log axis from min_freq_hz; else linear from 0 Hz
  double min_freq_hz = 20.0;  ///< bottom of a log axis
  double max_freq_hz = 0.0;   ///< top of the axis; 0 = Nyquist
  double range_db = 100.0;    ///< colours span [loudest - range_db, loudest]
  bool axis_labels = true;    ///< tick marks and labels (Hz, s) in margins, when the image is >= 160x100
};

/// Renders each channel's spectrogram (time on x, frequency on y, dB in the magma colour map) as
/// a panel, the channels stacked top to bottom, and writes them as one RGB PNG atomically
/// (temporary file beside `path`, then rename). The colours span range_db below the loudest cell
/// of all the channels, so the panels' levels compare. With more than one channel each panel is
/// labelled (spectrogramChannelLabel). A mono file gives one unlabelled panel.
Status writeSpectrogramPng(const std::string& path, const AudioBuffer& audio, const SpectrogramOptions& options);

/// The height of each channel's panel: height_px for one or two channels; for more (Ambisonics:
/// 4, 9, 16) a quarter of it, but no less than min(128, height_px), so 16 channels of the default
/// 512 make a 1024 x 2048 picture.
int spectrogramPanelHeight(int channels, int height_px);

/// A panel's label: "L" and "R" for two channels; "ACN n" and the channel's B-format letter
/// (W Y Z X, then V T R S U and Q O M K L N P of Furse-Malham's naming) for 4, 9 or 16 channels,
/// AmbiX's orders 1-3; else "CH n" counted from 1.
std::string spectrogramChannelLabel(int channel, int channels);

// ---- directions of arrival: target strike_fftw -----------------------------------------------

/// One short-time frame of an Ambisonics (AmbiX: ACN, SN3D) signal, and the direction its
/// sound comes from.
struct DirectionFrame {
  double time_s = 0.0;  ///< the frame's centre
  double level_dbfs =
      -std::numeric_limits<double>::infinity();  ///< the omni channel W's rms in the frame, dB re full scale
  bool has_direction = false;                    ///< false when the frame is silent or its intensity is zero
  double azimuth_deg = 0.0;    ///< counter-clockwise from the front (+x) toward the left (+y), -180..180
  double elevation_deg = 0.0;  ///< up from the horizontal plane (+z), -90..90
  /// 1 - |<W [X Y Z]>| / (<W^2 + (X^2 + Y^2 + Z^2)> / 2): 0 for one plane wave, near 1 for a
  /// diffuse field (Pulkki 2007's diffuseness, with SN3D's first-order channels).
  double diffuseness = 1.0;
};

struct DirectionOptions {
  double frame_s = 0.01;    ///< frame length; frames do not overlap
  int width_px = 1024;      ///< whole image, including the axis margins
  int height_px = 512;      ///< both panels (azimuth above, elevation below)
  double range_db = 60.0;   ///< frames down to this far below the loudest are drawn, coloured by level
  bool axis_labels = true;  ///< ticks and labels in margins, when the image is >= 160x200
};

/// Per frame of frame_s seconds, the direction of arrival from the first-order channels
/// (ACN 0-3: W, Y, Z, X; higher-order channels are ignored) by the active intensity method
/// (Merimaa & Pulkki, "Spatial impulse response rendering I", JAES 53(12), 2005; Pulkki,
/// "Spatial sound reproduction with directional audio coding", JAES 55(6), 2007): the frame's
/// mean of W times (X, Y, Z), the negative of the active intensity, points to the source. With
/// SN3D a plane wave from (azimuth a, elevation e) has X = W cos a cos e, Y = W sin a cos e,
/// Z = W sin e, so the direction is exact for one source. Fewer than 4 channels is BadInput.
Result<std::vector<DirectionFrame>> directionsOfArrival(const AudioBuffer& audio, double frame_s);

/// Draws directionsOfArrival as two panels over time, azimuth (-180..180 degrees) above and
/// elevation (-90..90) below, one dot per frame coloured by its level (magma), louder frames on
/// top; writes an RGB PNG atomically.
Status writeDirectionsPng(const std::string& path, const AudioBuffer& audio, const DirectionOptions& options);

/// Encodes 8-bit RGB pixels (row-major, top row first, width * height * 3 bytes) as a PNG:
/// signature, IHDR, one IDAT holding a zlib stream of stored (uncompressed) deflate blocks with
/// its Adler-32, IEND; every chunk with its CRC-32 (ISO/IEC 15948, RFC 1950, RFC 1951).
/// Returns an empty string if the sizes do not match or are not positive.
std::string encodePngRgb(int width, int height, const std::vector<uint8_t>& rgb);

}  // namespace strike
