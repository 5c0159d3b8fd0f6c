// SPDX-License-Identifier: MIT
// The acoustic transfer with exact similarity reuse (src/include/strike/precompute/normalized_problem.hpp):
// one unit transfer per shape, wave speed E/rho and number of modes kept, scaled to every size
// and density; against a direct solve of each object, against the scaling law to the bit, and a
// render that solves it once, reads it from the cache, and gives the same bytes either way.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <string>

#include "strike/bank/bank.hpp"
#include "strike/cache/bank_cache.hpp"
#include "strike/core/hash.hpp"
#include "strike/precompute/normalized_problem.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike {
namespace {

// Four bars of one shape (box 1 x 0.1 x 0.0667 at unit size), dropped side by side: steel at 0.3
// and 0.42 m (two sizes, one material), "heavy" at 0.36 m (twice steel's E and rho: steel's wave
// speed, another density) and "other" at 0.36 m (another E/rho, steel's Poisson ratio). Each keeps
// its lowest 4 modes (max_modes; the 4th lies at 4.35 kHz on the 0.3 m bar, 3.77 kHz on "other").
// Four are enough for every check below (the key holds the number kept, the scaling is per
// coefficient, each mode is compared with a direct solve), and the test's seven transfer solves,
// its slowest part under ASan, cost about half of what eight modes (up to 8.4 kHz) did.
constexpr const char* kFourBars = R"({
  "sample_rate": 48000, "duration": 0.3, "gravity": [0, 0, -9.81],
  "listener": {"position": [0.0, -1.0, 0.5]}, "ground": {"material": "concrete"}, "max_modes": 4,
  "objects": [
    {"name": "small", "mesh": "box:0.3,0.03,0.02", "material": "steel", "order": 2,
     "position": [0, 0, 0.1], "orientation": [0.99996, 0.0, 0.00873, 0.0]},
    {"name": "large", "mesh": "box:0.42,0.042,0.028", "material": "steel", "order": 2,
     "position": [0, 0.25, 0.12], "orientation": [0.99996, 0.00873, 0.0, 0.0]},
    {"name": "heavy", "mesh": "box:0.36,0.036,0.024", "order": 2,
     "material": {"name": "heavy", "youngs_pa": 4e11, "poisson": 0.29, "density_kg_m3": 15700, "loss_factor": 3e-4},
     "position": [0, 0.5, 0.11], "orientation": [0.99996, 0.0, 0.00873, 0.0]},
    {"name": "other", "mesh": "box:0.36,0.036,0.024", "order": 2,
     "material": {"name": "other", "youngs_pa": 1.1e11, "poisson": 0.29, "density_kg_m3": 4000, "loss_factor": 3e-4},
     "position": [0, 0.75, 0.11], "orientation": [0.99996, 0.00873, 0.0, 0.0]}
  ]
})";

std::string hex(uint64_t key) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(key));
  return text;
}

/// What the render asks of object i's precompute (src/scene/render.cpp, precomputeSettings).
PrecomputeSettings objectSettings(const Scene& scene, size_t i, double rate_hz) {
  const SceneObject& object = scene.objects[i];
  PrecomputeSettings settings;
  settings.mesh_spec = object.mesh;
  settings.material = object.material;
  settings.order = object.order;
  settings.target_edge_m = object.size_m;
  settings.mesh_scale = object.mesh_scale;
  settings.max_freq_hz = std::min(scene.max_freq_hz, 0.45 * rate_hz);
  settings.max_modes = scene.max_modes;
  settings.acoustic_transfer = true;
  return settings;
}

/// Object i's bank as the render makes it from its cache entries: the normalized solve scaled,
/// and the unit transfer scaled.
ModeBank bankFromCache(const Scene& scene, size_t i, const RenderResult& rendered, const std::string& cache) {
  const PrecomputeSettings settings = objectSettings(scene, i, 48000);
  Result<ModeBank> normalized = readBank(cache + "/" + hex(rendered.banks[i].cache_key) + ".modes");
  Result<ModeBank> unit = readBank(cache + "/" + hex(rendered.banks[i].transfer_key) + ".transfer");
  EXPECT_TRUE(normalized && unit);
  if (!normalized || !unit) return {};
  const NormalizedProblem problem = normalizeProblem(settings);
  Result<ModeBank> scaled = scaleNormalizedBank(*normalized, problem, settings,
                                                fnv1a64(settings.mesh_spec.data(), settings.mesh_spec.size()));
  EXPECT_TRUE(scaled);
  EXPECT_TRUE(isUnitTransferOf(*unit, *normalized, settings, scaled->modeCount()));
  Status attached = attachUnitTransfer(*scaled, *unit, problem, settings);
  EXPECT_TRUE(attached) << attached.error().message;
  return std::move(*scaled);
}

/// F' = f F with f = float(shape_factor s^2), shape_factor = 1 / sqrt((rho / rho_ref) s^3), from
/// the unit transfer: the scaling law written out here, not taken from the library.
float transferFactor(const PrecomputeSettings& settings) {
  const double s = normalizeProblem(settings).scale;
  const double shape_factor = 1.0 / std::sqrt(settings.material.density_kg_m3 / kNormalizedDensity_kg_m3 * s * s * s);
  return static_cast<float>(shape_factor * s * s);
}

TEST(SimilarTransfer, OneSolvePerShapeAndWaveSpeedScaledToTheBitAndEqualToADirectSolve) {
  Result<Scene> scene = parseScene(kFourBars, "/tmp/four-bars.json");
  ASSERT_TRUE(scene) << scene.error().message;
  const std::string cache = testing::TempDir() + "/similar_transfer_" + std::to_string(getpid());
  std::filesystem::remove_all(cache);
  RenderSettings settings;
  settings.similar_reuse = true;
  settings.acoustic_transfer = true;
  settings.cache_dir = cache;
  Result<RenderResult> cold = renderScene(*scene, settings);
  ASSERT_TRUE(cold) << cold.error().message;
  const RenderReport& r = cold->report;
  ASSERT_EQ(r.objects_sounded, 4u);
  EXPECT_EQ(r.banks_computed, 1u);
  EXPECT_EQ(r.banks_scaled, 3u);
  // small, large and heavy share steel's wave speed: one solve; other has its own.
  EXPECT_EQ(r.transfers_solved, 2u);
  EXPECT_EQ(r.transfers_shared, 2u);
  EXPECT_EQ(r.transfers_cached, 0u);
  const std::vector<BodyBank>& banks = cold->banks;
  EXPECT_NE(banks[0].transfer_key, 0u);
  EXPECT_EQ(banks[1].transfer_key, banks[0].transfer_key);
  EXPECT_EQ(banks[2].transfer_key, banks[0].transfer_key);
  EXPECT_NE(banks[3].transfer_key, banks[0].transfer_key);
  size_t transfer_entries = 0;
  Result<std::vector<CacheEntry>> entries = listCache(cache);  // what `strike cache` lists and prunes
  ASSERT_TRUE(entries);
  for (const CacheEntry& e : *entries)
    transfer_entries += e.path.size() > 9 && e.path.substr(e.path.size() - 9) == ".transfer";
  EXPECT_EQ(transfer_entries, 2u);

  // Every body's transfer is the shared unit transfer times its own factor, rounded once to
  // float: to the bit; so the large bar's is the small one's times the ratio of the factors, to
  // two roundings.
  Result<ModeBank> unit = readBank(cache + "/" + hex(banks[0].transfer_key) + ".transfer");
  ASSERT_TRUE(unit) << unit.error().message;
  ModeBank bodies[3];
  for (size_t i = 0; i < 3; ++i) {
    bodies[i] = bankFromCache(*scene, i, *cold, cache);
    const AcousticTransfer& t = bodies[i].transfer;
    ASSERT_EQ(bodies[i].modeCount(), 4u) << "the test needs every body to keep max_modes modes";
    ASSERT_EQ(t.coefficients.size(), unit->transfer.coefficients.size());
    const float f = transferFactor(objectSettings(*scene, i, 48000));
    size_t differing = 0;
    for (size_t j = 0; j < t.coefficients.size(); ++j)
      differing += t.coefficients[j] != unit->transfer.coefficients[j] * f;
    EXPECT_EQ(differing, 0u) << scene->objects[i].name;
    const double s = normalizeProblem(objectSettings(*scene, i, 48000)).scale;
    for (int k = 0; k < 9; ++k)
      EXPECT_EQ(t.translation_dipole_m3[k], unit->transfer.translation_dipole_m3[k] * (s * s * s));
  }
  const double ratio = double(transferFactor(objectSettings(*scene, 1, 48000))) /
                       double(transferFactor(objectSettings(*scene, 0, 48000)));
  EXPECT_NEAR(ratio, std::pow(1.4, 0.5), 1e-6);  // s^2 / s^1.5: 1.4 times larger, the same steel
  double worst_ratio = 0;
  for (size_t j = 0; j < bodies[0].transfer.coefficients.size(); ++j) {
    const std::complex<double> a(bodies[0].transfer.coefficients[j]), b(bodies[1].transfer.coefficients[j]);
    if (std::abs(a) > 0) worst_ratio = std::max(worst_ratio, std::abs(b / a - ratio) / ratio);
  }
  EXPECT_LT(worst_ratio, 3 * 0x1p-24 * 2);  // two roundings to float (and their quotient's)

  // Against a direct --transfer solve of each steel bar at its own size: per mode, the far field
  // (up to the eigenvector's sign) within the two solves' estimates, its rms and a few directions.
  const double directions[][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {-1, 2, 0.5}};
  for (size_t i = 0; i < 2; ++i) {
    Result<PrecomputeResult> direct = computeModeBank(objectSettings(*scene, i, 48000));
    ASSERT_TRUE(direct) << direct.error().message;
    const AcousticTransfer& d = direct->bank.transfer;
    const AcousticTransfer& s = bodies[i].transfer;
    ASSERT_EQ(d.modeCount(), s.modeCount());
    const uint32_t order = std::max(d.maxOrder(), s.maxOrder());
    std::vector<double> sh((order + 1) * (order + 1));
    std::vector<std::complex<double>> fd(d.modeCount()), fs(s.modeCount());
    double worst_rms = 0, worst_coefficients = 0, worst_direction = 0, worst_over_estimate = 0;
    for (size_t m = 0; m < d.modeCount(); ++m) {
      // Up to sign: F is linear in the mode shape, whose sign each eigen-solve picks.
      std::complex<double> dot = 0;
      const uint64_t common = std::min(d.offset[m + 1] - d.offset[m], s.offset[m + 1] - s.offset[m]);
      for (uint64_t j = 0; j < common; ++j)
        dot += std::complex<double>(s.coefficients[s.offset[m] + j]) *
               std::conj(std::complex<double>(d.coefficients[d.offset[m] + j]));
      const double sign = dot.real() < 0 ? -1.0 : 1.0;
      double difference = 0, norm = 0;
      const uint64_t longest = std::max(d.offset[m + 1] - d.offset[m], s.offset[m + 1] - s.offset[m]);
      for (uint64_t j = 0; j < longest; ++j) {
        const std::complex<double> cd =
            j < d.offset[m + 1] - d.offset[m] ? std::complex<double>(d.coefficients[d.offset[m] + j]) : 0.0;
        const std::complex<double> cs =
            j < s.offset[m + 1] - s.offset[m] ? std::complex<double>(s.coefficients[s.offset[m] + j]) : 0.0;
        difference += std::norm(cs - sign * cd);
        norm += std::norm(cd);
      }
      const double estimate = double(d.relative_error[m]) + double(s.relative_error[m]);
      const double coefficients = std::sqrt(difference / norm);  // = rms over directions of the difference
      const double rms = std::fabs(s.rmsFarField(m) / d.rmsFarField(m) - 1.0);
      EXPECT_LT(rms, estimate) << scene->objects[i].name << " mode " << m;
      EXPECT_LT(coefficients, estimate) << scene->objects[i].name << " mode " << m;
      worst_rms = std::max(worst_rms, rms);
      worst_coefficients = std::max(worst_coefficients, coefficients);
      worst_over_estimate = std::max(worst_over_estimate, coefficients / estimate);
    }
    for (const auto& direction : directions) {
      realSphericalHarmonics(order, direction, sh.data());
      evaluateFarField(d, sh.data(), fd.data());
      evaluateFarField(s, sh.data(), fs.data());
      for (size_t m = 0; m < d.modeCount(); ++m) {
        // A direction's error is not bounded by the rms one: within 4x the estimates of the rms.
        const double off = std::fabs(std::abs(fs[m]) - std::abs(fd[m])) / d.rmsFarField(m);
        EXPECT_LT(off, 4 * (double(d.relative_error[m]) + double(s.relative_error[m])))
            << scene->objects[i].name << " mode " << m;
        worst_direction = std::max(worst_direction, off);
      }
    }
    // The dipole has no estimate of its own: within the solver's target of its largest entry.
    // (The two solves do not agree to rounding: the solver is not covariant with a scale that is
    // not a power of 2. The same bank solved at unit size and scaled by 0.3 gives far fields 2-6%
    // apart, within the estimates, and dipoles 0.02-0.7% apart; by 2, 1e-5, as in
    // TransferSolver.ASimilarBankScalesItsTransferAsADirectSolveFindsIt. So they differ by the
    // discretization's error, not by the scaling.)
    const double largest =
        std::max({d.translation_dipole_m3[0], d.translation_dipole_m3[4], d.translation_dipole_m3[8]});
    double worst_dipole = 0;
    for (int k = 0; k < 9; ++k)
      worst_dipole =
          std::max(worst_dipole, std::fabs(s.translation_dipole_m3[k] - d.translation_dipole_m3[k]) / largest);
    EXPECT_LT(worst_dipole, TransferSettings{}.target_relative_error);
    std::printf(
        "  %s vs a direct solve: rms %.2g, coefficients %.2g (%.2g of the estimates), directions %.2g, "
        "dipole %.2g\n",
        scene->objects[i].name.c_str(), worst_rms, worst_coefficients, worst_over_estimate, worst_direction,
        worst_dipole);
  }

  // `strike modes --similar --transfer` (computeSimilarModeBank) solves the unit transfer afresh:
  // the very transfer the render read from its cache, to the bit.
  Result<PrecomputeResult> fresh = computeSimilarModeBank(objectSettings(*scene, 1, 48000));
  ASSERT_TRUE(fresh) << fresh.error().message;
  EXPECT_TRUE(fresh->bank.transfer.coefficients == bodies[1].transfer.coefficients);
  EXPECT_TRUE(fresh->bank.transfer.relative_error == bodies[1].transfer.relative_error);
  EXPECT_TRUE(fresh->bank.transfer.translation_dipole_m3 == bodies[1].transfer.translation_dipole_m3);

  // A warm cache solves nothing, and neither it nor no cache at all changes a byte.
  Result<RenderResult> warm = renderScene(*scene, settings);
  ASSERT_TRUE(warm) << warm.error().message;
  EXPECT_EQ(warm->report.banks_computed, 0u);
  EXPECT_EQ(warm->report.transfers_solved, 0u);
  EXPECT_EQ(warm->report.transfers_cached, 2u);
  EXPECT_EQ(warm->report.transfers_shared, 2u);
  settings.cache_dir.clear();
  Result<RenderResult> uncached = renderScene(*scene, settings);
  ASSERT_TRUE(uncached) << uncached.error().message;
  EXPECT_EQ(uncached->report.transfers_solved, 2u);
  ASSERT_EQ(cold->audio.samples.size(), warm->audio.samples.size());
  EXPECT_TRUE(cold->audio.samples == warm->audio.samples) << "a warm cache changed the render";
  EXPECT_TRUE(cold->audio.samples == uncached->audio.samples) << "the cache changed the render";
  std::filesystem::remove_all(cache);
}

TEST(SimilarTransfer, TheKeyHoldsTheWaveSpeedTheModesKeptAndTheSettings) {
  PrecomputeSettings steel;
  steel.material = {"steel", 2e11, 0.29, 7850, 0, 0};
  PrecomputeSettings heavy = steel;  // the same E/rho
  heavy.material = {"heavy", 4e11, 0.29, 15700, 0, 0};
  PrecomputeSettings other = steel;
  other.material = {"other", 1.1e11, 0.29, 4000, 0, 0};
  const uint64_t normalized_key = 0x1234;
  EXPECT_EQ(unitTransferCacheKey(normalized_key, steel, 8), unitTransferCacheKey(normalized_key, heavy, 8));
  EXPECT_NE(unitTransferCacheKey(normalized_key, steel, 8), unitTransferCacheKey(normalized_key, other, 8));
  EXPECT_NE(unitTransferCacheKey(normalized_key, steel, 8), unitTransferCacheKey(normalized_key, steel, 7));
  EXPECT_NE(unitTransferCacheKey(normalized_key, steel, 8), unitTransferCacheKey(normalized_key + 1, steel, 8));
  // No mode kept: the dipole alone, which no material changes.
  EXPECT_EQ(unitTransferCacheKey(normalized_key, steel, 0), unitTransferCacheKey(normalized_key, other, 0));
  PrecomputeSettings finer = steel;
  finer.transfer.target_relative_error = 0.02;
  EXPECT_NE(unitTransferCacheKey(normalized_key, steel, 8), unitTransferCacheKey(normalized_key, finer, 8));
  PrecomputeSettings one_thread = steel;  // the same bits on one thread or two
  one_thread.transfer.threads = 1;
  EXPECT_EQ(unitTransferCacheKey(normalized_key, steel, 8), unitTransferCacheKey(normalized_key, one_thread, 8));
}

}  // namespace
}  // namespace strike
