// SPDX-License-Identifier: MIT
// Contact physics end to end through `strike render`: bodies resting on concave (mesh) shapes
// fall asleep and go silent, and restitution and friction come from the scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "run_cli.hpp"
#include "strike/audio.hpp"

namespace strike {
namespace {

using test::CliResult;
using test::runCli;

std::string temp(const std::string& name) { return testing::TempDir() + "/" + name; }
const std::string kGlass = std::string(STRIKE_SOURCE_DIR) + "/assets/meshes/glass.obj";

/// One row of `render --events`: time, the two body names, the other fields as numbers.
struct EventRow {
  double time_s = 0.0;
  std::string body_a, body_b;
  std::vector<double> fields;  ///< from new_contact on (see writeEventsCsv)
};

std::vector<EventRow> readEvents(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  std::vector<EventRow> rows;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string field;
    EventRow row;
    std::getline(fields, field, ',');
    row.time_s = std::stod(field);
    std::getline(fields, row.body_a, ',');
    std::getline(fields, row.body_b, ',');
    while (std::getline(fields, field, ',')) row.fields.push_back(std::stod(field));
    rows.push_back(row);
  }
  return rows;
}

/// The largest |sample| of a file from `from_s` on, and over the whole file.
struct Levels {
  double peak = 0.0, tail = 0.0;
};
Levels levels(const std::string& wav, double from_s) {
  Result<AudioBuffer> audio = readAudio(wav);
  EXPECT_TRUE(audio) << (audio ? "" : audio.error().message);
  Levels out;
  if (!audio) return out;
  const size_t from = size_t(from_s * audio->sample_rate_hz);
  for (size_t n = 0; n < audio->samples.size(); ++n) {
    const double v = std::fabs(audio->samples[n]);
    out.peak = std::max(out.peak, v);
    if (n >= from) out.tail = std::max(out.tail, v);
  }
  return out;
}

// Issue 15 item 4. A glass set down tilted on a table rocks onto its base and rests. As a
// GImpact mesh its contacts are rebuilt every substep with 2 to 4 points, so the solver rocks it
// just over Bullet's still threshold every few hundred ms: Bullet's still-clock kept restarting,
// the glass never slept, and its resting force, varying ~3% per step, hummed 63 dB below the
// impact peak to the end. Resting where it is, it must sleep sleep_after_still_s (0.5 s) after it
// settles (by ~0.3 s) and from then on the render is silent: 90 dB below the peak (the synth's
// modes ring down from the settling below the audibility floor within ~0.2 s).
// As exact mesh ("concave", GImpact) and as convex pieces (the default for a concave moving
// body); the second render of the pieces reads them from the cache and gives the same bytes.
TEST(CliContact, GlassRestingOnATableFallsAsleepAndGoesSilent) {
  const std::string cache = temp("glass-rest-cache");  // one bank for both shapes
  std::filesystem::remove_all(cache);
  for (const std::string shape : {"concave", "auto"}) {
    const std::string dir = temp("glass-rest-" + shape);
    std::filesystem::create_directories(dir);
    const std::string scene = dir + "/scene.json", wav = dir + "/out.wav", events = dir + "/events.csv";
    std::ofstream(scene) << R"({"sample_rate": 48000, "duration": 1.5, "max_modes": 10,
      "listener": {"position": [0, -0.7, 1.0]},
      "objects": [
        {"name": "table", "mesh": "box:1.0,0.6,0.03", "material": "wood", "static": true, "position": [0, 0, 0.735]},
        {"name": "glass", "mesh": ")" << kGlass << R"(", "material": "glass", "size": 0.02, "shape": ")" << shape
                         << R"(", "position": [0, 0, 0.78], "orientation": [0.9962, 0.0872, 0.0, 0.0]}]})";
    CliResult r = runCli("render '" + scene + "' -o '" + wav + "' --events '" + events + "' --cache '" + cache + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    double last_contact_s = 0.0;
    for (const EventRow& row : readEvents(events)) last_contact_s = std::max(last_contact_s, row.time_s);
    std::printf("[ asleep   ] %s: last contact at %.3f s\n", shape.c_str(), last_contact_s);
    EXPECT_LT(last_contact_s, 1.0) << shape << ": the glass never fell asleep";
    const Levels level = levels(wav, 1.0);
    ASSERT_GT(level.peak, 0.0);
    const double below_db = level.tail > 0 ? 20 * std::log10(level.peak / level.tail) : 999.0;
    std::printf("[ silence  ] %s: after 1 s the render is %.1f dB below its peak\n", shape.c_str(), below_db);
    EXPECT_GE(below_db, 90.0) << shape << ": a resting glass hums";
    if (shape != "auto") continue;
    EXPECT_NE(r.err.find("convex pieces (computed in"), std::string::npos) << r.err;
    r = runCli("render '" + scene + "' -o '" + dir + "/again.wav' --cache '" + cache + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("glass: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("convex pieces (from the cache)"), std::string::npos) << r.err;
    EXPECT_EQ(test::slurp(dir + "/again.wav"), test::slurp(wav)) << "pieces from the cache change the render";
  }
}

}  // namespace
}  // namespace strike
