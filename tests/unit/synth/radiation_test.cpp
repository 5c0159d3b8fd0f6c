// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>

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
  // Triangle (0,1,2): mean shape 1, area 1; triangle (1,3,2): mean (1 - 3 + 1)/3, area 1.
  EXPECT_NEAR(w[2], gain * (1.0 + 1.0 / 3.0), 1e-12);
  // Inverse distance.
  EXPECT_NEAR(radiationWeights(mb, 2 * d)[0], w[0] / 2, 1e-15);
}

}  // namespace
}  // namespace strike
