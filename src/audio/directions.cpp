// SPDX-License-Identifier: MIT
// Directions of arrival of an Ambisonics file over time (target strike_fftw): the first-order
// active intensity per short-time frame, and its picture.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "plot.hpp"
#include "strike/core/atomic_file.hpp"
#include "strike/audio/audio.hpp"
#include "strike/core/constants.hpp"

namespace strike {
namespace {

using detail::Image;
using detail::kGlyphAdvance;
using detail::kGlyphHeight;
using detail::kGlyphScale;
using detail::Rgb;

/// The sums over one frame that its direction, level and diffuseness come from.
struct FrameSums {
  double ww = 0.0;                      ///< W^2
  double wx = 0.0, wy = 0.0, wz = 0.0;  ///< W times X, Y, Z (the negative of the active intensity)
  double velocity = 0.0;                ///< X^2 + Y^2 + Z^2
};

FrameSums frameSums(const AudioBuffer& audio, size_t begin, size_t end) {
  const size_t channels = static_cast<size_t>(audio.channels);
  auto at = [&](size_t f, size_t acn) {
    const double s = audio.samples[f * channels + acn];
    return std::isfinite(s) ? s : 0.0;
  };
  FrameSums sums;
  for (size_t f = begin; f < end; ++f) {
    const double w = at(f, 0), y = at(f, 1), z = at(f, 2), x = at(f, 3);  // ACN order: W Y Z X
    sums.ww += w * w;
    sums.wx += w * x;
    sums.wy += w * y;
    sums.wz += w * z;
    sums.velocity += x * x + y * y + z * z;
  }
  return sums;
}

DirectionFrame directionOf(const FrameSums& sums, size_t frames, double time_s) {
  DirectionFrame d;
  d.time_s = time_s;
  const double n = static_cast<double>(frames);
  if (!(sums.ww > 0.0)) return d;
  d.level_dbfs = 10.0 * std::log10(sums.ww / n);
  const double ix = sums.wx / n, iy = sums.wy / n, iz = sums.wz / n;
  const double intensity = std::sqrt(ix * ix + iy * iy + iz * iz);
  const double energy = 0.5 * (sums.ww + sums.velocity) / n;
  d.diffuseness = std::clamp(1.0 - intensity / energy, 0.0, 1.0);
  if (!(intensity > 1e-12 * energy)) return d;
  d.has_direction = true;
  d.azimuth_deg = std::atan2(iy, ix) * 180.0 / kPi;
  d.elevation_deg = std::atan2(iz, std::hypot(ix, iy)) * 180.0 / kPi;
  return d;
}

/// Where a panel's plot sits inside it: margins for the tick labels when there is room.
struct PanelLayout {
  int left = 0, right = 0, top = 0, bottom = 0;
  int plot_w = 0, plot_h = 0;
};

PanelLayout panelLayout(int width_px, int height_px, bool labels) {
  PanelLayout p;
  p.left = labels ? 5 * kGlyphAdvance + 4 : 0;
  p.bottom = labels ? 5 * kGlyphScale + 8 : 0;
  p.top = labels ? 6 : 0;
  p.right = labels ? 2 * kGlyphAdvance : 0;
  p.plot_w = width_px - p.left - p.right;
  p.plot_h = height_px - p.top - p.bottom;
  return p;
}

/// One panel's angle axis: `top_deg` at the top row, -top_deg at the bottom, a grid line and a
/// label every `step_deg`, and the panel's name in its top-left corner.
struct AngleAxis {
  const char* name;
  double top_deg;
  double step_deg;
  int row(double deg, const PanelLayout& p, int panel_y) const {
    const double u = (top_deg - deg) / (2.0 * top_deg);
    return panel_y + p.top + static_cast<int>(std::lround(u * (p.plot_h - 1)));
  }
};

void drawAngleAxis(Image& image, int panel_y, const PanelLayout& p, const AngleAxis& axis, bool labels, Rgb ink) {
  const Rgb grid{48, 48, 48};
  for (double deg = -axis.top_deg; deg <= axis.top_deg + 1e-9; deg += axis.step_deg) {
    const int y = axis.row(deg, p, panel_y);
    for (int x = 0; x < p.plot_w; ++x) image.set(p.left + x, y, grid);
    if (!labels) continue;
    for (int dx = 1; dx <= 3; ++dx) image.set(p.left - dx, y, ink);
    const std::string text = detail::tickLabel(deg, false);
    detail::drawText(image, p.left - 5 - detail::textWidth(text),
                     std::clamp(y - kGlyphHeight / 2, panel_y, panel_y + p.top + p.plot_h - kGlyphHeight), text, ink);
  }
  const int x = p.left + 4, y = panel_y + p.top + 4;
  image.fill(x - 2, y - 2, detail::textWidth(axis.name) + 4, kGlyphHeight + 4, Rgb{0, 0, 0});
  detail::drawText(image, x, y, axis.name, ink);
}

}  // namespace

Result<std::vector<DirectionFrame>> directionsOfArrival(const AudioBuffer& audio, double frame_s) {
  if (audio.channels < 4)
    return badInput(
        "directions of arrival need Ambisonics (AmbiX: ACN order, SN3D) of at least 4 channels; this "
        "sound has " +
        std::to_string(audio.channels));
  if (!(audio.sample_rate_hz > 0.0)) return badInput("directions of arrival: invalid sample rate");
  if (!(frame_s > 0.0) || !std::isfinite(frame_s))
    return badInput("directions of arrival: frame length " + std::to_string(frame_s) + " s (must be > 0)");
  const size_t frames = audio.frames();
  const size_t frame = std::max<size_t>(1, static_cast<size_t>(std::lround(frame_s * audio.sample_rate_hz)));
  std::vector<DirectionFrame> directions;
  for (size_t begin = 0; begin < frames; begin += frame) {
    const size_t end = std::min(frames, begin + frame);
    const double centre_s = 0.5 * static_cast<double>(begin + end) / audio.sample_rate_hz;
    directions.push_back(directionOf(frameSums(audio, begin, end), end - begin, centre_s));
  }
  return directions;
}

Status writeDirectionsPng(const std::string& path, const AudioBuffer& audio, const DirectionOptions& options) {
  if (options.width_px < 16 || options.height_px < 32 || options.width_px > 16384 || options.height_px > 16384)
    return badInput(path + ": error: directions picture size " + std::to_string(options.width_px) + "x" +
                    std::to_string(options.height_px) + " is outside 16..16384 x 32..16384 pixels");
  if (!(options.range_db > 0.0)) return badInput(path + ": error: range_db must be positive");
  Result<std::vector<DirectionFrame>> directions = directionsOfArrival(audio, options.frame_s);
  if (!directions) return badInput(path + ": error: " + directions.error().message);

  const int panel_h = options.height_px / 2;
  const bool labels = options.axis_labels && options.width_px >= 160 && options.height_px >= 200;
  const PanelLayout p = panelLayout(options.width_px, panel_h, labels);
  Image image(options.width_px, 2 * panel_h);
  const double duration_s = static_cast<double>(audio.frames()) / audio.sample_rate_hz;
  const Rgb ink{210, 210, 210};
  const AngleAxis azimuth{"AZIMUTH", 180.0, 90.0}, elevation{"ELEVATION", 90.0, 45.0};
  drawAngleAxis(image, 0, p, azimuth, labels, ink);
  drawAngleAxis(image, panel_h, p, elevation, labels, ink);
  if (labels) {
    detail::drawTimeAxis(image, p.left, p.top + p.plot_h, p.plot_w, duration_s, ink);
    detail::drawTimeAxis(image, p.left, panel_h + p.top + p.plot_h, p.plot_w, duration_s, ink);
  }

  // Quiet frames first, so the loud ones are drawn over them (equal levels in time order).
  const std::vector<DirectionFrame>& d = *directions;
  double loudest_db = -std::numeric_limits<double>::infinity();
  for (const DirectionFrame& f : d)
    if (f.has_direction) loudest_db = std::max(loudest_db, f.level_dbfs);
  std::vector<size_t> order(d.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return d[a].level_dbfs < d[b].level_dbfs; });
  for (const size_t i : order) {
    const DirectionFrame& f = d[i];
    if (!f.has_direction || f.level_dbfs < loudest_db - options.range_db) continue;
    // The dimmest drawn frames stay visible on the black background: the colour map from 0.3 up.
    const Rgb colour = detail::magma(0.3 + 0.7 * (f.level_dbfs - (loudest_db - options.range_db)) / options.range_db);
    const int x = p.left + static_cast<int>(std::lround(f.time_s / duration_s * (p.plot_w - 1)));
    image.fill(x - 1, azimuth.row(f.azimuth_deg, p, 0) - 1, 3, 3, colour);
    image.fill(x - 1, elevation.row(f.elevation_deg, p, panel_h) - 1, 3, 3, colour);
  }
  const std::string png = encodePngRgb(image.width, image.height, image.rgb);
  return writeFileAtomically(path, png.data(), png.size());
}

}  // namespace strike
