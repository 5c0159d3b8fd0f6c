// SPDX-License-Identifier: MIT
// Scenes that cannot be right are named with their numbers (issue 15, item 10).
#include "strike/scene_checks.hpp"

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
