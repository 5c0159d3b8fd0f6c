// SPDX-License-Identifier: MIT
// Rolling resistance and the contact state of events (strike_bullet), against closed forms:
// a rolling sphere's stopping distance and time, the slip of a sliding block, the rolling speed of
// a rolling ball, and the Hertz patch of a resting sphere.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "bodies.hpp"
#include "strike/sim/sim.hpp"

namespace strike {
namespace {

using namespace sim_bodies;

constexpr double kSteelCompliance = (1 - 0.29 * 0.29) / 2e11;  // (1 - nu^2) / E, 1/Pa
constexpr double kGlassCompliance = (1 - 0.22 * 0.22) / 7e10;

/// Volume enclosed by a closed triangle mesh (divergence theorem), m^3.
double volume(const SimBodyDesc& body) {
  double v = 0.0;
  const auto& p = body.surface_positions;
  for (size_t t = 0; t < body.surface_triangles.size(); t += 3) {
    const Vec3 a{p[3 * body.surface_triangles[t]], p[3 * body.surface_triangles[t] + 1],
                 p[3 * body.surface_triangles[t] + 2]};
    const Vec3 b{p[3 * body.surface_triangles[t + 1]], p[3 * body.surface_triangles[t + 1] + 1],
                 p[3 * body.surface_triangles[t + 1] + 2]};
    const Vec3 c{p[3 * body.surface_triangles[t + 2]], p[3 * body.surface_triangles[t + 2] + 1],
                 p[3 * body.surface_triangles[t + 2] + 2]};
    v += dot(a, cross(b, c)) / 6.0;
  }
  return v;
}

/// A geodesic sphere as the simulator sees it: Bullet's sphere of the mesh's volume (shapes.cpp).
struct Sphere {
  SimBodyDesc body;
  double radius_m;  ///< of the sphere of equal volume, Bullet's radius
};
Sphere sphere(double nominal_radius_m, double mass_kg) {
  Sphere s{makeSphere("ball", nominal_radius_m, mass_kg, 3), 0.0};
  s.radius_m = std::cbrt(3.0 * volume(s.body) / (4.0 * M_PI));
  s.body.position_m = {0, 0, s.radius_m};
  s.body.compliance_per_pa = kSteelCompliance;
  return s;
}

SimSettings flatGround(double duration_s) {
  SimSettings s;
  s.duration_s = duration_s;
  s.gravity_m_s2 = {0, 0, -kG};
  s.ground_friction = 0.5;
  s.ground_compliance_per_pa = kGlassCompliance;
  return s;
}

Result<SimResult> simulateOrFail(const std::vector<SimBodyDesc>& bodies, const SimSettings& settings) {
  Result<SimResult> r = simulate(bodies, settings);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r;
}

// A solid sphere launched rolling without slip (v0, omega0 = v0 / r) on flat ground.
// Rolling resistance c: Bullet resists the rolling with a torque c R N about the contact (R the
// sphere's radius, N = m g; contact_state.cpp). With the friction force F at the contact keeping
// v = omega R: m dv/dt = -F and I domega/dt = F R - c R N, so
//   dv/dt = -c g / (1 + I / (m R^2))  (= -(5/7) c g for a uniform sphere, I = 2/5 m R^2),
// and the sphere stops after t = v0 (1 + I/(m R^2)) / (c g) and d = v0^2 (1 + I/(m R^2)) / (2 c g)
// (7 v0 / (5 c g) and 7 v0^2 / (10 c g)). Tolerance 1%: the distance is exact to a substep's
// travel, and the torque limit acts per substep on Bullet's half-step-old velocities.
TEST(SimRolling, SphereStopsAtTheRollingResistanceDistanceAndTime) {
  const double c = 0.02, v0 = 0.3, mass = 0.26;
  Sphere s = sphere(0.02, mass);
  s.body.rolling_resistance = c;
  s.body.velocity_m_s = {v0, 0, 0};
  s.body.angular_velocity_rad_s = {0, v0 / s.radius_m, 0};
  SimSettings settings = flatGround(3.0);
  settings.ground_rolling_resistance = c;
  settings.record_states = true;
  const Result<SimResult> r = simulateOrFail({s.body}, settings);
  ASSERT_TRUE(r.ok());
  const double inertia_factor = 1.0 + s.body.inertia_kg_m2[0] / (mass * s.radius_m * s.radius_m);  // ~7/5
  const double distance = v0 * v0 * inertia_factor / (2 * c * kG);
  const double time = v0 * inertia_factor / (c * kG);
  double stopped_at = NAN;
  for (size_t k = 0; k < r->states.size(); ++k) {
    const Vec3& v = r->states[k].velocity_m_s;
    if (std::hypot(v[0], v[1]) < 1e-3) {
      stopped_at = double(k + 1) * settings.substep_s;
      break;
    }
  }
  std::printf("[ rolling  ] 1 + I/(m R^2) = %.5f; stopped after %.4f m in %.4f s; closed form %.4f m in %.4f s\n",
              inertia_factor, r->final_position_m[0][0], stopped_at, distance, time);
  EXPECT_NEAR(r->final_position_m[0][0], distance, 0.01 * distance);
  EXPECT_NEAR(stopped_at, time, 0.01 * time);
  EXPECT_NEAR(r->final_position_m[0][1], 0.0, 1e-6);
}

// The old behaviour, kept when the coefficient is 0: a sphere rolls on at its launch speed (no
// resistance but the solver's), so the test above measures the rolling resistance, not a loss of
// Bullet's own.
TEST(SimRolling, WithoutRollingResistanceASphereRollsOn) {
  const double v0 = 0.3;
  Sphere s = sphere(0.02, 0.26);
  s.body.velocity_m_s = {v0, 0, 0};
  s.body.angular_velocity_rad_s = {0, v0 / s.radius_m, 0};
  const Result<SimResult> r = simulateOrFail({s.body}, flatGround(3.0));
  ASSERT_TRUE(r.ok());
  std::printf("[ rolling  ] without rolling resistance: %.4f m in 3 s at %.4f m/s\n", r->final_position_m[0][0],
              r->final_velocity_m_s[0][0]);
  EXPECT_NEAR(r->final_velocity_m_s[0][0], v0, 1e-3 * v0);
  EXPECT_NEAR(r->final_position_m[0][0], 3.0 * v0, 1e-3 * 3.0 * v0);
}

// Spinning friction: a sphere spinning about the vertical on the ground, not rolling. Coulomb
// friction over its Hertz patch (radius a under m g) resists with the torque (3 pi / 16) mu m g a
// [Johnson 1985, sec. 7.4], so omega falls linearly at that torque / I: half of omega0 is left
// after t = I omega0 / (2 (3 pi / 16) mu m g a). Bullet applies it only where rolling friction is
// on, hence a rolling resistance here (it has no effect on a sphere that does not roll).
TEST(SimRolling, SpinningSphereSpinsDownAtTheHertzPatchTorque) {
  const double mass = 0.26, mu = 0.5, omega0 = 2.0;
  Sphere s = sphere(0.02, mass);
  s.body.rolling_resistance = 0.001;
  s.body.friction = mu;
  s.body.angular_velocity_rad_s = {0, 0, omega0};
  SimSettings settings = flatGround(1.0);
  settings.ground_friction = mu;
  settings.ground_rolling_resistance = 0.001;
  const double a = std::cbrt(3.0 * mass * kG * s.radius_m * (kSteelCompliance + kGlassCompliance) / 4.0);
  const double torque = 3.0 * M_PI / 16.0 * mu * mass * kG * a;
  settings.duration_s = std::round(s.body.inertia_kg_m2[8] * omega0 / (2.0 * torque) / 1e-3) * 1e-3;
  const Result<SimResult> r = simulateOrFail({s.body}, settings);
  ASSERT_TRUE(r.ok());
  const double expected = omega0 - torque / s.body.inertia_kg_m2[8] * settings.duration_s;
  std::printf("[ spinning ] after %.3f s: omega %.4f rad/s, closed form %.4f rad/s (patch %.3e m)\n",
              settings.duration_s, r->final_angular_velocity_rad_s[0][2], expected, a);
  EXPECT_NEAR(r->final_angular_velocity_rad_s[0][2], expected, 0.02 * omega0);
  EXPECT_NEAR(r->final_position_m[0][0], 0.0, 1e-6);  // it spins in place
}

// Combination: the compliance-weighted mean (sim.hpp, combineContact).
TEST(SimRolling, CombinationRule) {
  // One material on itself keeps its own value, whatever the compliances.
  EXPECT_NEAR(combineContact({0.5, 0.5, 1e-11, 0.003}, {0.5, 0.5, 4e-10, 0.003}).rolling_resistance, 0.003, 1e-15);
  // Equal compliances: the mean.
  EXPECT_NEAR(combineContact({0.5, 0.5, 1e-11, 0.001}, {0.5, 0.5, 1e-11, 0.011}).rolling_resistance, 0.006, 1e-15);
  // A steel ball on rubber (E 5 MPa, nu 0.49) rolls as on rubber: the rubber takes 99.998% of the
  // deformation.
  const double rubber = (1 - 0.49 * 0.49) / 5e6;
  const double pair = combineContact({0.6, 0.4, kSteelCompliance, 0.001}, {0.8, 0.9, rubber, 0.01}).rolling_resistance;
  EXPECT_NEAR(pair, (kSteelCompliance * 0.001 + rubber * 0.01) / (kSteelCompliance + rubber), 1e-15);
  EXPECT_GT(pair, 0.00999);
}

/// The events of one body with the ground in the substep starting at time_s.
std::vector<ContactEvent> stepEvents(const SimResult& r, double step_time_s) {
  std::vector<ContactEvent> out;
  for (const ContactEvent& e : r.events)
    if (std::abs(e.step_time_s - step_time_s) < 1e-9 && e.body_b == kGroundBody) out.push_back(e);
  return out;
}

// A block sliding on the ground at v0 decelerates at mu g (Coulomb): its contacts slip at
// v(t) = v0 - mu g t along +x, the contact points travel with the block (0 over its surface, v
// over the ground: no rolling), and the normal impulses add up to m g per second. Bullet's box
// chatters as it slides (one substep on one corner, the next on four, 2-18 N in all), pitching at
// up to ~0.1 rad/s (its bottom corners move +-2.5 mm/s about its centre) and yawing (a corner
// slips up to 1.2% of v0 sideways): hence each event's slip against the closed form (v, 0, 0)
// within 2% of v0 per component, and m g as the mean over 0.25 s within 1%.
TEST(SimContactState, SlidingBlockSlipsAtItsSpeed) {
  SimBodyDesc box = makeBox("block", {0.1, 0.1, 0.05}, 1.0);
  box.position_m = {0, 0, 0.025};
  const double v0 = 1.0, mu = 0.3;
  box.velocity_m_s = {v0, 0, 0};
  box.friction = mu;
  SimSettings settings = flatGround(0.4);
  settings.ground_friction = mu;
  const Result<SimResult> r = simulateOrFail({box}, settings);
  ASSERT_TRUE(r.ok());
  const double dt = settings.substep_s, from = 0.05, to = 0.3;
  double impulse = 0.0, worst_closed_form = 0.0;
  size_t checked = 0;
  for (const ContactEvent& e : r->events) {
    if (e.step_time_s < from - 1e-9 || e.step_time_s > to - 0.5 * dt) continue;
    const double v = v0 - mu * kG * (e.step_time_s + dt);
    EXPECT_NEAR(e.slip_velocity_m_s[0], v, 0.02 * v0) << "t = " << e.step_time_s;
    EXPECT_NEAR(e.slip_velocity_m_s[1], 0.0, 0.02 * v0) << "t = " << e.step_time_s;
    EXPECT_NEAR(e.slip_velocity_m_s[2], 0.0, 1e-9);
    worst_closed_form =
        std::max({worst_closed_form, std::abs(e.slip_velocity_m_s[0] - v), std::abs(e.slip_velocity_m_s[1])});
    EXPECT_LT(e.track_speed_a_m_s, 1e-3 * v0);
    EXPECT_NEAR(e.track_speed_b_m_s, std::hypot(e.slip_velocity_m_s[0], e.slip_velocity_m_s[1]), 1e-12);
    EXPECT_LT(e.rolling_speed_m_s, 1e-3 * v0);
    impulse += e.normal_impulse_n_s;
    EXPECT_NEAR(e.normal_force_n, e.normal_impulse_n_s / dt, 1e-12);
    ++checked;
  }
  const double mean_force = impulse / (to - from);
  std::printf("[ slide    ] %zu events: slip within %.2e m/s of v0 - mu g t; mean normal force %.4f N, m g %.4f N\n",
              checked, worst_closed_form, mean_force, box.mass_kg * kG);
  EXPECT_GT(checked, 250u);
  EXPECT_NEAR(mean_force, box.mass_kg * kG, 0.01 * box.mass_kg * kG);
}

// A ball rolling without slip at v (no rolling resistance): no slip, and the contact point
// travels at v over both the ball and the ground.
TEST(SimContactState, RollingBallRollsWithoutSlip) {
  const double v0 = 0.3;
  Sphere s = sphere(0.02, 0.26);
  s.body.velocity_m_s = {v0, 0, 0};
  s.body.angular_velocity_rad_s = {0, v0 / s.radius_m, 0};
  const SimSettings settings = flatGround(0.5);
  const Result<SimResult> r = simulateOrFail({s.body}, settings);
  ASSERT_TRUE(r.ok());
  size_t checked = 0;
  for (const ContactEvent& e : r->events) {
    if (e.step_time_s < 0.1 || e.body_b != kGroundBody) continue;
    EXPECT_LT(std::sqrt(dot(e.slip_velocity_m_s, e.slip_velocity_m_s)), 1e-3 * v0) << "t = " << e.time_s;
    EXPECT_NEAR(e.rolling_speed_m_s, v0, 1e-3 * v0) << "t = " << e.time_s;
    EXPECT_NEAR(e.track_speed_a_m_s, v0, 1e-3 * v0);
    EXPECT_NEAR(e.track_speed_b_m_s, v0, 1e-3 * v0);
    ++checked;
  }
  EXPECT_GT(checked, 300u);
}

// A steel sphere resting on glass: one contact carrying m g, whose patch radius is Hertz's
// a = (3 F R* / (4 E*))^(1/3) with F = m g, R* = R (the ground is flat) and 1/E* = the sum of
// (1 - nu^2) / E [Johnson 1985, eqs. 4.22-4.23]: 8.9e-5 m for a 2 cm, 0.26 kg ball.
TEST(SimContactState, RestingSpherePatchIsHertzUnderItsWeight) {
  const double mass = 0.26;
  Sphere s = sphere(0.02, mass);
  const Result<SimResult> r = simulateOrFail({s.body}, flatGround(0.3));
  ASSERT_TRUE(r.ok());
  const double weight = mass * kG;
  const double hertz = std::cbrt(3.0 * weight * s.radius_m * (kSteelCompliance + kGlassCompliance) / 4.0);
  size_t checked = 0;
  for (double t = 0.1; t < 0.29; t += 0.01) {
    const std::vector<ContactEvent> events = stepEvents(*r, std::round(t / 1e-3) * 1e-3);
    ASSERT_EQ(events.size(), 1u) << "t = " << t;
    EXPECT_NEAR(events[0].normal_force_n, weight, 1e-3 * weight);
    EXPECT_NEAR(events[0].patch_radius_m, hertz, 1e-3 * hertz);
    ++checked;
  }
  std::printf("[ hertz    ] resting patch radius %.4e m, Hertz %.4e m\n", stepEvents(*r, 0.2)[0].patch_radius_m, hertz);
  EXPECT_GT(checked, 10u);
  // The function itself: flat on flat, unknown stiffness and no load give no patch.
  EXPECT_EQ(hertzPatchRadius(1.0, 0.0, 0.0, 1e-11, 1e-11), 0.0);
  EXPECT_EQ(hertzPatchRadius(1.0, 0.01, 0.0, 0.0, 0.0), 0.0);
  EXPECT_EQ(hertzPatchRadius(0.0, 0.01, 0.0, 1e-11, 1e-11), 0.0);
}

// Marbles on a static steel plate, 3 cm apart, never touching: the first lies still, the others
// roll past it; and two blocks slide side by side, 2 cm apart, down a tilted plank. Each body's
// motion is its own: run together, each must move exactly (to the bit) as it does alone, and the
// still marble must fall asleep when it would alone. (Bullet joined bodies whose loose broadphase
// boxes overlapped into one island: solved until the slowest converged, each result depended on
// its neighbours, and the still marble stayed awake while its neighbours rolled.)
TEST(SimContactState, BodiesApartMoveAsIfAlone) {
  SimBodyDesc plate = makeBox("plate", {0.6, 0.4, 0.006}, 10.0);
  plate.is_static = true;
  plate.position_m = {0, 0, 0.003};
  const std::array<double, 4> tilt = quaternion({0, 1, 0}, 0.5);  // 29 degrees: the blocks slide
  SimBodyDesc plank = makeBox("plank", {1.0, 0.3, 0.02}, 10.0);
  plank.is_static = true;
  plank.position_m = {1.0, 0, 0.5};
  plank.orientation_wxyz = tilt;
  std::vector<SimBodyDesc> movers;
  for (int k = 0; k < 3; ++k) {
    Sphere s = sphere(0.01, 0.03);
    const double speed = k == 0 ? 0.0 : 0.1 * k;
    s.body.position_m = {-0.2, 0.03 * k, 0.006 + s.radius_m};
    s.body.velocity_m_s = {speed, 0, 0};
    s.body.angular_velocity_rad_s = {0, speed / s.radius_m, 0};
    s.body.rolling_resistance = 0.01;
    movers.push_back(s.body);
  }
  for (int k = 0; k < 2; ++k) {
    SimBodyDesc block = makeBox("block", {0.05, 0.04, 0.03}, 0.05);
    block.orientation_wxyz = tilt;
    // On the plank's upper face (its normal is the tilt's z axis), 2 cm apart across it.
    const double lift = 0.01 + 0.015 + 1e-4, s = std::sin(0.5), c = std::cos(0.5);
    block.position_m = {1.0 - 0.3 * c + lift * s, -0.035 + 0.07 * k, 0.5 + 0.3 * s + lift * c};
    block.friction = 0.3;
    movers.push_back(block);
  }
  SimSettings settings = flatGround(1.0);
  settings.end_when_all_asleep = false;
  std::vector<SimBodyDesc> together{plate, plank};
  together.insert(together.end(), movers.begin(), movers.end());
  const Result<SimResult> all = simulateOrFail(together, settings);
  ASSERT_TRUE(all.ok());
  for (size_t k = 0; k < movers.size(); ++k) {
    const Result<SimResult> alone = simulateOrFail({plate, plank, movers[k]}, settings);
    ASSERT_TRUE(alone.ok());
    EXPECT_EQ(all->final_position_m[k + 2], alone->final_position_m[2]) << "body " << k;
    EXPECT_EQ(all->final_velocity_m_s[k + 2], alone->final_velocity_m_s[2]) << "body " << k;
    EXPECT_EQ(all->final_angular_velocity_rad_s[k + 2], alone->final_angular_velocity_rad_s[2]) << "body " << k;
    std::vector<double> impulses_all, impulses_alone;
    for (const ContactEvent& e : all->events)
      if (e.body_a == k + 2 || e.body_b == k + 2) impulses_all.push_back(e.normal_impulse_n_s);
    for (const ContactEvent& e : alone->events) impulses_alone.push_back(e.normal_impulse_n_s);
    EXPECT_EQ(impulses_all, impulses_alone) << "body " << k;
    EXPECT_GT(impulses_alone.size(), 200u) << "body " << k;  // it touched throughout
    if (k >= 3) {
      EXPECT_LT(alone->final_position_m[2][2], movers[k].position_m[2] - 0.05) << "block " << k;  // it slid
    }
    if (k == 0) {
      EXPECT_NEAR(alone->sleep_start_s[2], settings.sleep_after_still_s, 0.01);
      EXPECT_EQ(all->sleep_start_s[2], alone->sleep_start_s[2]);
    }
  }
}

// A sphere on a box: the contact is the box's point nearest the sphere's centre, so the normal of
// a sphere rolling on the top face is the face's normal exactly (GJK's iterate left it 1e-15 off).
TEST(SimContactState, SphereOnABoxTouchesAlongTheFaceNormal) {
  SimBodyDesc plate = makeBox("plate", {0.6, 0.4, 0.006}, 10.0);
  plate.is_static = true;
  plate.position_m = {0, 0, 0.003};
  Sphere s = sphere(0.01, 0.03);
  s.body.position_m = {-0.2, 0.01, 0.006 + s.radius_m};
  s.body.velocity_m_s = {0.2, 0.05, 0};
  s.body.angular_velocity_rad_s = {-0.05 / s.radius_m, 0.2 / s.radius_m, 0};
  const Result<SimResult> r = simulateOrFail({plate, s.body}, flatGround(0.3));
  ASSERT_TRUE(r.ok());
  size_t on_plate = 0;
  for (const ContactEvent& e : r->events) {
    ASSERT_EQ(e.body_a, 0u);
    ASSERT_EQ(e.body_b, 1u);
    EXPECT_EQ(e.normal_world[0], 0.0);
    EXPECT_EQ(e.normal_world[1], 0.0);
    EXPECT_NEAR(std::abs(e.normal_world[2]), 1.0, 1e-15);
    ++on_plate;
  }
  EXPECT_GT(on_plate, 250u);
}

}  // namespace
}  // namespace strike
