// SPDX-License-Identifier: MIT
// The pictures' drawing helpers (target strike_fftw): colour map, font, ticks.
#include "plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace strike::detail {
namespace {

/// 3x5 pixel glyphs; each row is 3 bits, most significant bit on the left.
const std::array<uint8_t, 5>* glyph(char c) {
  static const std::array<uint8_t, 5> kDigits[10] = {{7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7},
                                                     {5, 5, 7, 1, 1}, {7, 4, 7, 1, 7}, {7, 4, 7, 5, 7}, {7, 1, 1, 1, 1},
                                                     {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}};
  static const std::array<uint8_t, 5> kLetters[26] = {
      {2, 5, 7, 5, 5}, {6, 5, 6, 5, 6}, {3, 4, 4, 4, 3}, {6, 5, 5, 5, 6}, {7, 4, 6, 4, 7}, {7, 4, 6, 4, 4},
      {3, 4, 5, 5, 3}, {5, 5, 7, 5, 5}, {7, 2, 2, 2, 7}, {1, 1, 1, 5, 2}, {5, 5, 6, 5, 5}, {4, 4, 4, 4, 7},
      {5, 7, 7, 5, 5}, {6, 5, 5, 5, 5}, {2, 5, 5, 5, 2}, {6, 5, 6, 4, 4}, {2, 5, 5, 6, 3}, {6, 5, 6, 5, 5},
      {3, 4, 2, 1, 6}, {7, 2, 2, 2, 2}, {5, 5, 5, 5, 7}, {5, 5, 5, 5, 2}, {5, 5, 7, 7, 5}, {5, 5, 2, 5, 5},
      {5, 5, 2, 2, 2}, {7, 1, 2, 4, 7}};
  static const std::array<uint8_t, 5> kDot = {0, 0, 0, 0, 2};
  static const std::array<uint8_t, 5> kMinus = {0, 0, 7, 0, 0};
  static const std::array<uint8_t, 5> kK = {4, 5, 6, 5, 5};
  if (c >= '0' && c <= '9') return &kDigits[c - '0'];
  if (c >= 'A' && c <= 'Z') return &kLetters[c - 'A'];
  if (c == '.') return &kDot;
  if (c == '-') return &kMinus;
  if (c == 'k') return &kK;
  return nullptr;
}

}  // namespace

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

Image::Image(int width_px, int height_px)
    : width(width_px), height(height_px), rgb(static_cast<size_t>(width_px) * static_cast<size_t>(height_px) * 3, 0) {}

void Image::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  const size_t i = (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * 3;
  rgb[i] = c[0];
  rgb[i + 1] = c[1];
  rgb[i + 2] = c[2];
}

void Image::fill(int x, int y, int w, int h, Rgb c) {
  for (int dy = 0; dy < h; ++dy)
    for (int dx = 0; dx < w; ++dx) set(x + dx, y + dy, c);
}

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
  if (s == "-0") s = "0";
  return s + suffix;
}

double niceStep(double span, double target) {
  const double raw = span / std::max(1.0, target);
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * decade >= raw) return m * decade;
  return 10.0 * decade;
}

void drawTimeAxis(Image& image, int left, int bottom_y, int plot_w, double duration_s, Rgb ink) {
  if (!(duration_s > 0.0)) return;
  const double step = niceStep(duration_s, plot_w / 70.0);
  for (double t = 0.0; t <= duration_s + 1e-12; t += step) {
    const int x = left + static_cast<int>(std::lround(t / duration_s * (plot_w - 1)));
    for (int dy = 0; dy < 3; ++dy) image.set(x, bottom_y + dy, ink);
    const std::string text = tickLabel(t, false);
    drawText(image, std::clamp(x - textWidth(text) / 2, 0, image.width - textWidth(text)), bottom_y + 5, text, ink);
  }
}

}  // namespace strike::detail
