// SPDX-License-Identifier: MIT
// Scenes that come to rest and fall silent (docs/contact.md, "Rolling resistance" and "Sleep"),
// end to end through renderScene(): the simulation's sleep and the oscillators' ring-down together.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "strike/precompute/materials.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"
#include "strike/sim/sim.hpp"

namespace strike {
namespace {

std::string cacheDir() { return testing::TempDir() + "/settling-" + std::to_string(static_cast<long>(getpid())); }

/// When the last sample that is not exactly zero plays, s (0 for a render of zeros).
double lastSoundS(const AudioBuffer& audio) {
  const size_t channels = size_t(std::max(audio.channels, 1));
  for (size_t i = audio.samples.size(); i > 0; --i)
    if (audio.samples[i - 1] != 0.0f) return double((i - 1) / channels) / audio.sample_rate_hz;
  return 0.0;
}

double peak(const AudioBuffer& audio) {
  double p = 0.0;
  for (float v : audio.samples) p = std::max(p, std::abs(double(v)));
  return p;
}

// examples/scenes/marbles-in-bowl.json, 60 s: the marbles clash, gather at the bottom and the
// round-bottomed bowl rocks with them on the table until the rolling resistance of its foot
// (docs/contact.md, "Rolling resistance") has taken the rocking; then everything sleeps and the
// render is digitally silent (exact zeros). Without the bowl's rolling resistance the bowl and its
// marbles rocked to the end, 42-56 dB SPL, with 560,110 contact events. The bound from the
// materials (docs/contact.md, "How long the marbles roll"): a marble rolling at v0 under
// rolling resistance c alone stops after 7 v0 / (5 c g), 64 s for glass on ceramic at 0.45 m/s;
// friction between the touching marbles takes most of their energy far sooner, so the render must
// be silent before that time, and before 20 s. Bowl order 1 (not the scene's 2): the silence is
// the simulation's, and the order-2 solve would be most of the test's time.
TEST(Settling, TheMarblesInTheBowlFallSilent) {
  Result<Scene> loaded = loadScene(std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/marbles-in-bowl.json");
  ASSERT_TRUE(loaded) << loaded.error().message;
  Scene scene = *loaded;
  ASSERT_EQ(scene.objects[0].name, "bowl");
  scene.objects[0].order = 1;
  // The pair's rolling resistance: the compliance-weighted mean, k = (1 - nu^2) / E.
  auto compliance = [](const Material& m) { return (1.0 - m.poisson * m.poisson) / m.youngs_pa; };
  const Material& bowl = scene.objects[0].material;
  const Material& marble = scene.objects[1].material;
  const double c_bowl = builtinMaterials().contactProperties(bowl.name).rolling_resistance;
  const double c_marble = builtinMaterials().contactProperties(marble.name).rolling_resistance;
  const double c =
      (compliance(bowl) * c_bowl + compliance(marble) * c_marble) / (compliance(bowl) + compliance(marble));
  const double g = std::hypot(scene.gravity_m_s2[0], scene.gravity_m_s2[1], scene.gravity_m_s2[2]);
  double slowest_launch_m_s = INFINITY;
  for (size_t i = 1; i < scene.objects.size(); ++i) {
    const auto& v = scene.objects[i].velocity_m_s;
    slowest_launch_m_s = std::min(slowest_launch_m_s, std::hypot(v[0], v[1], v[2]));
  }
  const double rolling_resistance_stop_s = 7.0 * slowest_launch_m_s / (5.0 * c * g);
  RenderSettings settings;
  settings.cache_dir = cacheDir();
  settings.duration_s = 60.0;
  Result<RenderResult> out = renderScene(scene, settings);
  ASSERT_TRUE(out) << out.error().message;
  double last_event_s = 0.0;
  for (const ContactEvent& e : out->events) last_event_s = std::max(last_event_s, e.time_s);
  const double silent_from_s = lastSoundS(out->audio);
  std::printf(
      "marbles in the bowl: %zu contact events, the last at %.3f s; silent from %.3f s; rolling resistance alone "
      "(c = %.4g, v0 = %.3f m/s) stops a marble after %.1f s (ratio %.3f)\n",
      out->events.size(), last_event_s, silent_from_s, c, slowest_launch_m_s, rolling_resistance_stop_s,
      silent_from_s / rolling_resistance_stop_s);
  EXPECT_GT(peak(out->audio), 1e-3);
  EXPECT_LT(last_event_s, silent_from_s);  // asleep, then rung down
  EXPECT_LT(silent_from_s, rolling_resistance_stop_s);
  EXPECT_LT(silent_from_s, 20.0);
}

// On a wooden table: a glass (assets/meshes/glass.obj) set down upright 0.5 mm above it, and a
// porcelain plate (a disc 24 cm across, 1 cm thick) tilted 10 degrees, its rim 4 mm above it,
// let go. Each touches, settles and sleeps; each render is silent within 2 s. The table takes the
// automatic order (a coarse Tet10 plate, fewer unknowns than its Tet4 mesh); order 1 for the glass
// and the plate: the silence is the simulation's, and their order-2 solves took most of a minute.
TEST(Settling, AGlassAndAPlateOnATableAreSilentWithinTwoSeconds) {
  const std::string table =
      R"({"sample_rate": 48000, "duration": 4, "listener": {"position": [0, -0.7, 1.0]}, "max_modes": 40,
    "objects": [
      {"name": "table", "mesh": "box:1.0,0.6,0.03", "material": "wood", "static": true,
       "position": [0, 0, 0.735]}, )";
  const std::string glass = R"({"name": "glass", "mesh": ")" + std::string(STRIKE_SOURCE_DIR) +
                            R"(/assets/meshes/glass.obj", "material": "glass", "order": 1,
       "position": [0, 0, 0.7505]}]})";
  const std::string plate = R"({"name": "plate", "mesh": "cylinder:0.12,0.01", "material": "porcelain",
       "order": 1, "position": [0, 0, 0.78], "orientation": [0.9962, 0.0872, 0, 0]}]})";
  for (const auto& [name, object] :
       {std::pair<std::string, std::string>{"glass set down", glass}, {"plate dropped", plate}}) {
    Result<Scene> scene = parseScene(table + object, "/tmp/on-a-table.json");
    ASSERT_TRUE(scene) << scene.error().message;
    RenderSettings settings;
    settings.cache_dir = cacheDir();  // one table bank for both
    Result<RenderResult> out = renderScene(*scene, settings);
    ASSERT_TRUE(out) << out.error().message;
    const double silent_from_s = lastSoundS(out->audio);
    std::printf("%s: peak %.3g, silent from %.3f s\n", name.c_str(), peak(out->audio), silent_from_s);
    EXPECT_GT(peak(out->audio), 1e-4) << name;  // it was heard touching down
    EXPECT_LT(silent_from_s, 2.0) << name;
  }
}

// examples/scenes/coin-spin.json: a brass coin spun onto stone. It ends as Euler's disk does: it
// rolls on its rim with the contact point circling the rim ever faster as it tips flat (the
// precession rate grows as the tilt falls [Moffatt 2000, Nature 404, 833]), lands flat, sleeps,
// and its own ring is the last sound before exact silence.
TEST(Settling, ASpunCoinEndsInItsOwnWobbleThenSilence) {
  Result<Scene> scene = loadScene(std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/coin-spin.json");
  ASSERT_TRUE(scene) << scene.error().message;
  RenderSettings settings;
  settings.cache_dir = cacheDir();
  settings.duration_s = 6.0;
  Result<RenderResult> out = renderScene(*scene, settings);
  ASSERT_TRUE(out) << out.error().message;
  // The coin's contact points, step by step, as angles about its axis (mesh z).
  std::map<double, std::vector<double>> angles_by_step;
  double last_event_s = 0.0;
  for (const ContactEvent& e : out->events) {
    ASSERT_EQ(e.body_b, kGroundBody);
    angles_by_step[e.step_time_s].push_back(std::atan2(e.point_a_mesh[1], e.point_a_mesh[0]));
    last_event_s = std::max(last_event_s, e.time_s);
  }
  // The wobble ends at the last step on a single rim point; then the coin rocks on its face.
  double wobble_end_s = 0.0;
  for (const auto& [t, angles] : angles_by_step)
    if (angles.size() == 1) wobble_end_s = t;
  // The wobble: steps on one rim point, each a turn of the point around the rim.
  std::vector<std::pair<double, double>> turn_rate;  // (t, rad/s)
  const std::vector<double>* previous = nullptr;
  double previous_t = 0.0;
  for (const auto& [t, angles] : angles_by_step) {
    if (angles.size() == 1 && previous && previous->size() == 1) {
      const double turn = std::remainder(angles[0] - (*previous)[0], 2.0 * M_PI);
      turn_rate.emplace_back(t, std::abs(turn) / (t - previous_t));
    }
    previous = &angles;
    previous_t = t;
  }
  ASSERT_GT(turn_rate.size(), 100u) << "no rolling on the rim";
  auto meanRate = [&](double t0, double t1) {
    double sum = 0.0, turned = 0.0;
    for (const auto& [t, rate] : turn_rate)
      if (t >= t0 && t < t1) sum += rate, turned += 1.0;
    return turned > 0 ? sum / turned : 0.0;
  };
  const double wobble_start_s = turn_rate.front().first;
  const double early = meanRate(wobble_start_s, wobble_start_s + 0.3),
               late = meanRate(wobble_end_s - 0.3, wobble_end_s);
  const double silent_from_s = lastSoundS(out->audio);
  std::printf(
      "coin: rolls on its rim from %.3f s, the point circling at %.3g rad/s, then %.3g rad/s in the "
      "0.3 s before it leaves the rim at %.3f s; last contact %.3f s, silent from %.3f s\n",
      wobble_start_s, early, late, wobble_end_s, last_event_s, silent_from_s);
  EXPECT_GT(late, 3.0 * early);                  // the finite-time singularity's rise
  EXPECT_GT(silent_from_s, wobble_end_s);        // the wobble's landing is heard
  EXPECT_LT(silent_from_s, wobble_end_s + 1.0);  // then the coin sleeps and its ring dies
}

}  // namespace
}  // namespace strike
