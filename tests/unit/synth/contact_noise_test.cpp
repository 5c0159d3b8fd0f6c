// SPDX-License-Identifier: MIT
// Rolling, sliding and scraping: the continuous force input of the oscillator bank,
// the rough-contact force generator against the closed forms of its linearized model
// (docs/contact.md, "Rolling, sliding and scraping"), and the engine's contact sources.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <vector>

#include "strike/synth/contact_noise.hpp"
#include "strike/synth/engine.hpp"
#include "strike/synth/synth.hpp"
#include "synth_fixtures.hpp"

namespace strike {
namespace {

using test::Cx;
constexpr double kFs = 48000.0;

// ---- the oscillator bank's force input -------------------------------------------------------

TEST(ForceInput, ConstantForceMatchesTheSharpForceStep) {
  // Both are the exact response to the same force: F applied from one 128-sample block boundary.
  const ModalObjectDesc object = test::makeObject({440.0, 1870.0, 5230.0}, 1e-6, 2.0, {1.0, 0.7, 0.3});
  SynthSettings settings;
  settings.sample_rate_hz = kFs;
  OscillatorBank driven(settings, object);
  OscillatorBank stepped(settings, object);
  driven.reserveForceInput();
  const std::vector<double> g = {0.8, -0.5, 0.25};
  const double t0 = 256.0 / kFs, force_n = 0.6;
  ForceWeightsDesc w;
  w.channel = 1;
  w.time_s = t0;
  w.modal_weight = g.data();
  ASSERT_TRUE(driven.setForceWeights(w));
  std::vector<double> dg(g.size());
  for (size_t i = 0; i < g.size(); ++i) dg[i] = g[i] * force_n;
  ForceStepDesc step;
  step.time_s = t0;
  step.modal_force_change = dg.data();
  ASSERT_EQ(stepped.addForceStep(step), ImpactResult::Scheduled);
  const size_t frames = 4800;
  std::vector<float> force(frames, static_cast<float>(force_n));
  std::vector<float> a(frames), b(frames);
  for (size_t done = 0; done < frames; done += 100) {  // odd call sizes: block-size independent
    const float* at[kForceChannels] = {nullptr, force.data() + done, nullptr, nullptr};
    driven.render(a.data() + done, 100, at);
  }
  stepped.render(b.data(), frames);
  const double peak = test::peakAbs(b);
  ASSERT_GT(peak, 0.1);
  double worst = 0.0;
  for (size_t n = 0; n < frames; ++n) worst = std::max(worst, std::fabs(double(a[n]) - double(b[n])));
  std::printf("constant force vs force step: peak %.4g, largest difference %.3g\n", peak, worst);
  EXPECT_LT(worst, 1e-4 * peak);  // float state, no anchor while driven
  EXPECT_EQ(a[255], 0.0f);        // nothing before the block the weights start at
}

TEST(ForceInput, DirectivityActsAsOnAForceStepAndASteadyForceStaysSilent) {
  // A per-mode complex factor (the direction toward the listener, sound_paths.cpp) on the force
  // input gives what the force step with the same factor gives, and once the onset has rung out a
  // steady force is silent (the feedthrough follows the factor).
  const ModalObjectDesc object = test::makeObject({440.0, 1870.0, 5230.0}, 1e-6, 40.0, {1.0, 0.7, 0.3});
  SynthSettings settings;
  settings.sample_rate_hz = kFs;
  OscillatorBank driven(settings, object);
  OscillatorBank stepped(settings, object);
  driven.reserveForceInput();
  const std::vector<double> g = {0.8, -0.5, 0.25};
  const std::vector<std::complex<double>> transfer = {{0.5, 0.8}, {-1.2, 0.3}, {0.0, -0.7}};
  const double t0 = 256.0 / kFs, force_n = 0.6;
  ForceWeightsDesc w;
  w.time_s = t0;
  w.modal_weight = g.data();
  w.modal_transfer = transfer.data();
  ASSERT_TRUE(driven.setForceWeights(w));
  std::vector<double> dg(g.size());
  for (size_t i = 0; i < g.size(); ++i) dg[i] = g[i] * force_n;
  ForceStepDesc step;
  step.time_s = t0;
  step.modal_force_change = dg.data();
  step.modal_transfer = transfer.data();
  ASSERT_EQ(stepped.addForceStep(step), ImpactResult::Scheduled);
  const size_t frames = kFs / 2;
  std::vector<float> force(frames, static_cast<float>(force_n));
  std::vector<float> a(frames), b(frames);
  const float* at[kForceChannels] = {force.data(), nullptr, nullptr, nullptr};
  driven.render(a.data(), frames, at);
  stepped.render(b.data(), frames);
  const double peak = test::peakAbs(b);
  ASSERT_GT(peak, 0.1);
  double worst = 0.0, tail = 0.0;
  for (size_t n = 0; n < frames; ++n) worst = std::max(worst, std::fabs(double(a[n]) - double(b[n])));
  for (size_t n = frames - 480; n < frames; ++n) tail = std::max(tail, std::fabs(double(a[n])));
  std::printf("directional force vs force step: peak %.4g, largest difference %.3g, last 10 ms %.3g\n", peak, worst,
              tail);
  EXPECT_LT(worst, 1e-4 * peak);
  EXPECT_LT(tail, 1e-4 * peak);  // rung out (decay 20 per s over 0.5 s): no offset left
}

TEST(ForceInput, StoppedChannelRingsOnFreely) {
  // Driven for 0.1 s, then the channel stops: the modes ring on exactly as a free mode (the state
  // is merged into the free oscillators), decaying at the material's rate.
  const ModalObjectDesc object = test::makeObject({700.0}, 0.0, 4.0);
  SynthSettings settings;
  settings.sample_rate_hz = kFs;
  OscillatorBank bank(settings, object);
  bank.reserveForceInput();
  const double g = 1.0;
  ForceWeightsDesc on;
  on.modal_weight = &g;
  ASSERT_TRUE(bank.setForceWeights(on));
  ForceWeightsDesc off;
  off.time_s = 0.1;
  ASSERT_TRUE(bank.setForceWeights(off));
  std::vector<float> force(kFs / 2);
  for (size_t n = 0; n < force.size(); ++n) force[n] = static_cast<float>(std::sin(2 * M_PI * 700.0 * n / kFs));
  std::vector<float> out(force.size());
  const float* channels[kForceChannels] = {force.data(), nullptr, nullptr, nullptr};
  bank.render(out.data(), out.size(), channels);
  // Envelope after the stop: amplitude ratio over 0.2 s is e^{-2 * 0.2} (c/2 = 2 per s).
  auto peakIn = [&](double t0, double t1) {
    double p = 0;
    for (size_t n = size_t(t0 * kFs); n < size_t(t1 * kFs); ++n) p = std::max(p, std::fabs(double(out[n])));
    return p;
  };
  const double a = peakIn(0.15, 0.16), b = peakIn(0.35, 0.36);
  ASSERT_GT(a, 0.0);
  EXPECT_NEAR(b / a, std::exp(-2.0 * 0.2), 0.01);
  EXPECT_FALSE(bank.forceDriven());
}

// ---- the force generator against its closed form ----------------------------------------------

struct Roll {
  RoughContactDesc desc;
  double force_n = 0.0;
};

// A steel ball (R = 12.5 mm, m = 64 g) rolling on a flat steel surface, both polished.
Roll steelBall(double mass_scale = 1.0) {
  Roll r;
  r.desc.a = {0.1e-6, 10e-6, 11};
  r.desc.b = {0.1e-6, 10e-6, 22};
  const double radius = 0.0125, density = 7850.0;
  r.desc.mass_kg = mass_scale * density * 4.0 / 3.0 * M_PI * radius * radius * radius;
  const double k = 2.0 * (1.0 - 0.29 * 0.29) / 2.0e11;
  r.desc.modulus_pa = 1.0 / k;
  r.desc.radius_m = radius;
  r.desc.damping_ratio = contactDampingRatio(0.6);
  r.desc.sample_rate_hz = kFs;
  r.force_n = r.desc.mass_kg * 9.81;
  return r;
}

// The force the generator makes while rolling at speed v for `seconds` (after 0.1 s settling).
std::vector<float> rollForce(const Roll& r, double v, double seconds, double x0 = 0.0, uint64_t start_sample = 0) {
  RoughContact c;
  c.start(r.desc, start_sample);
  const size_t total = static_cast<size_t>((seconds + 0.1) * kFs);
  std::vector<float> out(total);
  const size_t step = 48;  // 1 ms
  for (size_t n = 0; n < total; n += step) {
    const double t = static_cast<double>(n + step) / kFs;
    RoughContactState s;
    s.normal_force_n = r.force_n;
    s.speed_a_m_s = s.speed_b_m_s = v;
    s.spot_a = {x0 + v * t, 0.001, -0.0125};
    s.spot_b = {x0 + v * t, 0.002, 0.0};
    c.push(static_cast<double>(start_sample + n + step), s);
    c.generate(out.data() + n, std::min(step, total - n));
  }
  return std::vector<float>(out.begin() + static_cast<std::ptrdiff_t>(0.1 * kFs), out.end());
}

// Welch power spectrum (Hann, 4096 points, half overlap): power per bin, bins 0..2048.
std::vector<double> powerSpectrum(const std::vector<float>& x) {
  const size_t n = 4096;
  std::vector<double> p(n / 2 + 1, 0.0);
  std::vector<Cx> buf(n);
  size_t segments = 0;
  for (size_t at = 0; at + n <= x.size(); at += n / 2, ++segments) {
    for (size_t k = 0; k < n; ++k) buf[k] = x[at + k] * (0.5 - 0.5 * std::cos(2 * M_PI * k / n));
    // Radix-2 FFT.
    for (size_t i = 1, j = 0; i < n; ++i) {
      size_t bit = n >> 1;
      for (; j & bit; bit >>= 1) j ^= bit;
      j ^= bit;
      if (i < j) std::swap(buf[i], buf[j]);
    }
    for (size_t len = 2; len <= n; len <<= 1) {
      const Cx wl = std::polar(1.0, -2 * M_PI / len);
      for (size_t i = 0; i < n; i += len) {
        Cx w(1.0);
        for (size_t k = 0; k < len / 2; ++k, w *= wl) {
          const Cx u = buf[i + k], t = buf[i + k + len / 2] * w;
          buf[i + k] = u + t;
          buf[i + k + len / 2] = u - t;
        }
      }
    }
    for (size_t k = 0; k <= n / 2; ++k) p[k] += std::norm(buf[k]);
  }
  for (double& v : p) v /= std::max<size_t>(segments, 1);
  return p;
}

struct Level {
  double rms_n, centroid_hz;
};

Level measure(const std::vector<float>& f) {
  double s2 = 0;
  for (float x : f) s2 += double(x) * x;
  const std::vector<double> p = powerSpectrum(f);
  double num = 0, den = 0;
  for (size_t k = 0; k < p.size(); ++k) num += k * kFs / 4096.0 * p[k], den += p[k];
  return {std::sqrt(s2 / f.size()), num / den};
}

// The linearized model's force spectrum (docs/contact.md): both profiles (one-sided OU spectra
// 4 sigma^2 l / (1 + (2 pi k l)^2) in wavenumber k), the patch's two one-poles of length L, at
// f = v k, through the base-driven mass on the contact spring, |T|^2 = |k_c + i w c|^2 m^2 w^4 /
// |k_c - m w^2 + i w c|^2. Integrated from 1 Hz to fs/2.
Level closedForm(const Roll& r, double v) {
  const double kc = RoughContact::stiffness(r.desc, r.force_n, 0.0);
  const double a = std::cbrt(3.0 * r.force_n * r.desc.radius_m / (4.0 * r.desc.modulus_pa));
  const double L = RoughContact::patchLength(r.desc, a);
  const double m = r.desc.mass_kg;
  const double c = 2.0 * r.desc.damping_ratio * std::sqrt(kc * m);
  double num = 0, den = 0;
  const int steps = 200000;
  for (int i = 0; i < steps; ++i) {
    const double f = 1.0 + (kFs / 2 - 1.0) * (i + 0.5) / steps, df = (kFs / 2 - 1.0) / steps;
    const double k = f / v, w = 2 * M_PI * f;
    double s = 0;
    for (const SurfaceRoughness* sr : {&r.desc.a, &r.desc.b}) {
      const double x = 2 * M_PI * k * sr->correlation_m;
      s += 4.0 * sr->rms_m * sr->rms_m * sr->correlation_m / (1.0 + x * x);
    }
    const double y = 2 * M_PI * k * L;
    const double patch = 1.0 / ((1.0 + y * y) * (1.0 + y * y));
    const std::complex<double> T =
        std::complex<double>(kc, w * c) * (m * w * w) / std::complex<double>(kc - m * w * w, w * c);
    const double pf = std::norm(T) * patch * s / v * df;
    num += f * pf;
    den += pf;
  }
  return {std::sqrt(den), num / den};
}

TEST(RoughContact, DoublingSpeedRaisesLevelAndCentroidAsTheModelSays) {
  const Roll r = steelBall();
  const double v = 0.05;
  const Level m1 = measure(rollForce(r, v, 2.0)), m2 = measure(rollForce(r, 2 * v, 2.0));
  const Level c1 = closedForm(r, v), c2 = closedForm(r, 2 * v);
  const double level_db = 20 * std::log10(m2.rms_n / m1.rms_n), model_db = 20 * std::log10(c2.rms_n / c1.rms_n);
  std::printf(
      "speed %.2f -> %.2f m/s: level +%.2f dB (model +%.2f dB), centroid %.0f -> %.0f Hz (x%.3f; model %.0f -> "
      "%.0f Hz, x%.3f); rms %.3g N (model %.3g N)\n",
      v, 2 * v, level_db, model_db, m1.centroid_hz, m2.centroid_hz, m2.centroid_hz / m1.centroid_hz, c1.centroid_hz,
      c2.centroid_hz, c2.centroid_hz / c1.centroid_hz, m1.rms_n, c1.rms_n);
  EXPECT_GT(level_db, 3.0);  // louder, by what the model says within 1 dB
  EXPECT_NEAR(level_db, model_db, 1.0);
  EXPECT_GT(m2.centroid_hz / m1.centroid_hz, 1.05);  // brighter, by the model's ratio within 3%
  EXPECT_NEAR((m2.centroid_hz / m1.centroid_hz) / (c2.centroid_hz / c1.centroid_hz), 1.0, 0.03);
  EXPECT_NEAR(20 * std::log10(m1.rms_n / c1.rms_n), 0.0, 3.0);  // and the absolute level within 3 dB
}

TEST(RoughContact, DoublingLoadRaisesLevelAsTheModelSays) {
  // A ball of twice the density: twice the mass and load, a patch 2^(1/3) wider.
  const Roll r1 = steelBall(1.0), r2 = steelBall(2.0);
  const double v = 0.08;
  const Level m1 = measure(rollForce(r1, v, 2.0)), m2 = measure(rollForce(r2, v, 2.0));
  const Level c1 = closedForm(r1, v), c2 = closedForm(r2, v);
  const double level_db = 20 * std::log10(m2.rms_n / m1.rms_n), model_db = 20 * std::log10(c2.rms_n / c1.rms_n);
  std::printf("load %.3g -> %.3g N: level %+.2f dB (model %+.2f dB)\n", r1.force_n, r2.force_n, level_db, model_db);
  EXPECT_GT(level_db, 1.0);
  EXPECT_NEAR(level_db, model_db, 1.0);
}

TEST(RoughContact, FastRollOverARoughSurfaceLosesContactSlowOneDoesNot) {
  Roll r = steelBall();
  auto lost = [&](double v) {
    RoughContact c;
    c.start(r.desc, 0);
    std::vector<float> out(48);
    for (int k = 0; k < 500; ++k) {
      RoughContactState s;
      s.normal_force_n = r.force_n;
      s.speed_a_m_s = s.speed_b_m_s = v;
      s.spot_a = s.spot_b = {v * (k + 1) * 1e-3, 0, 0};
      c.push(48.0 * (k + 1), s);
      c.generate(out.data(), 48);
    }
    return c.lostSamples();
  };
  r.desc.b = {0.1e-6, 10e-6, 22};
  const uint64_t smooth_slow = lost(0.02);
  r.desc.b = {2e-6, 20e-6, 22};
  const uint64_t rough_fast = lost(1.0);
  std::printf("samples without contact in 0.5 s: polished, 2 cm/s: %llu; rough, 1 m/s: %llu\n",
              (unsigned long long)smooth_slow, (unsigned long long)rough_fast);
  EXPECT_EQ(smooth_slow, 0u);
  EXPECT_GT(rough_fast, 100u);
}

TEST(RoughContact, SameSpotSameSoundAndStillIsSilent) {
  const Roll r = steelBall();
  // The same track started at different times on the generator's clock: the same force.
  const std::vector<float> a = rollForce(r, 0.1, 0.3, 0.0, 0), b = rollForce(r, 0.1, 0.3, 0.0, 48000 * 7);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_TRUE(std::equal(a.begin(), a.end(), b.begin()));
  // Another part of the surface: a different force of the same level.
  const std::vector<float> c = rollForce(r, 0.1, 0.3, 0.05, 0);
  EXPECT_FALSE(std::equal(a.begin(), a.end(), c.begin()));
  EXPECT_NEAR(20 * std::log10(measure(a).rms_n / measure(c).rms_n), 0.0, 2.0);
  // At rest nothing moves: no force at all after the settling time.
  const std::vector<float> rest = rollForce(r, 0.0, 0.2);
  for (float x : rest) ASSERT_EQ(x, 0.0f);
}

}  // namespace
}  // namespace strike
