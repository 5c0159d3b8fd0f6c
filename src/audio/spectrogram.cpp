// SPDX-License-Identifier: MIT
// Spectrogram pictures (target strike_fftw): Hann-windowed STFT, magma colour map, PNG.
#include <fftw3.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <mutex>

#include "fftw_lock.hpp"
#include "strike/atomic_file.hpp"
#include "strike/audio.hpp"
#include "strike/constants.hpp"

namespace strike {
namespace {

using Rgb = std::array<uint8_t, 3>;

/// Matplotlib's magma (van der Walt & Smith, BIDS colormaps, CC0), sampled at nine points and
/// interpolated linearly: perceptually ordered, readable in grey scale.
Rgb magma(double v) {
  static constexpr double kStops[9][3] = {
      {0.001462, 0.000466, 0.013866}, {0.078815, 0.054184, 0.211667}, {0.232077, 0.059889, 0.437695},
      {0.390384, 0.100379, 0.501864}, {0.550287, 0.161158, 0.505719}, {0.716387, 0.214982, 0.475290},
      {0.868793, 0.287728, 0.409303}, {0.983868, 0.517360, 0.382016}, {0.987053, 0.991438, 0.749504}};
  const double x = std::clamp(v, 0.0, 1.0) * 8.0;
  const int i = std::min(7, static_cast<int>(x));
  const double f = x - i;
  Rgb rgb{};
  for (int c = 0; c < 3; ++c)
    rgb[static_cast<size_t>(c)] =
        static_cast<uint8_t>(std::lround(255.0 * ((1.0 - f) * kStops[i][c] + f * kStops[i + 1][c])));
  return rgb;
}

/// 3x5 pixel glyphs for tick labels; each row is 3 bits, most significant bit on the left.
const std::array<uint8_t, 5>* glyph(char c) {
  static const std::array<uint8_t, 5> kDigits[10] = {{7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7},
                                                     {5, 5, 7, 1, 1}, {7, 4, 7, 1, 7}, {7, 4, 7, 5, 7}, {7, 1, 1, 1, 1},
                                                     {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}};
  static const std::array<uint8_t, 5> kDot = {0, 0, 0, 0, 2};
  static const std::array<uint8_t, 5> kK = {4, 5, 6, 5, 5};
  if (c >= '0' && c <= '9') return &kDigits[c - '0'];
  if (c == '.') return &kDot;
  if (c == 'k') return &kK;
  return nullptr;
}

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
  void set(int x, int y, Rgb c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    const size_t i = (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * 3;
    rgb[i] = c[0];
    rgb[i + 1] = c[1];
    rgb[i + 2] = c[2];
  }
};

constexpr int kGlyphScale = 2;
constexpr int kGlyphAdvance = 4 * kGlyphScale;

void drawText(Image& image, int x, int y, const std::string& text, Rgb colour) {
  for (char ch : text) {
    if (const auto* g = glyph(ch)) {
      for (int row = 0; row < 5; ++row)
        for (int col = 0; col < 3; ++col)
          if (((*g)[static_cast<size_t>(row)] >> (2 - col)) & 1)
            for (int dy = 0; dy < kGlyphScale; ++dy)
              for (int dx = 0; dx < kGlyphScale; ++dx)
                image.set(x + col * kGlyphScale + dx, y + row * kGlyphScale + dy, colour);
    }
    x += kGlyphAdvance;
  }
}

int textWidth(const std::string& text) { return static_cast<int>(text.size()) * kGlyphAdvance - kGlyphScale; }

/// Shortest decimal for a tick value: "0.25", "3", "1.5k".
std::string tickLabel(double value, bool kilo) {
  std::string suffix;
  if (kilo && value >= 1000.0) {
    value /= 1000.0;
    suffix = "k";
  }
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3f", value);
  std::string s(buffer);
  while (!s.empty() && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s + suffix;
}

/// A 1-2-5 step giving about `target` intervals over `span`.
double niceStep(double span, double target) {
  const double raw = span / std::max(1.0, target);
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * decade >= raw) return m * decade;
  return 10.0 * decade;
}

}  // namespace

Status writeSpectrogramPng(const std::string& path, const AudioBuffer& audio, const SpectrogramOptions& options) {
  if (audio.channels < 1 || !(audio.sample_rate_hz > 0.0))
    return badInput(path + ": error: invalid audio (" + std::to_string(audio.channels) + " channels at " +
                    std::to_string(audio.sample_rate_hz) + " Hz)");
  if (options.width_px < 16 || options.height_px < 16 || options.width_px > 16384 || options.height_px > 16384)
    return badInput(path + ": error: spectrogram size " + std::to_string(options.width_px) + "x" +
                    std::to_string(options.height_px) + " is outside 16..16384 pixels");
  if (options.fft_size < 16 || options.fft_size > (1 << 22))
    return badInput(path + ": error: fft_size " + std::to_string(options.fft_size) + " is outside 16..4194304");
  if (!(options.range_db > 0.0)) return badInput(path + ": error: range_db must be positive");
  const double nyquist_hz = 0.5 * audio.sample_rate_hz;
  const double top_hz = options.max_freq_hz > 0.0 ? std::min(options.max_freq_hz, nyquist_hz) : nyquist_hz;
  if (options.log_frequency && !(options.min_freq_hz > 0.0 && options.min_freq_hz < top_hz))
    return badInput(path + ": error: log frequency axis needs 0 < min_freq_hz < " + std::to_string(top_hz) + ", got " +
                    std::to_string(options.min_freq_hz));
  const double bottom_hz = options.log_frequency ? options.min_freq_hz : 0.0;

  Image image;
  image.width = options.width_px;
  image.height = options.height_px;
  image.rgb.assign(static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * 3, 0);
  const bool labels = options.axis_labels && image.width >= 160 && image.height >= 100;
  const int left = labels ? 5 * kGlyphAdvance + 4 : 0;
  const int bottom = labels ? 5 * kGlyphScale + 8 : 0;
  const int top = labels ? 6 : 0;
  const int right = labels ? 2 * kGlyphAdvance : 0;
  const int plot_w = image.width - left - right;
  const int plot_h = image.height - top - bottom;

  // Mixdown.
  const size_t frames = audio.frames();
  const size_t channels = static_cast<size_t>(audio.channels);
  std::vector<double> mono(frames, 0.0);
  for (size_t f = 0; f < frames; ++f) {
    double sum = 0.0;
    for (size_t c = 0; c < channels; ++c) {
      const double s = audio.samples[f * channels + c];
      if (std::isfinite(s)) sum += s;
    }
    mono[f] = sum / static_cast<double>(channels);
  }
  const double duration_s = static_cast<double>(frames) / audio.sample_rate_hz;

  // STFT: one frame per pixel column. Blackman-Harris (-92 dB sidelobes; Harris 1978) rather
  // than Hann (-31 dB): the colour range is ~100 dB, and Hann's sidelobes would draw a skirt
  // around every strong line.
  const auto n = static_cast<size_t>(options.fft_size);
  std::vector<double> window(n);
  double window_sum = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double x = 2.0 * kPi * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
    window[i] = 0.35875 - 0.48829 * std::cos(x) + 0.14128 * std::cos(2.0 * x) - 0.01168 * std::cos(3.0 * x);
    window_sum += window[i];
  }
  double* in = fftw_alloc_real(n);
  fftw_complex* out = fftw_alloc_complex(n / 2 + 1);
  fftw_plan plan;
  {
    std::lock_guard<std::mutex> lock(detail::fftwPlannerMutex());
    plan = fftw_plan_dft_r2c_1d(static_cast<int>(n), in, out, FFTW_ESTIMATE);
  }
  const double bin_hz = audio.sample_rate_hz / static_cast<double>(n);
  auto rowFrequency = [&](double u) {  // u in [0, 1], bottom to top
    return options.log_frequency ? bottom_hz * std::pow(top_hz / bottom_hz, u) : top_hz * u;
  };
  std::vector<double> cells_db(static_cast<size_t>(plot_w) * static_cast<size_t>(plot_h));
  std::vector<double> amplitude(n / 2 + 1);
  double loudest_db = -std::numeric_limits<double>::infinity();
  for (int px = 0; px < plot_w; ++px) {
    const double centre_s = (px + 0.5) / plot_w * duration_s;
    // Frames are kept inside the signal: zeros past the end would cut a ringing tone off and
    // paint a broadband stripe that is not in the sound.
    auto start = static_cast<long long>(std::llround(centre_s * audio.sample_rate_hz)) - static_cast<long long>(n / 2);
    start = std::max(0LL, std::min(start, static_cast<long long>(frames) - static_cast<long long>(n)));
    for (size_t i = 0; i < n; ++i) {
      const long long j = start + static_cast<long long>(i);
      in[i] = (j >= 0 && j < static_cast<long long>(frames)) ? window[i] * mono[static_cast<size_t>(j)] : 0.0;
    }
    fftw_execute(plan);
    for (size_t k = 0; k <= n / 2; ++k) amplitude[k] = 2.0 / window_sum * std::hypot(out[k][0], out[k][1]);
    for (int py = 0; py < plot_h; ++py) {
      // Row py covers [f_lo, f_hi]: the loudest bin inside, or the interpolated value at the
      // centre when the row is narrower than a bin (so narrow lines are never skipped).
      const double f_lo = rowFrequency(static_cast<double>(plot_h - 1 - py) / plot_h);
      const double f_hi = rowFrequency(static_cast<double>(plot_h - py) / plot_h);
      const double k_lo = f_lo / bin_hz, k_hi = f_hi / bin_hz;
      double value = 0.0;
      const auto first = static_cast<size_t>(std::ceil(k_lo));
      const auto last = std::min(static_cast<size_t>(std::floor(k_hi)), n / 2);
      if (first <= last) {
        for (size_t k = first; k <= last; ++k) value = std::max(value, amplitude[k]);
      } else {
        const double k = std::min(0.5 * (k_lo + k_hi), static_cast<double>(n / 2));
        const auto k0 = std::min(static_cast<size_t>(k), n / 2 - 1);
        const double frac = k - static_cast<double>(k0);
        value = (1.0 - frac) * amplitude[k0] + frac * amplitude[k0 + 1];
      }
      const double db = 20.0 * std::log10(value + 1e-30);
      cells_db[static_cast<size_t>(py) * static_cast<size_t>(plot_w) + static_cast<size_t>(px)] = db;
      loudest_db = std::max(loudest_db, db);
    }
  }
  {
    std::lock_guard<std::mutex> lock(detail::fftwPlannerMutex());
    fftw_destroy_plan(plan);
  }
  fftw_free(in);
  fftw_free(out);

  for (int py = 0; py < plot_h; ++py)
    for (int px = 0; px < plot_w; ++px) {
      const double db = cells_db[static_cast<size_t>(py) * static_cast<size_t>(plot_w) + static_cast<size_t>(px)];
      image.set(left + px, top + py, magma((db - (loudest_db - options.range_db)) / options.range_db));
    }

  if (labels) {
    const Rgb ink{210, 210, 210};
    // Frequency ticks: 1-2-5 per decade on a log axis, a 1-2-5 step on a linear one; a label
    // is skipped when it would touch the previous one.
    std::vector<double> ticks_hz;
    if (options.log_frequency) {
      for (double decade = std::pow(10.0, std::floor(std::log10(bottom_hz))); decade <= top_hz; decade *= 10.0)
        for (double m : {1.0, 2.0, 5.0})
          if (m * decade >= bottom_hz && m * decade <= top_hz) ticks_hz.push_back(m * decade);
    } else {
      const double step = niceStep(top_hz, plot_h / 40.0);
      for (double f = 0.0; f <= top_hz + 1e-9; f += step) ticks_hz.push_back(f);
    }
    int last_label_y = image.height + 100;
    for (double f : ticks_hz) {
      const double u = options.log_frequency ? std::log(f / bottom_hz) / std::log(top_hz / bottom_hz) : f / top_hz;
      const int y = top + plot_h - 1 - static_cast<int>(std::lround(u * (plot_h - 1)));
      for (int dx = 1; dx <= 3; ++dx) image.set(left - dx, y, ink);
      if (last_label_y - y < 5 * kGlyphScale + 4 || f == 0.0) continue;
      const std::string text = tickLabel(f, true);
      drawText(image, left - 5 - textWidth(text),
               std::clamp(y - 5 * kGlyphScale / 2, 0, image.height - 5 * kGlyphScale), text, ink);
      last_label_y = y;
    }
    if (duration_s > 0.0) {
      const double step = niceStep(duration_s, plot_w / 70.0);
      for (double t = 0.0; t <= duration_s + 1e-12; t += step) {
        const int x = left + static_cast<int>(std::lround(t / duration_s * (plot_w - 1)));
        for (int dy = 0; dy < 3; ++dy) image.set(x, top + plot_h + dy, ink);
        const std::string text = tickLabel(t, false);
        drawText(image, std::clamp(x - textWidth(text) / 2, 0, image.width - textWidth(text)), top + plot_h + 5, text,
                 ink);
      }
    }
  }

  const std::string png = encodePngRgb(image.width, image.height, image.rgb);
  return writeFileAtomically(path, png.data(), png.size());
}

}  // namespace strike
