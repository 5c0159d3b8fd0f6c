// SPDX-License-Identifier: MIT
// What an impact sends to the listener (sound_paths.cpp): the oscillators' per-impact complex
// factor against the closed form, the ground's image source (delay and level from the
// geometry), and a bank's far field turned toward the listener.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <vector>

#include "strike/synth/engine.hpp"
#include "synth_fixtures.hpp"

namespace strike {
namespace {

constexpr double kRate = 48000.0;

TEST(ImpactFactor, TurnsEachModesPhaseAsTheClosedFormSays) {
  // An ideal impulse on a ringing mode rings as Re(b e^{pt}), b = -i p^2 / w_d; a factor i gives
  // Re(i b e^{pt}) = Re(p^2 e^{pt}) / w_d, and 2 - i gives 2 x the first minus that.
  SynthSettings s;
  s.sample_rate_hz = kRate;
  s.double_precision = true;
  s.audibility_threshold = 0.0;
  const ModalObjectDesc object = test::makeObject({880.0}, 1e-8, 4.0);
  const double lambda = object.eigenvalues[0], c = 1e-8 * lambda + 4.0;
  const std::complex<double> p(-0.5 * c, std::sqrt(lambda - 0.25 * c * c));
  for (std::complex<double> factor : {std::complex<double>(0, 1), std::complex<double>(2, -1)}) {
    OscillatorBank bank(s, object);
    const double g = 1.0;
    ImpactDesc impact{0.0, 0.0, &g};
    impact.modal_transfer = &factor;
    ASSERT_EQ(bank.addImpact(impact), ImpactResult::Scheduled);
    const std::vector<float> out = test::renderAll(bank, 2400);
    double worst = 0.0, peak = 0.0;
    for (size_t n = 1; n < out.size(); ++n) {
      const double t = n / kRate;
      const double expected = (factor * std::complex<double>(0, -1) * p * p * std::exp(p * t)).real() / p.imag();
      worst = std::max(worst, std::fabs(out[n] - expected));
      peak = std::max(peak, std::fabs(expected));
    }
    EXPECT_LT(worst, 1e-6 * peak) << factor;
  }
}

/// One ringing mode whose far field is a dipole along the bank's x axis (F = Y_11), on a small
/// triangle at the origin (for the projector), mass 1 kg.
std::shared_ptr<ModeBank> dipoleBank(bool with_transfer) {
  auto bank = std::make_shared<ModeBank>();
  ModeBank& b = *bank;
  b.material.youngs_pa = 2e11;
  b.material.poisson = 0.3;
  b.material.rayleigh_mass = 6.0;
  b.mass_kg = 1.0;
  b.volume_m3 = 0.0;  // no acceleration noise: these tests look at the modes
  b.eigenvalues = {std::pow(2.0 * M_PI * 1000.0, 2)};
  b.surface_positions = {0, 0, 0, 0.01, 0, 0, 0, 0.01, 0};
  b.surface_normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  b.surface_triangles = {0, 1, 2};
  b.surface_node_index = {0, 1, 2};
  b.shapes = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  b.radiation_m2 = {1e-3};
  if (with_transfer) {
    AcousticTransfer& t = b.transfer;
    t.order = {1};
    t.offset = {0, 4};
    t.coefficients = {0.0f, 0.0f, 0.0f, std::complex<float>(0.5f, 0.0f)};  // 0.5 Y_11 = 0.5 sqrt(3/4pi) x
    t.relative_error = {0.0f};
  }
  return bank;
}

struct Heard {
  std::vector<float> out;
  EngineStats stats;
};

Heard strike(const std::shared_ptr<ModeBank>& bank, const std::array<double, 3>& body_at,
             const std::array<double, 3>& listener_at, GroundReflection ground,
             std::array<double, 4> orientation_wxyz = {1, 0, 0, 0}, size_t frames = 9600) {
  EngineSettings settings;
  settings.synth.sample_rate_hz = kRate;
  settings.synth.audibility_threshold = 0.0;
  settings.max_voices = 1;
  settings.max_block_frames = 256;
  settings.ground = ground;
  settings.realtime = false;
  SoundEngine engine(settings);
  VoiceDesc desc;
  desc.bank = bank;
  desc.weights = radiationWeights(*bank, settings.reference_distance_m);
  desc.pressure_scale = 1.0;
  desc.pose.set(body_at.data(), orientation_wxyz.data());
  Voice voice(desc, settings);
  engine.install(0, &voice);
  Pose listener;
  listener.position_m = listener_at;
  engine.setListener(listener);
  EngineImpact impact;
  impact.point = {0.003, 0.003, 0.0};
  impact.impulse = {0, 0, -0.01};
  impact.contact_duration_s = 0.0;
  impact.time_s = 0.0;
  engine.impact(impact);
  Heard h;
  h.out.resize(frames);
  for (size_t at = 0; at < frames; at += 256) {
    float* channel = h.out.data() + at;
    engine.render(&channel, std::min<size_t>(256, frames - at));
  }
  h.stats = engine.stats();
  return h;
}

double energy(const std::vector<float>& x) {
  double e = 0.0;
  for (float v : x) e += double(v) * v;
  return e;
}

size_t onset(const std::vector<float>& x, double fraction_of_peak) {
  double peak = 0.0;
  for (float v : x) peak = std::max(peak, std::fabs(double(v)));
  for (size_t n = 0; n < x.size(); ++n)
    if (std::fabs(double(x[n])) > fraction_of_peak * peak) return n;
  return x.size();
}

TEST(GroundReflection, ImageArrivesOnTimeAtTheLevelOfItsPathAndCoefficient) {
  // A body 0.5 m above the ground, the listener 1 m away at the same height: the image path is
  // sqrt(1 + 1) m, so it arrives (sqrt 2 - 1) / c = 1.21 ms later at 1 / sqrt 2 the pressure
  // (-3 dB) times the reflection coefficient.
  const auto bank = dipoleBank(false);
  const std::array<double, 3> body = {0, 0, 0.5}, listener = {1.0, 0, 0.5};
  const Heard free_field = strike(bank, body, listener, GroundReflection{});
  for (double coefficient : {1.0, 0.5, -0.8}) {
    GroundReflection ground;
    ground.enabled = true;
    ground.reflection = coefficient;
    const Heard both = strike(bank, body, listener, ground);
    std::vector<float> image(both.out.size());
    for (size_t n = 0; n < image.size(); ++n) image[n] = both.out[n] - free_field.out[n];
    const double delay_samples = (std::sqrt(2.0) - 1.0) / kSpeedOfSoundAir_m_s * kRate;
    const double measured = double(onset(image, 1e-3)) - double(onset(free_field.out, 1e-3));
    EXPECT_NEAR(measured, delay_samples, 1.0) << coefficient;
    const double level_db = 10.0 * std::log10(energy(image) / energy(free_field.out));
    EXPECT_NEAR(level_db, 20.0 * std::log10(std::fabs(coefficient) / std::sqrt(2.0)), 0.05) << coefficient;
    EXPECT_EQ(both.stats.impacts, 1u) << "two paths, one impact";
  }
  // A listener below the ground hears no image; off means off.
  GroundReflection ground;
  ground.enabled = true;
  ground.height_m = 0.6;
  const Heard under = strike(bank, body, listener, ground);
  EXPECT_EQ(under.out, free_field.out);
}

TEST(Directivity, AFarFieldIsHeardAlongItsDirectionAndNotAcrossIt) {
  // F = 0.5 Y_11: a dipole along the bank's x. Heard along x: |F| = 0.5 sqrt(3 / 4 pi); at 60
  // degrees off: half that; along y: nothing. A rotated body turns its pattern with it.
  const auto bank = dipoleBank(true);
  const std::array<double, 3> body = {0, 0, 0};
  const double along = energy(strike(bank, body, {1, 0, 0}, GroundReflection{}).out);
  const double oblique = energy(strike(bank, body, {0.5, std::sqrt(0.75), 0}, GroundReflection{}).out);
  const double across = energy(strike(bank, body, {0, 1, 0}, GroundReflection{}).out);
  ASSERT_GT(along, 0.0);
  EXPECT_NEAR(10.0 * std::log10(oblique / along), 20.0 * std::log10(0.5), 0.05);
  EXPECT_LT(across, 1e-12 * along);
  // Turned 90 degrees about z, the body's x points along the world's y.
  const std::array<double, 4> turned = {std::sqrt(0.5), 0, 0, std::sqrt(0.5)};
  EXPECT_NEAR(energy(strike(bank, body, {0, 1, 0}, GroundReflection{}, turned).out) / along, 1.0, 1e-6);
  EXPECT_LT(energy(strike(bank, body, {1, 0, 0}, GroundReflection{}, turned).out), 1e-12 * along);
  // The weights hold the direction average, rms |F| = 0.5 / sqrt(4 pi); along x the level is
  // sqrt 3 times that. An older bank with that average (R = 4 pi rms / rho) is heard at the rms.
  const auto averaged = dipoleBank(false);
  averaged->radiation_m2 = {4.0 * M_PI * 0.5 / std::sqrt(4.0 * M_PI) / kAirDensity_kg_m3};
  const double rms_level = energy(strike(averaged, body, {1, 0, 0}, GroundReflection{}).out);
  EXPECT_NEAR(10.0 * std::log10(along / rms_level), 10.0 * std::log10(3.0), 0.05);
}

}  // namespace
}  // namespace strike
