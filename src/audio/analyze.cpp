// SPDX-License-Identifier: MIT
// Level statistics, spectral peaks and per-peak decay rates (target strike_fftw).
// The spectrum and its line shapes are in analyze_spectrum.cpp, the decay fits in
// analyze_decay.cpp; this file finds the lines (leakage and line tests), splits a file with
// several impacts into free rings and merges their lines.
#include <algorithm>
#include <cmath>
#include <limits>

#include "analyze_lines.hpp"
#include "impact_onsets.hpp"
#include "strike/audio/audio.hpp"
#include "strike/core/constants.hpp"

namespace strike {
namespace {

using detail::Candidate;
using detail::DecayFit;
using detail::decayFromHalfWidth;
using detail::fitDecay;
using detail::halfWidthHz;
using detail::interpolatePeak;
using detail::lineShape;
using detail::Mono;
using detail::Spectrum;
using detail::wholeSpectrum;

/// A spectral line must stand this many times (6 dB) above the modelled leakage of the
/// stronger lines at its frequency.
constexpr double kLeakageMargin = 2.0;
/// A line's frame-measured amplitude may fall this far (20 dB) below what its spectral peak
/// implies before the peak is taken for leakage (the frames see lines, not skirts).
constexpr double kMinLineAmplitudeRatio = 0.1;

/// Statistics over all channels, and the mean of the channels with non-finite samples as 0.
Mono mixdown(const AudioBuffer& audio, AudioAnalysis& analysis) {
  Mono mono;
  const size_t channels = static_cast<size_t>(audio.channels);
  const size_t frames = audio.frames();
  mono.x.assign(frames, 0.0);
  double sum_squares = 0.0;
  for (size_t f = 0; f < frames; ++f) {
    double sum = 0.0;
    for (size_t c = 0; c < channels; ++c) {
      const double s = audio.samples[f * channels + c];
      if (!std::isfinite(s)) {
        ++analysis.non_finite_samples;
        continue;
      }
      const double a = std::fabs(s);
      analysis.peak_amplitude = std::max(analysis.peak_amplitude, a);
      if (a >= 1.0) ++analysis.clipped_samples;
      sum_squares += s * s;
      sum += s;
    }
    mono.x[f] = sum / static_cast<double>(channels);
    mono.peak = std::max(mono.peak, std::fabs(mono.x[f]));
  }
  const size_t count = frames * channels;
  analysis.rms = count > 0 ? std::sqrt(sum_squares / static_cast<double>(count)) : 0.0;
  // The onset: first sample above -60 dB of the peak. Frames for the decay fit start here, so
  // none straddles the start of the sound (which would bend the log-envelope line).
  const double threshold = 1e-3 * mono.peak;
  while (mono.onset < frames && !(std::fabs(mono.x[mono.onset]) > threshold)) ++mono.onset;
  return mono;
}
struct Line {
  SpectralPeak peak;      ///< decay_per_s always fitted (analyzeAudio clears it if not wanted)
  double merge_hz = 0.0;  ///< lines of other segments within this are the same line
};

/// The genuine spectral lines of one free ring, mono.x from mono.onset on, strongest first:
/// candidates of the whole-signal spectrum that pass the leakage and line tests.
std::vector<Line> findLines(const Mono& mono, double rate_hz, const AnalyzeOptions& options) {
  std::vector<Line> lines;
  const size_t length = mono.x.size() - mono.onset;
  const Spectrum spectrum = wholeSpectrum(mono, options.window, rate_hz);
  // Local maxima within 1 dB of the floor (interpolation raises a peak by less than that);
  // a long file has millions of ripples far below it.
  const double* bins = spectrum.amplitude.data();
  const double loudest_bin = *std::max_element(spectrum.amplitude.begin(), spectrum.amplitude.end());
  const double candidate_floor = loudest_bin * std::pow(10.0, (options.floor_db - 1.0) / 20.0);
  std::vector<Candidate> candidates;
  for (size_t k = 1; k + 1 < spectrum.amplitude.size(); ++k) {
    if (bins[k] >= candidate_floor && bins[k] > bins[k - 1] && bins[k] >= bins[k + 1] && bins[k - 1] > 0.0 &&
        bins[k + 1] > 0.0)
      candidates.push_back(interpolatePeak(spectrum, k));
  }
  if (candidates.empty()) return lines;
  // Strongest first; equal levels by frequency, so the order is deterministic.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.amplitude != b.amplitude ? a.amplitude > b.amplitude : a.freq_hz < b.freq_hz;
  });
  const double strongest = candidates.front().amplitude;
  const double floor_amplitude = strongest * std::pow(10.0, options.floor_db / 20.0);
  const double bin_hz = rate_hz / static_cast<double>(length);  // of the unpadded DFT
  const double min_separation_hz = options.min_separation_bins * bin_hz;
  std::vector<Candidate> accepted;
  // Enough neighbours to choose decay frame lengths; more only costs time (a very low floor
  // in a noisy file has thousands of candidates).
  const size_t max_accepted = 4 * static_cast<size_t>(options.max_peaks) + 16;
  for (const Candidate& c : candidates) {
    if (c.amplitude < floor_amplitude || accepted.size() >= max_accepted) break;
    const bool separate = std::all_of(accepted.begin(), accepted.end(), [&](const Candidate& a) {
      const double df_hz = std::fabs(a.freq_hz - c.freq_hz);
      if (df_hz < min_separation_hz) return false;
      if (options.window != SpectrumWindow::Hann) return true;
      // Hann sidelobes: |W(b)| = |sin(pi b) / (pi b (1 - b^2))| at b bins; a candidate below
      // twice the sidelobe envelope of a stronger peak may be that sidelobe (Harris 1978).
      const double b = df_hz / bin_hz;
      return b >= 1.5 && c.amplitude > 2.0 * a.amplitude / (kPi * b * (b * b - 1.0));
    });
    if (!separate) continue;
    // Leakage test. Between and beside strong decaying modes the spectrum is the sum of their
    // skirts (a line of decay d falls only as d / (2 pi df) of its peak, 1/f, whatever the
    // window), and where those skirts cross it is flat to a fraction of a dB: any ripple there
    // (interference of the skirts, the window's end) is a local maximum. A genuine line stands
    // above the summed skirts of the stronger lines, modelled exactly by lineShape (with the
    // negative-frequency images); a ripple does not: its level is at most that sum.
    double leakage = 0.0;
    for (const Candidate& a : accepted) {
      const double at_peak = lineShape(0.0, a.skirt_decay_per_s, length, rate_hz, options.window);
      leakage += a.amplitude *
                 (lineShape(c.freq_hz - a.freq_hz, a.skirt_decay_per_s, length, rate_hz, options.window) +
                  lineShape(c.freq_hz + a.freq_hz, a.skirt_decay_per_s, length, rate_hz, options.window)) /
                 at_peak;
    }
    if (!(c.amplitude > kLeakageMargin * leakage)) continue;
    Candidate kept = c;
    kept.half_width_hz = halfWidthHz(spectrum, kept);
    kept.skirt_decay_per_s = decayFromHalfWidth(kept.half_width_hz, length, rate_hz, options.window);
    accepted.push_back(kept);
  }

  // Confirmation and decay, strongest first, until max_peaks lines are confirmed. The frame fit
  // runs even when no decay is wanted: it is what tells a line from a leakage ripple.
  std::vector<char> dropped(accepted.size(), 0);
  const size_t wanted = static_cast<size_t>(options.max_peaks);
  for (size_t i = 0; i < accepted.size() && lines.size() < wanted; ++i) {
    const Candidate& c = accepted[i];
    SpectralPeak peak;
    peak.freq_hz = c.freq_hz;
    peak.level_dbfs = 20.0 * std::log10(c.amplitude);
    peak.level_db = 20.0 * std::log10(c.amplitude / strongest);
    // Neighbours include peaks above the floor that are not reported (they still leak), but
    // not candidates already found to be leakage.
    double nearest_df_hz = 0.0;
    for (size_t j = 0; j < accepted.size(); ++j) {
      if (j == i || dropped[j]) continue;
      const double df = std::fabs(accepted[j].freq_hz - c.freq_hz);
      if (nearest_df_hz == 0.0 || df < nearest_df_hz) nearest_df_hz = df;
    }
    const DecayFit fit = fitDecay(mono, rate_hz, c, nearest_df_hz);
    if (fit.decay_per_s >= 0.0) {
      // Line test. The frames reject every other peak (> 4 of their bins away) to -92 dB, so
      // they see only what is really at this frequency. A line of amplitude A (at the onset)
      // and decay d gives the whole-signal peak A lineShape(0, d) / sum(w); if the frames
      // find less than a tenth of that A, the peak was the skirts of other lines.
      const double spectral_a =
          c.amplitude * spectrum.window_sum / lineShape(0.0, fit.decay_per_s, length, rate_hz, options.window);
      if (fit.amplitude < kMinLineAmplitudeRatio * spectral_a) {
        dropped[i] = 1;
        continue;
      }
    }
    peak.decay_per_s = fit.decay_per_s;  // cleared by analyzeAudio when no decay is wanted
    if (options.fit_decay) {
      // Take the phase-slope frequency when it lies within the line's own -3 dB half width
      // (a wide line's spectral peak is pulled by up to about that much) and nearer to this
      // peak than to any other, so it cannot have locked onto a neighbour.
      const double shift_hz = std::fabs(fit.freq_hz - c.freq_hz);
      if (fit.decay_per_s >= 0.0 && shift_hz < std::max(0.5 * min_separation_hz, c.half_width_hz) &&
          (nearest_df_hz == 0.0 || shift_hz < 0.5 * nearest_df_hz))
        peak.freq_hz = fit.freq_hz;
    }
    // Lines this close to this one are the same line seen in another impact's segment: the
    // bins that could not resolve them, or the line's own -3 dB half width d / 2 pi.
    const double merge_hz = std::max(min_separation_hz, peak.decay_per_s > 0.0 ? peak.decay_per_s / (2.0 * kPi) : 0.0);
    lines.push_back({peak, merge_hz});
  }
  return lines;
}

/// Lines found in each impact's segment, merged: a line is kept from the segment where it is
/// strongest (its frequency, level and decay), and lines of other segments within either's
/// merge_hz are that line again. Strongest first, at most max_peaks, above floor_db.
std::vector<SpectralPeak> mergeSegmentLines(std::vector<Line> lines, const AnalyzeOptions& options) {
  std::stable_sort(lines.begin(), lines.end(), [](const Line& a, const Line& b) {
    return a.peak.level_dbfs != b.peak.level_dbfs ? a.peak.level_dbfs > b.peak.level_dbfs
                                                  : a.peak.freq_hz < b.peak.freq_hz;
  });
  std::vector<SpectralPeak> peaks;
  if (lines.empty()) return peaks;
  const double strongest_dbfs = lines.front().peak.level_dbfs;
  std::vector<const Line*> kept;
  for (const Line& line : lines) {
    if (peaks.size() >= static_cast<size_t>(options.max_peaks)) break;
    if (line.peak.level_dbfs < strongest_dbfs + options.floor_db) break;
    const bool same = std::any_of(kept.begin(), kept.end(), [&](const Line* k) {
      return std::fabs(k->peak.freq_hz - line.peak.freq_hz) < std::max(k->merge_hz, line.merge_hz);
    });
    if (same) continue;
    kept.push_back(&line);
    SpectralPeak peak = line.peak;
    peak.level_db = peak.level_dbfs - strongest_dbfs;
    peaks.push_back(peak);
  }
  return peaks;
}

}  // namespace

AudioAnalysis analyzeAudio(const AudioBuffer& audio, const AnalyzeOptions& options) {
  AudioAnalysis analysis;
  analysis.sample_rate_hz = audio.sample_rate_hz;
  if (audio.channels < 1 || !(audio.sample_rate_hz > 0.0)) return analysis;
  analysis.duration_s = static_cast<double>(audio.frames()) / audio.sample_rate_hz;
  const Mono mono = mixdown(audio, analysis);
  analysis.onset_s = static_cast<double>(mono.onset) / audio.sample_rate_hz;
  const size_t length = mono.x.size() - mono.onset;
  if (!(mono.peak > 0.0) || length < 16 || options.max_peaks <= 0) return analysis;

  const std::vector<size_t> onsets = detail::impactOnsets(mono.x, mono.onset, mono.peak, audio.sample_rate_hz);
  for (const size_t onset : onsets)
    analysis.impact_onsets_s.push_back(static_cast<double>(onset) / audio.sample_rate_hz);
  std::vector<Line> lines;
  if (onsets.size() <= 1) {
    lines = findLines(mono, audio.sample_rate_hz, options);
    for (const Line& line : lines) analysis.peaks.push_back(line.peak);
  } else {
    // Several impacts. Over a window that spans two of them a mode is the same line twice,
    // delayed: its spectrum is multiplied by |1 + e^{-j 2 pi f dt}|, a comb of period 1/dt Hz
    // whose teeth pass as lines, and the frames see the envelope jump at each impact. Between
    // two onsets the sound is one free ring (earlier impacts' modes go on at the same
    // frequencies and decays), so each segment is analysed alone and the lines merged.
    // A segment starts 2 ms after its onset: during the contact (a Hertz half-sine, well under
    // 1 ms for the hard bodies Strike renders) stiff modes follow the force instead of ringing,
    // a broadband click whose ripples would pass as short-lived lines (blocks-falling: 12
    // "lines" from 70 to 3200 Hz at -10 dB, decaying at the click's 440-490 /s, none a mode).
    // It ends 1 ms before the next onset (the contact may start before the block that shows
    // it). Segments under 40 ms (25 Hz bins) are skipped: their ring continues into the next
    // segment, which sees it; if all are that short, the longest is used.
    const size_t contact = static_cast<size_t>(std::lround(2e-3 * audio.sample_rate_hz));
    const size_t guard = static_cast<size_t>(std::lround(1e-3 * audio.sample_rate_hz));
    const size_t min_length = static_cast<size_t>(std::lround(0.04 * audio.sample_rate_hz));
    struct Segment {
      size_t begin, end;
    };
    std::vector<Segment> segments;
    for (size_t i = 0; i < onsets.size(); ++i) {
      const size_t end =
          i + 1 < onsets.size() ? std::max(onsets[i], onsets[i + 1] - std::min(guard, onsets[i + 1])) : mono.x.size();
      segments.push_back({std::min(end, onsets[i] + contact), end});
    }
    std::vector<Segment> used;
    for (const Segment& s : segments)
      if (s.end - s.begin >= min_length) used.push_back(s);
    if (used.empty())
      used.push_back(*std::max_element(segments.begin(), segments.end(), [](const Segment& a, const Segment& b) {
        return a.end - a.begin < b.end - b.begin;
      }));
    for (const Segment& s : used) {
      if (s.end - s.begin < 16) continue;
      Mono part;
      part.x.assign(mono.x.begin() + static_cast<std::ptrdiff_t>(s.begin),
                    mono.x.begin() + static_cast<std::ptrdiff_t>(s.end));
      for (const double v : part.x) part.peak = std::max(part.peak, std::fabs(v));
      if (!(part.peak > 0.0)) continue;
      const std::vector<Line> found = findLines(part, audio.sample_rate_hz, options);
      lines.insert(lines.end(), found.begin(), found.end());
    }
    analysis.peaks = mergeSegmentLines(std::move(lines), options);
  }
  if (!options.fit_decay)
    for (SpectralPeak& peak : analysis.peaks) peak.decay_per_s = -1.0;
  return analysis;
}

}  // namespace strike
