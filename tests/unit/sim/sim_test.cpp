// SPDX-License-Identifier: MIT
// Tests of the Bullet world and contact events (strike_bullet). Bodies are built by hand: boxes,
// an icosahedron and geodesic spheres (bodies.hpp) and, here, an open-top tray.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "bodies.hpp"
#include "common/same_bytes.hpp"
#include "strike/sim/sim.hpp"

namespace strike {
namespace {

using namespace sim_bodies;

/// An open-top tray: outer a x a x h, walls and floor t thick, mesh origin at the centre of its
/// bottom face. A closed, watertight 16-vertex / 28-triangle surface (CCW from outside).
SimBodyDesc makeTray(const std::string& name, double a, double h, double t, double density) {
  SimBodyDesc body;
  body.name = name;
  const double o = a / 2, b = a / 2 - t;
  const double pts[16][3] = {{-o, -o, 0}, {o, -o, 0}, {o, o, 0}, {-o, o, 0},   // outer bottom
                             {-o, -o, h}, {o, -o, h}, {o, o, h}, {-o, o, h},   // outer rim
                             {-b, -b, h}, {b, -b, h}, {b, b, h}, {-b, b, h},   // inner rim
                             {-b, -b, t}, {b, -b, t}, {b, b, t}, {-b, b, t}};  // inner floor
  for (const auto& p : pts) body.surface_positions.insert(body.surface_positions.end(), {p[0], p[1], p[2]});
  const uint32_t quads[14][4] = {{0, 3, 2, 1},                                                         // bottom
                                 {0, 1, 5, 4},    {1, 2, 6, 5},    {2, 3, 7, 6},     {3, 0, 4, 7},     // outer walls
                                 {4, 5, 9, 8},    {5, 6, 10, 9},   {6, 7, 11, 10},   {7, 4, 8, 11},    // rim
                                 {12, 8, 9, 13},  {13, 9, 10, 14}, {14, 10, 11, 15}, {15, 11, 8, 12},  // inner walls
                                 {12, 13, 14, 15}};                                                    // floor
  for (const auto& q : quads) {
    body.surface_triangles.insert(body.surface_triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  }
  // Mass properties: the solid outer box minus the cavity, by the parallel-axis theorem.
  struct Part {
    double m;
    Vec3 c, l;
  };
  const Part outer{density * a * a * h, {0, 0, h / 2}, {a, a, h}};
  const Part cavity{-density * (2 * b) * (2 * b) * (h - t), {0, 0, (h + t) / 2}, {2 * b, 2 * b, h - t}};
  const double m = outer.m + cavity.m;
  const Vec3 com{0, 0, (outer.m * outer.c[2] + cavity.m * cavity.c[2]) / m};
  Mat3 inertia{};
  for (const Part& p : {outer, cavity}) {
    const Vec3 d = sub(p.c, com);
    const Vec3 own{p.m / 12 * (p.l[1] * p.l[1] + p.l[2] * p.l[2]), p.m / 12 * (p.l[0] * p.l[0] + p.l[2] * p.l[2]),
                   p.m / 12 * (p.l[0] * p.l[0] + p.l[1] * p.l[1])};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        inertia[3 * r + c] += (r == c ? own[r] + p.m * dot(d, d) : 0.0) - p.m * d[r] * d[c];
      }
    }
  }
  body.mass_kg = m;
  body.centre_m = com;
  body.inertia_kg_m2 = inertia;
  return body;
}

SimSettings settingsFor(double duration_s) {
  SimSettings s;
  s.duration_s = duration_s;
  s.gravity_m_s2 = {0, 0, -kG};
  return s;
}

SimResult run(const std::vector<SimBodyDesc>& bodies, const SimSettings& settings, const char* label) {
  Result<SimResult> r = simulate(bodies, settings);
  EXPECT_TRUE(r.ok()) << label << ": " << r.error().message;
  if (!r.ok()) return {};
  std::printf("[ scene    ] %-28s %6llu substeps, %6zu events, %.3f s wall\n", label,
              static_cast<unsigned long long>(r->substeps), r->events.size(), r->simulate_seconds);
  return std::move(r).value();
}

/// Energy may only go down: never above its initial value by more than 1% of |E0| (plus a
/// microjoule floor for scenes whose energy is near zero).
void expectNoEnergyGain(const SimResult& r, const char* label) {
  ASSERT_FALSE(r.energy_trace_j.empty());
  const double e0 = r.energy_trace_j.front();
  const double e_max = *std::max_element(r.energy_trace_j.begin(), r.energy_trace_j.end());
  EXPECT_LE(e_max, e0 + 0.01 * std::abs(e0) + 1e-6) << label << ": E0 = " << e0 << " J";
  for (double e : r.energy_trace_j) ASSERT_TRUE(std::isfinite(e)) << label;
}

TEST(SimFreeFall, HitsTheGroundOnTimeWithTheRightSpeed) {
  const double h = 1.0, lz = 0.02;
  SimBodyDesc box = makeBox("box", {0.04, 0.03, lz}, 0.1);
  box.position_m = {0, 0, h + lz / 2};  // bottom face 1 m above the ground
  SimSettings settings = settingsFor(0.6);
  std::vector<double> fractions;
  settings.progress = [&](std::string_view phase, double f) {
    EXPECT_EQ(phase, "simulate");
    fractions.push_back(f);
  };
  const SimResult r = run({box}, settings, "free fall 1 m");
  ASSERT_FALSE(r.events.empty());
  ASSERT_FALSE(fractions.empty());
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  EXPECT_EQ(r.substeps, 600u);
  EXPECT_EQ(r.energy_trace_j.size(), 601u);
  EXPECT_EQ(r.shape_used[0], SimBodyDesc::Shape::ConvexHull);

  const ContactEvent& first = r.events.front();
  const double t_hit = std::sqrt(2 * h / kG);
  EXPECT_NEAR(first.time_s, t_hit, 2 * settings.substep_s);
  EXPECT_NEAR(first.normal_speed_m_s, std::sqrt(2 * kG * h), 0.02 * std::sqrt(2 * kG * h));
  EXPECT_TRUE(first.new_contact);
  EXPECT_EQ(first.body_a, 0u);
  EXPECT_EQ(first.body_b, kGroundBody);
  EXPECT_NEAR(first.normal_world[2], 1.0, 1e-9);
  // The box is not rotated, so its mesh frame is the world's: the impulse points up.
  EXPECT_GT(first.impulse_on_a_mesh[2], 0.0);
  EXPECT_NEAR(first.impulse_on_a_mesh[2], first.normal_impulse_n_s, 1e-12);
  EXPECT_NEAR(first.impulse_on_b_mesh[2], -first.normal_impulse_n_s, 1e-12);
  EXPECT_NEAR(first.point_world[2], 0.0, 1e-3);
  // Every first-substep event of the impact is new; the impacts sum to about m (1 + e) v.
  double total_z = 0.0;
  for (const ContactEvent& e : r.events) {
    if (e.time_s <= first.time_s + 5e-3) total_z += e.impulse_on_a_mesh[2];
  }
  EXPECT_GT(total_z, 0.1 * std::sqrt(2 * kG * h));  // at least m v: the box is stopped
  expectNoEnergyGain(r, "free fall");
}

TEST(SimStates, RecordedPosesFollowTheFreeFallAndSleep) {
  // The body starts with the half-step velocity (buildBody), so semi-implicit Euler is exact for
  // constant gravity: after k substeps z = z_0 - g t^2 / 2 at t = k dt, and the stored velocity
  // is the half-step one, -g (k - 1/2) dt.
  const double z0 = 1.0, dt = 1e-3;
  SimBodyDesc box = makeBox("box", {0.04, 0.03, 0.02}, 0.1);
  box.position_m = {0.1, -0.2, z0};
  SimSettings settings = settingsFor(3.0);
  settings.record_states = true;
  const SimResult r = run({box}, settings, "free fall with states");
  ASSERT_EQ(r.states.size(), r.substeps);
  for (uint64_t k : {1u, 10u, 200u}) {
    const SimBodyState& s = r.states[k - 1];
    const double t = double(k) * dt;
    EXPECT_NEAR(s.position_m[2], z0 - kG * t * t / 2, 1e-9) << "substep " << k;
    EXPECT_NEAR(s.velocity_m_s[2], -kG * (t - dt / 2), 1e-9) << "substep " << k;
    EXPECT_DOUBLE_EQ(s.position_m[0], 0.1);
    EXPECT_DOUBLE_EQ(s.orientation_wxyz[0], 1.0);
    EXPECT_FALSE(s.asleep);
  }
  // At rest on the ground at the end, asleep from sleep_start_s on (the substep ending then).
  ASSERT_TRUE(std::isfinite(r.sleep_start_s[0]));
  const SimBodyState& last = r.states.back();
  EXPECT_TRUE(last.asleep);
  EXPECT_NEAR(last.position_m[2], 0.01, 1e-3);
  const size_t first_asleep = size_t(std::lround(r.sleep_start_s[0] / dt)) - 1;
  EXPECT_TRUE(r.states[first_asleep].asleep);
  EXPECT_FALSE(r.states[first_asleep - 1].asleep);
}

TEST(SimResting, ConstantForceAndNoNewContacts) {
  const double m = 1.0, dt = 1e-3;
  SimBodyDesc box = makeBox("block", {0.1, 0.1, 0.05}, m);
  box.position_m = {0, 0, 0.025};
  SimSettings settings = settingsFor(1.0);
  settings.sleep_after_still_s = 2.0;  // awake for the whole second: the resting force every step
  const SimResult r = run({box}, settings, "resting box");
  const double t_settled = 0.2;
  std::map<long, double> per_step;
  for (const ContactEvent& e : r.events) {
    if (e.time_s < t_settled) continue;
    EXPECT_FALSE(e.new_contact) << "at t = " << e.time_s;
    EXPECT_EQ(e.body_b, kGroundBody);
    per_step[std::lround(e.time_s / dt)] += e.normal_impulse_n_s;
  }
  EXPECT_EQ(per_step.size(), 800u);  // a contact force in every substep
  for (const auto& [step, sum] : per_step) {
    EXPECT_NEAR(sum, m * kG * dt, 0.01 * m * kG * dt) << "step " << step;
  }
  EXPECT_NEAR(r.final_position_m[0][2], 0.025, 1e-3);
  expectNoEnergyGain(r, "resting");
}

TEST(SimResting, SleepingBodyIsQuiet) {
  SimBodyDesc box = makeBox("block", {0.1, 0.1, 0.05}, 1.0);
  box.position_m = {0, 0, 0.03};  // a 5 mm drop, then rest
  const SimResult r = run({box}, settingsFor(4.0), "settling box, 4 s");
  ASSERT_FALSE(r.events.empty());
  EXPECT_LT(r.events.back().time_s, 3.5) << "a resting body should fall asleep and stop reporting";
  // Still from ~0.1 s on, asleep sleep_after_still_s (0.5 s) later, not after Bullet's 2 s.
  EXPECT_LT(r.events.back().time_s, 1.0);
  EXPECT_GT(r.events.back().time_s, SimSettings{}.sleep_after_still_s);
  // It reports when it fell asleep: the substep after its last contact.
  ASSERT_EQ(r.sleep_start_s.size(), 1u);
  EXPECT_NEAR(r.sleep_start_s[0], r.events.back().step_time_s + 2e-3, 1.5e-3);
}

TEST(SimMeshFrame, PointsLieOnTheBoxSurfaceInMeshCoordinates) {
  const Vec3 l{0.06, 0.04, 0.02}, offset{0.1, -0.05, 0.2};
  const Mat3 axes = rotation({1, 1, 0}, 0.5);  // box axes in the mesh frame: inertia not diagonal
  SimBodyDesc box = makeBox("tilted", l, 0.2, offset, axes);
  const Vec3 axis{0.3, -0.5, 0.8};
  const double angle = 0.7;
  box.orientation_wxyz = quaternion(axis, angle);
  const Mat3 world_from_mesh = rotation(axis, angle);
  box.position_m = sub({0, 0, 0.3}, mul(world_from_mesh, offset));  // centre 0.3 m up
  const SimResult r = run({box}, settingsFor(1.0), "tilted off-centre box");
  ASSERT_FALSE(r.events.empty());
  const double tolerance = 2 * r.collision_margin_m[0] + 1e-6;
  int count = 0;
  for (const ContactEvent& e : r.events) {
    ASSERT_EQ(e.body_b, kGroundBody);
    // In the box's own axes the point must be inside the box and on one of its faces.
    const Vec3 local = mulT(axes, sub(e.point_a_mesh, offset));
    double gap = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(std::abs(local[k]), l[k] / 2 + tolerance) << "t = " << e.time_s;
      gap = std::min(gap, l[k] / 2 - std::abs(local[k]));
    }
    EXPECT_LE(gap, tolerance) << "t = " << e.time_s << ": point is " << gap << " m inside the surface";
    // The mesh-frame impulse, rotated back to the world, has the normal impulse along +z (the
    // box has not turned yet on its first substep of contact); its length is frame-free.
    const double n = e.normal_impulse_n_s, f = e.friction_impulse_n_s;
    EXPECT_NEAR(std::sqrt(dot(e.impulse_on_a_mesh, e.impulse_on_a_mesh)), std::sqrt(n * n + f * f), 1e-9 * (n + f));
    if (e.time_s == r.events.front().time_s) {
      const Vec3 j_world = mul(world_from_mesh, e.impulse_on_a_mesh);
      EXPECT_NEAR(j_world[2], n, 1e-9 * n);
      EXPECT_TRUE(e.new_contact);
    }
    ++count;
  }
  EXPECT_GT(count, 10);
  expectNoEnergyGain(r, "tilted box");
}

TEST(SimEnergy, HeavyBoxOnLightBox) {
  SimBodyDesc light = makeBox("light", {0.1, 0.1, 0.05}, 0.1);
  light.position_m = {0, 0, 0.025};
  SimBodyDesc heavy = makeBox("heavy", {0.1, 0.1, 0.05}, 100.0);
  heavy.position_m = {0.01, 0, 0.05 + 0.025 + 0.2};
  const SimResult r = run({light, heavy}, settingsFor(1.5), "heavy on light (1000:1)");
  expectNoEnergyGain(r, "heavy on light");
  EXPECT_GT(r.final_position_m[0][2], 0.0);
  EXPECT_GT(r.final_position_m[1][2], r.final_position_m[0][2] + 0.04) << "heavy box sank into the light one";
  bool pair_contact = false;
  for (const ContactEvent& e : r.events) pair_contact |= (e.body_a == 0 && e.body_b == 1);
  EXPECT_TRUE(pair_contact);
}

TEST(SimEnergy, StackAtRestStaysAtRest) {
  std::vector<SimBodyDesc> stack;
  for (int k = 0; k < 4; ++k) {
    SimBodyDesc box = makeBox("stack" + std::to_string(k), {0.1, 0.1, 0.05}, 1.0);
    box.position_m = {0, 0, 0.025 + 0.05 * k};
    stack.push_back(box);
  }
  const SimResult r = run(stack, settingsFor(2.0), "stack of 4");
  expectNoEnergyGain(r, "stack");
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(r.final_position_m[size_t(k)][2], 0.025 + 0.05 * k, 2e-3) << "box " << k;
    EXPECT_NEAR(r.final_position_m[size_t(k)][0], 0.0, 2e-3) << "box " << k;
  }
}

// Mass ratio 1e4: a 100 kg box set down (1 mm gap) on a 10 g box of the same size. Bullet's
// sequential-impulse solver is known to push light bodies out of heavy stacks ("explode"). The
// test is that it does not explode: total energy never rises, and no body ever holds more
// kinetic energy than the whole stack can release by falling to the ground (the heavy box's
// 52 mm to the ground, 100 kg g 0.052 m = 51 J, plus the light box's 1 mm), and both end at rest.
// Measured (not asserted): the solver does not hold the stack at this ratio; the light box is
// squeezed out sideways (ends 0.11 m off centre) and the heavy box lands on the ground
// (max kinetic energy 33.9 J, below the 51 J it released), the light box's at most 0.8 mJ: pushed
// aside, not thrown. At 1000:1 the stack holds (HeavyBoxOnLightBox).
TEST(SimEnergy, MassRatio1e4DoesNotExplode) {
  SimBodyDesc light = makeBox("light", {0.1, 0.1, 0.05}, 0.01);
  light.position_m = {0, 0, 0.025 + 0.001};
  SimBodyDesc heavy = makeBox("heavy", {0.1, 0.1, 0.05}, 100.0);
  heavy.position_m = {0, 0, 0.05 + 0.025 + 0.002};
  const SimResult r = run({light, heavy}, settingsFor(2.0), "heavy on light (10000:1)");
  expectNoEnergyGain(r, "10000:1");
  const double releasable_j = 100.0 * kG * (heavy.position_m[2] - 0.025) + 0.01 * kG * 0.001;
  ASSERT_EQ(r.max_kinetic_energy_j.size(), 2u);
  for (size_t b = 0; b < 2; ++b) EXPECT_LE(r.max_kinetic_energy_j[b], releasable_j) << "body " << b;
  // The light box can take at most what a 10 g box gains from the heavy one's push: its kinetic
  // energy staying under 1 J means under 14 m/s; an explosion would throw it far faster.
  EXPECT_LE(r.max_kinetic_energy_j[0], 1.0) << "light box thrown";
  std::printf("[ measured ] light box ends at (%.3f, %.3f, %.3f) m, heavy at z = %.3f m; max KE %.3g / %.3g J\n",
              r.final_position_m[0][0], r.final_position_m[0][1], r.final_position_m[0][2], r.final_position_m[1][2],
              r.max_kinetic_energy_j[0], r.max_kinetic_energy_j[1]);
  for (size_t b = 0; b < 2; ++b) EXPECT_LT(std::sqrt(dot(r.final_velocity_m_s[b], r.final_velocity_m_s[b])), 1e-2) << b;
}

/// A coin: regular n-gon prism of radius r and thickness h, axis along mesh z, centred at the
/// origin; a solid cylinder's inertia (m r^2 / 4 + m h^2 / 12 across, m r^2 / 2 about the axis).
SimBodyDesc makeCoin(const std::string& name, double r, double h, double mass_kg, int n = 32) {
  SimBodyDesc body;
  body.name = name;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / n;
    for (double z : {-h / 2, h / 2})
      body.surface_positions.insert(body.surface_positions.end(), {r * std::cos(a), r * std::sin(a), z});
  }
  for (uint32_t k = 0; k < uint32_t(n); ++k) {
    const uint32_t next = (k + 1) % uint32_t(n);
    body.surface_triangles.insert(body.surface_triangles.end(),
                                  {2 * k, 2 * next, 2 * next + 1, 2 * k, 2 * next + 1, 2 * k + 1});
    if (k >= 2) {  // fans over the two faces
      body.surface_triangles.insert(body.surface_triangles.end(), {0, 2 * k, 2 * (k - 1)});
      body.surface_triangles.insert(body.surface_triangles.end(), {1, 2 * (k - 1) + 1, 2 * k + 1});
    }
  }
  orientOutward(body, {0, 0, 0});
  body.mass_kg = mass_kg;
  const double across = mass_kg * r * r / 4 + mass_kg * h * h / 12;
  body.inertia_kg_m2 = {across, 0, 0, 0, across, 0, 0, 0, mass_kg * r * r / 2};
  return body;
}

// A brass coin (examples/scenes/coin-spin.json: r = 11.6 mm, 2.3 mm thick, 8.3 g) dropped 45 mm
// spinning at 30 rad/s on its edge, tilted 70 degrees, sliding at 0.15 m/s. It may wobble down
// like Euler's disk but must never gain energy, and after 6 s it must lie flat (centre at half
// its thickness, 1.15 mm, within 0.5 mm), at rest, and silent: no impact (approach faster than
// the engine's impact rule, 5 cm/s: EngineSettings::impact_speed_m_s) in the last second.
TEST(SimEnergy, SpinningCoinComesToRestFlatAndSilent) {
  SimBodyDesc coin = makeCoin("coin", 0.0116, 0.0023, 8.3e-3);
  coin.position_m = {0, 0, 0.045};
  coin.orientation_wxyz = {0.819152, 0.5735764, 0.0, 0.0};
  coin.angular_velocity_rad_s = {0, 0, 30.0};
  coin.velocity_m_s = {0.15, 0, 0};
  const SimResult r = run({coin}, settingsFor(6.0), "spinning coin, 6 s");
  expectNoEnergyGain(r, "coin");
  EXPECT_NEAR(r.final_position_m[0][2], 0.00115, 5e-4) << "not lying flat";
  EXPECT_LT(std::sqrt(dot(r.final_velocity_m_s[0], r.final_velocity_m_s[0])), 1e-3);
  EXPECT_LT(std::sqrt(dot(r.final_angular_velocity_rad_s[0], r.final_angular_velocity_rad_s[0])), 0.1);
  for (const ContactEvent& e : r.events) {
    if (e.time_s > 5.0) {
      EXPECT_LE(e.normal_speed_m_s, 0.05) << "impact at t = " << e.time_s;
    }
  }
}

class SimTunnelling : public ::testing::TestWithParam<double> {};

TEST_P(SimTunnelling, FastBoxHitsTheGround) {
  const double speed = GetParam();
  SimBodyDesc box = makeBox("pellet", {0.02, 0.02, 0.02}, 0.008);
  box.position_m = {0, 0, 0.5};
  box.velocity_m_s = {0, 0, -speed};
  SimSettings settings = settingsFor(0.3);
  const SimResult r = run({box}, settings, speed > 60 ? "pellet at 100 m/s" : "pellet at 50 m/s");
  ASSERT_FALSE(r.events.empty());
  const double impact = std::sqrt(speed * speed + 2 * kG * 0.49);
  double best = 0.0;
  for (const ContactEvent& e : r.events) {
    EXPECT_EQ(e.body_b, kGroundBody);
    best = std::max(best, e.normal_speed_m_s);
  }
  EXPECT_NEAR(best, impact, 0.03 * impact);
  EXPECT_TRUE(r.events.front().new_contact);
  EXPECT_NEAR(r.events.front().normal_speed_m_s, impact, 0.03 * impact);
  // A CCD contact is timed too: 0.49 m at `speed` under gravity, to 10 us of its 5-10 ms.
  const double t_meet = (std::sqrt(speed * speed + 2 * kG * 0.49) - speed) / kG;
  EXPECT_NEAR(r.events.front().time_s, t_meet, 0.01e-3);
  EXPECT_GT(r.final_position_m[0][2], 0.0) << "tunnelled through the ground";
  expectNoEnergyGain(r, "pellet");
}

INSTANTIATE_TEST_SUITE_P(Speeds, SimTunnelling, ::testing::Values(50.0, 100.0));

void expectBallInTray(bool tray_static, SimBodyDesc::Shape shape, SimBodyDesc::Shape expected_shape) {
  SimBodyDesc tray = makeTray("tray", 0.2, 0.06, 0.01, 1000.0);
  tray.is_static = tray_static;
  tray.shape = shape;
  SimBodyDesc ball = makeBall("ball", 0.02, 0.05);
  ball.position_m = {0.02, -0.01, 0.3};
  ball.restitution = 0.3;
  const char* label = tray_static                                     ? "ball into static tray"
                      : expected_shape == SimBodyDesc::Shape::Concave ? "ball into GImpact tray"
                                                                      : "ball into tray of convex pieces";
  const SimResult r = run({tray, ball}, settingsFor(1.5), label);
  EXPECT_EQ(r.shape_used[0], expected_shape);
  EXPECT_EQ(r.shape_used[1], SimBodyDesc::Shape::ConvexHull);
  const Vec3 t = r.final_position_m[0], b = r.final_position_m[1];
  EXPECT_NEAR(t[2], 0.0, 2e-3) << "tray left the ground";
  EXPECT_LT(std::abs(b[0] - t[0]), 0.09);
  EXPECT_LT(std::abs(b[1] - t[1]), 0.09);
  EXPECT_GT(b[2], t[2] + 0.01) << "ball is below the tray's floor";
  EXPECT_LT(b[2], t[2] + 0.06) << "ball is not inside the tray";
  int pair_events = 0;
  bool pair_new = false;
  for (const ContactEvent& e : r.events) {
    if (e.body_a == 0 && e.body_b == 1) {
      ++pair_events;
      pair_new |= e.new_contact;
    }
  }
  EXPECT_GT(pair_events, 0);
  EXPECT_TRUE(pair_new);
  if (!tray_static) expectNoEnergyGain(r, "tray");
}

using Shape = SimBodyDesc::Shape;
TEST(SimConcave, BallLandsInsideDynamicTray) { expectBallInTray(false, Shape::Concave, Shape::Concave); }
TEST(SimConcave, BallLandsInsideDynamicTrayOfConvexPieces) {
  expectBallInTray(false, Shape::Auto, Shape::ConvexPieces);
}
TEST(SimConcave, BallLandsInsideStaticTray) { expectBallInTray(true, Shape::Auto, Shape::Concave); }

TEST(SimShape, AutoPicksHullForConvexAndConcaveForTray) {
  SimBodyDesc box = makeBox("box", {0.1, 0.05, 0.02}, 0.5);
  box.position_m = {0, 0, 0.5};
  SimBodyDesc tray = makeTray("tray", 0.2, 0.06, 0.01, 1000.0);
  tray.position_m = {1, 0, 0};
  SimBodyDesc fixed_tray = tray;
  fixed_tray.is_static = true;
  fixed_tray.position_m = {-1, 0, 0};
  const SimResult r = run({box, tray, fixed_tray}, settingsFor(0.01), "shape choice");
  EXPECT_EQ(r.shape_used[0], SimBodyDesc::Shape::ConvexHull);
  EXPECT_EQ(r.shape_used[1], SimBodyDesc::Shape::ConvexPieces);  // a moving concave body
  EXPECT_GE(r.collision_pieces[1], 5u);                          // a floor and four walls at least
  EXPECT_EQ(r.shape_used[2], SimBodyDesc::Shape::Concave);       // a static one: its exact mesh
  EXPECT_GT(r.collision_margin_m[0], 0.0);
  // A small hull (polyhedral contacts on its bare points): 0.1% of the thinnest extent.
  EXPECT_LE(r.collision_margin_m[0], 0.001 * 0.02 + 1e-12);
}

std::vector<SimBodyDesc> busyScene() {
  std::vector<SimBodyDesc> bodies;
  for (int k = 0; k < 3; ++k) {
    SimBodyDesc box = makeBox("stack" + std::to_string(k), {0.1, 0.1, 0.05}, 1.0);
    box.position_m = {0, 0, 0.025 + 0.05 * k};
    bodies.push_back(box);
  }
  SimBodyDesc thrown = makeBox("thrown", {0.06, 0.04, 0.02}, 0.2, {0.01, 0, 0}, rotation({0, 1, 1}, 0.3));
  thrown.orientation_wxyz = quaternion({1, 2, 3}, 0.8);
  thrown.position_m = {-0.3, 0.02, 0.25};
  thrown.velocity_m_s = {3, 0, 0};
  thrown.angular_velocity_rad_s = {0, 5, 2};
  bodies.push_back(thrown);
  // Rolling resistance, spinning friction and the contact state (contact_state.cpp).
  SimBodyDesc rolling = makeSphere("rolling", 0.02, 0.26);
  rolling.position_m = {0, 0.4, 0.05};
  rolling.velocity_m_s = {0.5, 0, 0};
  rolling.angular_velocity_rad_s = {0, 10, 30};
  rolling.rolling_resistance = 0.01;
  rolling.compliance_per_pa = 4.6e-12;
  bodies.push_back(rolling);
  return bodies;
}

TEST(SimDeterminism, TwoRunsGiveIdenticalEvents) {
  const auto bodies = busyScene();
  const SimResult a = run(bodies, settingsFor(1.0), "busy scene, run 1");
  const SimResult b = run(bodies, settingsFor(1.0), "busy scene, run 2");
  ASSERT_EQ(a.events.size(), b.events.size());
  ASSERT_GT(a.events.size(), 100u);
  for (size_t k = 0; k < a.events.size(); ++k) {
    const ContactEvent& x = a.events[k];
    const ContactEvent& y = b.events[k];
    ASSERT_TRUE(x.time_s == y.time_s && x.step_time_s == y.step_time_s && x.body_a == y.body_a &&
                x.body_b == y.body_b && x.point_a_mesh == y.point_a_mesh && x.point_b_mesh == y.point_b_mesh &&
                x.impulse_on_a_mesh == y.impulse_on_a_mesh && x.impulse_on_b_mesh == y.impulse_on_b_mesh &&
                x.point_world == y.point_world && x.normal_world == y.normal_world &&
                x.normal_impulse_n_s == y.normal_impulse_n_s && x.friction_impulse_n_s == y.friction_impulse_n_s &&
                x.normal_speed_m_s == y.normal_speed_m_s && x.new_contact == y.new_contact &&
                x.normal_force_n == y.normal_force_n && x.slip_velocity_m_s == y.slip_velocity_m_s &&
                x.rolling_speed_m_s == y.rolling_speed_m_s && x.track_speed_a_m_s == y.track_speed_a_m_s &&
                x.track_speed_b_m_s == y.track_speed_b_m_s && x.patch_radius_m == y.patch_radius_m)
        << "event " << k << " differs";
    if (k > 0) {
      ASSERT_LE(a.events[k - 1].time_s, x.time_s) << "events out of time order";
    }
  }
  EXPECT_TRUE(test::sameValues(a.energy_trace_j, b.energy_trace_j));
  EXPECT_EQ(a.final_position_m, b.final_position_m);
  // The impulses on a and b are equal and opposite (compare in the world for a ground contact).
  const double step = settingsFor(1.0).substep_s;
  int timed = 0;
  for (const ContactEvent& e : a.events) {
    EXPECT_GE(e.normal_speed_m_s, 0.0);
    EXPECT_NEAR(std::sqrt(dot(e.normal_world, e.normal_world)), 1.0, 1e-9);
    // Substeps on the 1 ms grid; impacts within a step of theirs, other contacts on it.
    EXPECT_NEAR(e.step_time_s / step, std::round(e.step_time_s / step), 1e-6);
    EXPECT_LE(std::abs(e.time_s - e.step_time_s), step * (1 + 1e-9));
    if (e.normal_speed_m_s <= settingsFor(1.0).impact_speed_m_s) {
      EXPECT_EQ(e.time_s, e.step_time_s);
    }
    timed += e.time_s != e.step_time_s;
  }
  EXPECT_GT(timed, 0);
}

TEST(SimDeterminism, EndingOnceAllAsleepGivesTheFullRunToTheBit) {
  // SimSettings::end_when_all_asleep stops stepping once every moving body sleeps and writes the
  // rest; it must be exactly what stepping to the end records. Two boxes land on a static slab
  // and the ground, a third drops onto one of them, and all sleep well before the 3 s end.
  std::vector<SimBodyDesc> bodies;
  SimBodyDesc slab = makeBox("slab", {0.3, 0.3, 0.02}, 1.0);
  slab.is_static = true;
  slab.position_m = {0.3, 0, 0.01};
  bodies.push_back(slab);
  SimBodyDesc a = makeBox("a", {0.06, 0.04, 0.02}, 0.2, {0.005, 0, 0}, rotation({0, 1, 1}, 0.3));
  a.orientation_wxyz = quaternion({1, 2, 3}, 0.8);
  a.position_m = {0.3, 0.02, 0.12};
  a.angular_velocity_rad_s = {0, 3, 1};
  bodies.push_back(a);
  SimBodyDesc b = makeBox("b", {0.05, 0.05, 0.03}, 0.3);
  b.position_m = {-0.2, 0, 0.1};
  b.velocity_m_s = {0.3, 0, 0};
  bodies.push_back(b);
  SimBodyDesc c = makeBox("c", {0.03, 0.02, 0.01}, 0.05);
  c.position_m = {-0.19, 0.01, 0.3};
  bodies.push_back(c);
  SimSettings full = settingsFor(3.0);
  full.record_states = true;
  full.end_when_all_asleep = false;
  SimSettings early = full;
  early.end_when_all_asleep = true;
  const SimResult x = run(bodies, full, "settling boxes, stepped");
  const SimResult y = run(bodies, early, "settling boxes, ended early");
  // All asleep before 2 s: the early end had a second to skip.
  ASSERT_EQ(x.sleep_start_s.size(), 4u);
  for (size_t i = 1; i < 4; ++i) EXPECT_LT(x.sleep_start_s[i], 2.0) << "body " << i;
  ASSERT_GT(x.events.size(), 50u);
  ASSERT_EQ(x.events.size(), y.events.size());
  for (size_t k = 0; k < x.events.size(); ++k) {
    const ContactEvent& p = x.events[k];
    const ContactEvent& q = y.events[k];
    ASSERT_TRUE(p.time_s == q.time_s && p.step_time_s == q.step_time_s && p.body_a == q.body_a &&
                p.body_b == q.body_b && p.point_a_mesh == q.point_a_mesh && p.point_b_mesh == q.point_b_mesh &&
                p.impulse_on_a_mesh == q.impulse_on_a_mesh && p.impulse_on_b_mesh == q.impulse_on_b_mesh &&
                p.point_world == q.point_world && p.normal_world == q.normal_world &&
                p.normal_impulse_n_s == q.normal_impulse_n_s && p.normal_speed_m_s == q.normal_speed_m_s &&
                p.new_contact == q.new_contact && p.slip_velocity_m_s == q.slip_velocity_m_s &&
                p.rolling_speed_m_s == q.rolling_speed_m_s && p.patch_radius_m == q.patch_radius_m)
        << "event " << k << " differs";
  }
  EXPECT_EQ(x.substeps, y.substeps);
  ASSERT_EQ(x.states.size(), y.states.size());
  ASSERT_EQ(x.states.size(), x.substeps * bodies.size());
  for (size_t k = 0; k < x.states.size(); ++k) {
    const SimBodyState& p = x.states[k];
    const SimBodyState& q = y.states[k];
    ASSERT_TRUE(p.position_m == q.position_m && p.orientation_wxyz == q.orientation_wxyz &&
                p.velocity_m_s == q.velocity_m_s && p.asleep == q.asleep)
        << "state " << k << " (substep " << k / bodies.size() << ") differs";
  }
  EXPECT_TRUE(test::sameValues(x.energy_trace_j, y.energy_trace_j));
  EXPECT_TRUE(test::sameValues(x.max_kinetic_energy_j, y.max_kinetic_energy_j));
  ASSERT_EQ(x.sleep_start_s.size(), y.sleep_start_s.size());
  for (size_t i = 0; i < x.sleep_start_s.size(); ++i)  // NaN for the static slab
    EXPECT_TRUE(x.sleep_start_s[i] == y.sleep_start_s[i] || (std::isnan(x.sleep_start_s[i]) && std::isnan(y.sleep_start_s[i])))
        << "body " << i;
  EXPECT_EQ(x.final_position_m, y.final_position_m);
  EXPECT_EQ(x.final_velocity_m_s, y.final_velocity_m_s);
  EXPECT_EQ(x.final_angular_velocity_rad_s, y.final_angular_velocity_rad_s);
}

TEST(SimBadInput, ErrorsNameTheBodyFieldAndValue) {
  SimBodyDesc box = makeBox("cube", {0.05, 0.05, 0.05}, 0.1);
  box.position_m = {0, 0, 0.5};
  {
    SimBodyDesc bad = box;
    bad.velocity_m_s[1] = std::nan("");
    auto r = simulate({box, bad}, settingsFor(0.1));
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().kind, ErrorKind::BadInput);
    EXPECT_NE(r.error().message.find("body 1 \"cube\""), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find("velocity_m_s[1] = nan"), std::string::npos) << r.error().message;
  }
  {
    SimBodyDesc bad = box;
    bad.name = "weightless";
    bad.mass_kg = 0.0;
    auto r = simulate({bad}, settingsFor(0.1));
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().kind, ErrorKind::BadInput);
    EXPECT_NE(r.error().message.find("body 0 \"weightless\""), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find("mass_kg = 0"), std::string::npos) << r.error().message;
  }
  {
    SimSettings settings = settingsFor(0.1);
    settings.substep_s = 2e-3;
    auto r = simulate({box}, settings);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("substep_s = 0.002"), std::string::npos) << r.error().message;
  }
  {
    SimSettings settings = settingsFor(0.1);
    settings.impact_speed_m_s = -1.0;
    auto r = simulate({box}, settings);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("impact_speed_m_s = -1"), std::string::npos) << r.error().message;
  }
  {
    SimBodyDesc bad = box;
    bad.orientation_wxyz = {1, 0.1, 0, 0};
    auto r = simulate({bad}, settingsFor(0.1));
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("orientation_wxyz"), std::string::npos) << r.error().message;
    bad.orientation_wxyz = {1.0004, 0, 0, 0};  // close enough: normalized
    EXPECT_TRUE(simulate({bad}, settingsFor(0.01)).ok());
  }
  {
    SimBodyDesc bad = box;
    bad.surface_triangles.clear();
    auto r = simulate({bad}, settingsFor(0.1));
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("empty geometry"), std::string::npos) << r.error().message;
  }
  {
    SimSettings settings = settingsFor(0.0);
    auto r = simulate({box}, settings);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("duration_s = 0"), std::string::npos) << r.error().message;
  }
  {
    SimBodyDesc bad = box;
    bad.inertia_kg_m2[4] = std::numeric_limits<double>::infinity();
    auto r = simulate({bad}, settingsFor(0.1));
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("inertia_kg_m2[4] = inf"), std::string::npos) << r.error().message;
  }
}

// Memory cap: a run that records more contact events than SimSettings::max_events stops with a
// message that names the cap and the flag that raises it.
TEST(Sim, ContactEventCapNamesTheFlag) {
  SimBodyDesc box = makeBox("block", {0.1, 0.1, 0.05}, 1.0);
  box.position_m = {0, 0, 0.1};
  SimSettings settings;
  settings.duration_s = 1.0;
  settings.max_events = 3;
  Result<SimResult> r = simulate({box}, settings);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, ErrorKind::BadInput);
  EXPECT_NE(r.error().message.find("more than 3 contact events"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("--max-events"), std::string::npos) << r.error().message;
  settings.max_events = SimSettings{}.max_events;
  EXPECT_TRUE(simulate({box}, settings).ok());
}

/// Radius of the sphere the simulator puts in a geodesic mesh's place: the sphere of equal volume.
double volumeRadius(const SimBodyDesc& body) {
  double six_v = 0.0;
  const auto& x = body.surface_positions;
  for (size_t t = 0; t < body.surface_triangles.size(); t += 3) {
    const double* a = &x[3 * body.surface_triangles[t]];
    const double* b = &x[3 * body.surface_triangles[t + 1]];
    const double* c = &x[3 * body.surface_triangles[t + 2]];
    six_v += dot({a[0], a[1], a[2]}, cross({b[0], b[1], b[2]}, {c[0], c[1], c[2]}));
  }
  return std::cbrt(std::abs(six_v) / 6.0 * 3.0 / (4.0 * M_PI));
}

/// The impacts of a run (contacts closing faster than the impact speed), first of each substep.
std::vector<ContactEvent> impacts(const SimResult& r, const SimSettings& settings) {
  std::vector<ContactEvent> out;
  for (const ContactEvent& e : r.events) {
    if (e.normal_speed_m_s <= settings.impact_speed_m_s) continue;
    if (out.empty() || e.step_time_s > out.back().step_time_s + 1.5 * settings.substep_s) out.push_back(e);
  }
  return out;
}

// Dropped from rest with its lowest point at height h, a ball meets the ground at sqrt(2 h / g).
// The heights put that moment at tenths of the 1 ms step: an event stamped with its substep is
// up to a step late (and Bullet's integrator, started from the scene's velocity, is half a step
// early); the estimate within the step must hit it to a small fraction of the step.
TEST(SimImpactTime, DropFromRestMeetsTheGroundAtTheClosedFormTime) {
  const SimBodyDesc ball_shape = makeSphere("ball", 0.02, 0.26);
  const double radius = volumeRadius(ball_shape);
  double worst_stamp = 0.0, worst_step = 0.0;
  for (double fraction : {0.05, 0.25, 0.5, 0.75, 0.95}) {
    const SimSettings settings = settingsFor(0.2);
    const double t_meet = 0.150 + fraction * settings.substep_s;
    const double h = 0.5 * kG * t_meet * t_meet;
    SimBodyDesc ball = ball_shape;
    ball.position_m = {0, 0, h + radius};
    const SimResult r = run({ball}, settings, "ball dropped from rest");
    ASSERT_EQ(r.shape_used[0], SimBodyDesc::Shape::ConvexHull);  // Bullet's sphere (makeSphere)
    const std::vector<ContactEvent> hits = impacts(r, settings);
    ASSERT_FALSE(hits.empty());
    const ContactEvent& first = hits.front();
    std::printf("[ impact   ] h = %.4f m: closed form %.6f s, stamped %.6f s (%+.2f us), step %.3f s (%+.1f us)\n", h,
                t_meet, first.time_s, 1e6 * (first.time_s - t_meet), first.step_time_s,
                1e6 * (first.step_time_s - t_meet));
    EXPECT_NEAR(first.time_s, t_meet, 0.05e-3) << "h = " << h;
    EXPECT_NEAR(first.point_world[2], 0.0, 1e-5) << "placed where the surfaces met";
    EXPECT_NEAR(first.normal_speed_m_s, kG * t_meet, 0.01 * kG * t_meet);
    worst_stamp = std::max(worst_stamp, std::abs(first.time_s - t_meet));
    worst_step = std::max(worst_step, std::abs(first.step_time_s - t_meet));
  }
  // The substep's own time misses by most of a step at some height: the test can tell.
  EXPECT_GT(worst_step, 0.5e-3);
  std::printf("[ impact   ] worst error: stamped %.2f us, substep start %.1f us\n", 1e6 * worst_stamp,
              1e6 * worst_step);
}

// Two balls of equal mass meet head-on without gravity: they touch when the gap between their
// surfaces has closed at the relative speed, and part with the momentum-conserving velocities
// of restitution e (the pair's, set for the two), v_a,b = v_mean -/+ e (v_a - v_b) / 2. Both bodies carry the
// bounce from that moment, so their positions at the end are the closed form's too.
TEST(SimImpactTime, HeadOnBallsMeetAndPartAtTheClosedFormTime) {
  SimBodyDesc a = makeSphere("a", 0.02, 0.26), b = makeSphere("b", 0.02, 0.26);
  const double radius = volumeRadius(a), e = 0.5, va = 1.3, vb = -1.1, end = 0.2;
  a.position_m = {-0.1, 0, 0.5};
  b.position_m = {0.1, 0, 0.5};
  a.velocity_m_s = {va, 0, 0};
  b.velocity_m_s = {vb, 0, 0};
  SimSettings settings = settingsFor(end);
  settings.gravity_m_s2 = {0, 0, 0};
  settings.ground = false;
  settings.contact_pairs.push_back({0, 1, e, NAN});
  const SimResult r = run({a, b}, settings, "balls head-on");
  ASSERT_EQ(r.events.size(), 1u);
  const double t_meet = (0.2 - 2 * radius) / (va - vb);
  EXPECT_NEAR(r.events[0].time_s, t_meet, 1e-6);
  EXPECT_GT(std::abs(r.events[0].step_time_s - t_meet), 0.1e-3);  // half-way through its step
  const double mean = 0.5 * (va + vb), after_a = mean - 0.5 * e * (va - vb), after_b = mean + 0.5 * e * (va - vb);
  EXPECT_NEAR(r.final_velocity_m_s[0][0], after_a, 1e-9);
  EXPECT_NEAR(r.final_velocity_m_s[1][0], after_b, 1e-9);
  EXPECT_NEAR(r.final_position_m[0][0], -0.1 + va * t_meet + after_a * (end - t_meet), 1e-8);
  EXPECT_NEAR(r.final_position_m[1][0], 0.1 + vb * t_meet + after_b * (end - t_meet), 1e-8);
}

/// Times of a ball's impacts on the ground, for `settings` (restitution e of the ball-ground pair,
/// however set): the first at t1 = sqrt(2 h / g), then after each flight of 2 v_k / g,
/// v_k = e^k sqrt(2 g h): the intervals shrink by e. Each interval must match to 0.05 ms.
void expectBounceIntervals(SimBodyDesc ball, SimSettings settings, double e, const char* label) {
  const double h = 0.1;
  ball.position_m = {0, 0, h + volumeRadius(ball)};
  const SimResult r = run({ball}, settings, label);
  const std::vector<ContactEvent> hits = impacts(r, settings);
  ASSERT_GE(hits.size(), 4u) << label;
  double t = std::sqrt(2 * h / kG), v = std::sqrt(2 * kG * h);
  EXPECT_NEAR(hits[0].time_s, t, 0.05e-3) << label;
  for (size_t k = 1; k < 4; ++k) {
    const double interval = 2 * e * v / kG;
    v *= e;
    t += interval;
    std::printf("[ bounce   ] %s: interval %zu: closed form %.6f s, stamped %.6f s, substeps %.6f s\n", label, k,
                interval, hits[k].time_s - hits[k - 1].time_s, hits[k].step_time_s - hits[k - 1].step_time_s);
    EXPECT_NEAR(hits[k].time_s - hits[k - 1].time_s, interval, 0.05e-3) << label << ": interval " << k;
    EXPECT_NEAR(hits[k].time_s, t, 0.1e-3) << label << ": impact " << k;
    // Its speed at the start of the substep is within a step of gravity of the closed form.
    EXPECT_NEAR(hits[k].normal_speed_m_s, v, 2 * kG * settings.substep_s) << label << ": impact " << k;
  }
}

// Bullet alone bounces a ball found 0.6 mm above the ground 0.6 m/s slower and from there (see
// Simulation::timeImpacts). The pair's restitution set for ball and ground wins over the bodies' own.
TEST(SimImpactTime, BounceIntervalsShrinkByTheRestitution) {
  SimBodyDesc ball = makeSphere("ball", 0.02, 0.26);
  ball.restitution = 0.3;
  SimSettings settings = settingsFor(1.0);
  settings.ground_restitution = 0.2;
  settings.contact_pairs.push_back({0, kGroundBody, 0.8, NAN});
  expectBounceIntervals(ball, settings, 0.8, "pair e = 0.8");
}

// A material's restitution is that of the material on itself: two bodies of equal restitution
// bounce with it, whatever their compliances (Bullet's product gave 0.7 x 0.7 = 0.49: a steel
// ball on a glass plate stopped after 4 bounces in 0.46 s).
TEST(SimContact, EqualRestitutionsBounceWithThatRestitution) {
  SimBodyDesc ball = makeSphere("ball", 0.02, 0.26);
  ball.restitution = 0.7;
  ball.compliance_per_pa = (1 - 0.29 * 0.29) / 2e11;  // steel
  SimSettings settings = settingsFor(1.2);
  settings.ground_restitution = 0.7;
  settings.ground_compliance_per_pa = (1 - 0.22 * 0.22) / 7e10;  // glass
  expectBounceIntervals(ball, settings, 0.7, "0.7 on 0.7");
}

// The combination rules' limits and fixed points (sim.hpp, combineContact).
TEST(SimContact, CombinationRules) {
  const ContactSide steel{0.6, 0.4, (1 - 0.29 * 0.29) / 2e11}, glass{0.7, 0.4, (1 - 0.22 * 0.22) / 7e10};
  // Same coefficients: the pair has them (any compliances).
  EXPECT_NEAR(combineContact({0.7, 0.4, 1e-11}, {0.7, 0.4, 5e-10}).restitution, 0.7, 1e-12);
  EXPECT_NEAR(combineContact(steel, {0.6, 0.4, 1e-9}).friction, 0.4, 1e-12);
  // A body far more compliant than the other decides: rubber (E 5 MPa) on concrete (30 GPa).
  const ContactSide rubber{0.8, 0.9, (1 - 0.49 * 0.49) / 5e6}, concrete{0.4, 0.6, (1 - 0.2 * 0.2) / 3e10};
  EXPECT_NEAR(combineContact(rubber, concrete).restitution, 0.8, 1e-3);
  // Equal compliances: the mean energy loss, e^2 = (e1^2 + e2^2) / 2.
  EXPECT_NEAR(combineContact({0.6, 0.4, 1e-11}, {0.8, 0.4, 1e-11}).restitution, std::sqrt(0.5), 1e-12);
  // Symmetric; the pair's restitution lies between the two.
  const ContactCoefficients sg = combineContact(steel, glass), gs = combineContact(glass, steel);
  EXPECT_EQ(sg.restitution, gs.restitution);
  EXPECT_GT(sg.restitution, 0.6);
  EXPECT_LT(sg.restitution, 0.7);
  // Friction: the geometric mean; zero on either side makes the pair frictionless.
  EXPECT_NEAR(combineContact({0.5, 0.9, 0}, {0.5, 0.4, 0}).friction, 0.6, 1e-12);
  EXPECT_EQ(combineContact({0.5, 0.0, 0}, {0.5, 0.4, 0}).friction, 0.0);
}

// Friction of a pair: a box sliding on the ground at v0 stops after v0^2 / (2 mu g) (Coulomb).
// The pair's friction set for box and ground wins over the bodies' own (0.1 and 0.9 here).
TEST(SimContact, SlidingBoxStopsAtTheCoulombDistance) {
  SimBodyDesc box = makeBox("block", {0.1, 0.1, 0.05}, 1.0);
  box.position_m = {0, 0, 0.025};
  const double v0 = 1.0, mu = 0.3;
  box.velocity_m_s = {v0, 0, 0};
  box.friction = 0.1;
  SimSettings settings = settingsFor(1.0);
  settings.ground_friction = 0.9;
  settings.contact_pairs.push_back({0, kGroundBody, NAN, mu});
  const SimResult r = run({box}, settings, "sliding box");
  const double distance = v0 * v0 / (2 * mu * kG);
  std::printf("[ slide    ] stopped after %.4f m, Coulomb %.4f m\n", r.final_position_m[0][0], distance);
  EXPECT_NEAR(r.final_position_m[0][0], distance, 0.01 * distance);
}

TEST(SimIslands, ABodyMovesTheSameToTheBitWhateverTouchesNothingOfIt) {
  // Bodies linked by no contact are separate islands, each solved to the residual threshold on its
  // own (Simulation::build): a box sliding to rest on the ground records the same events, to the
  // bit, with or without a second box resting on the ground elsewhere. (Solved in one batch, the
  // slowly converging resting box kept the sliding one iterating: other last bits.)
  SimBodyDesc slider = makeBox("slider", {0.1, 0.1, 0.05}, 1.0);
  slider.position_m = {0, 0, 0.025};
  slider.velocity_m_s = {1.0, 0, 0};
  slider.friction = 0.3;
  SimBodyDesc rester = makeBox("rester", {0.12, 0.08, 0.004}, 0.3);
  rester.position_m = {0, 1.0, 0.01};
  rester.friction = 0.3;
  const SimResult alone = run({slider}, settingsFor(1.0), "sliding box alone");
  const SimResult beside = run({slider, rester}, settingsFor(1.0), "sliding box, box beside");
  std::vector<ContactEvent> of_slider;
  for (const ContactEvent& e : beside.events)
    if (e.body_a == 0) of_slider.push_back(e);
  ASSERT_GT(alone.events.size(), 100u);
  ASSERT_GT(beside.events.size(), of_slider.size());  // the second box did touch the ground
  ASSERT_EQ(alone.events.size(), of_slider.size());
  for (size_t k = 0; k < of_slider.size(); ++k) {
    const ContactEvent& x = alone.events[k];
    const ContactEvent& y = of_slider[k];
    ASSERT_TRUE(x.time_s == y.time_s && x.point_a_mesh == y.point_a_mesh && x.normal_world == y.normal_world &&
                x.impulse_on_a_mesh == y.impulse_on_a_mesh && x.slip_velocity_m_s == y.slip_velocity_m_s)
        << "event " << k << " differs";
  }
  EXPECT_EQ(alone.final_position_m[0], beside.final_position_m[0]);
}

}  // namespace
}  // namespace strike
