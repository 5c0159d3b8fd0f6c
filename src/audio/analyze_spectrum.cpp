// SPDX-License-Identifier: MIT
// The analysis' whole-signal spectrum (target strike_fftw): one FFT of the ring from its onset,
// its peaks interpolated, their widths, and the closed-form shape of a decaying line seen through
// the window, which the leakage test of analyze.cpp compares candidates against.
#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <mutex>

#include "analyze_lines.hpp"
#include "fftw_lock.hpp"
#include "strike/core/constants.hpp"

namespace strike::detail {
namespace {

size_t nextPowerOfTwo(size_t n) {
  size_t p = 1;
  while (p < n) p <<= 1;
  return p;
}

/// -3 dB half width of lineShape (bisection: the main lobe falls monotonically to it).
double modelHalfWidthHz(double decay_per_s, size_t length, double rate_hz, SpectrumWindow window) {
  const double target = lineShape(0.0, decay_per_s, length, rate_hz, window) / std::sqrt(2.0);
  double lo = 0.0, hi = rate_hz / static_cast<double>(length);
  while (lineShape(hi, decay_per_s, length, rate_hz, window) > target && hi < 0.25 * rate_hz) hi *= 2.0;
  for (int i = 0; i < 50; ++i) {
    const double mid = 0.5 * (lo + hi);
    (lineShape(mid, decay_per_s, length, rate_hz, window) > target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

Spectrum wholeSpectrum(const Mono& mono, SpectrumWindow window, double rate_hz) {
  const size_t length = mono.x.size() - mono.onset;
  // Zero-padding by at least 2 keeps the quadratic interpolation's bias small (SASP, "Bias of
  // Parabolic Peak Interpolation"); above 2^24 points padding only to N bounds the memory.
  size_t size = nextPowerOfTwo(2 * length);
  if (size > (size_t{1} << 24)) size = nextPowerOfTwo(length);
  double* in = fftw_alloc_real(size);
  fftw_complex* out = fftw_alloc_complex(size / 2 + 1);
  fftw_plan plan;
  {
    std::lock_guard<std::mutex> lock(detail::fftwPlannerMutex());
    plan = fftw_plan_dft_r2c_1d(static_cast<int>(size), in, out, FFTW_ESTIMATE);
  }
  double window_sum = 0.0;
  const double n_total = static_cast<double>(length);
  for (size_t n = 0; n < size; ++n) {
    double w = 0.0;
    if (n < length) {
      const double t = static_cast<double>(n);
      if (window == SpectrumWindow::Hann) {
        const double s = std::sin(kPi * (t + 0.5) / n_total);
        w = s * s;
      } else {
        const double c = std::cos(0.5 * kPi * t / n_total);
        w = c * c;
      }
      window_sum += w;
      in[n] = w * mono.x[mono.onset + n];
    } else {
      in[n] = 0.0;
    }
  }
  fftw_execute(plan);
  Spectrum spectrum;
  spectrum.bin_hz = rate_hz / static_cast<double>(size);
  spectrum.window_sum = window_sum;
  spectrum.amplitude.resize(size / 2 + 1);
  const double scale = window_sum > 0.0 ? 2.0 / window_sum : 0.0;
  for (size_t k = 0; k <= size / 2; ++k) spectrum.amplitude[k] = scale * std::hypot(out[k][0], out[k][1]);
  {
    std::lock_guard<std::mutex> lock(detail::fftwPlannerMutex());
    fftw_destroy_plan(plan);
  }
  fftw_free(in);
  fftw_free(out);
  return spectrum;
}

/// The whole-signal window's response to one decaying complex line, in closed form: for
/// x(n) = e^{(-a + j t) n} (a = d / fs, t = 2 pi (f_line - f) / fs) and a window that is a sum of
/// complex exponentials, sum_n w(n) x(n) is a sum of geometric series (1 - q^L) / (1 - q).
/// OnsetHalfHann: cos^2(pi n / 2L) = 1/2 + (e^{j pi n / L} + e^{-j pi n / L}) / 4.
/// Hann: sin^2(pi (n + 1/2) / L) = 1/2 - (e^{j pi / L} e^{j 2 pi n / L} + conj) / 4.
/// Exact for any offset and decay (the Lorentzian line convolved with the window's transform),
/// so it gives a mode's leakage ("skirt") at any distance, not only its asymptote.
double lineShape(double offset_hz, double decay_per_s, size_t length, double rate_hz, SpectrumWindow window) {
  const double a = decay_per_s / rate_hz;
  const double l = static_cast<double>(length);
  auto series = [&](double theta) {
    // 1 - q with q = e^{-a} e^{j theta}, without cancellation when a and theta are tiny.
    const double c = std::cos(theta), s = std::sin(theta), half = std::sin(0.5 * theta);
    const std::complex<double> one_minus_q(-std::expm1(-a) * c + 2.0 * half * half, -std::exp(-a) * s);
    const std::complex<double> q_l = std::exp(std::complex<double>(-a * l, theta * l));
    if (std::abs(one_minus_q) < 1e-14) return std::complex<double>(l, 0.0);
    return (1.0 - q_l) / one_minus_q;
  };
  const double theta = -2.0 * kPi * offset_hz / rate_hz;
  if (window == SpectrumWindow::Hann) {
    const std::complex<double> e(std::cos(kPi / l), std::sin(kPi / l));
    return std::abs(0.5 * series(theta) - 0.25 * e * series(theta + 2.0 * kPi / l) -
                    0.25 * std::conj(e) * series(theta - 2.0 * kPi / l));
  }
  return std::abs(0.5 * series(theta) + 0.25 * series(theta + kPi / l) + 0.25 * series(theta - kPi / l));
}

/// The decay whose model line is as wide as the measured one (0 if it is no wider than the
/// window's own main lobe). For the leakage test before the decay is fitted; a merged pair
/// looks wider than either mode, which over-estimates its skirt (the safe side).
double decayFromHalfWidth(double half_width_hz, size_t length, double rate_hz, SpectrumWindow window) {
  if (!(half_width_hz > modelHalfWidthHz(0.0, length, rate_hz, window))) return 0.0;
  double lo = 0.0, hi = 2.0 * kPi * half_width_hz;
  while (modelHalfWidthHz(hi, length, rate_hz, window) < half_width_hz && hi < rate_hz) hi *= 2.0;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    (modelHalfWidthHz(mid, length, rate_hz, window) < half_width_hz ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// Quadratic interpolation of log|X| through bins k-1, k, k+1 (Smith, SASP, "Quadratic
/// Interpolation of Spectral Peaks"): offset p = (a - c) / (2 (a - 2b + c)) bins, log peak
/// b - (a - c) p / 4. On log magnitude the fit is exact for a Gaussian main lobe and close for
/// Hann-like lobes.
Candidate interpolatePeak(const Spectrum& spectrum, size_t k) {
  const double a = std::log(spectrum.amplitude[k - 1]);
  const double b = std::log(spectrum.amplitude[k]);
  const double c = std::log(spectrum.amplitude[k + 1]);
  const double denominator = a - 2.0 * b + c;
  const double p = denominator < 0.0 ? std::clamp(0.5 * (a - c) / denominator, -0.5, 0.5) : 0.0;
  Candidate candidate;
  candidate.freq_hz = (static_cast<double>(k) + p) * spectrum.bin_hz;
  candidate.amplitude = std::exp(b - 0.25 * (a - c) * p);
  return candidate;
}

/// -3 dB half width of a peak: walk out on both sides (stopping at a valley, which belongs to
/// a neighbour) and interpolate linearly.
double halfWidthHz(const Spectrum& spectrum, const Candidate& candidate) {
  const double half_power = candidate.amplitude / std::sqrt(2.0);
  const double k_peak = candidate.freq_hz / spectrum.bin_hz;
  const auto k = static_cast<size_t>(std::lround(k_peak));
  const size_t last = spectrum.amplitude.size() - 1;
  const double* a = spectrum.amplitude.data();
  auto edge = [&](int direction) {
    size_t j = k;
    for (;;) {
      const size_t next = direction > 0 ? j + 1 : j - 1;
      if (j == 0 || j == last || a[j] <= half_power || a[next] > a[j]) break;
      j = next;
    }
    if (j == k) return 0.5;
    const size_t inner = direction > 0 ? j - 1 : j + 1;
    const double y0 = a[inner], y1 = a[j];
    const double frac = y0 > y1 ? std::clamp((y0 - half_power) / (y0 - y1), 0.0, 1.0) : 1.0;
    return std::fabs(static_cast<double>(inner) + direction * frac - k_peak);
  };
  return 0.5 * (edge(+1) + edge(-1)) * spectrum.bin_hz;
}

}  // namespace strike::detail
