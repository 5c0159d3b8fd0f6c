// SPDX-License-Identifier: MIT
// The windowed-sinc fractional delay (fractional_delay.hpp).
#include "fractional_delay.hpp"

#include <cmath>

namespace strike {
namespace {

constexpr double kKaiserBeta = 8.0;

// The modified Bessel function I0 by its power series (converges fast for the beta used here).
double besselI0(double x) {
  double sum = 1.0, term = 1.0;
  for (int k = 1; k < 50; ++k) {
    const double half = x / (2.0 * k);
    term *= half * half;
    sum += term;
  }
  return sum;
}

}  // namespace

FractionalDelay::FractionalDelay() : table_(static_cast<size_t>(kPhases + 1) * kTaps) {
  constexpr int half = kTaps / 2;
  const double norm = besselI0(kKaiserBeta);
  for (int p = 0; p <= kPhases; ++p) {
    const double f = static_cast<double>(p) / kPhases;
    double taps[kTaps];
    double sum = 0.0;
    // Tap j weighs sample floor(x) + j - (half - 1), at distance (j - (half - 1)) - f from x.
    for (int j = 0; j < kTaps; ++j) {
      const double d = static_cast<double>(j - (half - 1)) - f;
      const double sinc = d == 0.0 ? 1.0 : std::sin(M_PI * d) / (M_PI * d);
      const double r = d / half;
      const double window = r * r < 1.0 ? besselI0(kKaiserBeta * std::sqrt(1.0 - r * r)) / norm : 0.0;
      taps[j] = sinc * window;
      sum += taps[j];
    }
    for (int j = 0; j < kTaps; ++j) table_[static_cast<size_t>(p) * kTaps + j] = static_cast<float>(taps[j] / sum);
  }
}

float FractionalDelay::read(const float* ring, uint64_t mask, double x) const {
  const double base = std::floor(x);
  const double phase = (x - base) * kPhases;
  const int p = static_cast<int>(phase);  // 0 .. kPhases - 1 (kPhases only by rounding: its row exists)
  const float t = static_cast<float>(phase - p);
  const float* a = table_.data() + static_cast<size_t>(p) * kTaps;
  const float* b = a + kTaps;
  const uint64_t first = static_cast<uint64_t>(base) - (kTaps / 2 - 1);
  float sum = 0.0f;
  for (int j = 0; j < kTaps; ++j) {
    const float w = a[j] + t * (b[j] - a[j]);
    sum += w * ring[(first + static_cast<uint64_t>(j)) & mask];
  }
  return sum;
}

}  // namespace strike
