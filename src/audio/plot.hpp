// SPDX-License-Identifier: MIT
// Private to strike_fftw: what the pictures (spectrogram.cpp, directions.cpp) draw with. An RGB
// image, the magma colour map, a 3x5 pixel font for tick and panel labels, and tick steps.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace strike::detail {

using Rgb = std::array<uint8_t, 3>;

/// Matplotlib's magma colour map at v in [0, 1] (clamped).
Rgb magma(double v);

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  ///< row-major, top row first, 3 bytes a pixel
  Image(int width_px, int height_px);
  void set(int x, int y, Rgb c);  ///< ignored outside the image
  void fill(int x, int y, int w, int h, Rgb c);
};

constexpr int kGlyphScale = 2;                  ///< each font pixel is this many image pixels
constexpr int kGlyphAdvance = 4 * kGlyphScale;  ///< from one character to the next
constexpr int kGlyphHeight = 5 * kGlyphScale;

/// Draws `text` with its top-left corner at (x, y): digits, '.', '-', 'k', capital letters and
/// spaces (other characters leave a space).
void drawText(Image& image, int x, int y, const std::string& text, Rgb colour);
int textWidth(const std::string& text);

/// Shortest decimal for a tick value: "0.25", "3", "-90", and "1.5k" when `kilo`.
std::string tickLabel(double value, bool kilo);

/// A 1-2-5 step giving about `target` intervals over `span`.
double niceStep(double span, double target);

/// Time ticks and labels under a plot whose left edge is `left` and bottom row `bottom_y`.
void drawTimeAxis(Image& image, int left, int bottom_y, int plot_w, double duration_s, Rgb ink);

}  // namespace strike::detail
