// SPDX-License-Identifier: MIT
// Scenes that come to rest and fall silent (docs/contact.md, "Coming to rest"), end to end
// through renderScene(): the simulation's sleep and the oscillators' ring-down together.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "strike/render.hpp"
#include "strike/scene.hpp"

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
// render is digitally silent (exact zeros) well before 20 s. Without the bowl's rolling
// resistance the bowl and its marbles rocked to the end, 42-56 dB SPL, with 560,110 contact
// events. Bowl order 1 (not the scene's 2): the silence is the simulation's, and the order-2
// solve would be most of the test's time.
TEST(Settling, TheMarblesInTheBowlFallSilent) {
  Result<Scene> loaded = loadScene(std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/marbles-in-bowl.json");
  ASSERT_TRUE(loaded) << loaded.error().message;
  Scene scene = *loaded;
  ASSERT_EQ(scene.objects[0].name, "bowl");
  scene.objects[0].order = 1;
  RenderSettings settings;
  settings.cache_dir = cacheDir();
  settings.duration_s = 60.0;
  Result<RenderResult> out = renderScene(scene, settings);
  ASSERT_TRUE(out) << out.error().message;
  double last_event_s = 0.0;
  for (const ContactEvent& e : out->events) last_event_s = std::max(last_event_s, e.time_s);
  const double silent_from_s = lastSoundS(out->audio);
  std::printf("marbles in the bowl: %zu contact events, the last at %.3f s; silent from %.3f s\n", out->events.size(),
              last_event_s, silent_from_s);
  EXPECT_GT(peak(out->audio), 1e-3);
  EXPECT_LT(last_event_s, silent_from_s);  // asleep, then rung down
  EXPECT_LT(silent_from_s, 20.0);
}

// A glass (assets/meshes/glass.obj) set down upright 0.5 mm above a wooden table: it touches,
// settles on its foot and sleeps; the render is silent within 2 s. Order 1: the silence is the
// simulation's.
TEST(Settling, AGlassSetDownOnATableIsSilentWithinTwoSeconds) {
  const std::string text =
      R"({"sample_rate": 48000, "duration": 4, "listener": {"position": [0, -0.7, 1.0]},
    "max_modes": 40,
    "objects": [
      {"name": "table", "mesh": "box:1.0,0.6,0.03", "material": "wood", "static": true, "position": [0, 0, 0.735]},
      {"name": "glass", "mesh": ")" +
      std::string(STRIKE_SOURCE_DIR) +
      R"(/assets/meshes/glass.obj", "material": "glass", "order": 1, "position": [0, 0, 0.7505]}]})";
  Result<Scene> scene = parseScene(text, "/tmp/glass-set-down.json");
  ASSERT_TRUE(scene) << scene.error().message;
  RenderSettings settings;
  settings.cache_dir = cacheDir();
  Result<RenderResult> out = renderScene(*scene, settings);
  ASSERT_TRUE(out) << out.error().message;
  const double silent_from_s = lastSoundS(out->audio);
  std::printf("glass set down: peak %.3g, silent from %.3f s\n", peak(out->audio), silent_from_s);
  EXPECT_GT(peak(out->audio), 1e-4);  // it was heard touching down
  EXPECT_LT(silent_from_s, 2.0);
}

}  // namespace
}  // namespace strike
