// SPDX-License-Identifier: MIT
// The scene's ground reflects by default (docs/listener.md, "Ground reflection"): a scene that
// names only the ground's material hears the image source of every body [Allen & Berkley 1979]
// at its delay, (r_image - r_direct) / c, and its level, R r_direct / r_image, with R the
// material's pressure reflection coefficient at normal incidence, (Z - rho c) / (Z + rho c),
// Z = rho_s c_p [Kinsler et al. 2000, sec. 6.2]. The figures are computed here from the geometry
// and the material's constants, not taken from the engine.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "strike/bank/bank.hpp"
#include "strike/core/air.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike {
namespace {

// Two glass beads meet head-on 0.5 m above the ground, with no gravity, heard 1 m away at the
// same height: the listener's image is 1 m below the ground, sqrt(1 + 1) m from the contact.
std::string beads(const std::string& ground) {
  return R"({"sample_rate": 48000, "duration": 0.15, "gravity": [0, 0, 0], "max_modes": 8,
    "listener": {"position": [0, -1, 0.5]}, "ground": )" +
         ground + R"(,
    "objects": [
      {"name": "left", "mesh": "sphere:0.01", "material": "glass", "position": [-0.0102, 0, 0.5], "velocity": [0.5, 0, 0]},
      {"name": "right", "mesh": "sphere:0.01", "material": "glass", "position": [0.0102, 0, 0.5], "velocity": [-0.5, 0, 0]}
    ]})";
}

std::vector<float> render(const std::string& ground) {
  Result<Scene> scene = parseScene(beads(ground), "beads.json");
  EXPECT_TRUE(scene) << scene.error().message;
  if (!scene) return {};
  Result<RenderResult> r = renderScene(*scene, RenderSettings{});
  EXPECT_TRUE(r) << r.error().message;
  if (!r) return {};
  EXPECT_GE(r->report.impacts, 2u) << "the beads must meet";
  return r->audio.samples;
}

double energy(const std::vector<float>& x) {
  double e = 0.0;
  for (float v : x) e += double(v) * v;
  return e;
}

size_t onset(const std::vector<float>& x, double fraction_of_peak) {
  double peak = 0.0;
  for (float v : x) peak = std::max(peak, std::fabs(double(v)));
  for (size_t n = 0; n < x.size(); ++n)
    if (std::fabs(double(x[n])) > fraction_of_peak * peak) return n;
  return x.size();
}

TEST(GroundDefault, AConcreteGroundReflectsAtTheDelayAndLevelOfItsImage) {
  const std::vector<float> with_ground = render(R"({"material": "concrete"})");
  const std::vector<float> without_image = render(R"({"material": "concrete", "reflection": false})");
  ASSERT_EQ(with_ground.size(), without_image.size());
  ASSERT_GT(energy(without_image), 0.0);
  std::vector<float> image(with_ground.size());
  for (size_t n = 0; n < image.size(); ++n) image[n] = with_ground[n] - without_image[n];

  Result<Material> concrete = builtinMaterials().find("concrete");
  ASSERT_TRUE(concrete);
  const double nu = concrete->poisson;
  const double z_concrete =
      std::sqrt(concrete->youngs_pa * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) * concrete->density_kg_m3);
  const double z_air = kAirDensity_kg_m3 * kSpeedOfSoundAir_m_s;
  const double reflection = (z_concrete - z_air) / (z_concrete + z_air);
  const double direct_m = 1.0, image_m = std::sqrt(2.0);
  const double delay_samples = (image_m - direct_m) / kSpeedOfSoundAir_m_s * 48000.0;  // 58.0
  EXPECT_NEAR(double(onset(image, 1e-3)) - double(onset(without_image, 1e-3)), delay_samples, 1.0);
  const double level_db = 10.0 * std::log10(energy(image) / energy(without_image));
  EXPECT_NEAR(level_db, 20.0 * std::log10(reflection * direct_m / image_m), 0.05);

  // "reflection": true is the default; a scene that leaves the ground out has the concrete one.
  EXPECT_EQ(render(R"({"material": "concrete", "reflection": true})"), with_ground);
  Result<Scene> unnamed =
      parseScene(R"({"objects": [{"name": "a", "mesh": "sphere:0.01", "material": "glass"}]})", "a.json");
  ASSERT_TRUE(unnamed);
  EXPECT_TRUE(unnamed->has_ground && unnamed->ground_reflects && std::isnan(unnamed->ground_reflection));
}

// A warm render's "saved" is what the cached banks cost to solve as they record it, the acoustic
// transfer included (it was the eigen-solve alone).
TEST(CacheSavings, AWarmRenderSavesTheBanksWholeSolveTransferIncluded) {
  const std::string cache = testing::TempDir() + "/saved-" + std::to_string(::getpid());
  std::filesystem::remove_all(cache);
  Result<Scene> scene = parseScene(beads(R"({"material": "concrete"})"), "beads.json");
  ASSERT_TRUE(scene) << scene.error().message;
  RenderSettings settings;
  settings.cache_dir = cache;
  settings.acoustic_transfer = true;
  Result<RenderResult> cold = renderScene(*scene, settings);
  ASSERT_TRUE(cold) << cold.error().message;
  Result<RenderResult> warm = renderScene(*scene, settings);
  ASSERT_TRUE(warm) << warm.error().message;
  ASSERT_EQ(warm->report.banks_cached, 1u);
  // The two beads are one bank (identical objects), read once: read it from the cache.
  double recorded = 0.0, transfer = 0.0;
  for (const auto& entry : std::filesystem::directory_iterator(cache)) {
    if (entry.path().extension() != ".modes") continue;
    Result<ModeBank> bank = readBank(entry.path().string());
    ASSERT_TRUE(bank) << bank.error().message;
    recorded += bank->total_seconds;
    transfer += bank->transfer_seconds;
  }
  ASSERT_GT(transfer, 0.0);
  EXPECT_NEAR(warm->report.precompute_saved_seconds, recorded, 1e-9);
  EXPECT_GT(warm->report.precompute_saved_seconds, transfer);
  std::filesystem::remove_all(cache);
}

}  // namespace
}  // namespace strike
