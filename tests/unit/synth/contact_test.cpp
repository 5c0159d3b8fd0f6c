// SPDX-License-Identifier: MIT
// Hertz contact duration and modal projection of an impulse.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include "strike/synth/synth.hpp"

namespace strike {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(HertzContact, SteelSphereOnSteelHalfSpace) {
  // Hand computation: R = 1 cm, E = 200 GPa, nu = 0.3, rho = 7850 kg/m^3, v = 1 m/s.
  //   m = 7850 * 4/3 pi 1e-6 = 0.032882 kg, 1/E* = 2 (1 - 0.09) / 2e11 -> E* = 1.09890e11 Pa,
  //   m*^2 / (R* E*^2 v) = 1.08123e-3 / (0.01 * 1.20758e22) = 8.9537e-24,
  //   ^(1/5) = 10^(-23.0480 / 5) = 2.45696e-5;  tau = 2.868 * 2.45696e-5 = 7.0466e-5 s.
  const double m = 7850.0 * 4.0 / 3.0 * M_PI * 1e-6;
  const double tau = hertzContactDuration(2e11, 0.3, 0.01, m, 2e11, 0.3, kInf, kInf, 1.0);
  EXPECT_NEAR(tau, 7.0466e-5, 1e-8);
  // Swapping the bodies changes nothing; tau ~ v^(-1/5).
  EXPECT_DOUBLE_EQ(hertzContactDuration(2e11, 0.3, kInf, kInf, 2e11, 0.3, 0.01, m, 1.0), tau);
  EXPECT_NEAR(hertzContactDuration(2e11, 0.3, 0.01, m, 2e11, 0.3, kInf, kInf, 32.0), tau / 2.0, 1e-12);
  // Degenerate: no approach speed, or two half-spaces.
  EXPECT_EQ(hertzContactDuration(2e11, 0.3, 0.01, m, 2e11, 0.3, kInf, kInf, 0.0), 0.0);
  EXPECT_EQ(hertzContactDuration(2e11, 0.3, kInf, m, 2e11, 0.3, kInf, kInf, 1.0), 0.0);
}

// A unit right triangle in z = 0 plus a second one, with mode shapes linear in position.
ModeBank linearShapeBank() {
  ModeBank mb;
  mb.eigenvalues = {1e6, 4e6, 9e6};
  mb.surface_positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  mb.surface_triangles = {0, 1, 2, 1, 3, 2};
  mb.surface_normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  for (int m = 0; m < 3; ++m)
    for (int v = 0; v < 4; ++v) {
      const double x = mb.surface_positions[3 * v], y = mb.surface_positions[3 * v + 1];
      // phi_m(x, y) = (m + 1) * (0.25 + 0.5 x - 0.75 y) in every component, scaled per axis.
      const double s = (m + 1) * (0.25 + 0.5 * x - 0.75 * y);
      mb.shapes.push_back(static_cast<float>(s));
      mb.shapes.push_back(static_cast<float>(2 * s));
      mb.shapes.push_back(static_cast<float>(-s));
    }
  return mb;
}

TEST(ModalProjection, ExactAtVerticesAndLinearInsideTriangles) {
  const ModeBank mb = linearShapeBank();
  const double j[3] = {0.1, -0.2, 0.3};
  for (size_t v = 0; v < 4; ++v) {
    const std::vector<double> at_vertex = projectImpulseAtVertex(mb, v, j);
    const std::vector<double> at_point = projectImpulse(mb, &mb.surface_positions[3 * v], j);
    for (size_t m = 0; m < 3; ++m) {
      const float* phi = mb.shapeAt(m, v);
      EXPECT_DOUBLE_EQ(at_vertex[m], phi[0] * j[0] + phi[1] * j[1] + phi[2] * j[2]);
      EXPECT_NEAR(at_point[m], at_vertex[m], 1e-12);
    }
  }
  // Inside a triangle, and above the surface (projected onto it): linear shapes are reproduced.
  for (const auto& p : {std::array<double, 3>{0.2, 0.3, 0.0}, std::array<double, 3>{0.7, 0.8, 0.05},
                        std::array<double, 3>{0.5, 0.5, -0.3}}) {
    const std::vector<double> g = projectImpulse(mb, p.data(), j);
    for (size_t m = 0; m < 3; ++m) {
      const double s = (m + 1) * (0.25 + 0.5 * p[0] - 0.75 * p[1]);
      EXPECT_NEAR(g[m], s * j[0] + 2 * s * j[1] - s * j[2], 1e-7);
    }
  }
  // Outside the mesh: clamped to the nearest edge point (1, 0.5).
  const double out[3] = {2.0, 0.5, 0.0};
  const std::vector<double> g = projectImpulse(mb, out, j);
  const double s = 0.25 + 0.5 * 1.0 - 0.75 * 0.5;
  EXPECT_NEAR(g[0], s * j[0] + 2 * s * j[1] - s * j[2], 1e-7);
  // Bad vertex index: zeros, no crash.
  EXPECT_EQ(projectImpulseAtVertex(mb, 99, j), std::vector<double>(3, 0.0));
}

// The projector remembers points: repeated points (a resting body's corners), new points, and
// more points than it remembers (round-robin eviction) must all give the locator's values, to the
// bit, and the linear shapes' closed form.
TEST(ModalProjection, ContactProjectorMatchesTheLocatorWhileRemembering) {
  const ModeBank mb = linearShapeBank();
  const SurfaceLocator locator(mb);
  ContactProjector projector(mb, 2);
  const double j[3] = {0.1, -0.2, 0.3};
  const std::array<double, 3> points[] = {{0.2, 0.3, 0.0},  {0.7, 0.8, 0.05}, {0.2, 0.3, 0.0}, {0.5, 0.1, -0.3},
                                          {0.7, 0.8, 0.05}, {0.2, 0.3, 0.0},  {0.2, 0.3, 0.0}, {2.0, 0.5, 0.0}};
  for (int pass = 0; pass < 2; ++pass)
    for (const auto& p : points) {
      double from_projector[3], from_locator[3];
      projector.projectImpulseInto(p.data(), j, from_projector);
      locator.projectImpulseInto(p.data(), j, from_locator);
      const double x = std::min(p[0], 1.0);  // (2, 0.5) clamps to the edge point (1, 0.5)
      for (size_t m = 0; m < 3; ++m) {
        EXPECT_EQ(from_projector[m], from_locator[m]) << "point " << p[0] << "," << p[1] << " mode " << m;
        const double s = (m + 1) * (0.25 + 0.5 * x - 0.75 * p[1]);
        EXPECT_NEAR(from_projector[m], s * j[0] + 2 * s * j[1] - s * j[2], 1e-7);
      }
    }
}

// A render projects a cached bank's contacts through shape rows read from the file at the
// vertices the locator finds (BankFile::readShapeRows): the same values, to the bit, as the whole
// bank; a vertex whose row was not read projects to zero rather than to garbage.
TEST(ModalProjection, ContactProjectorWithShapeRowsMatchesTheWholeBank) {
  const ModeBank mb = linearShapeBank();
  const std::vector<uint8_t> bytes = encodeBank(mb);
  Result<BankFile> file = BankFile::openBytes(bytes.data(), bytes.size(), "linear.modes");
  ASSERT_TRUE(file) << file.error().message;
  const ModeBank without_shapes = file->bank();
  ContactProjector whole(mb, 2), from_rows(without_shapes, 2);
  const std::array<double, 3> points[] = {{0.2, 0.3, 0.0}, {0.7, 0.8, 0.05}, {0.5, 0.1, -0.3}, {2.0, 0.5, 0.0}};
  std::vector<uint32_t> vertices;
  for (const auto& p : points) {
    uint32_t v[3];
    double w[3];
    from_rows.locator().nearest(p.data(), v, w);
    vertices.insert(vertices.end(), v, v + 3);
  }
  Result<ShapeRows> rows = file->readShapeRows(vertices);
  ASSERT_TRUE(rows) << rows.error().message;
  from_rows.useRows(*rows);
  const double j[3] = {0.1, -0.2, 0.3};
  for (const auto& p : points) {
    double a[3], b[3], once_whole[3], once_rows[3];
    whole.projectImpulseInto(p.data(), j, a);
    from_rows.projectImpulseInto(p.data(), j, b);
    // projectOnce (impacts: nothing remembered) gives the same bits from the bank or the rows.
    whole.projectOnce(p.data(), j, once_whole);
    from_rows.projectOnce(p.data(), j, once_rows);
    for (int m = 0; m < 3; ++m) {
      EXPECT_EQ(a[m], b[m]) << p[0] << "," << p[1] << " mode " << m;
      EXPECT_EQ(a[m], once_whole[m]) << p[0] << "," << p[1] << " mode " << m;
      EXPECT_EQ(a[m], once_rows[m]) << p[0] << "," << p[1] << " mode " << m;
    }
  }
  // Only vertex 3's row: a point on triangle (0, 1, 2) sees zeros.
  ContactProjector partial(without_shapes, 2);
  Result<ShapeRows> one = file->readShapeRows({3});
  ASSERT_TRUE(one);
  partial.useRows(*one);
  double g[3];
  const double inside[3] = {0.2, 0.2, 0.0};
  partial.projectImpulseInto(inside, j, g);
  for (double value : g) EXPECT_EQ(value, 0.0);
  partial.projectOnce(inside, j, g);
  for (double value : g) EXPECT_EQ(value, 0.0);
}

}  // namespace
}  // namespace strike
