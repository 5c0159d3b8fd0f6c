// SPDX-License-Identifier: MIT
// The binaural responses' cache (src/cache/hrtf_cache.hpp): a set reads back to the bit, a
// damaged or foreign file is refused, the key follows the file's bytes and the rate, and a
// binaural render gives the same samples with the cache cold and warm.
#include "hrtf_cache.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

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

TEST(HrtfCache, ReadsBackWhatItWroteAndRefusesADamagedOrForeignFile) {
  const std::string dir = freshFolder("hrtf_cache_file");
  HrtfSet set;
  set.sample_rate_hz = 48000.0;
  set.taps = 5;
  set.directions = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -2, 0}};
  for (size_t i = 0; i < set.directions.size() * set.taps; ++i) {
    set.left.push_back(0.01f * float(i) - 0.3f);
    set.right.push_back(-1e-3f * float(i * i));
  }
  const std::string sofa(1001, 'x');  // not a multiple of 8 bytes: the tail counts too
  const uint64_t key = hrtfKey(sofa, 48000.0);
  EXPECT_NE(key, hrtfKey(sofa, 44100.0)) << "another rate is another set";
  std::string other = sofa;
  other.back() = 'y';
  EXPECT_NE(key, hrtfKey(other, 48000.0)) << "another file is another set";
  EXPECT_NE(key, hrtfKey(sofa + 'x', 48000.0));
  const std::string path = hrtfPath(dir, key);
  ASSERT_TRUE(writeHrtf(path, key, set));
  Result<HrtfSet> back = readHrtf(path, key);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->sample_rate_hz, set.sample_rate_hz);
  EXPECT_EQ(back->taps, set.taps);
  EXPECT_EQ(back->directions, set.directions);
  ASSERT_EQ(back->left.size(), set.left.size());
  EXPECT_EQ(std::memcmp(back->left.data(), set.left.data(), set.left.size() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(back->right.data(), set.right.data(), set.right.size() * sizeof(float)), 0);

  Result<HrtfSet> foreign = readHrtf(path, key + 1);
  ASSERT_FALSE(foreign);
  EXPECT_NE(foreign.error().message.find("another file"), std::string::npos) << foreign.error().message;
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(60);
    f.put('\x7f');
  }
  Result<HrtfSet> damaged = readHrtf(path, key);
  ASSERT_FALSE(damaged);
  EXPECT_NE(damaged.error().message.find("damaged hrtf file"), std::string::npos) << damaged.error().message;
  EXPECT_FALSE(readHrtf(dir + "/missing.hrtf", key));
  fs::remove_all(dir);
}

TEST(HrtfCache, ABinauralRenderIsTheSameColdAndWarm) {
  const std::string dir = freshFolder("hrtf_cache_render");
  Result<Scene> scene = loadScene(std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/bar-drop.json");
  ASSERT_TRUE(scene) << scene.error().message;
  RenderSettings settings;
  settings.cache_dir = dir;
  settings.duration_s = 0.3;
  settings.output_format = OutputFormat::Binaural;
  Result<RenderResult> cold = renderScene(*scene, settings);
  ASSERT_TRUE(cold) << cold.error().message;
  size_t files = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) files += e.path().extension() == ".hrtf";
  EXPECT_EQ(files, 1u);
  Result<RenderResult> warm = renderScene(*scene, settings);
  ASSERT_TRUE(warm) << warm.error().message;
  ASSERT_EQ(cold->audio.samples.size(), warm->audio.samples.size());
  EXPECT_EQ(std::memcmp(cold->audio.samples.data(), warm->audio.samples.data(),
                        cold->audio.samples.size() * sizeof(cold->audio.samples[0])),
            0);
  double energy = 0.0;
  for (float x : warm->audio.samples) energy += double(x) * x;
  EXPECT_GT(energy, 0.0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace strike
