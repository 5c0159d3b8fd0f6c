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
double pulseReference(double lambda, double c, double t0, double tau, double t,
                      PulseShape shape = PulseShape::HalfSine) {
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
      const double f = shape == PulseShape::Box ? 1.0 / tau : M_PI / (2 * tau) * std::sin(M_PI * (s - t0) / tau);
      sum += 0.5 * width * gl.w[i] * f * test::generalImpulseResponse(lambda, c, t - s);
    }
  }
  // A box is a sustained force: its feedthrough f(t) is part of the output while it acts.
  if (shape == PulseShape::Box && t >= t0 && t < t0 + tau) sum += 1.0 / tau;
  return sum;
}

std::vector<float> renderPulse(double f0, double c, double t0, double tau, bool dp, size_t frames,
                               double rate = 48000.0, PulseShape shape = PulseShape::HalfSine) {
  SynthSettings s;
  s.sample_rate_hz = rate;
  s.double_precision = dp;
  s.audibility_threshold = 0.0;
  ModalObjectDesc obj = test::makeObject({f0}, 0.0, c);
  OscillatorBank bank(s, obj);
  const double g = 1.0;
  bank.addImpact(ImpactDesc{t0, tau, &g, shape});
  return test::renderAll(bank, frames);
}

TEST(ContactPulse, MatchesQuadratureOfTheConvolution) {
  const double rate = 48000.0, h = 1.0 / rate;
  struct ModeCase {
    double f0, c;
  };
  // Ringing (light and heavy damping), critically damped, over-damped.
  const ModeCase modes[] = {
      {3000.0, 50.0}, {9000.0, 8000.0}, {500.0, 2 * 2 * M_PI * 500.0}, {500.0, 6 * 2 * M_PI * 500.0}};
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

TEST(ContactPulse, BoxPulseMatchesQuadratureOfTheConvolution) {
  const double rate = 48000.0, h = 1.0 / rate;
  const double modes[][2] = {
      {3000.0, 50.0}, {9000.0, 8000.0}, {500.0, 2 * 2 * M_PI * 500.0}, {500.0, 6 * 2 * M_PI * 500.0}};
  for (const auto& m : modes) {
    const double lambda = std::pow(2 * M_PI * m[0], 2);
    for (double tau_samples : {0.3, 3.7, 24.0, 200.0}) {
      for (bool dp : {false, true}) {
        const double t0 = 10.25 * h, tau = tau_samples * h;
        const std::vector<float> out = renderPulse(m[0], m[1], t0, tau, dp, 400, rate, PulseShape::Box);
        double peak = 0, err = 0;
        for (size_t n = 0; n < out.size(); ++n) {
          const double ref = pulseReference(lambda, m[1], t0, tau, n * h, PulseShape::Box);
          peak = std::max(peak, std::fabs(ref));
          err = std::max(err, std::fabs(out[n] - ref));
        }
        ASSERT_GT(peak, 0.0);
        // The box's static part (-lambda q + g f) cancels in float: a few float ulps of the peak.
        EXPECT_LT(err / peak, dp ? 2e-7 : 5e-6) << "f0 " << m[0] << " c " << m[1] << " tau " << tau_samples;
      }
    }
  }
}

// Resting contact arrives as one impulse per physics step. As contiguous boxes they are exactly a
// constant force: the onset rings once and dies away, nothing buzzes at the step rate. Half-sines
// of the same impulses would buzz at 2 kHz forever.
TEST(ContactPulse, SteadyForceAsContiguousBoxesIsSilentAfterItsOnset) {
  const double rate = 48000.0, step = 0.5e-3, force = 3.0;
  for (PulseShape shape : {PulseShape::Box, PulseShape::HalfSine}) {
    SynthSettings s;
    s.sample_rate_hz = rate;
    s.audibility_threshold = 0.0;
    OscillatorBank bank(s, test::makeObject({1000.0, 4000.0, 6000.0}, 0.0, 20.0));  // decay 10/s
    const double g[] = {force * step, force * step, force * step};
    for (int k = 0; k < 4000; ++k) bank.addImpact(ImpactDesc{0.01 + k * step, step, g, shape});
    const std::vector<float> out = test::renderAll(bank, static_cast<size_t>(2.0 * rate));
    const double onset = test::peakAbs(std::vector<float>(out.begin(), out.begin() + static_cast<size_t>(0.1 * rate)));
    const double tail = test::peakAbs(std::vector<float>(out.end() - static_cast<size_t>(0.2 * rate), out.end()));
    if (shape == PulseShape::Box)
      // -100 dB: what is left is float32 rounding of the cancelling static parts.
      EXPECT_LT(tail / onset, 1e-5) << "a steady force must be silent once its onset has decayed";
    else
      EXPECT_GT(tail / onset, 1e-2) << "half-sine trains buzz: the reason resting contact uses boxes";
  }
}

TEST(ContactPulse, ContiguousBoxesAddUpToOneLongBox) {
  const double rate = 48000.0, h = 1.0 / rate;
  auto render = [&](int pieces) {
    SynthSettings s;
    s.sample_rate_hz = rate;
    s.double_precision = true;
    s.audibility_threshold = 0.0;
    OscillatorBank bank(s, test::makeObject({700.0, 2500.0}, 1e-7, 5.0));
    const double tau = 37.3 * h / pieces;
    const double g[] = {1.0 / pieces, 1.0 / pieces};
    for (int k = 0; k < pieces; ++k) bank.addImpact(ImpactDesc{5.2 * h + k * tau, tau, g, PulseShape::Box});
    return test::renderAll(bank, 2000);
  };
  const std::vector<float> one = render(1), many = render(10);
  double err = 0;
  for (size_t n = 0; n < one.size(); ++n) err = std::max(err, std::fabs(double(one[n]) - many[n]));
  EXPECT_LT(err / test::peakAbs(one), 1e-6);
}

// A box with ramped edges is the box convolved with a unit box of the ramp: a trapezoid of area 1.
TEST(ContactPulse, RampedBoxMatchesQuadratureOfTheTrapezoid) {
  static const GaussLegendre gl(12);
  const double rate = 48000.0, h = 1.0 / rate;
  for (double f0 : {150.0, 3000.0, 15000.0}) {
    const double c = 30.0, lambda = std::pow(2 * M_PI * f0, 2);
    for (double tau_samples : {24.0, 300.0}) {
      const double t0 = 10.25 * h, tau = tau_samples * h, r = 24.0 * h;
      auto force = [&](double u) {  // trapezoid: ramps of r, plateau, total area 1
        const double a = std::clamp(u, 0.0, r), b = std::clamp(u - tau, 0.0, r);
        return (a - b) / (tau * r);
      };
      SynthSettings s;
      s.sample_rate_hz = rate;
      s.double_precision = true;
      s.audibility_threshold = 0.0;
      OscillatorBank bank(s, test::makeObject({f0}, 0.0, c));
      const double g = 1.0;
      ImpactDesc impact{t0, tau, &g, PulseShape::Box};
      impact.ramp_s = r;
      bank.addImpact(impact);
      const std::vector<float> out = test::renderAll(bank, 800);
      double peak = 0, err = 0;
      for (size_t n = 0; n < out.size(); ++n) {
        const double t = n * h;
        // Response = convolution with the impulse response, plus the force's own feedthrough.
        // Piecewise quadrature between the trapezoid's kinks (0, r, tau, tau + r), 64 panels each.
        double ref = 0;
        const double kinks[] = {0.0, r, tau, tau + r};
        for (int piece = 0; piece < 3; ++piece) {
          const double lo = kinks[piece], hi = std::min(kinks[piece + 1], t - t0);
          if (hi <= lo) continue;
          const int panels = 64;
          const double width = (hi - lo) / panels;
          for (int k = 0; k < panels; ++k)
            for (size_t i = 0; i < gl.x.size(); ++i) {
              const double u = lo + (k + 0.5) * width + 0.5 * width * gl.x[i];
              ref += 0.5 * width * gl.w[i] * force(u) * test::generalImpulseResponse(lambda, c, t - t0 - u);
            }
        }
        if (t >= t0) ref += force(t - t0);
        peak = std::max(peak, std::fabs(ref));
        err = std::max(err, std::fabs(out[n] - ref));
      }
      EXPECT_LT(err / peak, 1e-5) << "f0 " << f0 << " tau " << tau_samples;
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
