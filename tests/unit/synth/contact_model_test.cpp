// SPDX-License-Identifier: MIT
// The contact-model seam (contact_model.hpp): a model of one's own, added to the engine, plays
// the contacts instead of the built-in ones. The "tick" model here sends each contact's impulse
// as an ideal click, whose sound is known in closed form: mode i of a mass-normalized bank
// (modal mass phi_i^T M phi_i = 1) struck by the impulse J at point p rings from the arrival on
// with amplitude g_i = phi_i(p) . J / 1 and its own pole.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "strike/synth/contact_model.hpp"
#include "synth_fixtures.hpp"

namespace strike {
namespace {

constexpr double kRate = 48000.0;

/// Every contact, whatever its speed, as an ideal impulse: a click.
class TickModel final : public ContactModel {
 public:
  const char* name() const override { return "tick"; }
  bool takes(const ResolvedContact&) const override { return true; }
  void play(const ResolvedContact& contact, VoiceInput& voice) override {
    voice.pulse(voice.project(contact, Projection::Once), contact.time_s, 0.0, PulseShape::HalfSine, contact);
  }
};

/// A 10 cm square as a 3x3 vertex grid around its centre of mass at the origin, with shapes that
/// differ in all three components from vertex to vertex.
std::shared_ptr<const ModeBank> gridBank() {
  auto bank = std::make_shared<ModeBank>();
  ModeBank& b = *bank;
  b.material.youngs_pa = 2.0e11;
  b.material.poisson = 0.3;
  b.material.rayleigh_stiffness = 1e-8;
  b.material.rayleigh_mass = 10.0;
  b.mass_kg = 1.0;
  b.volume_m3 = 1.0 / 7850.0;
  for (double f : {523.0, 1187.0, 2450.0, 4100.0}) b.eigenvalues.push_back(std::pow(2.0 * M_PI * f, 2));
  const double h = 0.05;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      b.surface_positions.insert(b.surface_positions.end(), {(i - 1) * h, (j - 1) * h, 0.0});
      b.surface_normals.insert(b.surface_normals.end(), {0.0f, 0.0f, 1.0f});
      b.surface_node_index.push_back(static_cast<uint32_t>(3 * j + i));
    }
  for (uint32_t j = 0; j < 2; ++j)
    for (uint32_t i = 0; i < 2; ++i) {
      const uint32_t a = 3 * j + i;
      b.surface_triangles.insert(b.surface_triangles.end(), {a, a + 4, a + 1, a, a + 3, a + 4});
    }
  for (size_t m = 0; m < b.eigenvalues.size(); ++m)
    for (size_t v = 0; v < 9; ++v)
      b.shapes.insert(b.shapes.end(),
                      {0.3f - 0.1f * float(m), 0.05f * float(v % 3), float(std::cos(0.7 * double(m + 1) * double(v)))});
  b.centre_m = {0.0, 0.0, 0.0};
  return bank;
}

struct Strike {
  size_t vertex;
  std::array<double, 3> impulse;  // N s
  double speed_m_s;               // approach speed: 0 is sustained contact for the built-in models
  double time_s;
};

const std::vector<Strike>& strikes() {
  static const std::vector<Strike> s = {{4, {0.0, 0.0, 0.02}, 0.0, 0.0100},
                                        {0, {0.004, -0.003, 0.01}, 2.0, 0.0523},
                                        {8, {0.0, 0.002, -0.015}, 0.3, 0.1371}};
  return s;
}

/// The engine's modal acceleration output (weights 1, listener 1 m away) of the strikes, each
/// reported in a 1 ms physics step of its own.
std::vector<float> render(const std::shared_ptr<const ModeBank>& bank, bool tick, size_t frames) {
  EngineSettings settings;
  settings.synth.sample_rate_hz = kRate;
  settings.synth.double_precision = true;
  settings.synth.audibility_threshold = 0.0;
  settings.max_voices = 1;
  settings.max_block_frames = 256;
  SoundEngine engine(settings);
  if (tick) engine.addContactModel(std::make_unique<TickModel>());
  VoiceDesc desc;
  desc.bank = bank;
  Voice voice(desc, settings);
  engine.install(0, &voice);
  Pose listener;
  listener.position_m = {1.0, 0.0, 0.0};
  engine.setListener(listener);
  for (const Strike& s : strikes()) {
    engine.beginStep(s.time_s + 1e-3, 1e-3);
    EngineContact c;
    c.point = {bank->surface_positions[3 * s.vertex], bank->surface_positions[3 * s.vertex + 1],
               bank->surface_positions[3 * s.vertex + 2]};
    c.impulse = s.impulse;
    c.normal_speed_m_s = s.speed_m_s;
    c.time_s = s.time_s;
    engine.contact(c);
    engine.endStep();
  }
  std::vector<float> out(frames);
  for (size_t n = 0; n < frames; n += 256) {
    float* ch[1] = {out.data() + n};
    engine.render(ch, std::min<size_t>(256, frames - n));
  }
  return out;
}

TEST(ContactModel, ATickModelSendsEachImpulseAsTheClickOfTheModes) {
  const std::shared_ptr<const ModeBank> bank = gridBank();
  const size_t frames = static_cast<size_t>(0.25 * kRate);
  const std::vector<float> out = render(bank, true, frames);
  // The closed form: per strike k and mode i, g_ik = phi_i(p_k) . J_k (unit modal mass) times
  // the ringing acceleration of an ideal impulse from t_k + r_k / c on, r_k its distance.
  std::vector<double> expected(frames, 0.0);
  for (const Strike& s : strikes()) {
    const double* p = &bank->surface_positions[3 * s.vertex];
    const double arrival_s = s.time_s + std::hypot(p[0] - 1.0, p[1], p[2]) / kSpeedOfSoundAir_m_s;
    for (size_t i = 0; i < bank->modeCount(); ++i) {
      const float* phi = &bank->shapes[(i * bank->surfaceVertexCount() + s.vertex) * 3];
      const double g = phi[0] * s.impulse[0] + phi[1] * s.impulse[1] + phi[2] * s.impulse[2];
      const double lambda = bank->eigenvalues[i];
      const double c = bank->material.rayleigh_stiffness * lambda + bank->material.rayleigh_mass;
      for (size_t n = static_cast<size_t>(std::ceil(arrival_s * kRate)); n < frames; ++n)
        expected[n] += g * test::ringingImpulseResponse(lambda, c, static_cast<double>(n) / kRate - arrival_s);
    }
  }
  double peak = 0.0, worst = 0.0;
  for (size_t n = 0; n < frames; ++n) {
    peak = std::max(peak, std::fabs(expected[n]));
    worst = std::max(worst, std::fabs(static_cast<double>(out[n]) - expected[n]));
  }
  ASSERT_GT(peak, 0.0);
  EXPECT_LT(worst, 1e-6 * peak) << "worst " << worst << " of peak " << peak;
  // Without it the built-in models play the same contacts: a Hertz pulse for the strike at
  // 2 m/s, a load for the slow ones (no click): another sound.
  const std::vector<float> builtin = render(bank, false, frames);
  double difference = 0.0;
  for (size_t n = 0; n < frames; ++n) difference = std::max(difference, std::fabs(double(builtin[n]) - expected[n]));
  EXPECT_GT(difference, 0.1 * peak);
}

TEST(ContactModel, TheBuiltInModelsSplitContactsByTheImpactRule) {
  const std::vector<std::unique_ptr<ContactModel>> models = builtInContactModels();
  ASSERT_EQ(models.size(), 2u);
  ResolvedContact fast, slow;
  fast.impact = true;
  EXPECT_TRUE(models[0]->takes(fast));
  EXPECT_FALSE(models[0]->takes(slow));
  EXPECT_TRUE(models[1]->takes(slow));
  EXPECT_FALSE(models[1]->takes(fast));
}

}  // namespace
}  // namespace strike
