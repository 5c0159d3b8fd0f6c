// SPDX-License-Identifier: MIT
// The half-sine contact pulse: exact against a high-order quadrature of the convolution, converges
// to the ideal impulse, continuous in its duration.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "synth/synth_fixtures.hpp"

namespace strike {
namespace {

// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n).
struct GaussLegendre {
  std::vector<double> x, w;
  explicit GaussLegendre(int n) {
    for (int i = 1; i <= n; ++i) {
      double z = std::cos(M_PI * (i - 0.25) / (n + 0.5)), dp = 0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1, p1 = z;
        for (int k = 2; k <= n; ++k) {
          const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
          p0 = p1, p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        const double dz = p1 / dp;
        z -= dz;
        if (std::fabs(dz) < 1e-16) break;
      }
      x.push_back(z);
      w.push_back(2 / ((1 - z * z) * dp * dp));
    }
  }
};

// Output at time t of a mode (R = g = 1) driven by the unit-area half-sine on [t0, t0 + tau]:
// integral of h_acc(t - s) f(s) ds, composite 12-point Gauss-Legendre on 64 panels.
double pulseReference(double lambda, double c, double t0, double tau, double t) {
  static const GaussLegendre gl(12);
  const double b = std::min(t, t0 + tau);
  if (b <= t0) return 0.0;
  const int panels = 64;
  const double width = (b - t0) / panels;
  double sum = 0;
  for (int k = 0; k < panels; ++k) {
    const double mid = t0 + (k + 0.5) * width;
    for (size_t i = 0; i < gl.x.size(); ++i) {
      const double s = mid + 0.5 * width * gl.x[i];
      const double f = M_PI / (2 * tau) * std::sin(M_PI * (s - t0) / tau);
      sum += 0.5 * width * gl.w[i] * f * test::generalImpulseResponse(lambda, c, t - s);
    }
  }
  return sum;
}

std::vector<float> renderPulse(double f0, double c, double t0, double tau, bool dp, size_t frames, double rate = 48000.0) {
  SynthSettings s;
  s.sample_rate_hz = rate;
  s.double_precision = dp;
  s.audibility_threshold = 0.0;
  OscillatorBank bank(s);
  ModalObjectDesc obj = test::makeObject({f0}, 0.0, c);
  bank.addObject(obj);
  const double g = 1.0;
  bank.addImpact(ImpactDesc{0, t0, tau, &g});
  return test::renderAll(bank, frames);
}

TEST(ContactPulse, MatchesQuadratureOfTheConvolution) {
  const double rate = 48000.0, h = 1.0 / rate;
  struct ModeCase {
    double f0, c;
  };
  // Ringing (light and heavy damping), critically damped, over-damped.
  const ModeCase modes[] = {{3000.0, 50.0}, {9000.0, 8000.0}, {500.0, 2 * 2 * M_PI * 500.0}, {500.0, 6 * 2 * M_PI * 500.0}};
  for (const ModeCase& m : modes) {
    const double lambda = std::pow(2 * M_PI * m.f0, 2);
    for (double tau_samples : {0.3, 3.7, 50.2, 200.0}) {
      for (bool dp : {false, true}) {
        const double t0 = 10.25 * h, tau = tau_samples * h;
        const std::vector<float> out = renderPulse(m.f0, m.c, t0, tau, dp, 400);
        double peak = 0, err = 0;
        for (size_t n = 0; n < out.size(); ++n) {
          const double ref = pulseReference(lambda, m.c, t0, tau, n * h);
          peak = std::max(peak, std::fabs(ref));
          err = std::max(err, std::fabs(out[n] - ref));
        }
        ASSERT_GT(peak, 0.0);
        EXPECT_LT(err / peak, dp ? 2e-7 : 2e-6)
            << "f0 " << m.f0 << " c " << m.c << " tau " << tau_samples << " samples" << (dp ? " double" : " float");
      }
    }
  }
}

TEST(ContactPulse, ShortPulseConvergesToIdealImpulse) {
  const double rate = 48000.0, h = 1.0 / rate, t0 = 10.25 * h;
  for (double c : {30.0, 6 * 2 * M_PI * 700.0}) {
    const std::vector<float> ideal = renderPulse(700.0, c, t0, 0.0, true, 2000);
    const double peak = test::peakAbs(ideal);
    double prev = 1e300;
    for (double tau_samples : {1e-1, 1e-3, 1e-5, 1e-7}) {
      const std::vector<float> pulse = renderPulse(700.0, c, t0, tau_samples * h, true, 2000);
      double err = 0;
      for (size_t n = 0; n < ideal.size(); ++n) err = std::max(err, std::fabs(double(pulse[n]) - ideal[n]));
      EXPECT_LT(err, prev) << tau_samples;
      prev = err;
    }
    EXPECT_LT(prev / peak, 1e-6);
  }
}

TEST(ContactPulse, ContinuousInDurationAcrossASampleBoundary) {
  const double rate = 48000.0, h = 1.0 / rate, t0 = 10.25 * h;
  const double tau_c = 2.75 * h;  // the pulse ends exactly on sample 13
  for (bool dp : {false, true}) {
    for (double c : {30.0, 6 * 2 * M_PI * 700.0}) {
      const std::vector<float> mid = renderPulse(700.0, c, t0, tau_c, dp, 600);
      const double peak = test::peakAbs(mid);
      for (double eps : {-1e-9, 1e-9}) {
        const std::vector<float> near = renderPulse(700.0, c, t0, tau_c * (1 + eps), dp, 600);
        double err = 0;
        for (size_t n = 0; n < mid.size(); ++n) err = std::max(err, std::fabs(double(near[n]) - mid[n]));
        EXPECT_LT(err / peak, dp ? 2e-7 : 1e-6) << eps;
      }
    }
  }
  // And across a sample boundary with t0 moving (tau fixed): the pulse start crosses sample 10.
  for (double t0s : {10.0 - 1e-9, 10.0, 10.0 + 1e-9}) {
    const std::vector<float> a = renderPulse(700.0, 30.0, t0s * h, 3.3 * h, true, 300);
    const std::vector<float> b = renderPulse(700.0, 30.0, 10.0 * h, 3.3 * h, true, 300);
    double err = 0;
    for (size_t n = 0; n < a.size(); ++n) err = std::max(err, std::fabs(double(a[n]) - b[n]));
    EXPECT_LT(err / test::peakAbs(b), 1e-7) << t0s;
  }
}

}  // namespace
}  // namespace strike
