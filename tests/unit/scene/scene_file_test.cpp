// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <string>

#include "strike/scene/scene.hpp"

namespace strike {
namespace {

const char kGoodScene[] = R"({
  "sample_rate": 48000,
  "duration": 3.0,
  "gravity": [0, 0, -9.81],
  "listener": {"position": [0.0, -1.0, 0.5]},
  "ground": {"material": "concrete"},
  "objects": [
    {"name": "bar", "mesh": "box:0.3,0.02,0.02", "material": "steel",
     "position": [0, 0, 0.5], "orientation": [1, 0, 0, 0],
     "velocity": [0, 0, 0], "angular_velocity": [0, 0, 0]},
    {"mesh": "sphere:0.01", "material": {"youngs_pa": 7e10, "poisson": 0.22, "density_kg_m3": 2500, "loss_factor": 1e-3},
     "position": [0, 0, 1], "order": 2}
  ]
})";

TEST(SceneFile, ParsesTheArchitectureExample) {
  Result<Scene> scene = parseScene(kGoodScene, "/tmp/s/scene.json");
  ASSERT_TRUE(scene) << scene.error().message;
  EXPECT_EQ(scene->sample_rate_hz, 48000);
  EXPECT_EQ(scene->duration_s, 3.0);
  ASSERT_EQ(scene->objects.size(), 2u);
  EXPECT_EQ(scene->objects[0].name, "bar");
  EXPECT_EQ(scene->objects[0].material.name, "steel");
  EXPECT_EQ(scene->objects[0].position_m[2], 0.5);
  EXPECT_EQ(scene->objects[1].name, "object1");
  EXPECT_EQ(scene->objects[1].order, 2);
  EXPECT_GT(scene->objects[1].material.rayleigh_mass, 0.0);
  EXPECT_TRUE(scene->has_ground);
  EXPECT_EQ(scene->ground_material.name, "concrete");
  EXPECT_EQ(scene->listener_position_m[1], -1.0);
}

struct BadCase {
  std::string json, expected;
};

void expectError(const BadCase& c) {
  Result<Scene> scene = parseScene(c.json, "bad.json");
  ASSERT_FALSE(scene) << c.json;
  EXPECT_EQ(scene.error().kind, ErrorKind::BadInput);
  EXPECT_NE(scene.error().message.find(c.expected), std::string::npos)
      << "expected '" << c.expected << "' in: " << scene.error().message;
  EXPECT_EQ(scene.error().message.rfind("bad.json", 0), 0u) << scene.error().message;
}

TEST(SceneFile, ErrorsNameTheKeyPathAndValue) {
  const std::string obj = R"("mesh": "box:0.1,0.1,0.1", "material": "steel")";
  const BadCase cases[] = {
      {R"({"objects": [{)" + obj + R"(, "velocty": [0,0,1]}]})", "objects[0].velocty: unknown key"},
      {R"({"objects": [{)" + obj + R"(, "velocity": [0,"fast",1]}]})",
       "objects[0].velocity[1]: expected a number, got \"fast\""},
      {R"({"objects": [{)" + obj + R"(, "velocity": [0,1]}]})", "objects[0].velocity: expected an array of 3 numbers"},
      {R"({"objects": [{)" + obj + R"(, "velocity": [0,1e999,0]}]})", "number overflow parsing '1e999'"},
      {R"({"objects": [{)" + obj + R"(, "orientation": [2,0,0,0]}]})",
       "objects[0].orientation: expected a unit quaternion"},
      {R"({"objects": [{"mesh": "box:0.1,0.1,0.1", "material": "adamantium"}]})",
       "objects[0].material: unknown material 'adamantium'"},
      {R"({"objects": [{"mesh": "box:0.1,0.1,0.1", "material": {"youngs_pa": 1e9, "poisson": 0.6, "density_kg_m3": 1000}}]})",
       "objects[0].material: poisson = 0.6"},
      {R"({"objects": [{"mesh": "missing.obj", "material": "steel"}]})", "objects[0].mesh: file not found"},
      {R"({"objects": [{"material": "steel"}]})", "objects[0]: needs \"mesh\""},
      {R"({"objects": [{"mesh": "box:1,1,1"}]})", "objects[0]: needs \"material\""},
      {R"({"objects": [{)" + obj + R"(, "order": 3}]})", "objects[0].order: expected 1 or 2, got 3"},
      {R"({"objects": [{)" + obj + R"(, "name": "a"}, {)" + obj + R"(, "name": "a"}]})",
       "objects[1].name: duplicate name"},
      {R"({"objects": []})", "objects: the list is empty"},
      {R"({"sample_rate": 100, "objects": [{)" + obj + R"(}]})", "sample_rate: must be 8000 to 384000 Hz, got 100"},
      {R"({"duration": -1, "objects": [{)" + obj + R"(}]})", "duration: must be in (0, 3600] s, got -1"},
      {R"({"listener": {"pos": [0,0,0]}, "objects": [{)" + obj + R"(}]})", "listener.pos: unknown key"},
      {R"({"objets": []})", "objets: unknown key"},
      {R"({"objects": "all"})", "objects: expected a list, got \"all\""},
      {"{\"objects\": [\n {\"mesh\": \"box:1,1,1\", \"velocity\": [NaN, 0, 0]}]}", "bad.json:2:"},
      {"[1, 2", "invalid JSON"},
      {std::string(100, '[') + std::string(100, ']'), "nested deeper than 64"},
  };
  for (const BadCase& c : cases) expectError(c);
}

TEST(SceneFile, PathKeyframesAreReadAndCheckedNamingTheKey) {
  const std::string obj = R"("mesh": "box:0.1,0.02,0.002", "material": "steel")";
  Result<Scene> ok = parseScene(R"({"objects": [{)" + obj + R"(, "path": [
      {"t": 0, "position": [0, 0, 0.1], "orientation": [0.965925826, 0, 0.258819045, 0]},
      {"t": 0.5, "position": [0.1, 0, 0.1]},
      {"t": 1, "position": [0.1, 0, 0.2], "orientation": [1, 0, 0, 0]}]}]})",
                                "s.json");
  ASSERT_TRUE(ok) << ok.error().message;
  const std::vector<PathKey>& path = ok->objects[0].path;
  ASSERT_EQ(path.size(), 3u);
  EXPECT_EQ(path[1].t_s, 0.5);
  EXPECT_EQ(path[1].position_m[0], 0.1);
  // A key without an orientation keeps the one before.
  EXPECT_NEAR(path[1].orientation_wxyz[2], 0.258819045, 1e-9);
  EXPECT_EQ(path[2].orientation_wxyz[0], 1.0);

  const std::string key0 = R"({"t": 0, "position": [0, 0, 0.1]})";
  const BadCase cases[] = {
      {R"({"objects": [{)" + obj + R"(, "path": []}]})", "objects[0].path: expected a list of keyframes"},
      {R"({"objects": [{)" + obj + R"(, "path": {"t": 0}}]})", "objects[0].path: expected a list of keyframes"},
      {R"({"objects": [{)" + obj + R"(, "path": [)" + key0 + R"(, {"t": 0, "position": [0, 0, 0]}]}]})",
       "objects[0].path[1].t: must be later than the key before (0), got 0"},
      {R"({"objects": [{)" + obj + R"(, "path": [)" + key0 + R"(, {"t": 1, "position": [0, 0, 0]}, )" +
           R"({"t": 0.5, "position": [0, 0, 0]}]}]})",
       "objects[0].path[2].t: must be later than the key before (1), got 0.5"},
      {R"({"objects": [{)" + obj + R"(, "path": [{"t": -1, "position": [0, 0, 0]}]}]})",
       "objects[0].path[0].t: must be >= 0 s, got -1"},
      {R"({"objects": [{)" + obj + R"(, "path": [{"t": "soon", "position": [0, 0, 0]}]}]})",
       "objects[0].path[0].t: expected a number, got \"soon\""},
      {R"({"objects": [{)" + obj + R"(, "path": [{"position": [0, 0, 0]}]}]})",
       "objects[0].path[0].t: missing (a keyframe needs \"t\" and \"position\")"},
      {R"({"objects": [{)" + obj + R"(, "path": [{"t": 0}]}]})", "objects[0].path[0].position: missing"},
      {R"({"objects": [{)" + obj + R"(, "path": [{"t": 0, "position": [0, 0]}]}]})",
       "objects[0].path[0].position: expected an array of 3 numbers, got [0,0]"},
      {R"({"objects": [{)" + obj + R"(, "path": [{"t": 0, "position": [0, null, 0]}]}]})",
       "objects[0].path[0].position[1]: expected a number, got null"},
      {R"({"objects": [{)" + obj + R"(, "path": [)" + key0 +
           R"(, {"t": 1, "position": [0, 0, 0], "orientation": [1, 1, 0, 0]}]}]})",
       "objects[0].path[1].orientation: expected a unit quaternion [w, x, y, z], got [1,1,0,0]"},
      {R"({"objects": [{)" + obj + R"(, "path": [{"t": 0, "position": [0, 0, 0], "speed": 1}]}]})",
       "objects[0].path[0].speed: unknown key (known keys here: t, position, orientation)"},
      {R"({"objects": [{)" + obj + R"(, "static": true, "path": [)" + key0 + R"(]}]})",
       "objects[0].path: a static object never moves"},
      {R"({"objects": [{)" + obj + R"(, "velocity": [1, 0, 0], "path": [)" + key0 + R"(]}]})",
       "objects[0].velocity: not used with \"path\", got [1,0,0]"},
      {R"({"objects": [{)" + obj + R"(, "position": [0, 0, 1], "path": [)" + key0 + R"(]}]})",
       "objects[0].position: not used with \"path\""},
  };
  for (const BadCase& c : cases) expectError(c);
}

TEST(SceneFile, GroundCanBeRemovedOrRaised) {
  const std::string obj = R"([{"mesh": "box:0.1,0.1,0.1", "material": "steel"}])";
  Result<Scene> none = parseScene(R"({"ground": null, "objects": )" + obj + "}", "s.json");
  ASSERT_TRUE(none) << none.error().message;
  EXPECT_FALSE(none->has_ground);
  Result<Scene> raised =
      parseScene(R"({"ground": {"height": 0.75, "material": "wood"}, "objects": )" + obj + "}", "s.json");
  ASSERT_TRUE(raised) << raised.error().message;
  EXPECT_EQ(raised->ground_height_m, 0.75);
  EXPECT_EQ(raised->ground_material.name, "wood");
}

TEST(SceneFile, ANumberTooLargeForADoubleIsNamedWithItsLineAndColumn) {
  const std::string text =
      "{\"objects\": [\n  {\"name\": \"a\", \"mesh\": \"sphere:0.01\", \"material\": \"steel\",\n"
      "   \"position\": [0, 0, 1e999]}]}";
  Result<Scene> scene = parseScene(text, "big.json");
  ASSERT_FALSE(scene);
  // Line 3, column 23: where 1e999 starts.
  EXPECT_NE(scene.error().message.find("big.json:3:23: error: invalid JSON: number overflow parsing '1e999'"),
            std::string::npos)
      << scene.error().message;
}

TEST(SceneFile, ListenerOrientationIsAQuaternionOrAPointToLookAt) {
  const std::string obj = R"([{"mesh": "box:0.1,0.1,0.1", "material": "steel"}])";
  Result<Scene> plain = parseScene(R"({"objects": )" + obj + "}", "s.json");
  ASSERT_TRUE(plain) << plain.error().message;
  EXPECT_EQ(plain->listener_orientation_wxyz, (std::array<double, 4>{1, 0, 0, 0}));
  // Turned 90 degrees to the left about +z: w = x... = cos 45, z = sin 45.
  Result<Scene> turned = parseScene(
      R"({"listener": {"position": [0, 0, 1], "orientation": [0.70710678, 0, 0, 0.70710678]}, "objects": )" + obj + "}",
      "s.json");
  ASSERT_TRUE(turned) << turned.error().message;
  EXPECT_NEAR(turned->listener_orientation_wxyz[3], std::sqrt(0.5), 1e-8);
  // Looking at a point on its left (-x) is the same turn.
  Result<Scene> looking =
      parseScene(R"({"listener": {"position": [0, 0, 1], "look_at": [-3, 0, 1]}, "objects": )" + obj + "}", "s.json");
  ASSERT_TRUE(looking) << looking.error().message;
  for (int k = 0; k < 4; ++k)
    EXPECT_NEAR(looking->listener_orientation_wxyz[k], turned->listener_orientation_wxyz[k], 1e-8) << k;
  const BadCase cases[] = {
      {R"({"listener": {"orientation": [1, 1, 0, 0]}, "objects": )" + obj + "}",
       "listener.orientation: expected a unit quaternion"},
      {R"({"listener": {"position": [0, 0, 1], "look_at": [0, 0, 5]}, "objects": )" + obj + "}",
       "listener.look_at: must be a point beside the listener's position"},
      {R"({"listener": {"orientation": [1, 0, 0, 0], "look_at": [0, 1, 0]}, "objects": )" + obj + "}",
       "listener.look_at: give either orientation or look_at"},
  };
  for (const BadCase& c : cases) expectError(c);
}

TEST(SceneFile, AirIsOffUnlessAskedForAndChecked) {
  const std::string obj = R"([{"mesh": "box:0.1,0.1,0.1", "material": "steel"}])";
  Result<Scene> none = parseScene(R"({"objects": )" + obj + "}", "s.json");
  ASSERT_TRUE(none) << none.error().message;
  EXPECT_FALSE(none->air_absorption);
  Result<Scene> standard = parseScene(R"({"air": true, "objects": )" + obj + "}", "s.json");
  ASSERT_TRUE(standard) << standard.error().message;
  EXPECT_TRUE(standard->air_absorption);
  EXPECT_EQ(standard->air.relative_humidity_percent, 50.0);
  Result<Scene> humid = parseScene(R"({"air": {"humidity": 80, "temperature": 5}, "objects": )" + obj + "}", "s.json");
  ASSERT_TRUE(humid) << humid.error().message;
  EXPECT_EQ(humid->air.relative_humidity_percent, 80.0);
  EXPECT_EQ(humid->air.temperature_c, 5.0);
  EXPECT_EQ(humid->air.pressure_kpa, 101.325);
  expectError({R"({"air": {"humidity": 120}, "objects": )" + obj + "}", "air.humidity: must be 0 to 100"});
  expectError({R"({"air": {"wind": 3}, "objects": )" + obj + "}", "air.wind: unknown key"});
}

}  // namespace
}  // namespace strike
