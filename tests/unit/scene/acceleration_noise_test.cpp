// SPDX-License-Identifier: MIT
// Acceleration noise: a small steel ball, whose elastic modes are all ultrasonic,
// dropped on a rigid ground clicks as a rigid sphere translating with the Hertz pulse's
// acceleration radiates. The closed form is the exact rigid sphere [Morse & Ingard 1968, 7.2]:
//   P(w) = rho / (4 pi c r) 2 pi a^3 cos(theta) (-i w) A(w) 2 / (2 - 2 i x - x^2),  x = w a / c,
// A(w) = (J / m) F(w), F the spectrum of the unit-area half-sine of the Hertz duration tau
// [Johnson 1985]: F(w) = (pi / 2 tau) Om (1 + e^{i w tau}) / (Om^2 - w^2), Om = pi / tau.
// Nothing in it is the engine's code: the ball's impulse and speed come from the simulation's
// events, the rest from the ball's radius, the materials and the listener's place.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

#include "strike/core/air.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"
#include "strike/synth/synth.hpp"

namespace strike {
namespace {

using Cx = std::complex<double>;

struct Spectrum {
  std::vector<double> freq_hz, magnitude;  ///< |continuous Fourier transform|, Pa s
};

/// |FT| of samples x (rate) on [0, top_hz], zero-padded to `n` points, by a direct DFT.
Spectrum spectrumOf(const std::vector<double>& x, double rate, size_t n, double top_hz) {
  Spectrum s;
  for (size_t k = 0; k * rate / n <= top_hz; ++k) {
    const double w = 2.0 * M_PI * k / n;
    Cx sum = 0.0;
    for (size_t j = 0; j < x.size(); ++j) sum += x[j] * std::polar(1.0, -w * j);
    s.freq_hz.push_back(k * rate / n);
    s.magnitude.push_back(std::abs(sum) / rate);
  }
  return s;
}

TEST(AccelerationNoise, SteelBallOnRigidGroundMatchesTheRigidSphereDipole) {
  const double a = 0.005, rate = 96000.0;
  const std::array<double, 3> listener = {0.6, 0.0, 0.8 + a};  // 1 m from the contact, 36.9 deg off vertical
  char json[1024];
  std::snprintf(json, sizeof json, R"({"sample_rate": %g, "duration": 0.03,
      "listener": {"position": [%g, %g, %g]},
      "ground": {"material": "concrete", "reflection": false},
      "objects": [{"name": "ball", "mesh": "sphere:%g", "material": "steel",
                   "position": [0, 0, %g], "velocity": [0, 0, -3]}]})",
                rate, listener[0], listener[1], listener[2], a, a + 0.006);
  Result<Scene> scene = parseScene(json, "ball.json");
  ASSERT_TRUE(scene) << scene.error().message;
  RenderSettings settings;
  Result<RenderResult> r = renderScene(*scene, settings);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->banks.size(), 1u);

  // The first impact on the ground.
  const ContactEvent* hit = nullptr;
  for (const ContactEvent& e : r->events)
    if (e.normal_speed_m_s > kImpactSpeed_m_s) {
      hit = &e;
      break;
    }
  ASSERT_NE(hit, nullptr);
  const double impulse = std::sqrt(hit->impulse_on_a_mesh[0] * hit->impulse_on_a_mesh[0] +
                                   hit->impulse_on_a_mesh[1] * hit->impulse_on_a_mesh[1] +
                                   hit->impulse_on_a_mesh[2] * hit->impulse_on_a_mesh[2]);
  const Material steel = *builtinMaterials().find("steel");
  const Material concrete = *builtinMaterials().find("concrete");
  const double mass = steel.density_kg_m3 * 4.0 / 3.0 * M_PI * a * a * a;
  const double tau = hertzContactDuration(steel.youngs_pa, steel.poisson, a, mass, concrete.youngs_pa, concrete.poisson,
                                          INFINITY, INFINITY, hit->normal_speed_m_s);
  ASSERT_GT(tau, 1e-5);
  const std::array<double, 3> to = {listener[0] - hit->point_world[0], listener[1] - hit->point_world[1],
                                    listener[2] - (hit->point_world[2] + a)};
  const double r_m = std::sqrt(to[0] * to[0] + to[1] * to[1] + to[2] * to[2]);
  const double cos_theta = to[2] / r_m;  // the force is vertical

  // The rendered click: from 1 ms before its arrival to 3 ms after.
  const double arrival_s = hit->time_s + r_m / kSpeedOfSoundAir_m_s;
  const size_t first = static_cast<size_t>((arrival_s - 1e-3) * rate), count = static_cast<size_t>(4e-3 * rate);
  ASSERT_LT(first + count, r->audio.samples.size());
  std::vector<double> click(count);
  double peak = 0.0;
  for (size_t n = 0; n < count; ++n) {
    click[n] = r->audio.samples[first + n] * kFullScalePascal;  // Pa
    peak = std::max(peak, std::fabs(click[n]));
  }
  ASSERT_GT(peak, 1e-3) << "a 5 mm steel ball hitting concrete at 3 m/s clicks at well above 1 mPa at 1 m";
  const double top_hz = 20000.0;
  const Spectrum rendered = spectrumOf(click, rate, 4096, top_hz);

  // The closed form on the same frequencies.
  const double c = kSpeedOfSoundAir_m_s, rho = kAirDensity_kg_m3, om = M_PI / tau;
  double energy_rendered = 0.0, energy_exact = 0.0, peak_rendered = 0.0, peak_exact = 0.0;
  double f_rendered = 0.0, f_exact = 0.0;
  for (size_t k = 1; k < rendered.freq_hz.size(); ++k) {
    const double f = rendered.freq_hz[k], w = 2.0 * M_PI * f, x = w * a / c;
    const Cx half_sine = (M_PI / (2.0 * tau)) * om * (1.0 + std::polar(1.0, w * tau)) / (om * om - w * w);
    const Cx exact = rho / (4.0 * M_PI * c * r_m) * 2.0 * M_PI * a * a * a * cos_theta * Cx(0.0, -w) *
                     (impulse / mass) * half_sine * 2.0 / Cx(2.0 - x * x, -2.0 * x);
    const double e = std::abs(exact), m = rendered.magnitude[k];
    energy_exact += e * e, energy_rendered += m * m;
    if (e > peak_exact) peak_exact = e, f_exact = f;
    if (m > peak_rendered) peak_rendered = m, f_rendered = f;
  }
  const double level_db = 10.0 * std::log10(energy_rendered / energy_exact);
  std::printf("click: J %.4g N s at %.3g m/s, tau %.3g us, r %.3f m, cos %.3f; peak %.3g Pa (%.1f dB SPL)\n", impulse,
              hit->normal_speed_m_s, tau * 1e6, r_m, cos_theta, peak, 20.0 * std::log10(peak / 20e-6));
  std::printf("       energy 0-20 kHz rendered / exact %+.2f dB; spectral peak %.0f Hz rendered, %.0f Hz exact\n",
              level_db, f_rendered, f_exact);
  EXPECT_LT(std::fabs(level_db), 1.0);
  EXPECT_LT(std::fabs(f_rendered / f_exact - 1.0), 0.10);
}

}  // namespace
}  // namespace strike
