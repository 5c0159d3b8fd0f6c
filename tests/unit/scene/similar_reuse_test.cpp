// SPDX-License-Identifier: MIT
// Exact similarity reuse (src/include/strike/precompute/normalized_problem.hpp): a bank scaled from the
// normalized solve against a direct solve of the object itself, and a render of two objects of one
// shape at different sizes and materials that solves once and does not depend on the cache.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "strike/core/hash.hpp"
#include "strike/precompute/normalized_problem.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike {
namespace {

TEST(SimilarReuse, OneShapeAtOtherSizesAndMaterialsIsOneNormalizedProblem) {
  PrecomputeSettings steel_bar;
  steel_bar.mesh_spec = "box:0.3,0.02,0.02";
  steel_bar.material = {"steel", 2.0e11, 0.29, 7850.0, 0, 0};
  steel_bar.max_freq_hz = 20000.0;
  PrecomputeSettings other = steel_bar;  // 1.4 x as long, lighter and softer
  other.mesh_spec = "box:0.42,0.028,0.028";
  other.material = {"custom", 1.1e11, 0.29, 4000.0, 0, 0};
  const NormalizedProblem a = normalizeProblem(steel_bar), b = normalizeProblem(other);
  EXPECT_EQ(a.settings.mesh_spec, "box:1,0.0666666666667,0.0666666666667");
  EXPECT_EQ(b.settings.mesh_spec, a.settings.mesh_spec);
  EXPECT_EQ(a.scale, 0.3);
  EXPECT_EQ(b.scale, 0.42);
  EXPECT_EQ(a.settings.material.youngs_pa, b.settings.material.youngs_pa);
  EXPECT_EQ(a.settings.target_edge_m, 0.0);  // automatic: relative already
  const uint64_t hash = fnv1a64(a.settings.mesh_spec.data(), a.settings.mesh_spec.size());
  EXPECT_EQ(normalizedBankCacheKey(hash, a), normalizedBankCacheKey(hash, b));
  // Another Poisson ratio has other mode shapes: another problem.
  PrecomputeSettings aluminium = steel_bar;
  aluminium.material = {"aluminium", 6.9e10, 0.33, 2700.0, 0, 0};
  EXPECT_NE(normalizedBankCacheKey(hash, normalizeProblem(aluminium)), normalizedBankCacheKey(hash, a));
}

TEST(SimilarReuse, AScaledSolveEqualsADirectSolveOfTheObjectToSolverPrecision) {
  PrecomputeSettings object;
  object.mesh_spec = "box:0.5,0.075,0.025";  // 2.5 x box:0.2,0.03,0.01
  object.material = {"soft", 7.0e10, 0.29, 2700.0, 1e-7, 3.0};
  object.order = 2;
  object.target_edge_m = 0.0125;
  object.max_freq_hz = 6000.0;
  object.max_modes = 40;
  object.error_estimate = false;
  Result<PrecomputeResult> direct = computeModeBank(object);
  Result<PrecomputeResult> similar = computeSimilarModeBank(object);
  ASSERT_TRUE(direct) << direct.error().message;
  ASSERT_TRUE(similar) << similar.error().message;
  const ModeBank& d = direct->bank;
  const ModeBank& s = similar->bank;
  ASSERT_GE(d.modeCount(), 8u);
  ASSERT_LT(d.modeCount(), 40u) << "the test needs a bank cut by frequency, not by count";
  ASSERT_EQ(s.modeCount(), d.modeCount());
  ASSERT_EQ(s.surfaceVertexCount(), d.surfaceVertexCount());
  double worst_lambda = 0, worst_shape = 0, worst_position = 0;
  for (size_t m = 0; m < d.modeCount(); ++m) {
    worst_lambda = std::max(worst_lambda, std::fabs(s.eigenvalues[m] / d.eigenvalues[m] - 1));
    // Up to sign: an eigenvector's sign is arbitrary (no degenerate pair in this box).
    double dot = 0, largest = 0;
    for (size_t v = 0; v < d.surfaceVertexCount(); ++v)
      for (int a = 0; a < 3; ++a) dot += double(s.shapeAt(m, v)[a]) * d.shapeAt(m, v)[a];
    const double sign = dot < 0 ? -1 : 1;
    double difference = 0;
    for (size_t v = 0; v < d.surfaceVertexCount(); ++v)
      for (int a = 0; a < 3; ++a) {
        largest = std::max(largest, std::fabs(double(d.shapeAt(m, v)[a])));
        difference = std::max(difference, std::fabs(s.shapeAt(m, v)[a] - sign * d.shapeAt(m, v)[a]));
      }
    worst_shape = std::max(worst_shape, difference / largest);
  }
  for (size_t i = 0; i < d.surface_positions.size(); ++i)
    worst_position = std::max(worst_position, std::fabs(s.surface_positions[i] - d.surface_positions[i]));
  // The eigen-solve converges eigenvalues to ~1e-12 (src/modal/eigensolver.cpp); shapes are
  // stored as float (7 digits).
  EXPECT_LT(worst_lambda, 1e-9);
  EXPECT_LT(worst_shape, 1e-5);
  EXPECT_LT(worst_position, 1e-15);
  EXPECT_NEAR(s.mass_kg / d.mass_kg, 1.0, 1e-12);
  for (size_t m = 0; m < d.modeCount(); ++m) EXPECT_NEAR(s.decayPerS(m) / d.decayPerS(m), 1.0, 1e-9) << m;
  for (size_t m = 0; m < d.modeCount(); ++m) EXPECT_NEAR(s.radiation_m2[m] / d.radiation_m2[m], 1.0, 1e-4) << m;
  EXPECT_EQ(s.mesh_hash, d.mesh_hash);
  EXPECT_EQ(s.mesh_source, d.mesh_source);
  EXPECT_EQ(s.material.name, "soft");
  std::printf("  scaled vs direct: eigenvalues %.2g, shapes %.2g (of each mode's largest), positions %.2g m\n",
              worst_lambda, worst_shape, worst_position);
}

// Two bars of one shape: steel 0.3 m and a softer, lighter 0.42 m copy (the same Poisson ratio),
// both dropped on the ground, both heard.
constexpr const char* kTwoBars = R"({
  "sample_rate": 48000, "duration": 0.6, "gravity": [0, 0, -9.81],
  "listener": {"position": [0.0, -1.0, 0.5]}, "ground": {"material": "concrete"}, "max_modes": 30,
  "objects": [
    {"name": "steel", "mesh": "box:0.3,0.02,0.02", "material": "steel", "order": 2,
     "position": [0, 0, 0.1], "orientation": [0.99996, 0.0, 0.00873, 0.0]},
    {"name": "other", "mesh": "box:0.42,0.028,0.028", "order": 2,
     "material": {"name": "other", "youngs_pa": 1.1e11, "poisson": 0.29, "density_kg_m3": 4000, "loss_factor": 3e-4},
     "position": [0, 0.2, 0.12], "orientation": [0.99996, 0.00873, 0.0, 0.0]}
  ]
})";

TEST(SimilarReuse, TwoSizesAndMaterialsOfOneShapeAreOneSolveAndTheCacheChangesNoByte) {
  Result<Scene> scene = parseScene(kTwoBars, "/tmp/two-bars.json");
  ASSERT_TRUE(scene) << scene.error().message;
  const std::string cache = testing::TempDir() + "/similar_reuse_" + std::to_string(getpid());
  std::filesystem::remove_all(cache);
  RenderSettings settings;
  settings.similar_reuse = true;
  settings.cache_dir = cache;
  Result<RenderResult> cold = renderScene(*scene, settings);
  ASSERT_TRUE(cold) << cold.error().message;
  EXPECT_EQ(cold->report.objects_sounded, 2u);
  EXPECT_EQ(cold->report.banks_computed, 1u);
  EXPECT_EQ(cold->report.banks_scaled, 1u);
  EXPECT_EQ(cold->banks[0].cache_key, cold->banks[1].cache_key);
  Result<RenderResult> warm = renderScene(*scene, settings);
  ASSERT_TRUE(warm) << warm.error().message;
  EXPECT_EQ(warm->report.banks_computed, 0u);
  EXPECT_EQ(warm->report.banks_cached, 1u);
  EXPECT_EQ(warm->report.banks_scaled, 1u);
  settings.cache_dir.clear();
  Result<RenderResult> uncached = renderScene(*scene, settings);
  ASSERT_TRUE(uncached) << uncached.error().message;
  ASSERT_EQ(cold->audio.samples.size(), warm->audio.samples.size());
  EXPECT_TRUE(cold->audio.samples == warm->audio.samples) << "a warm cache changed the render";
  EXPECT_TRUE(cold->audio.samples == uncached->audio.samples) << "the cache changed the render";
  std::filesystem::remove_all(cache);
}

}  // namespace
}  // namespace strike
