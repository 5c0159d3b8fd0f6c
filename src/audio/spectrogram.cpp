// SPDX-License-Identifier: MIT
// Spectrogram pictures (target strike_fftw): a Blackman-Harris STFT of each channel, the magma
// colour map, one panel per channel stacked top to bottom, PNG.
#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "fftw_lock.hpp"
#include "plot.hpp"
#include "strike/core/atomic_file.hpp"
#include "strike/audio/audio.hpp"
#include "strike/core/constants.hpp"

namespace strike {
namespace {

using detail::Image;
using detail::kGlyphAdvance;
using detail::kGlyphScale;
using detail::Rgb;

/// Where a panel's plot sits inside it: margins for the tick labels when there is room.
struct PanelLayout {
  bool labels = false;
  int left = 0, right = 0, top = 0, bottom = 0;
  int plot_w = 0, plot_h = 0;
};

PanelLayout panelLayout(int width_px, int height_px, bool axis_labels) {
  PanelLayout p;
  p.labels = axis_labels && width_px >= 160 && height_px >= 100;
  p.left = p.labels ? 5 * kGlyphAdvance + 4 : 0;
  p.bottom = p.labels ? 5 * kGlyphScale + 8 : 0;
  p.top = p.labels ? 6 : 0;
  p.right = p.labels ? 2 * kGlyphAdvance : 0;
  p.plot_w = width_px - p.left - p.right;
  p.plot_h = height_px - p.top - p.bottom;
  return p;
}

/// The frequency axis: from bottom_hz (0 on a linear axis) to top_hz.
struct FrequencyAxis {
  bool log = true;
  double bottom_hz = 0.0, top_hz = 0.0;
  double at(double u) const { return log ? bottom_hz * std::pow(top_hz / bottom_hz, u) : top_hz * u; }  ///< u: 0..1
};

Result<FrequencyAxis> checkOptions(const std::string& path, const AudioBuffer& audio,
                                   const SpectrogramOptions& options) {
  if (audio.channels < 1 || !(audio.sample_rate_hz > 0.0))
    return badInput(path + ": error: invalid audio (" + std::to_string(audio.channels) + " channels at " +
                    std::to_string(audio.sample_rate_hz) + " Hz)");
  if (options.width_px < 16 || options.height_px < 16 || options.width_px > 16384 || options.height_px > 16384)
    return badInput(path + ": error: spectrogram size " + std::to_string(options.width_px) + "x" +
                    std::to_string(options.height_px) + " is outside 16..16384 pixels");
  if (options.fft_size < 16 || options.fft_size > (1 << 22))
    return badInput(path + ": error: fft_size " + std::to_string(options.fft_size) + " is outside 16..4194304");
  if (!(options.range_db > 0.0)) return badInput(path + ": error: range_db must be positive");
  FrequencyAxis axis;
  const double nyquist_hz = 0.5 * audio.sample_rate_hz;
  axis.log = options.log_frequency;
  axis.top_hz = options.max_freq_hz > 0.0 ? std::min(options.max_freq_hz, nyquist_hz) : nyquist_hz;
  if (axis.log && !(options.min_freq_hz > 0.0 && options.min_freq_hz < axis.top_hz))
    return badInput(path + ": error: log frequency axis needs 0 < min_freq_hz < " + std::to_string(axis.top_hz) +
                    ", got " + std::to_string(options.min_freq_hz));
  axis.bottom_hz = axis.log ? options.min_freq_hz : 0.0;
  return axis;
}

/// One channel's samples, non-finite ones as 0.
std::vector<double> channelSamples(const AudioBuffer& audio, size_t channel) {
  const size_t frames = audio.frames(), channels = static_cast<size_t>(audio.channels);
  std::vector<double> x(frames, 0.0);
  for (size_t f = 0; f < frames; ++f) {
    const double s = audio.samples[f * channels + channel];
    x[f] = std::isfinite(s) ? s : 0.0;
  }
  return x;
}

/// The value of row py's frequency band [f_lo, f_hi]: the loudest bin inside, or the value
/// interpolated at its centre when the row is narrower than a bin (so narrow lines are never
/// skipped).
double rowAmplitude(const std::vector<double>& amplitude, double k_lo, double k_hi) {
  const size_t half = amplitude.size() - 1;
  double value = 0.0;
  const auto first = static_cast<size_t>(std::ceil(k_lo));
  const auto last = std::min(static_cast<size_t>(std::floor(k_hi)), half);
  if (first <= last) {
    for (size_t k = first; k <= last; ++k) value = std::max(value, amplitude[k]);
  } else {
    const double k = std::min(0.5 * (k_lo + k_hi), static_cast<double>(half));
    const auto k0 = std::min(static_cast<size_t>(k), half - 1);
    const double frac = k - static_cast<double>(k0);
    value = (1.0 - frac) * amplitude[k0] + frac * amplitude[k0 + 1];
  }
  return value;
}

/// A signal's STFT as dB cells, plot_h rows (top row = top_hz) by plot_w columns, one frame per
/// column. Blackman-Harris (-92 dB sidelobes; Harris 1978) rather than Hann (-31 dB): the colour
/// range is ~100 dB, and Hann's sidelobes would draw a skirt around every strong line.
std::vector<double> stftCellsDb(const std::vector<double>& x, double rate_hz, size_t n, const FrequencyAxis& axis,
                                int plot_w, int plot_h) {
  const size_t frames = x.size();
  const double duration_s = static_cast<double>(frames) / rate_hz;
  std::vector<double> window(n);
  double window_sum = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double u = 2.0 * kPi * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
    window[i] = 0.35875 - 0.48829 * std::cos(u) + 0.14128 * std::cos(2.0 * u) - 0.01168 * std::cos(3.0 * u);
    window_sum += window[i];
  }
  double* in = fftw_alloc_real(n);
  fftw_complex* out = fftw_alloc_complex(n / 2 + 1);
  fftw_plan plan;
  {
    std::lock_guard<std::mutex> lock(detail::fftwPlannerMutex());
    plan = fftw_plan_dft_r2c_1d(static_cast<int>(n), in, out, FFTW_ESTIMATE);
  }
  const double bin_hz = rate_hz / static_cast<double>(n);
  std::vector<double> cells_db(static_cast<size_t>(plot_w) * static_cast<size_t>(plot_h));
  std::vector<double> amplitude(n / 2 + 1);
  for (int px = 0; px < plot_w; ++px) {
    const double centre_s = (px + 0.5) / plot_w * duration_s;
    // Frames are kept inside the signal: zeros past the end would cut a ringing tone off and
    // paint a broadband stripe that is not in the sound.
    auto start = static_cast<long long>(std::llround(centre_s * rate_hz)) - static_cast<long long>(n / 2);
    start = std::max(0LL, std::min(start, static_cast<long long>(frames) - static_cast<long long>(n)));
    for (size_t i = 0; i < n; ++i) {
      const long long j = start + static_cast<long long>(i);
      in[i] = (j >= 0 && j < static_cast<long long>(frames)) ? window[i] * x[static_cast<size_t>(j)] : 0.0;
    }
    fftw_execute(plan);
    for (size_t k = 0; k <= n / 2; ++k) amplitude[k] = 2.0 / window_sum * std::hypot(out[k][0], out[k][1]);
    for (int py = 0; py < plot_h; ++py) {
      const double f_lo = axis.at(static_cast<double>(plot_h - 1 - py) / plot_h);
      const double f_hi = axis.at(static_cast<double>(plot_h - py) / plot_h);
      const double value = rowAmplitude(amplitude, f_lo / bin_hz, f_hi / bin_hz);
      cells_db[static_cast<size_t>(py) * static_cast<size_t>(plot_w) + static_cast<size_t>(px)] =
          20.0 * std::log10(value + 1e-30);
    }
  }
  {
    std::lock_guard<std::mutex> lock(detail::fftwPlannerMutex());
    fftw_destroy_plan(plan);
  }
  fftw_free(in);
  fftw_free(out);
  return cells_db;
}

/// Frequency ticks: 1-2-5 per decade on a log axis, a 1-2-5 step on a linear one; a label is
/// skipped when it would touch the previous one.
void drawFrequencyAxis(Image& image, int panel_y, const PanelLayout& p, const FrequencyAxis& axis, Rgb ink) {
  std::vector<double> ticks_hz;
  if (axis.log) {
    for (double decade = std::pow(10.0, std::floor(std::log10(axis.bottom_hz))); decade <= axis.top_hz; decade *= 10.0)
      for (double m : {1.0, 2.0, 5.0})
        if (m * decade >= axis.bottom_hz && m * decade <= axis.top_hz) ticks_hz.push_back(m * decade);
  } else {
    const double step = detail::niceStep(axis.top_hz, p.plot_h / 40.0);
    for (double f = 0.0; f <= axis.top_hz + 1e-9; f += step) ticks_hz.push_back(f);
  }
  const int top = panel_y + p.top, panel_end = panel_y + p.top + p.plot_h + p.bottom;
  int last_label_y = panel_end + 100;
  for (double f : ticks_hz) {
    const double u = axis.log ? std::log(f / axis.bottom_hz) / std::log(axis.top_hz / axis.bottom_hz) : f / axis.top_hz;
    const int y = top + p.plot_h - 1 - static_cast<int>(std::lround(u * (p.plot_h - 1)));
    for (int dx = 1; dx <= 3; ++dx) image.set(p.left - dx, y, ink);
    if (last_label_y - y < 5 * kGlyphScale + 4 || f == 0.0) continue;
    const std::string text = detail::tickLabel(f, true);
    detail::drawText(image, p.left - 5 - detail::textWidth(text),
                     std::clamp(y - 5 * kGlyphScale / 2, panel_y, panel_end - 5 * kGlyphScale), text, ink);
    last_label_y = y;
  }
}

/// The channel's name in the top-left corner of its plot, on a black box so it reads on any colour.
void drawChannelLabel(Image& image, int panel_y, const PanelLayout& p, const std::string& label, Rgb ink) {
  const int x = p.left + 4, y = panel_y + p.top + 4;
  image.fill(x - 2, y - 2, detail::textWidth(label) + 4, detail::kGlyphHeight + 4, Rgb{0, 0, 0});
  detail::drawText(image, x, y, label, ink);
}

}  // namespace

int spectrogramPanelHeight(int channels, int height_px) {
  return channels <= 2 ? height_px : std::max(std::min(128, height_px), height_px / 4);
}

std::string spectrogramChannelLabel(int channel, int channels) {
  if (channels == 2) return channel == 0 ? "L" : "R";
  // The first-order letters of B-format, and of the higher orders in Furse-Malham's naming, in
  // ACN order (Nachbar et al. 2011, table 1).
  static const char* kAcnLetters = "WYZXVTRSUQOMKLNP";
  if (channels == 4 || channels == 9 || channels == 16)
    return "ACN " + std::to_string(channel) + " " + std::string(1, kAcnLetters[channel]);
  return "CH " + std::to_string(channel + 1);
}

Status writeSpectrogramPng(const std::string& path, const AudioBuffer& audio, const SpectrogramOptions& options) {
  Result<FrequencyAxis> axis = checkOptions(path, audio, options);
  if (!axis) return axis.error();
  const int channels = audio.channels;
  const int panel_h = spectrogramPanelHeight(channels, options.height_px);
  if (static_cast<long long>(panel_h) * channels > 16384)
    return badInput(path + ": error: " + std::to_string(channels) + " channels of " + std::to_string(panel_h) +
                    " pixels make a picture taller than 16384 pixels");
  const PanelLayout p = panelLayout(options.width_px, panel_h, options.axis_labels);
  Image image(options.width_px, panel_h * channels);
  const double duration_s = static_cast<double>(audio.frames()) / audio.sample_rate_hz;

  // Every channel's cells first: the colours span range_db below the loudest cell of all the
  // channels, so the panels' levels compare.
  std::vector<std::vector<double>> cells_db;
  double loudest_db = -std::numeric_limits<double>::infinity();
  for (int c = 0; c < channels; ++c) {
    cells_db.push_back(stftCellsDb(channelSamples(audio, static_cast<size_t>(c)), audio.sample_rate_hz,
                                   static_cast<size_t>(options.fft_size), *axis, p.plot_w, p.plot_h));
    for (double db : cells_db.back()) loudest_db = std::max(loudest_db, db);
  }
  const Rgb ink{210, 210, 210};
  for (int c = 0; c < channels; ++c) {
    const int panel_y = c * panel_h;
    for (int py = 0; py < p.plot_h; ++py)
      for (int px = 0; px < p.plot_w; ++px) {
        const double db = cells_db[static_cast<size_t>(c)]
                                  [static_cast<size_t>(py) * static_cast<size_t>(p.plot_w) + static_cast<size_t>(px)];
        image.set(p.left + px, panel_y + p.top + py,
                  detail::magma((db - (loudest_db - options.range_db)) / options.range_db));
      }
    if (p.labels) {
      drawFrequencyAxis(image, panel_y, p, *axis, ink);
      detail::drawTimeAxis(image, p.left, panel_y + p.top + p.plot_h, p.plot_w, duration_s, ink);
    }
    if (channels > 1) drawChannelLabel(image, panel_y, p, spectrogramChannelLabel(c, channels), ink);
  }
  const std::string png = encodePngRgb(image.width, image.height, image.rgb);
  return writeFileAtomically(path, png.data(), png.size());
}

}  // namespace strike
