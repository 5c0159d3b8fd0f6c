// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "strike/synth.hpp"

namespace strike {
namespace {

TEST(Radiation, PistonModeRadiatesItsAreaTangentialModeIsSilent) {
  // A 2 m x 1 m plate face (two triangles, normal +z). Mode 0 moves it along the normal with unit
  // shape, mode 1 slides it sideways, mode 2 moves half of it in and half out (|.| adds them).
  ModeBank mb;
  mb.eigenvalues = {1e6, 2e6, 3e6};
  mb.surface_positions = {0, 0, 0, 2, 0, 0, 0, 1, 0, 2, 1, 0};
  mb.surface_triangles = {0, 1, 2, 1, 3, 2};
  const float shapes[3][4][3] = {{{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}},
                                 {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}, {1, 0, 0}},
                                 {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, -3}}};
  for (auto& mode : shapes)
    for (auto& v : mode)
      for (float c : v) mb.shapes.push_back(c);
  const double d = 3.0;
  const std::vector<double> w = radiationWeights(mb, d);
  const double gain = 1.204 / (4 * M_PI * d);
  ASSERT_EQ(w.size(), 3u);
  EXPECT_NEAR(w[0], gain * 2.0, 1e-12);
  EXPECT_EQ(w[1], 0.0);
  // Triangle (0,1,2): mean shape 1, area 1; triangle (1,3,2): mean (1 - 3 + 1)/3, area 1: the
  // in-phase bound is 4/3; the compact estimate (monopole 2/3, dipole (2/9, 1/9, 0) about the
  // origin, k = sqrt(3e6) / 343) is below it.
  const double k = std::sqrt(3e6) / 343.0;
  const double compact = std::sqrt(4.0 / 9.0 + k * k * (4.0 / 81 + 1.0 / 81) / 3.0);
  ASSERT_LT(compact, 4.0 / 3.0);
  EXPECT_NEAR(w[2], gain * compact, 1e-12);
  // Inverse distance.
  EXPECT_NEAR(radiationWeights(mb, 2 * d)[0], w[0] / 2, 1e-15);
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
  // Translation: no net volume change, dipole moment V u, rms over directions k V / sqrt(3).
  EXPECT_NEAR(w[0] / gain, k * V / std::sqrt(3.0), 1e-9 * k * V);
  // Breathing: net volume acceleration = surface area * s/2 = 3 V (divergence of x), no dipole.
  EXPECT_NEAR(w[1] / gain, 3 * V, 1e-6 * V);
  // Far below the in-phase bound for the translating cube (2 faces of s^2 moving): compact.
  EXPECT_LT(w[0] / gain, 2 * s * s);
}

}  // namespace
}  // namespace strike
