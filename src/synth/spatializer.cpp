// SPDX-License-Identifier: MIT
// The spatializer's formats (spatializer.hpp): a pan and the AmbiX spherical harmonics.
#include "strike/synth/spatializer.hpp"

#include <algorithm>
#include <cmath>

namespace strike {

uint32_t outputChannels(OutputFormat format) {
  const uint32_t order = ambisonicOrder(format);
  if (order > 0) return (order + 1) * (order + 1);
  return format == OutputFormat::Stereo || format == OutputFormat::Binaural ? 2 : 1;
}

bool outputHasDirections(OutputFormat format) { return format != OutputFormat::Mono; }

uint32_t ambisonicOrder(OutputFormat format) {
  switch (format) {
    case OutputFormat::Ambix1: return 1;
    case OutputFormat::Ambix2: return 2;
    case OutputFormat::Ambix3: return 3;
    default: return 0;
  }
}

const char* outputFormatName(OutputFormat format) {
  switch (format) {
    case OutputFormat::Mono: return "mono";
    case OutputFormat::Stereo: return "stereo";
    case OutputFormat::Ambix1: return "ambix1";
    case OutputFormat::Ambix2: return "ambix2";
    case OutputFormat::Ambix3: return "ambix3";
    case OutputFormat::Binaural: return "binaural";
  }
  return "mono";
}

std::optional<OutputFormat> parseOutputFormat(const std::string& name) {
  for (OutputFormat f : {OutputFormat::Mono, OutputFormat::Stereo, OutputFormat::Ambix1, OutputFormat::Ambix2,
                         OutputFormat::Ambix3, OutputFormat::Binaural})
    if (name == outputFormatName(f)) return f;
  return std::nullopt;
}

// Y_n^m = N_n^|m| Pbar_n^|m|(z) {Re, Im}((x + i y)^|m|), where Pbar_n^m = P_n^m / (1 - z^2)^(m/2)
// is a polynomial in z (the associated Legendre function without the Condon-Shortley phase and
// without its sin^m of the polar angle, which (x + i y)^m carries), by the standard recurrences
// Pbar_m^m = (2m - 1)!!, Pbar_{m+1}^m = (2m + 1) z Pbar_m^m and
// (n - m) Pbar_n^m = (2n - 1) z Pbar_{n-1}^m - (n + m - 1) Pbar_{n-2}^m; and the SN3D factor
// N_n^m = sqrt((2 - delta_m0) (n - m)! / (n + m)!) [Zotter & Frank 2019, Ambisonics, sec. A.3].
void ambixHarmonics(uint32_t order, const std::array<double, 3>& u, double* out) {
  order = std::min<uint32_t>(order, 3);
  double factorial[8] = {1, 1, 2, 6, 24, 120, 720, 5040};
  double re = 1.0, im = 0.0;  // (x + i y)^m
  double pmm = 1.0;           // Pbar_m^m
  for (uint32_t m = 0; m <= order; ++m) {
    double before = 0.0, p = pmm;  // Pbar_{n-1}^m, Pbar_n^m from n = m
    for (uint32_t n = m; n <= order; ++n) {
      if (n == m + 1) {
        before = p;
        p = (2.0 * m + 1.0) * u[2] * pmm;
      } else if (n > m + 1) {
        const double next = ((2.0 * n - 1.0) * u[2] * p - (n + m - 1.0) * before) / (n - m);
        before = p;
        p = next;
      }
      const double norm = std::sqrt((m == 0 ? 1.0 : 2.0) * factorial[n - m] / factorial[n + m]);
      out[n * (n + 1) + m] = norm * p * re;  // ACN n (n + 1) + m
      if (m > 0) out[n * (n + 1) - m] = norm * p * im;
    }
    const double next_re = re * u[0] - im * u[1];
    im = re * u[1] + im * u[0];
    re = next_re;
    pmm *= 2.0 * m + 1.0;
  }
}

std::optional<std::array<double, 4>> lookAtOrientation(const std::array<double, 3>& position,
                                                       const std::array<double, 3>& target) {
  std::array<double, 3> f = {target[0] - position[0], target[1] - position[1], target[2] - position[2]};
  const double length = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  const double level = std::sqrt(f[0] * f[0] + f[1] * f[1]);
  if (!(length > 0.0) || !std::isfinite(length) || !(level > 1e-9 * length)) return std::nullopt;
  for (double& x : f) x /= length;
  const std::array<double, 3> r = {f[1] * length / level, -f[0] * length / level, 0.0};  // f x z, unit
  const std::array<double, 3> u = {r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]};
  // The rotation's columns are the listener's axes in the world: x = r, y = f, z = u. Its
  // quaternion by the largest of the four candidates [Shepperd 1978].
  const double m00 = r[0], m01 = f[0], m02 = u[0], m10 = r[1], m11 = f[1], m12 = u[1], m20 = r[2], m21 = f[2],
               m22 = u[2];
  const double trace = m00 + m11 + m22;
  std::array<double, 4> q;
  if (trace > 0.0) {
    const double s = 2.0 * std::sqrt(1.0 + trace);
    q = {0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s};
  } else if (m00 > m11 && m00 > m22) {
    const double s = 2.0 * std::sqrt(1.0 + m00 - m11 - m22);
    q = {(m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s};
  } else if (m11 > m22) {
    const double s = 2.0 * std::sqrt(1.0 + m11 - m00 - m22);
    q = {(m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s};
  } else {
    const double s = 2.0 * std::sqrt(1.0 + m22 - m00 - m11);
    q = {(m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s};
  }
  if (q[0] < 0.0)
    for (double& x : q) x = -x;
  return q;
}

void spatialGains(OutputFormat format, const std::array<double, 3>& local, double distance_m, double level,
                  float* gains) {
  if (format == OutputFormat::Mono) {
    gains[0] = static_cast<float>(level);
    return;
  }
  if (format == OutputFormat::Binaural) {  // the direction is the head-related filters' (hrtf.hpp)
    gains[0] = gains[1] = static_cast<float>(level);
    return;
  }
  if (format == OutputFormat::Stereo) {
    const double pan = distance_m > 1e-9 ? std::clamp(local[0] / distance_m, -1.0, 1.0) : 0.0;
    const double theta = (pan + 1.0) * (M_PI / 4.0);  // constant power: gl^2 + gr^2 = level^2
    gains[0] = static_cast<float>(level * std::cos(theta));
    gains[1] = static_cast<float>(level * std::sin(theta));
    return;
  }
  // The listener's frame (x right, y forward, z up) to the Ambisonics frame (x forward, y left).
  std::array<double, 3> u = {1.0, 0.0, 0.0};
  if (distance_m > 1e-9) u = {local[1] / distance_m, -local[0] / distance_m, local[2] / distance_m};
  double y[kMaxOutputChannels];
  const uint32_t order = ambisonicOrder(format);
  ambixHarmonics(order, u, y);
  for (uint32_t c = 0; c < (order + 1) * (order + 1); ++c) gains[c] = static_cast<float>(level * y[c]);
}

}  // namespace strike
