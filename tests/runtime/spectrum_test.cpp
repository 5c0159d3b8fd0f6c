// SPDX-License-Identifier: MIT
// A struck bank sounds at its modes' frequencies and decays at the Rayleigh rate, through the C
// API. The references are closed forms of the numbers put into the bank, not the library's own
// reports: f = sqrt(lambda) / 2 pi, and a mode's envelope exp(-sigma t) with
// sigma = (a_mass + a_stiff omega^2) / 2 for damping C = a_mass M + a_stiff K.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <vector>

#include "check.hpp"
#include "strike/core/constants.hpp"
#include "struck_bank.hpp"

namespace {

using strike::kPi;
using strike::runtime_test::bankBytes;
using strike::runtime_test::strikeOnce;

constexpr double kSampleRate_hz = 48000.0;

/// In-place radix-2 FFT (size a power of two).
void fft(std::vector<std::complex<double>>& x) {
  const size_t n = x.size();
  for (size_t i = 1, j = 0; i < n; ++i) {  // bit reversal
    size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(x[i], x[j]);
  }
  for (size_t len = 2; len <= n; len <<= 1) {
    const std::complex<double> step = std::polar(1.0, -2.0 * kPi / static_cast<double>(len));
    for (size_t i = 0; i < n; i += len) {
      std::complex<double> w = 1.0;
      for (size_t k = 0; k < len / 2; ++k, w *= step) {
        const std::complex<double> even = x[i + k], odd = w * x[i + k + len / 2];
        x[i + k] = even + odd;
        x[i + k + len / 2] = even - odd;
      }
    }
  }
}

/// |X(f)| of the Hann-windowed signal at every bin.
std::vector<double> hannSpectrum(const std::vector<float>& signal) {
  const size_t n = signal.size();
  std::vector<std::complex<double>> x(n);
  for (size_t k = 0; k < n; ++k)
    x[k] = (0.5 - 0.5 * std::cos(2.0 * kPi * static_cast<double>(k) / static_cast<double>(n))) * signal[k];
  fft(x);
  std::vector<double> magnitude(n / 2);
  for (size_t k = 0; k < n / 2; ++k) magnitude[k] = std::abs(x[k]);
  return magnitude;
}

/// The largest bin within [low_hz, high_hz], refined by a parabola through the log magnitudes
/// of it and its neighbours (Hann: a fraction of a bin).
double peakHz(const std::vector<double>& magnitude, double bin_hz, double low_hz, double high_hz) {
  const size_t lo = std::max<size_t>(1, static_cast<size_t>(low_hz / bin_hz));
  const size_t hi = std::min(magnitude.size() - 2, static_cast<size_t>(high_hz / bin_hz));
  size_t best = lo;
  for (size_t k = lo; k <= hi; ++k)
    if (magnitude[k] > magnitude[best]) best = k;
  const double a = std::log(magnitude[best - 1]), b = std::log(magnitude[best]), c = std::log(magnitude[best + 1]);
  const double offset = 0.5 * (a - c) / (a - 2.0 * b + c);
  return (static_cast<double>(best) + offset) * bin_hz;
}

double energy(const std::vector<float>& x, double from_s, double to_s) {
  double sum = 0.0;
  for (size_t k = static_cast<size_t>(from_s * kSampleRate_hz); k < static_cast<size_t>(to_s * kSampleRate_hz); ++k)
    sum += static_cast<double>(x[k]) * x[k];
  return sum;
}

void peaksAtTheModeFrequencies() {
  // Frequencies no default or test elsewhere uses, well apart; light damping (narrow peaks).
  const std::vector<double> freqs_hz = {523.25, 1234.5, 3001.0};
  const size_t n = 1 << 16;  // 1.37 s, bins of 0.73 Hz
  const std::vector<float> sound = strikeOnce(bankBytes(freqs_hz, 1e-9, 2.0), kSampleRate_hz, n);
  const std::vector<double> magnitude = hannSpectrum(sound);
  const double bin_hz = kSampleRate_hz / static_cast<double>(n);
  for (double f : freqs_hz) {
    const double peak = peakHz(magnitude, bin_hz, f - 50.0, f + 50.0);
    std::printf("mode %.2f Hz: spectrum peak %.3f Hz\n", f, peak);
    CHECK_NEAR(peak, f, 0.1);
    // A real peak: 30 dB above the spectrum a sixth of the way to the next mode.
    const double off = magnitude[static_cast<size_t>(f * 1.17 / bin_hz)];
    CHECK(magnitude[static_cast<size_t>(std::lround(peak / bin_hz))] > 31.6 * off);
  }
  // The strongest peak of the whole audible band is one of the modes: nothing else sounds louder.
  const double strongest = peakHz(magnitude, bin_hz, 20.0, 20000.0);
  CHECK(std::any_of(freqs_hz.begin(), freqs_hz.end(), [&](double f) { return std::fabs(strongest - f) < 0.5; }));
}

/// One mode at f_hz; its envelope's decay rate from the energy in two windows, against sigma.
void decaysAtTheRayleighRate(double f_hz, double rayleigh_stiffness_s, double rayleigh_mass_per_s, double t1_s,
                             double t2_s, double window_s) {
  const double omega = 2.0 * kPi * f_hz;
  const double sigma = 0.5 * (rayleigh_mass_per_s + rayleigh_stiffness_s * omega * omega);
  const size_t frames = static_cast<size_t>((t2_s + window_s) * kSampleRate_hz) + 512;
  const std::vector<float> sound =
      strikeOnce(bankBytes({f_hz}, rayleigh_stiffness_s, rayleigh_mass_per_s), kSampleRate_hz, frames);
  // Energy of A exp(-sigma t) sin(omega t) over a window many periods long: A^2 exp(-2 sigma t) W/2
  // to well under 1 %, so the ratio of two windows gives sigma.
  const double e1 = energy(sound, t1_s, t1_s + window_s), e2 = energy(sound, t2_s, t2_s + window_s);
  CHECK(e1 > 0.0 && e2 > 0.0);
  const double measured = -std::log(e2 / e1) / (2.0 * (t2_s - t1_s));
  std::printf("mode %.0f Hz: decay rate %.4f 1/s, Rayleigh %.4f 1/s\n", f_hz, measured, sigma);
  CHECK_NEAR(measured, sigma, 0.01 * sigma);
}

}  // namespace

int main() {
  peaksAtTheModeFrequencies();
  // The same Rayleigh pair at two frequencies: 700 Hz is mostly the mass term (sigma 6.87 1/s),
  // 3000 Hz mostly the stiffness term (sigma 74.06 1/s), so both coefficients are tested.
  decaysAtTheRayleighRate(700.0, 4e-7, 6.0, 0.05, 0.45, 0.1);
  decaysAtTheRayleighRate(3000.0, 4e-7, 6.0, 0.01, 0.05, 0.02);
  return strike::check::checkExitCode("spectrum_test");
}
