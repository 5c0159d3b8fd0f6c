// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "strike/synth/synth.hpp"

namespace strike {
namespace {

TEST(Radiation, TangentialModeIsSilentAndLevelFallsAsOneOverDistance) {
  // A 2 cm x 1 cm plate face (two triangles, normal +z): mode 0 moves it along the normal (a
  // compact piston: R = its area), mode 1 slides it sideways (no normal motion: silent).
  ModeBank mb;
  mb.eigenvalues = {1e6, 2e6};
  mb.surface_positions = {0, 0, 0, 0.02, 0, 0, 0, 0.01, 0, 0.02, 0.01, 0};
  mb.surface_triangles = {0, 1, 2, 1, 3, 2};
  for (int v = 0; v < 4; ++v) mb.shapes.insert(mb.shapes.end(), {0.0f, 0.0f, 1.0f});
  for (int v = 0; v < 4; ++v) mb.shapes.insert(mb.shapes.end(), {1.0f, 0.0f, 0.0f});
  const double d = 3.0, gain = 1.204 / (4 * M_PI * d);
  const std::vector<double> w = radiationWeights(mb, d);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NEAR(w[0] / gain, 2e-4, 1e-6);  // k L = 0.06: compact, all in phase
  EXPECT_EQ(w[1], 0.0);
  EXPECT_NEAR(radiationWeights(mb, 2 * d)[0], w[0] / 2, 1e-15);
}

TEST(Radiation, DistantPatchesAddIncoherently) {
  // Two 1 cm^2 patches 10 m apart at 10 kHz (k d ~ 1800): R^2 = s1^2 + s2^2 (+ 2 s1 s2 sinc(kd)).
  ModeBank mb;
  const double f = 10000.0, k = 2 * M_PI * f / 343.0, sep = 10.0;
  mb.eigenvalues = {std::pow(2 * M_PI * f, 2)};
  mb.surface_positions = {0, 0, 0, 0.01, 0, 0, 0, 0.01, 0, sep, 0, 0, sep + 0.01, 0, 0, sep, 0.01, 0};
  mb.surface_triangles = {0, 1, 2, 3, 4, 5};
  for (int v = 0; v < 3; ++v) mb.shapes.insert(mb.shapes.end(), {0.0f, 0.0f, 1.0f});
  for (int v = 0; v < 3; ++v) mb.shapes.insert(mb.shapes.end(), {0.0f, 0.0f, -2.0f});
  const double gain = 1.204 / (4 * M_PI);
  const double s1 = 0.5e-4, s2 = -1e-4;
  const double expected = std::sqrt(s1 * s1 + s2 * s2 + 2 * s1 * s2 * std::sin(k * sep) / (k * sep));
  // The direction average is sampled on 162 directions: within 5% (0.4 dB) when k L >> 1.
  EXPECT_NEAR(radiationWeights(mb, 1.0)[0] / gain, expected, 5e-2 * expected);
}

// A closed cube of side s centred at the origin, 8 vertices and 12 outward triangles.
ModeBank cube(double s) {
  ModeBank mb;
  const double h = s / 2;
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 3; ++k) mb.surface_positions.push_back(((i >> k) & 1) ? h : -h);
  mb.surface_triangles = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                          2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  return mb;
}

TEST(Radiation, CompactCubeTranslatingIsADipoleBreathingIsAMonopole) {
  const double s = 0.02, V = s * s * s, d = 1.0, gain = 1.204 / (4 * M_PI * d);
  ModeBank mb = cube(s);
  const double f = 500.0, k = 2 * M_PI * f / 343.0;
  mb.eigenvalues = {std::pow(2 * M_PI * f, 2), std::pow(2 * M_PI * f, 2)};
  // Mode 0: rigid translation along x, unit shape. Mode 1: breathing, phi = x (radial, so n.phi = s/2
  // on every face).
  for (int v = 0; v < 8; ++v) mb.shapes.insert(mb.shapes.end(), {1.0f, 0.0f, 0.0f});
  for (int v = 0; v < 8; ++v)
    for (int c = 0; c < 3; ++c) mb.shapes.push_back(static_cast<float>(mb.surface_positions[v * 3 + c]));
  const std::vector<double> w = radiationWeights(mb, d);
  // Translation: no net volume change, dipole moment V u, rms over directions k V / sqrt(3)
  // (k s = 0.18: the next term of the expansion is (k s)^2 / 10 smaller).
  EXPECT_NEAR(w[0] / gain, k * V / std::sqrt(3.0), 5e-3 * k * V);
  // Breathing: net volume acceleration = surface area * s/2 = 3 V (divergence of x), no dipole.
  EXPECT_NEAR(w[1] / gain, 3 * V, 1e-2 * V);
  // Far below the in-phase bound for the translating cube (2 faces of s^2 moving): compact.
  EXPECT_LT(w[0] / gain, 2 * s * s);
}

}  // namespace
}  // namespace strike
