// SPDX-License-Identifier: MIT
// Rolling and sliding sound end to end: Bullet's contacts, the contact state, the
// rough-contact generators and the oscillator banks, through renderScene().
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "render_helpers.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike {
namespace {

using render_helpers::renderCached;
using render_helpers::rms;

std::string cacheDir() { return testing::TempDir() + "/rolling-sound-" + std::to_string(static_cast<long>(getpid())); }

// A polished steel ball (R 12.5 mm, 64 g) rolling at 0.2 m/s on a static ground-steel plate;
// rolling resistance 0.1 stops it within the second. `rough` false: both surfaces smooth.
std::string ballOnPlate(bool rough) {
  const std::string plate_r = rough ? "" : R"(, "roughness_rms_m": 0)";
  const std::string ball_r = rough ? R"(, "roughness_rms_m": 2.5e-8)" : R"(, "roughness_rms_m": 0)";
  return R"({"sample_rate": 48000, "duration": 1.2, "listener": {"position": [0, -0.5, 0.3]},
    "ground": {"material": "wood"}, "max_modes": 30,
    "objects": [
      {"name": "plate", "mesh": "box:0.24,0.16,0.004", "material": "steel", "static": true,
       "position": [0, 0, 0.002])" +
         plate_r + R"(},
      {"name": "ball", "mesh": "sphere:0.0125", "material": "steel", "rolling_resistance": 0.1,
       "position": [-0.06, 0, 0.0165], "velocity": [0.2, 0, 0], "angular_velocity": [0, 16, 0])" +
         ball_r + R"(}]})";
}

RenderResult render(const std::string& text) {
  Result<Scene> scene = parseScene(text, "/tmp/rolling.json");
  EXPECT_TRUE(scene) << (scene ? "" : scene.error().message);
  return scene ? renderCached(*scene, cacheDir()) : RenderResult{};
}

TEST(RollingSound, SphereRollingOnAPlateSoundsStopsAndRadiatesLessThanItLoses) {
  const RenderResult rough = render(ballOnPlate(true)), smooth = render(ballOnPlate(false));
  ASSERT_FALSE(rough.audio.samples.empty());
  const double rate = rough.audio.sample_rate_hz;
  // At rest: the last step the ball still rolled on the plate (events carry the contact state).
  double rest_s = 0.0, v0 = 0.0;
  for (const ContactEvent& e : rough.events)
    if (e.rolling_speed_m_s > 1e-3) rest_s = std::max(rest_s, e.step_time_s), v0 = std::max(v0, e.rolling_speed_m_s);
  ASSERT_GT(rest_s, 0.3);
  ASSERT_LT(rest_s, 1.0);
  // The summary's work share counts the free modes: at most every in-band mode for every sample.
  // The copies the roll drives and the ground image's oscillators are counted apart (with them the
  // share came out over 100%).
  const RenderReport& work = rough.report;
  EXPECT_GT(work.forced_mode_samples, 0u);
  EXPECT_LE(work.forced_mode_samples + work.image_mode_samples, work.mode_samples);
  EXPECT_LE(work.mode_samples - work.forced_mode_samples - work.image_mode_samples,
            (work.modes_total - work.modes_out_of_band) * rough.audio.frames());
  // While it rolls: >= 30 dB above the render's floor (the smooth roll, or 0 dB SPL, the
  // audibility threshold, whichever is higher).
  const double level = rms(rough.audio.samples, 0.1, rest_s - 0.05, rate);
  const double floor = std::max(rms(smooth.audio.samples, 0.1, rest_s - 0.05, rate), 1e-6);
  std::printf(
      "rolling %.2f dB SPL, floor %.2f dB SPL (smooth %.3g), rest at %.3f s, rough-contact force until %.3f s, "
      "%llu samples without contact\n",
      20 * std::log10(level / 1e-6), 20 * std::log10(floor / 1e-6), rms(smooth.audio.samples, 0.1, rest_s - 0.05, rate),
      rest_s, rough.report.continuous_last_force_s, (unsigned long long)rough.report.continuous_lost_samples);
  EXPECT_GE(20 * std::log10(level / floor), 30.0);
  // It stops within 50 ms of the ball coming to rest (then the plate only rings down).
  EXPECT_GT(rough.report.continuous_last_force_s, rest_s - 0.1);
  EXPECT_LE(rough.report.continuous_last_force_s, rest_s + 0.05);
  // Energy: radiated over a sphere of the listener's distance, 4 pi d^2 int p^2 dt / (rho c),
  // below the mechanical energy lost: the rolling sphere's (7/10) m v0^2.
  const double d = std::sqrt(0.5 * 0.5 + 0.3 * 0.3), rho_c = 1.2 * 343.0;
  double p2 = 0;
  for (float s : rough.audio.samples) p2 += std::pow(double(s) * 20.0, 2) / rate;
  const double radiated = 4 * M_PI * d * d * p2 / rho_c;
  const double mass = 7850.0 * 4.0 / 3.0 * M_PI * std::pow(0.0125, 3);
  const double lost = 0.7 * mass * v0 * v0;
  std::printf("radiated %.3g J of %.3g J dissipated: ratio %.3g\n", radiated, lost, radiated / lost);
  EXPECT_LT(radiated / lost, 1.0);
  EXPECT_GT(radiated, 0.0);
  // Deterministic: the same bytes again.
  const RenderResult again = render(ballOnPlate(true));
  EXPECT_EQ(again.audio.samples, rough.audio.samples);
}

// A wood block on a static wood plank inclined by `degrees` (friction wood on wood 0.4: the
// friction angle is atan 0.4 = 21.8 degrees).
std::string blockOnIncline(double degrees) {
  const double t = degrees * M_PI / 180.0;
  const double qw = std::cos(t / 2), qy = std::sin(t / 2);
  // Plank centre (0, 0, 0.3); the block's centre 26 mm above the plank's mid-plane, 0.1 m up the slope.
  const double nx = std::sin(t), nz = std::cos(t);   // plank normal after rotating about +y
  const double ux = -std::cos(t), uz = std::sin(t);  // up the slope (towards -x)
  char text[2048];
  std::snprintf(text, sizeof text, R"({"sample_rate": 48000, "duration": 0.8, "listener": {"position": [0, -0.6, 0.4]},
    "max_modes": 30,
    "objects": [
      {"name": "plank", "mesh": "box:0.6,0.12,0.02", "material": "wood", "static": true,
       "position": [0, 0, 0.3], "orientation": [%.9f, 0, %.9f, 0]},
      {"name": "block", "mesh": "box:0.06,0.05,0.03", "material": "wood",
       "position": [%.9f, 0, %.9f], "orientation": [%.9f, 0, %.9f, 0]}]})",
                qw, qy, 0.1 * ux + 0.0255 * nx, 0.3 + 0.1 * uz + 0.0255 * nz, qw, qy);
  return text;
}

TEST(RollingSound, BlockBelowTheFrictionAngleIsSilentAboveItSlidesAudibly) {
  const RenderResult below = render(blockOnIncline(15.0)), above = render(blockOnIncline(30.0));
  ASSERT_FALSE(below.audio.samples.empty());
  const double rate = below.audio.sample_rate_hz;
  std::printf(
      "15 deg: %zu sliding contacts, force until %.3f s, rms after 0.3 s %.3g; 30 deg: %zu, rms 0.2-0.5 s %.3g, %.1f "
      "dB SPL\n",
      below.report.continuous_contacts, below.report.continuous_last_force_s, rms(below.audio.samples, 0.3, 0.8, rate),
      above.report.continuous_contacts, rms(above.audio.samples, 0.2, 0.5, rate),
      20 * std::log10(rms(above.audio.samples, 0.2, 0.5, rate) / 1e-6));
  // Below: it settles (its first steps' creep may scrape for a moment) and then makes no sound
  // at all: no drone.
  EXPECT_LT(below.report.continuous_last_force_s, 0.2);
  EXPECT_LT(rms(below.audio.samples, 0.3, 0.8, rate), 1e-6);
  // Above: it slides, and the slide is heard (>= 30 dB above 0 dB SPL).
  EXPECT_GE(above.report.continuous_contacts, 1u);
  EXPECT_GT(20 * std::log10(rms(above.audio.samples, 0.2, 0.5, rate) / 1e-6), 30.0);
  // Energy, over 0.05-0.6 s (after its first settling, before it leaves the plank's end): radiated
  // over a sphere of the listener's distance, 4 pi d^2 int p^2 dt / (rho c), below what friction
  // dissipates, sum of |friction impulse| |slip speed| over the steps' contact points.
  const double t0 = 0.05, t1 = 0.6;
  double dissipated = 0.0;
  for (const ContactEvent& e : above.events) {
    if (e.step_time_s <= t0 || e.step_time_s > t1) continue;
    const double slip =
        std::sqrt(e.slip_velocity_m_s[0] * e.slip_velocity_m_s[0] + e.slip_velocity_m_s[1] * e.slip_velocity_m_s[1] +
                  e.slip_velocity_m_s[2] * e.slip_velocity_m_s[2]);
    dissipated += e.friction_impulse_n_s * slip;
  }
  const double d = std::sqrt(0.6 * 0.6 + 0.1 * 0.1), rho_c = 1.2 * 343.0;
  double p2 = 0.0;
  for (size_t n = static_cast<size_t>(t0 * rate); n < static_cast<size_t>(t1 * rate); ++n)
    p2 += std::pow(double(above.audio.samples[n]) * 20.0, 2) / rate;
  const double radiated = 4 * M_PI * d * d * p2 / rho_c;
  std::printf("sliding: radiated %.3g J of %.3g J dissipated by friction: ratio %.3g\n", radiated, dissipated,
              radiated / dissipated);
  EXPECT_GT(dissipated, 0.0);
  EXPECT_LT(radiated / dissipated, 1.0);
}

// examples/scenes/marbles-in-bowl.json: four glass marbles launched around the wall of a ceramic
// bowl roll and clink. The simulation does not depend on roughness, so the render with every
// surface smooth has the same clinks and no rolling, and (the oscillators being linear) the
// difference of the two renders is the rolling sound alone.
TEST(RollingSound, TheMarblesInTheBowlAudiblyRoll) {
  Result<Scene> scene = loadScene(std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/marbles-in-bowl.json");
  ASSERT_TRUE(scene) << scene.error().message;
  Scene smooth_scene = *scene;
  for (SceneObject& object : smooth_scene.objects) object.roughness_rms_m = 0.0;
  RenderSettings settings;
  settings.cache_dir = cacheDir();
  settings.duration_s = 1.5;
  Result<RenderResult> rough = renderScene(*scene, settings), smooth = renderScene(smooth_scene, settings);
  ASSERT_TRUE(rough && smooth);
  ASSERT_EQ(rough->audio.samples.size(), smooth->audio.samples.size());
  const double rate = rough->audio.sample_rate_hz;
  std::vector<float> rolling(rough->audio.samples.size());
  for (size_t i = 0; i < rolling.size(); ++i) rolling[i] = rough->audio.samples[i] - smooth->audio.samples[i];
  // The premise: marbles still roll on the bowl at >= 5 cm/s after 1.2 s (the bowl is body 0).
  double rolling_until_s = 0.0;
  for (const ContactEvent& e : rough->events)
    if ((e.body_a == 0 || e.body_b == 0) && e.rolling_speed_m_s >= 0.05)
      rolling_until_s = std::max(rolling_until_s, e.step_time_s);
  const double t0 = 0.2, t1 = 1.2;  // after the launch's first landings
  const double heard = rms(rolling, t0, t1, rate), clinks = rms(smooth->audio.samples, t0, t1, rate);
  std::printf(
      "marbles roll at >= 5 cm/s until %.3f s; %.2f-%.2f s: rolling %.1f dB SPL, clinks and ring %.1f dB SPL, "
      "%zu rolling contacts\n",
      rolling_until_s, t0, t1, 20 * std::log10(std::max(heard, 1e-30) / 1e-6),
      20 * std::log10(std::max(clinks, 1e-30) / 1e-6), rough->report.continuous_contacts);
  ASSERT_GT(rolling_until_s, t1);
  // Audible: 30 dB above the threshold of hearing (0 dB SPL = 1e-6 of full scale), and not
  // buried under the clinks (within 10 dB of them over the same window).
  EXPECT_GT(20 * std::log10(heard / 1e-6), 30.0);
  EXPECT_GT(20 * std::log10(heard / clinks), -10.0);
}

}  // namespace
}  // namespace strike
