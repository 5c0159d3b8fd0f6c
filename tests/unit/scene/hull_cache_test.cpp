// SPDX-License-Identifier: MIT
// The hull cache (src/cache/hull_cache.hpp): a hull file reads back to the bit, a damaged or
// foreign one is refused, and a render reads the hulls an earlier render cached (it does not
// write them again) and gives the same samples with the cache cold, warm or damaged.
#include "hull_cache.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike {
namespace {

namespace fs = std::filesystem;

std::string freshFolder(const std::string& name) {
  const std::string dir = testing::TempDir() + "/" + name + "_" + std::to_string(getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(HullCache, ReadsBackWhatItWroteAndRefusesADamagedOrForeignFile) {
  const std::string dir = freshFolder("hull_cache_file");
  const std::vector<double> points{0, 0, 0, 0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1, 0.01, 0.01, 0.01};
  SimHull hull;
  hull.vertices_xyz = {0, 0, 0, 0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
  hull.volume_m3 = 0.1 * 0.1 * 0.1 / 6.0;
  hull.shrink_m = 0.001;
  const uint64_t key = hullKey(points, 0.001, 0.25);
  EXPECT_NE(key, hullKey(points, 0.002, 0.25)) << "another shrink is another hull";
  const std::string path = hullPath(dir, key);
  ASSERT_TRUE(writeHull(path, key, hull));
  Result<SimHull> back = readHull(path, key);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(std::memcmp(back->vertices_xyz.data(), hull.vertices_xyz.data(), 12 * sizeof(double)), 0);
  EXPECT_EQ(back->vertices_xyz.size(), hull.vertices_xyz.size());
  EXPECT_EQ(back->volume_m3, hull.volume_m3);
  EXPECT_EQ(back->shrink_m, hull.shrink_m);

  Result<SimHull> foreign = readHull(path, key + 1);
  ASSERT_FALSE(foreign);
  EXPECT_NE(foreign.error().message.find("another body"), std::string::npos) << foreign.error().message;
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(40);
    f.put('\x7f');
  }
  Result<SimHull> damaged = readHull(path, key);
  ASSERT_FALSE(damaged);
  EXPECT_NE(damaged.error().message.find(path), std::string::npos) << damaged.error().message;
  EXPECT_NE(damaged.error().message.find("damaged hull file"), std::string::npos) << damaged.error().message;
  EXPECT_FALSE(readHull(dir + "/missing.hull", key));
  fs::remove_all(dir);
}

std::vector<fs::path> hullFiles(const std::string& dir) {
  std::vector<fs::path> out;
  for (const fs::directory_entry& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".hull") out.push_back(e.path());
  return out;
}

// The key must tell apart any two point sets that differ: every single bit flipped anywhere gives
// another key, and so do mirror images (sign bits flipped in pairs, which a hash that only
// multiplies would cancel), reordered points and one point more or less.
TEST(HullCache, KeyChangesWithAnyBitOfThePoints) {
  std::vector<double> points;
  for (int i = 0; i < 40; ++i) points.push_back(0.01 * i - 0.13 + 1e-5 * i * i);
  const uint64_t key = hullKey(points, 0.001, 0.25);
  std::vector<uint64_t> keys{key};
  for (size_t i = 0; i < points.size(); ++i)
    for (int bit = 0; bit < 64; ++bit) {
      std::vector<double> changed = points;
      uint64_t word;
      std::memcpy(&word, &changed[i], sizeof word);
      word ^= uint64_t(1) << bit;
      std::memcpy(&changed[i], &word, sizeof word);
      keys.push_back(hullKey(changed, 0.001, 0.25));
    }
  std::vector<double> mirrored = points;
  for (size_t i = 0; i < mirrored.size(); i += 3) mirrored[i] = -mirrored[i];  // x -> -x
  keys.push_back(hullKey(mirrored, 0.001, 0.25));
  std::vector<double> two_signs = points;
  two_signs[3] = -two_signs[3], two_signs[7] = -two_signs[7];
  keys.push_back(hullKey(two_signs, 0.001, 0.25));
  std::vector<double> swapped = points;
  std::swap(swapped[0], swapped[3]);
  keys.push_back(hullKey(swapped, 0.001, 0.25));
  keys.push_back(hullKey(std::vector<double>(points.begin(), points.end() - 3), 0.001, 0.25));
  std::vector<double> more = points;
  more.insert(more.end(), {0.0, 0.0, 0.0});
  keys.push_back(hullKey(more, 0.001, 0.25));
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(std::adjacent_find(keys.begin(), keys.end()), keys.end()) << "two point sets share a key";
}

TEST(HullCache, ARenderReadsTheCachedHullsAndGivesTheSameSamples) {
  const std::string cache = freshFolder("hull_cache_render");
  Result<Scene> scene = parseScene(R"({
  "sample_rate": 48000, "duration": 0.4, "max_modes": 8,
  "listener": {"position": [0.3, -0.8, 0.4]}, "ground": {"material": "wood"},
  "objects": [
    {"name": "plate", "mesh": "box:0.1,0.07,0.004", "material": "steel", "position": [0, 0, 0.05],
     "orientation": [0.985, 0.1, 0.14, 0.0], "velocity": [0, 0, -0.5]},
    {"name": "rod", "mesh": "cylinder:0.015,0.1", "material": "aluminium", "position": [-0.2, 0.1, 0.1],
     "orientation": [0.9, 0.3, 0.3, 0.1]}
  ]
})",
                                   "/tmp/hull-cache.json");
  ASSERT_TRUE(scene) << scene.error().message;
  RenderSettings settings;
  settings.cache_dir = cache;
  settings.acoustic_transfer = false;  // the hulls are the point here, not the transfer's seconds
  Result<RenderResult> cold = renderScene(*scene, settings);
  ASSERT_TRUE(cold) << cold.error().message;
  const std::vector<fs::path> files = hullFiles(cache);
  ASSERT_GE(files.size(), 2u) << "one hull a body at least";
  std::vector<fs::file_time_type> written;
  for (const fs::path& f : files) written.push_back(fs::last_write_time(f));

  Result<RenderResult> warm = renderScene(*scene, settings);
  ASSERT_TRUE(warm) << warm.error().message;
  EXPECT_TRUE(warm->audio.samples == cold->audio.samples) << "the cached hulls changed the render";
  EXPECT_EQ(hullFiles(cache).size(), files.size());
  for (size_t k = 0; k < files.size(); ++k)
    EXPECT_EQ(fs::last_write_time(files[k]), written[k]) << files[k] << ": read, not computed and written again";

  for (const fs::path& f : files) std::ofstream(f, std::ios::trunc) << "not a hull";
  Result<RenderResult> damaged = renderScene(*scene, settings);
  ASSERT_TRUE(damaged) << damaged.error().message;
  EXPECT_TRUE(damaged->audio.samples == cold->audio.samples) << "a damaged hull file must be computed again";
  for (const fs::path& f : files) {
    const std::string name = f.stem().string();
    EXPECT_TRUE(readHull(f.string(), std::stoull(name, nullptr, 16))) << f << ": written again after the damage";
  }
  fs::remove_all(cache);
}

}  // namespace
}  // namespace strike
