// SPDX-License-Identifier: MIT
// Stiff and extreme precompute cases, each with its expectation stated next to
// it. Synth-side extremes (damping, 60 s rings, linearity, pulse durations, allocation-free
// rendering) are covered in tests/unit/synth; see the table in the issue-6 report.
#include <gtest/gtest.h>

#include <cmath>

#include "strike/precompute/precompute.hpp"

namespace strike {
namespace {

Material material(double E, double nu, double rho) {
  Material m;
  m.name = "custom";
  m.youngs_pa = E;
  m.poisson = nu;
  m.density_kg_m3 = rho;
  return m;
}

Result<PrecomputeResult> run(const std::string& spec, const Material& m, int order, double max_freq, int max_modes,
                             double edge = 0.0) {
  PrecomputeSettings s;
  s.mesh_spec = spec;
  s.material = m;
  s.order = order;
  s.max_freq_hz = max_freq;
  s.max_modes = max_modes;
  s.target_edge_m = edge;
  return computeModeBank(s);
}

bool allFinite(const ModeBank& bank) {
  for (double l : bank.eigenvalues)
    if (!std::isfinite(l) || !(l > 0)) return false;
  for (float v : bank.shapes)
    if (!std::isfinite(v)) return false;
  return true;
}

// Expectation: a 5 mm steel cube's first elastic mode is ~300 kHz, far above a 20 kHz band:
// no mode is kept, the 6 rigid modes are dropped, and the cut-off count says modes were found
// above the band (the CLI prints "none below ... too small or too stiff"). Same for E = 1e12.
TEST(Stiff, FiveMillimetreSteelCubeAndDiamondLikeKeepNothingInBand) {
  for (double E : {2e11, 1e12}) {
    Result<PrecomputeResult> r = run("box:0.005,0.005,0.005", material(E, 0.29, 7850), 1, 20000.0, 50);
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_EQ(r->bank.modeCount(), 0u) << "E " << E;
    EXPECT_EQ(r->bank.rigid_modes_dropped, 6u);
  }
  // With the band opened (1 GHz) the modes exist, are finite, and scale as sqrt(E): the solve
  // copes with eigenvalues ~1e13 rad^2/s^2 (no loss of accuracy from units, to 1e-6).
  Result<PrecomputeResult> a = run("box:0.005,0.005,0.005", material(2e11, 0.29, 7850), 1, 1e9, 6);
  Result<PrecomputeResult> b = run("box:0.005,0.005,0.005", material(1e12, 0.29, 7850), 1, 1e9, 6);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->bank.modeCount(), b->bank.modeCount());
  ASSERT_GT(a->bank.modeCount(), 0u);
  EXPECT_TRUE(allFinite(a->bank) && allFinite(b->bank));
  EXPECT_GT(a->bank.frequencyHz(0), 1e5);
  for (size_t i = 0; i < a->bank.modeCount(); ++i)
    EXPECT_NEAR(b->bank.frequencyHz(i) / a->bank.frequencyHz(i), std::sqrt(5.0), 1e-6 * std::sqrt(5.0));
}

// Expectation: nearly incompressible rubber (nu 0.49, 0.4999) gives finite modes in Tet4 and
// Tet10. Tet4 volumetric locking shows as Tet4 frequencies well above Tet10 on the same mesh.
// Measured (0.1 x 0.02 x 0.02 m, 5 mm cells): first mode Tet4/Tet10 = 1.49 at nu 0.49 and 1.72
// at 0.4999 (Tet10 77.4 Hz both); required: > 1.10 at 0.4999. Use --order 2 for rubber.
TEST(NearlyIncompressible, RubberFiniteAndTet4LockingDetected) {
  for (double nu : {0.49, 0.4999}) {
    const Material rubber = material(2e6, nu, 1100);
    Result<PrecomputeResult> t4 = run("box:0.1,0.02,0.02", rubber, 1, 1e6, 6, 0.005);
    Result<PrecomputeResult> t10 = run("box:0.1,0.02,0.02", rubber, 2, 1e6, 6, 0.005);
    ASSERT_TRUE(t4.ok() && t10.ok());
    ASSERT_GT(t4->bank.modeCount(), 0u);
    ASSERT_GT(t10->bank.modeCount(), 0u);
    EXPECT_TRUE(allFinite(t4->bank)) << nu;
    EXPECT_TRUE(allFinite(t10->bank)) << nu;
    const double ratio = t4->bank.frequencyHz(0) / t10->bank.frequencyHz(0);
    std::printf("rubber nu %.4f: Tet4 %.2f Hz, Tet10 %.2f Hz, ratio %.3f\n", nu, t4->bank.frequencyHz(0),
                t10->bank.frequencyHz(0), ratio);
    EXPECT_GT(ratio, 1.0) << "Tet4 is stiffer than Tet10 (nu " << nu << ")";
    if (nu > 0.499) {
      EXPECT_GT(ratio, 1.10) << "locking at nu " << nu;
    }
  }
}

// Expectation: frequency ~ 1/size at fixed shape and material, from 1 mm to 5 m (ratio 5000),
// to 1e-6 relative: no overflow or underflow in mass (0.1 g ... 1 t scale) or eigenvalues.
TEST(Scale, TinyAndLargeObjectsScaleAsOneOverSize) {
  const Material steel = material(2e11, 0.29, 7850);
  double reference = 0;
  for (double L : {0.001, 0.05, 5.0}) {
    Result<PrecomputeResult> r =
        run("box:" + std::to_string(L) + "," + std::to_string(L / 4) + "," + std::to_string(L / 4), steel, 1, 1e12, 4,
            L / 8);
    ASSERT_TRUE(r.ok()) << r.error().message;
    ASSERT_EQ(r->bank.modeCount(), 4u);
    EXPECT_TRUE(allFinite(r->bank));
    EXPECT_NEAR(r->bank.mass_kg, 7850 * L * L * L / 16, 1e-9 * 7850 * L * L * L / 16);
    const double fL = r->bank.frequencyHz(0) * L;
    if (reference == 0) reference = fL;
    EXPECT_NEAR(fL, reference, 1e-6 * reference) << "L " << L;
  }
}

}  // namespace
}  // namespace strike
