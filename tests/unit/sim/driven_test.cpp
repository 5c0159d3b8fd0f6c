// SPDX-License-Identifier: MIT
// Driven bodies (SimBodyDesc::path, scene key "path"): the pose between keyframes, a body that
// follows its path in free air to rounding, and one whose path goes into a plate: it rests its
// own weight there and slides at the keyframed speed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include "bodies.hpp"
#include "strike/sim/path.hpp"
#include "strike/sim/sim.hpp"

namespace strike {
namespace {

using namespace sim_bodies;

double distance(const Vec3& a, const Vec3& b) {
  const Vec3 d = sub(a, b);
  return std::sqrt(dot(d, d));
}

/// 1 - |<a, b>|: 0 for the same rotation (q and -q are one), ~angle^2 / 8 apart.
double turnApart(const std::array<double, 4>& a, const std::array<double, 4>& b) {
  return 1.0 - std::abs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
}

TEST(Path, KeysAreHitExactlyAndTheSpanBetweenIsLinearWithASlerp) {
  const std::vector<PathKey> keys = {{0.5, {0, 0, 0}, {1, 0, 0, 0}},
                                     {1.5, {1, 2, 3}, quaternion({0, 0, 1}, M_PI / 2)},
                                     {3.5, {1, 2, 5}, quaternion({0, 0, 1}, M_PI / 2)}};
  for (const PathKey& key : keys) {
    const PathPose pose = pathPose(keys, key.t_s);
    EXPECT_EQ(pose.position_m, key.position_m);
    EXPECT_LT(turnApart(pose.orientation_wxyz, key.orientation_wxyz), 1e-15);
  }
  // Before the first key: the first; after the last: the last.
  EXPECT_EQ(pathPose(keys, 0.0).position_m, keys[0].position_m);
  EXPECT_EQ(pathPose(keys, 99.0).position_m, keys[2].position_m);
  // Between: a constant speed, and the rotation half-way is the half turn.
  const PathPose half = pathPose(keys, 1.0);
  EXPECT_NEAR(half.position_m[0], 0.5, 1e-15);
  EXPECT_NEAR(half.position_m[1], 1.0, 1e-15);
  EXPECT_NEAR(half.position_m[2], 1.5, 1e-15);
  EXPECT_LT(turnApart(half.orientation_wxyz, quaternion({0, 0, 1}, M_PI / 4)), 1e-15);
  EXPECT_NEAR(pathPose(keys, 3.0).position_m[2], 4.5, 1e-15);
}

// A box whose centre of mass is off its mesh origin and whose principal axes are turned, so the
// mesh frame, Bullet's body frame and the world all differ; driven in free fall (gravity on, no
// ground) along a path that moves and turns it.
TEST(DrivenBody, FollowsItsPathInFreeAirToRounding) {
  SimBodyDesc box = makeBox("box", {0.08, 0.03, 0.01}, 0.2, {0.02, -0.01, 0.005}, rotation({1, 1, 0}, 0.3));
  box.path = {{0.0, {0.0, 0.0, 0.5}, {1, 0, 0, 0}},
              {0.1, {0.02, 0.0, 0.5}, {1, 0, 0, 0}},
              {0.3, {0.02, 0.05, 0.45}, quaternion({0, 1, 0}, 0.6)},
              {0.4, {0.02, 0.05, 0.45}, quaternion({1, 0, 0}, -0.4)}};
  SimSettings settings;
  settings.duration_s = 0.5;
  settings.ground = false;
  settings.record_states = true;
  Result<SimResult> run = simulate({box}, settings);
  ASSERT_TRUE(run) << run.error().message;
  ASSERT_EQ(run->states.size(), 500u);
  double worst_m = 0.0, worst_turn = 0.0;
  for (size_t k = 0; k < run->states.size(); ++k) {
    const double t = double(k + 1) * settings.substep_s;
    const PathPose want = pathPose(box.path, t);
    worst_m = std::max(worst_m, distance(run->states[k].position_m, want.position_m));
    worst_turn = std::max(worst_turn, turnApart(run->states[k].orientation_wxyz, want.orientation_wxyz));
  }
  std::printf("largest distance from the path %.3g m, largest 1 - |q.q'| %.3g\n", worst_m, worst_turn);
  EXPECT_LT(worst_m, 1e-12);
  EXPECT_LT(worst_turn, 1e-12);
  // The velocity Bullet reports is the path's: 0.2 m/s along x on the first span (no turn there,
  // so every point moves so).
  EXPECT_NEAR(run->states[50].velocity_m_s[0], 0.2, 1e-9);
  EXPECT_NEAR(run->states[50].velocity_m_s[2], 0.0, 1e-9);
  // After the last key it holds still.
  EXPECT_LT(std::sqrt(dot(run->final_velocity_m_s[0], run->final_velocity_m_s[0])), 1e-9);
  EXPECT_LT(distance(run->final_position_m[0], box.path.back().position_m), 1e-12);
}

// A 100 g steel block driven across a static plate with its path 0.5 mm inside the plate: the
// hand moves it, its weight presses it on. Then lifted off.
TEST(DrivenBody, RestsItsWeightWherePathGoesInAndSlidesAtTheKeyedSpeed) {
  SimBodyDesc plate = makeBox("plate", {0.3, 0.2, 0.01}, 1.0);
  plate.is_static = true;
  plate.position_m = {0, 0, 0.005};
  plate.compliance_per_pa = (1 - 0.29 * 0.29) / 2e11;
  SimBodyDesc block = makeBox("block", {0.04, 0.02, 0.01}, 0.1);
  block.compliance_per_pa = plate.compliance_per_pa;
  block.friction = plate.friction = 0.4;
  const double z_in = 0.01 + 0.005 - 0.0005;  // 0.5 mm into the plate
  block.path = {{0.0, {-0.05, 0, z_in}, {1, 0, 0, 0}},
                {0.1, {-0.05, 0, z_in}, {1, 0, 0, 0}},
                {0.6, {0.05, 0, z_in}, {1, 0, 0, 0}},  // 0.2 m/s
                {0.8, {0.05, 0, z_in}, {1, 0, 0, 0}},
                {0.9, {0.05, 0, z_in + 0.02}, {1, 0, 0, 0}}};
  SimSettings settings;
  settings.duration_s = 1.0;
  settings.gravity_m_s2 = {0, 0, -kG};
  settings.ground = false;
  settings.record_states = true;
  Result<SimResult> run = simulate({plate, block}, settings);
  ASSERT_TRUE(run) << run.error().message;
  std::map<double, double> load_n;  // per substep
  double slip_lo = 1e9, slip_hi = 0.0, track_block = 0.0, track_plate_lo = 1e9, last_event_s = 0.0;
  for (const ContactEvent& e : run->events) {
    ASSERT_EQ(e.body_a, 0u);
    ASSERT_EQ(e.body_b, 1u);
    last_event_s = std::max(last_event_s, e.step_time_s);
    if (e.step_time_s < 0.15 || e.step_time_s > 0.55) continue;  // steady sliding
    load_n[e.step_time_s] += e.normal_force_n;
    const double slip = std::sqrt(dot(e.slip_velocity_m_s, e.slip_velocity_m_s));
    slip_lo = std::min(slip_lo, slip), slip_hi = std::max(slip_hi, slip);
    track_block = std::max(track_block, e.track_speed_b_m_s);
    track_plate_lo = std::min(track_plate_lo, e.track_speed_a_m_s);
  }
  double mean_n = 0.0;
  for (const auto& [t, n] : load_n) mean_n += n / double(load_n.size());
  std::printf("load %.5f N (weight %.5f N) over %zu substeps, slip %.5f to %.5f m/s, last contact %.3f s\n", mean_n,
              0.1 * kG, load_n.size(), slip_lo, slip_hi, last_event_s);
  ASSERT_GT(load_n.size(), 390u);  // in contact every substep
  EXPECT_NEAR(mean_n, 0.1 * kG, 0.01 * 0.1 * kG);
  EXPECT_GT(slip_lo, 0.2 * 0.98);
  EXPECT_LT(slip_hi, 0.2 * 1.02);
  // The hand drags the contact along the block: it travels over the plate only.
  EXPECT_LT(track_block, 1e-3);
  EXPECT_GT(track_plate_lo, 0.2 * 0.98);
  // Friction holds it back within a substep; the next substep makes that up: it stays on its path
  // (sideways) within micrometres, and leaves the plate once lifted.
  for (size_t k = 150; k < 550; ++k) {
    const PathPose want = pathPose(block.path, double(k + 1) * settings.substep_s);
    EXPECT_NEAR(run->states[2 * k + 1].position_m[0], want.position_m[0], 1e-5) << k;
    EXPECT_NEAR(run->states[2 * k + 1].position_m[2], z_in + 0.0005, 1e-4) << k;  // on the plate, above its path
  }
  EXPECT_GT(last_event_s, 0.79);
  EXPECT_LT(last_event_s, 0.81);
  EXPECT_LT(distance(run->final_position_m[1], block.path.back().position_m), 1e-12);
}

// The same block scraped over a 2 kg plate that lies free on the ground: the plate moves a
// little too, yet the contact travels with the tool (two moving bodies would otherwise share it),
// and the plate's ground contact carries the block's weight besides its own.
TEST(DrivenBody, ItsContactTravelsWithItOverAPlateLyingFree) {
  SimBodyDesc plate = makeBox("plate", {0.3, 0.2, 0.01}, 2.0);
  plate.position_m = {0, 0, 0.005};
  plate.friction = 0.6;
  SimBodyDesc block = makeBox("block", {0.04, 0.02, 0.01}, 0.1);
  block.friction = 0.4;
  const double z_in = 0.01 + 0.005 - 0.0005;
  block.path = {{0.0, {-0.05, 0, z_in}, {1, 0, 0, 0}},
                {0.1, {-0.05, 0, z_in}, {1, 0, 0, 0}},
                {0.6, {0.05, 0, z_in}, {1, 0, 0, 0}}};
  SimSettings settings;
  settings.duration_s = 0.6;
  settings.gravity_m_s2 = {0, 0, -kG};
  settings.ground_friction = 0.6;
  Result<SimResult> run = simulate({plate, block}, settings);
  ASSERT_TRUE(run) << run.error().message;
  std::map<double, double> tool_n, ground_n;
  double track_block = 0.0, track_plate_lo = 1e9, slip_lo = 1e9, slip_hi = 0.0;
  for (const ContactEvent& e : run->events) {
    if (e.step_time_s < 0.15 || e.step_time_s > 0.55) continue;
    if (e.body_b == kGroundBody) {
      ground_n[e.step_time_s] += e.normal_force_n;
      continue;
    }
    tool_n[e.step_time_s] += e.normal_force_n;
    track_block = std::max(track_block, e.track_speed_b_m_s);
    track_plate_lo = std::min(track_plate_lo, e.track_speed_a_m_s);
    const double slip = std::sqrt(dot(e.slip_velocity_m_s, e.slip_velocity_m_s));
    slip_lo = std::min(slip_lo, slip), slip_hi = std::max(slip_hi, slip);
  }
  double tool = 0.0, ground = 0.0;
  for (const auto& [t, n] : tool_n) tool += n / double(tool_n.size());
  for (const auto& [t, n] : ground_n) ground += n / double(ground_n.size());
  std::printf("on the plate %.4f N, plate on the ground %.4f N (weights %.4f and %.4f N); track over the block "
              "%.2g m/s, over the plate from %.4f m/s; slip %.4f to %.4f m/s\n",
              tool, ground, 0.1 * kG, 2.1 * kG, track_block, track_plate_lo, slip_lo, slip_hi);
  ASSERT_GT(tool_n.size(), 390u);
  EXPECT_NEAR(tool, 0.1 * kG, 0.01 * 0.1 * kG);
  EXPECT_NEAR(ground, 2.1 * kG, 0.01 * 2.1 * kG);
  EXPECT_LT(track_block, 1e-3);
  EXPECT_GT(track_plate_lo, 0.2 * 0.98);
  EXPECT_GT(slip_lo, 0.2 * 0.98);
  EXPECT_LT(slip_hi, 0.2 * 1.02);
}

TEST(DrivenBody, BadPathsAreRefusedNamingTheKey) {
  SimBodyDesc block = makeBox("block", {0.04, 0.02, 0.01}, 0.1);
  SimSettings settings;
  settings.duration_s = 0.01;
  block.path = {{0.0, {0, 0, 1}, {1, 0, 0, 0}}, {0.0, {0, 0, 1}, {1, 0, 0, 0}}};
  Result<SimResult> twice = simulate({block}, settings);
  ASSERT_FALSE(twice);
  EXPECT_NE(twice.error().message.find("path[1]: t_s = 0 (must be later"), std::string::npos)
      << twice.error().message;
  block.path = {{0.0, {0, NAN, 1}, {1, 0, 0, 0}}};
  Result<SimResult> nan = simulate({block}, settings);
  ASSERT_FALSE(nan);
  EXPECT_NE(nan.error().message.find("path[0]"), std::string::npos) << nan.error().message;
  block.path = {{0.0, {0, 0, 1}, {1, 0, 0, 0}}};
  block.is_static = true;
  Result<SimResult> fixed = simulate({block}, settings);
  ASSERT_FALSE(fixed);
  EXPECT_NE(fixed.error().message.find("a static body cannot follow a path"), std::string::npos)
      << fixed.error().message;
}

}  // namespace
}  // namespace strike
