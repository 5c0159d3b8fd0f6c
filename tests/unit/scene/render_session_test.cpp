// SPDX-License-Identifier: MIT
// RenderSession (src/include/strike/render_session.hpp): renders with a session, cold and warm,
// give the same samples as renders without one, and its memory stays under its cap.
#include "strike/render_session.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "strike/render.hpp"
#include "strike/scene.hpp"

namespace strike {
namespace {

// Three shapes (a plate: polyhedral hull; a cylinder; a sphere: Bullet's sphere), two plates
// alike (one bank file, two bodies), all dropped so that every one is struck and heard.
std::string scene(double plate_scale, double x_m) {
  const std::string plate = "box:" + std::to_string(0.12 * plate_scale) + "," + std::to_string(0.08 * plate_scale) +
                            "," + std::to_string(0.004 * plate_scale);
  const std::string x = std::to_string(x_m);
  return R"({
  "sample_rate": 48000, "duration": 0.5, "max_modes": 12,
  "listener": {"position": [0.3, -0.8, 0.4]}, "ground": {"material": "wood"},
  "objects": [
    {"name": "plate", "mesh": ")" +
         plate + R"(", "material": "steel", "position": [)" + x + R"(, 0, 0.05],
     "orientation": [0.985, 0.1, 0.14, 0.0], "velocity": [0, 0, -0.5]},
    {"name": "plate 2", "mesh": ")" +
         plate + R"(", "material": "steel", "position": [0.3, 0.2, 0.08],
     "orientation": [0.96, 0.0, 0.28, 0.0]},
    {"name": "rod", "mesh": "cylinder:0.02,0.12", "material": "aluminium", "position": [-0.2, 0.1, 0.1],
     "orientation": [0.9, 0.3, 0.3, 0.1]},
    {"name": "ball", "mesh": "sphere:0.03", "material": "glass", "position": [0.0, -0.25, 0.06]}
  ]
})";
}

Result<RenderResult> render(const std::string& text, const std::string& cache, RenderSession* session) {
  Result<Scene> parsed = parseScene(text, "/tmp/render-session.json");
  if (!parsed) return parsed.error();
  RenderSettings settings;
  settings.cache_dir = cache;
  settings.session = session;
  return renderScene(*parsed, settings);
}

TEST(RenderSession, ColdAndWarmSessionsGiveTheSamplesOfNoSession) {
  const std::string cache = testing::TempDir() + "/render_session_" + std::to_string(getpid());
  std::filesystem::remove_all(cache);
  RenderSession session;
  for (const std::string& text : {scene(1.0, 0.0), scene(1.4, 0.1)}) {
    ASSERT_TRUE(render(text, cache, nullptr));  // solves and caches the banks
    Result<RenderResult> none = render(text, cache, nullptr);
    ASSERT_TRUE(none) << none.error().message;
    ASSERT_EQ(none->report.objects_sounded, 4u) << "every body must be heard for the test to compare them";
    EXPECT_GT(none->report.shape_vertices_read, 0u);
    EXPECT_LT(none->report.shape_vertices_read, none->report.shape_vertices_total) << "the locator path is tested";
    for (int pass = 0; pass < 2; ++pass) {  // cold for this scene's plates, then warm
      Result<RenderResult> with = render(text, cache, &session);
      ASSERT_TRUE(with) << with.error().message;
      EXPECT_TRUE(with->audio.samples == none->audio.samples) << "pass " << pass << ": the session changed the render";
      EXPECT_EQ(with->report.shape_vertices_read, none->report.shape_vertices_read);
    }
  }
  const RenderSession::Stats stats = session.stats();
  // Hulls: plate (x 2 bodies), rod, ball per scale; bank surfaces: plate, rod, ball per scale.
  EXPECT_GE(stats.hits, 10u);
  EXPECT_GE(stats.misses, 6u);
  EXPECT_LE(stats.bytes, stats.max_bytes);
  std::filesystem::remove_all(cache);
}

TEST(RenderSession, StaysUnderItsCapAndStillGivesTheSameSamples) {
  const std::string cache = testing::TempDir() + "/render_session_cap_" + std::to_string(getpid());
  std::filesystem::remove_all(cache);
  ASSERT_TRUE(render(scene(0.7, 0.0), cache, nullptr));  // solves and caches the banks
  Result<RenderResult> none = render(scene(0.7, 0.0), cache, nullptr);
  ASSERT_TRUE(none) << none.error().message;
  RenderSession tiny(1);  // 1 byte: every entry evicts the one before it
  for (int pass = 0; pass < 2; ++pass) {
    Result<RenderResult> with = render(scene(0.7, 0.0), cache, &tiny);
    ASSERT_TRUE(with) << with.error().message;
    EXPECT_TRUE(with->audio.samples == none->audio.samples);
    EXPECT_EQ(tiny.stats().entries, 1u);
  }
  EXPECT_GT(tiny.stats().evicted, 5u);

  // Many distinct hulls through a 64 kB session: the bytes stay under the cap.
  RenderSession small(64 << 10);
  for (int k = 0; k < 200; ++k) {
    std::vector<double> points{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1.0 + k};
    points.resize(300, 0.25);
    const double top = 1.0 + k;
    std::shared_ptr<const SimHull> hull = small.hull(points, 0.0, 0.0, [&] {
      SimHull h;
      h.vertices_xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, top};
      return h;
    });
    ASSERT_EQ(hull->vertices_xyz.back(), top) << "a hull of other points";
    EXPECT_LE(small.stats().bytes, small.stats().max_bytes);
  }
  EXPECT_EQ(small.stats().misses, 200u);
  EXPECT_LT(small.stats().entries, 200u);
  std::filesystem::remove_all(cache);
}

}  // namespace
}  // namespace strike
