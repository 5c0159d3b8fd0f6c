// SPDX-License-Identifier: MIT
// examples/scenes/spoon-scrapes-plate.json end to end: a hand drives a steel spoon
// over a ceramic plate (scene key "path") at three speeds, stops it, lifts it off. The speeds
// and times come from the example's own keyframes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "render_helpers.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike {
namespace {

using render_helpers::renderCached;
using render_helpers::rms;

const std::string kExample = std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/spoon-scrapes-plate.json";

std::string tempDir() { return testing::TempDir() + "/spoon-scrape-" + std::to_string(static_cast<long>(getpid())); }

RenderResult render(const Scene& scene) { return renderCached(scene, tempDir() + "/cache"); }

double db(double ratio) { return 20.0 * std::log10(ratio); }

/// A span of the spoon's path between two keys: its speed, and whether it keeps its height.
struct Span {
  double t0_s, t1_s, speed_m_s;
  bool level;
};
std::vector<Span> spans(const std::vector<PathKey>& path) {
  std::vector<Span> out;
  for (size_t k = 1; k < path.size(); ++k) {
    double d2 = 0;
    for (int i = 0; i < 3; ++i) d2 += std::pow(path[k].position_m[i] - path[k - 1].position_m[i], 2);
    out.push_back({path[k - 1].t_s, path[k].t_s, std::sqrt(d2) / (path[k].t_s - path[k - 1].t_s),
                   path[k].position_m[2] == path[k - 1].position_m[2]});
  }
  return out;
}

/// The events CSV (`strike render --events`) as rows of fields.
std::vector<std::vector<std::string>> eventsCsv(const RenderResult& result) {
  const std::string path = tempDir() + "/events.csv";
  EXPECT_TRUE(writeEventsCsv(path, result));
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream s(line);
    std::string field;
    while (std::getline(s, field, ',')) fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

TEST(SpoonScrapesPlate, SoundsWhileItSlidesAtTheKeyedSpeedAndStopsWithIt) {
  std::filesystem::create_directories(tempDir());
  Result<Scene> scene = loadScene(kExample);
  ASSERT_TRUE(scene) << scene.error().message;
  ASSERT_EQ(scene->objects[1].name, "spoon");
  const std::vector<Span> path = spans(scene->objects[1].path);
  // The scrape: the spans that move the spoon at its height on the plate, up to where it stops.
  std::vector<Span> scrape;
  double stop_s = 0.0, lift_s = 0.0;
  for (const Span& s : path) {
    if (stop_s == 0.0 && s.level && s.speed_m_s > 0.0) scrape.push_back(s);
    if (stop_s == 0.0 && !scrape.empty() && s.speed_m_s == 0.0) stop_s = s.t0_s;
    if (stop_s > 0.0 && lift_s == 0.0 && !s.level) lift_s = s.t0_s;
  }
  ASSERT_EQ(scrape.size(), 3u);
  ASSERT_GT(stop_s, 0.0);
  ASSERT_GT(lift_s, stop_s);
  const RenderResult rough = render(*scene);
  Scene smooth_scene = *scene;
  for (SceneObject& o : smooth_scene.objects) o.roughness_rms_m = 0.0;
  const RenderResult smooth = render(smooth_scene);
  ASSERT_FALSE(rough.audio.samples.empty());
  const double rate = rough.audio.sample_rate_hz;

  // While it moves: in every 50 ms window, >= 30 dB above the floor (the same render with both
  // surfaces smooth, or 0 dB SPL, whichever is higher); louder at each faster span.
  double previous_db = -1e9;
  for (const Span& s : scrape) {
    double lowest_db = 1e9, sum2 = 0.0;
    int windows = 0;
    for (double t = s.t0_s + 0.02; t + 0.05 <= s.t1_s; t += 0.05, ++windows) {
      const double level = rms(rough.audio.samples, t, t + 0.05, rate);
      const double floor = std::max(rms(smooth.audio.samples, t, t + 0.05, rate), 1e-6);
      lowest_db = std::min(lowest_db, db(level / floor));
      sum2 += level * level;
    }
    const double span_db = db(std::sqrt(sum2 / windows) / 1e-6);
    std::printf("%.3f m/s (%.2f to %.2f s): %.1f dB SPL, lowest window %.1f dB above the floor\n", s.speed_m_s,
                s.t0_s, s.t1_s, span_db, lowest_db);
    EXPECT_GE(lowest_db, 30.0);
    EXPECT_GT(span_db, previous_db + 3.0);
    previous_db = span_db;
  }
  // It stops: the rough-contact excitation ends within 50 ms of the spoon's stop (it still rests
  // on the plate; then it is lifted off: no scrape from that either).
  std::printf("stop at %.3f s, rough-contact force until %.4f s\n", stop_s, rough.report.continuous_last_force_s);
  EXPECT_GT(rough.report.continuous_last_force_s, stop_s - 0.05);
  EXPECT_LE(rough.report.continuous_last_force_s, stop_s + 0.05);
  // ...and what is heard after it is the ring-down: 50 ms on, no 10 ms window rises over the
  // one before (beating of close modes aside, 1 dB).
  double last = rms(rough.audio.samples, stop_s + 0.05, stop_s + 0.06, rate), worst_rise_db = -1e9;
  for (double t = stop_s + 0.06; t + 0.01 <= stop_s + 0.25; t += 0.01) {
    const double level = rms(rough.audio.samples, t, t + 0.01, rate);
    worst_rise_db = std::max(worst_rise_db, db(level / last));
    last = level;
  }
  const double drop_db = db(rms(rough.audio.samples, stop_s - 0.05, stop_s, rate) /
                            rms(rough.audio.samples, stop_s + 0.05, stop_s + 0.1, rate));
  std::printf("after the stop: level %.1f dB below the last 50 ms of the scrape, largest rise %.2f dB per 10 ms\n",
              drop_db, worst_rise_db);
  EXPECT_LT(worst_rise_db, 1.0);

  // Lifted off: its last contact with the plate within 50 ms of the lift's start (the path rises
  // at 0.2 m/s from 0.5 mm inside the plate: 2.5 ms), and nothing heard from the spoon after.
  double last_contact_s = 0.0;
  for (const ContactEvent& e : rough.events) last_contact_s = std::max(last_contact_s, e.step_time_s);
  std::printf("lift at %.3f s, last contact %.3f s\n", lift_s, last_contact_s);
  EXPECT_GT(last_contact_s, lift_s - 0.001);
  EXPECT_LT(last_contact_s, lift_s + 0.05);

  // The events CSV: the spoon's contacts while it moves are "sliding", at the keyed speed.
  const std::vector<std::vector<std::string>> csv = eventsCsv(rough);
  ASSERT_GT(csv.size(), 1u);
  const std::vector<std::string>& header = csv[0];
  auto column = [&](const char* name) {
    return static_cast<size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const size_t a = column("body_a"), b = column("body_b"), t = column("step_time_s"), sx = column("slip_x_m_s"),
               motion = column("motion");
  ASSERT_LT(motion, header.size());
  for (const Span& s : scrape) {
    size_t sliding = 0, other = 0;
    double lo = 1e9, hi = 0.0;
    for (size_t r = 1; r < csv.size(); ++r) {
      const std::vector<std::string>& row = csv[r];
      if (row[a] != "spoon" && row[b] != "spoon") continue;
      const double time = std::stod(row[t]);
      if (time < s.t0_s + 0.02 || time >= s.t1_s) continue;  // a step's change of speed settles in 20 ms
      (row[motion] == "sliding" ? sliding : other)++;
      const double slip = std::hypot(std::stod(row[sx]), std::stod(row[sx + 1]), std::stod(row[sx + 2]));
      lo = std::min(lo, slip), hi = std::max(hi, slip);
    }
    std::printf("%.3f m/s: %zu events sliding, %zu not; slip %.4f to %.4f m/s (%+.1f%% to %+.1f%%)\n", s.speed_m_s,
                sliding, other, lo, hi, 100 * (lo / s.speed_m_s - 1), 100 * (hi / s.speed_m_s - 1));
    EXPECT_GT(sliding, size_t(100 * (s.t1_s - s.t0_s)));
    EXPECT_EQ(other, 0u);
    EXPECT_GT(lo, 0.97 * s.speed_m_s);
    EXPECT_LT(hi, 1.03 * s.speed_m_s);
  }

  // Determinism: a second render (its banks now from the cache) gives the same samples and events.
  const RenderResult again = render(*scene);
  ASSERT_EQ(again.audio.samples.size(), rough.audio.samples.size());
  EXPECT_EQ(std::memcmp(again.audio.samples.data(), rough.audio.samples.data(),
                        rough.audio.samples.size() * sizeof(float)),
            0);
  EXPECT_EQ(eventsCsv(again), csv);
  std::filesystem::remove_all(tempDir());
}

}  // namespace
}  // namespace strike
