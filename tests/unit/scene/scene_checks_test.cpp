// SPDX-License-Identifier: MIT
// Scenes that cannot be right are named with their numbers.
#include "strike/scene/scene_checks.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace strike {
namespace {

/// A closed box surface of side `side` centred at the origin, triangles CCW from outside.
SimBodyDesc box(const std::string& name, double side, std::array<double, 3> position, double mass_kg = 1.0) {
  SimBodyDesc b;
  b.name = name;
  b.mass_kg = mass_kg;
  b.position_m = position;
  const double h = side / 2;
  for (int i = 0; i < 8; ++i)
    b.surface_positions.insert(b.surface_positions.end(), {i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h});
  // Faces as quads (outward normal by the right-hand rule), two triangles each.
  const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    b.surface_triangles.insert(b.surface_triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  return b;
}

Scene sceneOf(const std::vector<SimBodyDesc>& bodies) {
  Scene scene;
  for (const SimBodyDesc& b : bodies) {
    SceneObject o;
    o.name = b.name;
    o.mesh = "box:1,1,1";
    scene.objects.push_back(o);
  }
  return scene;
}

TEST(SceneChecks, DepthInsideAClosedBoxIsTheDistanceToItsNearestFace) {
  const SimBodyDesc b = box("b", 1.0, {0, 0, 0});
  const double inside[3] = {0.1, -0.2, 0.05}, outside[3] = {0.7, 0, 0}, near_face[3] = {0.49, 0, 0};
  EXPECT_NEAR(depthInside(inside, b.surface_positions, b.surface_triangles), 0.3, 1e-12);  // to the y = -0.5 face
  EXPECT_NEAR(depthInside(near_face, b.surface_positions, b.surface_triangles), 0.01, 1e-12);
  EXPECT_EQ(depthInside(outside, b.surface_positions, b.surface_triangles), 0.0);
}

/// A closed latitude-longitude sphere (poles as single vertices), CCW from outside, moved by
/// `centre`: many triangles meeting at the poles, and slanted faces everywhere.
void uvSphere(double r, const std::array<double, 3>& centre, std::vector<double>& xyz, std::vector<uint32_t>& tris) {
  const int rings = 9, segments = 14;
  xyz = {centre[0], centre[1], centre[2] + r};
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double theta = M_PI * i / rings, phi = 2 * M_PI * j / segments;
      xyz.insert(xyz.end(), {centre[0] + r * std::sin(theta) * std::cos(phi),
                             centre[1] + r * std::sin(theta) * std::sin(phi), centre[2] + r * std::cos(theta)});
    }
  xyz.insert(xyz.end(), {centre[0], centre[1], centre[2] - r});
  const uint32_t south = uint32_t(xyz.size() / 3 - 1);
  auto at = [&](int i, int j) { return uint32_t(1 + (i - 1) * segments + (j % segments)); };
  for (int j = 0; j < segments; ++j) {
    tris.insert(tris.end(), {0, at(1, j), at(1, j + 1)});
    for (int i = 1; i + 1 < rings; ++i)
      tris.insert(tris.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    tris.insert(tris.end(), {at(rings - 1, j), south, at(rings - 1, j + 1)});
  }
}

TEST(SceneChecks, InsideTestDecidesAsDepthInsideDoes) {
  // Random points in and around a rotated box and a sphere: every point the ray test decides, it
  // decides as depthInside's winding number does (depth > 0 inside), and it decides nearly all.
  std::vector<std::pair<std::vector<double>, std::vector<uint32_t>>> surfaces;
  {
    SimBodyDesc b = box("b", 0.1, {0, 0, 0});
    const double c = std::cos(0.7), s = std::sin(0.7), c2 = std::cos(0.4), s2 = std::sin(0.4);
    for (size_t v = 0; v < b.surface_positions.size(); v += 3) {
      double* p = &b.surface_positions[v];
      const double x = c * p[0] - s * p[1], y = s * p[0] + c * p[1];
      const double y2 = c2 * y - s2 * p[2], z2 = s2 * y + c2 * p[2];
      p[0] = x + 0.3, p[1] = y2 - 0.1, p[2] = z2 + 0.2;
    }
    surfaces.emplace_back(b.surface_positions, b.surface_triangles);
  }
  {
    std::vector<double> xyz;
    std::vector<uint32_t> tris;
    uvSphere(0.03, {-0.1, 0.05, 0.12}, xyz, tris);
    surfaces.emplace_back(xyz, tris);
  }
  uint64_t seed = 12345;
  auto uniform = [&] {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return double(seed >> 11) / double(1ull << 53);
  };
  for (const auto& [xyz, tris] : surfaces) {
    const InsideTest test(xyz, tris);
    ASSERT_TRUE(test.closed());
    double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < xyz.size(); v += 3)
      for (int k = 0; k < 3; ++k) low[k] = std::min(low[k], xyz[v + k]), high[k] = std::max(high[k], xyz[v + k]);
    int decided = 0, inside = 0;
    const int points = 4000;
    for (int n = 0; n < points; ++n) {
      double p[3];
      for (int k = 0; k < 3; ++k) p[k] = low[k] - 0.1 * (high[k] - low[k]) + 1.2 * (high[k] - low[k]) * uniform();
      if (n % 10 == 0) p[0] = xyz[3 * size_t(n / 10 % (xyz.size() / 3))], p[1] = xyz[3 * size_t(n / 10 % (xyz.size() / 3)) + 1];
      const int verdict = test.classify(p);
      if (verdict < 0) continue;
      ++decided;
      inside += verdict;
      EXPECT_EQ(verdict == 1, depthInside(p, xyz, tris) > 0.0) << "point " << p[0] << ", " << p[1] << ", " << p[2];
    }
    EXPECT_GT(decided, points * 8 / 10);  // the points above a vertex are left to depthInside
    EXPECT_GT(inside, points / 10);
  }
  // An open surface (a box without its top) has no integer winding number: always undecided.
  SimBodyDesc open = box("open", 0.1, {0, 0, 0});
  open.surface_triangles.resize(open.surface_triangles.size() - 6);
  const InsideTest test(open.surface_positions, open.surface_triangles);
  EXPECT_FALSE(test.closed());
  const double centre[3] = {0.01, 0.02, 0.0};
  EXPECT_EQ(test.classify(centre), -1);
}

TEST(SceneChecks, OverlapsAndTheGroundAreNamedWithTheirDepth) {
  // a and b overlap by 3 cm along x (b's corner x = -0.02 lies 0.03 m inside a, whose face is at 0.05).
  const std::vector<SimBodyDesc> bodies = {box("a", 0.1, {0, 0, 0.2}), box("b", 0.1, {0.07, 0.0, 0.2}),
                                           box("sunk", 0.1, {1, 0, 0.04}), box("apart", 0.1, {-1, 0, 0.0501})};
  const std::vector<std::string> w = checkStartingPlacement(sceneOf(bodies), bodies);
  ASSERT_EQ(w.size(), 2u) << (w.empty() ? "" : w[0]);
  EXPECT_NE(w[0].find("\"sunk\": starts 10 mm inside the ground"), std::string::npos) << w[0];
  EXPECT_NE(w[1].find("\"a\" and \"b\" start inside each other (a surface point 30 mm deep)"), std::string::npos)
      << w[1];
}

TEST(SceneChecks, TouchingIsNotOverlapping) {
  // Resting exactly on the ground and face to face: nothing to say.
  const std::vector<SimBodyDesc> bodies = {box("a", 0.1, {0, 0, 0.05}), box("b", 0.1, {0.1, 0, 0.05})};
  EXPECT_TRUE(checkStartingPlacement(sceneOf(bodies), bodies).empty());
}

TEST(SceneChecks, ARotatedBoxIsTestedInItsOwnFrame) {
  // a, turned 45 degrees about z, reaches x = 0.05 sqrt 2 = 70.7 mm: its corners there are 20.7 mm
  // inside b (b's face at x = 50 mm; b is twice a's size, so no other face is nearer). Then a cube resting on a's tilted face (30 degrees about y, 0.5 mm
  // above it) is inside a's world box but not in a: nothing to say.
  const double c45 = std::cos(M_PI / 8), s45 = std::sin(M_PI / 8);
  SimBodyDesc a = box("a", 0.1, {0, 0, 0.5});
  a.orientation_wxyz = {c45, 0, 0, s45};
  const std::vector<SimBodyDesc> overlapping = {a, box("b", 0.2, {0.15, 0.0, 0.5})};
  const std::vector<std::string> w = checkStartingPlacement(sceneOf(overlapping), overlapping);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("start inside each other (a surface point 20.7 mm deep)"), std::string::npos) << w[0];
  // A 0.4 x 0.1 x 0.02 m plank tilted 30 degrees about y, and a 2 cm cube 0.15 m along it (its
  // world box holds the cube): resting 0.5 mm above its face, nothing to say; sunk 5 mm into it,
  // the cube's lower points are found in the plank's own frame.
  const double t = M_PI / 6;
  SimBodyDesc plank = box("plank", 0.1, {0, 0, 0.5}), cube = box("cube", 0.02, {0, 0, 0});
  for (size_t v = 0; v < plank.surface_positions.size(); v += 3)
    plank.surface_positions[v] *= 4.0, plank.surface_positions[v + 2] *= 0.2;
  plank.orientation_wxyz = cube.orientation_wxyz = {std::cos(t / 2), 0, std::sin(t / 2), 0};
  auto place = [&](double above_face_m) {  // along (cos t, 0, -sin t), off the face along (sin t, 0, cos t)
    const double along = 0.15, off = 0.01 + 0.01 + above_face_m;
    cube.position_m = {along * std::cos(t) + off * std::sin(t), 0.0, 0.5 - along * std::sin(t) + off * std::cos(t)};
    const std::vector<SimBodyDesc> bodies = {plank, cube};
    return checkStartingPlacement(sceneOf(bodies), bodies);
  };
  EXPECT_TRUE(place(0.0005).empty());
  const std::vector<std::string> sunk = place(-0.005);
  ASSERT_EQ(sunk.size(), 1u);
  EXPECT_NE(sunk[0].find("(a surface point 5 mm deep)"), std::string::npos) << sunk[0];
}

TEST(SceneChecks, AMeshInMillimetresIsImplausiblyLargeAndHeavy) {
  // An 80 mm cube read as 80 m: 512,000 m^3 of porcelain.
  const std::vector<SimBodyDesc> bodies = {box("mug", 80.0, {0, 0, 40.0}, 2400.0 * 512000.0)};
  Scene scene = sceneOf(bodies);
  scene.objects[0].mesh = "mug.obj";
  const std::vector<std::string> w = checkStartingPlacement(scene, bodies);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("80 x 80 x 80 m, 1.23e+09 kg (1.23e+06 tonnes): implausibly large"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("\"units\": \"mm\""), std::string::npos) << w[0];
}

TEST(SceneChecks, NeverStruckSaysHowLongTheFallTakes) {
  const SimBodyDesc high = box("high", 0.02, {0, 0, 800.01});
  Scene scene = sceneOf({high});
  const std::string w = neverStruckWarning(scene, high, 3.0);
  // Lowest point 800 m up: t = sqrt(2 h / g) = sqrt(1600 / 9.81) = 12.77 s.
  EXPECT_NE(w.find("its lowest point 800 m above the ground; falling from there takes 12.8 s, the render lasts 3 s"),
            std::string::npos)
      << w;
}

TEST(SceneChecks, NeverStruckOnAPathSaysWhereThePathEnds) {
  SimBodyDesc held = box("held", 0.02, {0, 0, 0.5});
  held.path = {{0.0, {0, 0, 0.5}, {1, 0, 0, 0}}, {1.5, {0.2, 0, 0.5}, {1, 0, 0, 0}}};
  Scene scene = sceneOf({held});
  const std::string w = neverStruckWarning(scene, held, 3.0);
  EXPECT_NE(w.find("its path ends at (0.2, 0, 0.5) m at 1.5 s without touching anything"), std::string::npos) << w;
  EXPECT_EQ(w.find("falling"), std::string::npos) << w;
}

}  // namespace
}  // namespace strike
