// SPDX-License-Identifier: MIT
// RenderSession (src/include/strike/scene/render_session.hpp): renders with a session, cold and warm,
// give the same samples as renders without one, and its memory stays under its cap.
#include "strike/scene/render_session.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

#include "strike/bank/bank.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"
#include "strike/synth/synth.hpp"

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

// Holds each of two threads until both have arrived, or until `timeout` has passed (C++17 has no
// std::barrier). False when the other did not come.
class Rendezvous {
 public:
  bool arriveAndWait(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (++arrived_ == 2) {
      both_.notify_all();
      return true;
    }
    return both_.wait_for(lock, timeout, [&] { return arrived_ >= 2; });
  }

 private:
  std::mutex mutex_;
  std::condition_variable both_;
  int arrived_ = 0;
};

// Starts `work(thread_index)` on two threads released together (spinning, so neither waits for a
// wake-up), and joins them.
template <class Work>
void onTwoThreadsAtOnce(const Work& work) {
  std::atomic<int> ready{0};
  auto run = [&](int index) {
    ready.fetch_add(1);
    while (ready.load() < 2) std::this_thread::yield();
    work(index);
  };
  std::thread other(run, 1);
  run(0);
  other.join();
}

bool sameBits(const SimHull& a, const SimHull& b) {
  return a.vertices_xyz.size() == b.vertices_xyz.size() &&
         std::memcmp(a.vertices_xyz.data(), b.vertices_xyz.data(), a.vertices_xyz.size() * sizeof(double)) == 0 &&
         std::memcmp(&a.volume_m3, &b.volume_m3, sizeof(double)) == 0 &&
         std::memcmp(&a.shrink_m, &b.shrink_m, sizeof(double)) == 0;
}

TEST(RenderSession, TwoThreadsThatMissTogetherShareOneHull) {
  // A tetrahedron's corners; the "hull" is a function of the points alone, as Bullet's is.
  const std::vector<double> points{0, 0, 0, 0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
  auto hullOfPoints = [&] {
    SimHull h;
    h.vertices_xyz = points;
    h.volume_m3 = 0.1 * 0.1 * 0.1 / 6.0;
    h.shrink_m = 0.001;
    return h;
  };
  const SimHull alone = hullOfPoints();  // session-less
  constexpr int kCalls = 200;
  for (int round = 0; round < 5; ++round) {
    RenderSession session;
    Rendezvous both_computing;
    std::shared_ptr<const SimHull> got[2][kCalls];
    onTwoThreadsAtOnce([&](int t) {
      for (int call = 0; call < kCalls; ++call)
        got[t][call] = session.hull(points, 0.001, 0.5, [&] {
          // Hold each thread here until the other is computing too: neither can have kept its hull
          // before the other looked, so both miss and both come to keep one (the wait is bounded
          // only so that a broken session fails instead of hanging).
          both_computing.arriveAndWait(std::chrono::milliseconds(500));
          return hullOfPoints();
        });
    });
    const RenderSession::Stats stats = session.stats();
    EXPECT_EQ(stats.entries, 1u) << "round " << round << ": one hull kept per points, however many threads built it";
    EXPECT_EQ(stats.misses, 2u) << "both threads built: both missed";
    EXPECT_EQ(stats.hits, 2u * kCalls - 2u);
    for (int t = 0; t < 2; ++t)
      for (int call = 0; call < kCalls; ++call) {
        ASSERT_EQ(got[t][call].get(), got[0][0].get())
            << "round " << round << ", thread " << t << ", call " << call << ": every caller shares the kept hull";
      }
    EXPECT_TRUE(sameBits(*got[0][0], alone));
  }
}

// The nearest surface points of a grid of points through `locator`, as bits.
std::vector<uint64_t> nearestBits(const SurfaceLocator& locator, const ModeBank& bank) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < bank.surface_positions.size() / 3; ++v)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], bank.surface_positions[3 * v + k]);
      hi[k] = std::max(hi[k], bank.surface_positions[3 * v + k]);
    }
  std::vector<uint64_t> bits;
  for (int i = 0; i <= 6; ++i)
    for (int j = 0; j <= 6; ++j)
      for (int k = 0; k <= 6; ++k) {
        const double point[3] = {lo[0] + (hi[0] - lo[0]) * (i / 5.0 - 0.1), lo[1] + (hi[1] - lo[1]) * (j / 5.0 - 0.1),
                                 lo[2] + (hi[2] - lo[2]) * (k / 5.0 - 0.1)};
        uint32_t vertices[3];
        double weights[3];
        locator.nearest(point, vertices, weights);
        for (int c = 0; c < 3; ++c) {
          uint64_t w;
          std::memcpy(&w, &weights[c], sizeof w);
          bits.push_back(vertices[c]);
          bits.push_back(w);
        }
      }
  return bits;
}

TEST(RenderSession, TwoThreadsThatMissTogetherShareOneBankSurfaceAndRenderTheSameSamples) {
  const std::string cache = testing::TempDir() + "/render_session_threads_" + std::to_string(getpid());
  std::filesystem::remove_all(cache);
  ASSERT_TRUE(render(scene(1.0, 0.0), cache, nullptr));  // solves and caches the banks
  std::string bank_path;
  for (const auto& item : std::filesystem::directory_iterator(cache))
    if (item.path().extension() == ".modes" && bank_path.empty()) bank_path = item.path().string();
  ASSERT_FALSE(bank_path.empty()) << "no bank in " << cache;
  Result<BankFile> file = BankFile::open(bank_path);
  ASSERT_TRUE(file) << file.error().message;
  const ModeBank& header = file->bank();
  ASSERT_FALSE(header.surface_triangles.empty());
  const std::vector<uint64_t> alone = nearestBits(SurfaceLocator(header), header);  // session-less

  // Two threads miss together only when neither has kept its surface before the other looks, a
  // window of one locator's build: many rounds, each with a new session.
  constexpr int kCalls = 50;
  int rounds_with_two_misses = 0;
  for (int round = 0; round < 200; ++round) {
    RenderSession session;
    RenderSession::BankSurface got[2][kCalls];
    onTwoThreadsAtOnce([&](int t) {
      for (int call = 0; call < kCalls; ++call) got[t][call] = session.bankSurface(*file);
    });
    const RenderSession::Stats stats = session.stats();
    rounds_with_two_misses += stats.misses == 2;
    ASSERT_EQ(stats.entries, 1u) << "round " << round << " (" << stats.misses
                                 << " misses): one surface kept per bank, however many threads built it";
    ASSERT_EQ(stats.hits + stats.misses, 2u * kCalls);
    for (int t = 0; t < 2; ++t)
      for (int call = 0; call < kCalls; ++call) {
        ASSERT_EQ(got[t][call].bank.get(), got[0][0].bank.get())
            << "round " << round << ": every caller shares the kept bank";
        ASSERT_EQ(got[t][call].locator.get(), got[0][0].locator.get());
      }
    ASSERT_TRUE(got[0][0].locator->builtFor(*got[0][0].bank));
    if (round == 0) {
      const ModeBank& kept = *got[0][0].bank;
      EXPECT_TRUE(kept.eigenvalues == header.eigenvalues && kept.surface_positions == header.surface_positions &&
                  kept.surface_triangles == header.surface_triangles && kept.radiation_m2 == header.radiation_m2);
      EXPECT_TRUE(nearestBits(*got[0][0].locator, kept) == alone) << "the kept locator finds what a new one finds";
    }
  }
  std::printf("rounds where both threads missed: %d of 200\n", rounds_with_two_misses);

  // Whole renders on two threads through one session: the samples of a render without one, and
  // the entries of one render through a session of its own.
  Result<RenderResult> none = render(scene(1.0, 0.0), cache, nullptr);
  ASSERT_TRUE(none) << none.error().message;
  RenderSession single;
  ASSERT_TRUE(render(scene(1.0, 0.0), cache, &single));
  RenderSession shared;
  Result<RenderResult> with[2] = {Error{}, Error{}};
  onTwoThreadsAtOnce([&](int t) { with[t] = render(scene(1.0, 0.0), cache, &shared); });
  for (int t = 0; t < 2; ++t) {
    ASSERT_TRUE(with[t]) << with[t].error().message;
    EXPECT_TRUE(with[t]->audio.samples == none->audio.samples) << "thread " << t;
  }
  EXPECT_EQ(shared.stats().entries, single.stats().entries);
  std::filesystem::remove_all(cache);
}

}  // namespace
}  // namespace strike
