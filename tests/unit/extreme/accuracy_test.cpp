// SPDX-License-Identifier: MIT
// Validation of the per-mode frequency error estimate (src/precompute/error_estimate.cpp) on cases
// with known answers: the free-free bar (Timoshenko bending, src/references/beam_theory.hpp),
// the free solid sphere (Lamb 1882, lamb_sphere.hpp), and a free thick plate against finer meshes. "Covered" means the true relative
// error is at most the estimate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "references/beam_theory.hpp"
#include "references/lamb_sphere.hpp"
#include "strike/precompute/element_order.hpp"
#include "strike/mesh/mesh.hpp"
#include "strike/precompute/precompute.hpp"

namespace strike {
namespace {

struct Coverage {
  int modes = 0, covered = 0;
  double worst_ratio = 0;  // largest true / estimate
};

PrecomputeResult compute(const std::string& spec, int order, const Material& material, double max_freq, int max_modes) {
  PrecomputeSettings settings;
  settings.mesh_spec = spec;
  settings.material = material;
  settings.order = order;
  settings.max_freq_hz = max_freq;
  settings.max_modes = max_modes;
  settings.error_estimate = true;
  Result<PrecomputeResult> r = computeModeBank(settings);
  EXPECT_TRUE(r.ok()) << r.error().message;
  return r.ok() ? std::move(*r) : PrecomputeResult{};
}

Material steel() {
  Material m;
  m.name = "steel";
  m.youngs_pa = 2.0e11;
  m.poisson = 0.29;
  m.density_kg_m3 = 7850;
  return m;
}

// Bar 0.3 x 0.02 x 0.02 m, Tet4 at the default size (4 cells across): the Tet4 error (8-16%)
// dwarfs the Timoshenko reference's own ~0.1% deviation from 3D elasticity, so the check is
// meaningful. Bending modes are the FEM modes nearest to a Timoshenko frequency (pairs).
// Measured: 6 of 6 bending modes covered, true/estimate <= 0.45 (the estimate is ~2-3x high).
TEST(ErrorEstimate, Tet4BarBendingCoveredByEstimate) {
  const PrecomputeResult r = compute("box:0.3,0.02,0.02", 1, steel(), 7000.0, 12);
  const ModeBank& bank = r.bank;
  ASSERT_EQ(bank.frequency_error_estimate.size(), bank.modeCount());
  EXPECT_EQ(r.report.error_estimate_method, "richardson");
  const test::BarProperties bar{2.0e11, 0.29, 7850, 0.3, 0.02, 0.02};
  const std::vector<double> timoshenko = test::timoshenkoFreeFreeHz(bar, 3);
  Coverage c;
  for (double ref : timoshenko) {
    // the two FEM modes nearest to this reference (square section: a degenerate pair)
    std::vector<std::pair<double, size_t>> near;
    for (size_t i = 0; i < bank.modeCount(); ++i) near.push_back({std::abs(bank.frequencyHz(i) - ref), i});
    std::sort(near.begin(), near.end());
    for (int k = 0; k < 2; ++k) {
      const size_t i = near[static_cast<size_t>(k)].second;
      const double truth = std::abs(bank.frequencyHz(i) - ref) / ref, est = bank.frequency_error_estimate[i];
      ++c.modes;
      c.covered += truth <= est;
      c.worst_ratio = std::max(c.worst_ratio, truth / est);
      std::printf("bar Tet4 %8.1f Hz ref %8.1f true %.3f%% est %.3f%%\n", bank.frequencyHz(i), ref, 100 * truth,
                  100 * est);
    }
  }
  std::printf("bar Tet4: %d of %d covered, worst true/estimate %.2f, estimate cost %.3f s of %.3f s\n", c.covered,
              c.modes, c.worst_ratio, r.report.error_estimate_seconds, bank.total_seconds);
  EXPECT_EQ(c.covered, c.modes);
}

// Solid steel-like sphere R = 0.05 m, nu = 0.25: sorted FEM modes against sorted Lamb modes
// (torsional + spheroidal, each root repeated 2n + 1 times), so no mode classification is
// needed. The faceted sphere's geometric error is part of what the coarser mesh sees.
Coverage sphereCoverage(int order, int count, double* cost_fraction) {
  Material m = steel();
  m.poisson = 0.25;
  const double R = 0.05, cs = std::sqrt(m.youngs_pa / (2 * (1 + m.poisson)) / m.density_kg_m3);
  const PrecomputeResult r = compute("sphere:0.05", order, m, 1e9, count);
  const ModeBank& bank = r.bank;
  const std::vector<double> etas = test::lambSphereEtas(m.poisson, 7.0);
  Coverage c;
  EXPECT_EQ(bank.frequency_error_estimate.size(), bank.modeCount()) << r.report.error_estimate_note;
  if (bank.frequency_error_estimate.size() != bank.modeCount()) return c;
  std::printf("sphere Tet%d: %s, h ratio %.2f\n", order == 2 ? 10 : 4, r.report.error_estimate_method.c_str(),
              r.report.error_estimate_ratio);
  for (size_t i = 0; i < bank.modeCount() && i < etas.size(); ++i) {
    const double ref = etas[i] * cs / (2 * 3.14159265358979323846 * R);
    const double truth = std::abs(bank.frequencyHz(i) - ref) / ref, est = bank.frequency_error_estimate[i];
    ++c.modes;
    c.covered += truth <= est;
    c.worst_ratio = std::max(c.worst_ratio, truth / est);
    std::printf("sphere Tet%d mode %2zu %9.1f Hz ref %9.1f true %.3f%% est %.3f%%\n", order == 2 ? 10 : 4, i,
                bank.frequencyHz(i), ref, 100 * truth, 100 * est);
  }
  *cost_fraction = r.report.error_estimate_seconds / bank.total_seconds;
  std::printf("sphere Tet%d: %d of %d covered, worst true/estimate %.2f, estimate cost %.0f%%\n", order == 2 ? 10 : 4,
              c.covered, c.modes, c.worst_ratio, 100 * *cost_fraction);
  return c;
}

// Measured (R = 5 cm, default mesh, 28 lowest modes, coarse h ratio 1.62): Tet4 28 of 28
// covered, true/estimate 0.07 to 0.81 (the estimate is 1.2x to 15x the true error); estimate
// cost 77-88% of this tiny bank's 0.1 s (TetGen remeshing, tried up to 3 times, dominates).
TEST(ErrorEstimate, SphereTet4AgainstLamb) {
  double cost = 0;
  const Coverage c = sphereCoverage(1, 28, &cost);
  ASSERT_GE(c.modes, 28);
  EXPECT_GE(c.covered, c.modes * 9 / 10);
  EXPECT_LT(c.worst_ratio, 1.5);
}

// Measured: Tet10 27 of 27 covered, true/estimate 0.11 to 0.75, estimate cost 29-36%. (With
// p = 4, before the re-faceting rule in error_estimate.cpp, 19 of 27 were covered and the worst
// was 2.7x under: the straight-edged sphere converges as h^2.)
TEST(ErrorEstimate, SphereTet10AgainstLamb) {
  double cost = 0;
  const Coverage c = sphereCoverage(2, 28, &cost);
  ASSERT_GE(c.modes, 27);
  EXPECT_GE(c.covered, c.modes * 9 / 10);
  EXPECT_LT(c.worst_ratio, 1.5);
}

PrecomputeResult plate(int order, double edge_m) {
  PrecomputeSettings settings;
  settings.mesh_spec = "box:0.1,0.1,0.01";  // h/a = 0.1, free edges
  settings.material = steel();
  settings.order = order;
  settings.target_edge_m = edge_m;
  settings.max_freq_hz = 1e9;
  settings.max_modes = 4;
  settings.error_estimate = true;
  Result<PrecomputeResult> r = computeModeBank(settings);
  EXPECT_TRUE(r.ok()) << r.error().message;
  return r.ok() ? std::move(*r) : PrecomputeResult{};
}

// Free thick plate, one Tet10 layer through the thickness (10 x 10 x 1 cells). Its coarse mesh
// keeps that one layer, so a count-based Richardson ratio sees only the in-plane coarsening:
// before the per-axis rule it estimated 0.45% for the first mode while the 2-layer mesh already
// moves it by 0.9% (true error against a 4-layer reference: 1.07%; `strike bench accuracy --plate`).
// Expectation: the estimate covers the change to the 2-layer mesh (the Tet4-on-corners bound).
TEST(ErrorEstimate, ThickPlateOneLayerTet10IsCovered) {
  const PrecomputeResult coarse = plate(2, 0.01), fine = plate(2, 0.005);
  ASSERT_GE(coarse.bank.modeCount(), 4u);
  ASSERT_GE(fine.bank.modeCount(), 4u);
  ASSERT_EQ(coarse.bank.frequency_error_estimate.size(), coarse.bank.modeCount()) << coarse.report.error_estimate_note;
  for (size_t i = 0; i < 4; ++i) {
    const double change = std::abs(coarse.bank.frequencyHz(i) - fine.bank.frequencyHz(i)) / fine.bank.frequencyHz(i);
    EXPECT_GE(coarse.bank.frequency_error_estimate[i], change)
        << "mode " << i << " (" << coarse.report.error_estimate_method << ")";
  }
}

// Tet4 plate with two layers: its coarse mesh has one, where Tet4 locks, and the difference said
// 10% for a true 34%. Expectation: every mode's estimate is "unknown" (1.0).
TEST(ErrorEstimate, ThickPlateTet4WithOneCoarseLayerIsUnknown) {
  const PrecomputeResult r = plate(1, 0.005);
  ASSERT_EQ(r.bank.frequency_error_estimate.size(), r.bank.modeCount()) << r.report.error_estimate_note;
  for (double e : r.bank.frequency_error_estimate) EXPECT_EQ(e, 1.0);
}

Material porcelain() {
  Material m;
  m.name = "porcelain";
  m.youngs_pa = 7.0e10;
  m.poisson = 0.22;
  m.density_kg_m3 = 2400;
  return m;
}

const std::string kThinCup = std::string(STRIKE_SOURCE_DIR) + "/tests/data/mesh/thin_cup.obj";

// Issue 15: a thin-walled cup (4 cm, 3 mm wall; tools/dev/make_mesh_assets.py). Its automatic
// mesh is as coarse as its walls allow, so no coarser mesh exists, and the estimate fell back to
// Tet4 on the Tet10 corners: 88% for a true 2.3% (the mug of the issue: 105% for 0.55%).
// Now a finer mesh is solved instead. Reference: Tet10 at --size 0.0018, 71.5k tets (20x the
// tested mesh's 3.5k), 359k DOF: `strike modes tests/data/mesh/thin_cup.obj --material porcelain
// --order 2 --size 0.0018 --max-modes 4 --no-error-estimate`. Expectation: the estimate covers
// the true error and is within 5x of it (measured: 3.77% for 1.46%, 2.6x).
TEST(ErrorEstimate, ThinWalledCupTet10WithinASmallFactor) {
  const double reference_hz[] = {6730.172, 6730.548};
  const PrecomputeResult r = compute(kThinCup, 2, porcelain(), 20000.0, 2);
  ASSERT_EQ(r.bank.frequency_error_estimate.size(), 2u) << r.report.error_estimate_note;
  EXPECT_EQ(r.report.error_estimate_method, "richardson-finer") << r.report.error_estimate_note;
  for (size_t i = 0; i < 2; ++i) {
    const double truth = std::abs(r.bank.frequencyHz(i) - reference_hz[i]) / reference_hz[i];
    const double estimate = r.bank.frequency_error_estimate[i];
    std::printf("    mode %zu: %.3f Hz, true error %.3f%%, estimate %.3f%% (%.2fx)\n", i, r.bank.frequencyHz(i),
                100 * truth, 100 * estimate, estimate / truth);
    EXPECT_GE(estimate, truth) << "mode " << i;
    EXPECT_LE(estimate, 5.0 * truth) << "mode " << i;
  }
}

// Issue 15 item 13: the default order follows the wall. 2 V / A is the thickness of a flat wall
// (a plate 4 mm thick: 3.85 mm, its edges add area) and L / 3 for a cube.
TEST(ElementOrder, ThinShapesGetTet10AndSolidsTet4) {
  struct Case {
    std::string spec;
    int order;
    double wall_m;
  };
  const Case cases[] = {{kThinCup, 2, 0.0},
                        {"box:0.2,0.2,0.004", 2, 2.0 * 0.2 * 0.2 * 0.004 / (2 * 0.2 * 0.2 + 4 * 0.2 * 0.004)},
                        {"box:0.3,0.02,0.02", 2, 0.0},
                        {"box:0.1,0.1,0.1", 1, 0.1 / 3.0},
                        {"sphere:0.05", 1, 0.0}};
  for (const Case& c : cases) {
    Result<LoadedMesh> mesh = loadTetMesh(c.spec, MeshOptions{});
    ASSERT_TRUE(mesh.ok()) << mesh.error().message;
    const OrderChoice choice = chooseElementOrder(mesh->mesh);
    std::printf("    %s: %s\n", c.spec.c_str(), choice.reason.c_str());
    EXPECT_EQ(choice.order, c.order) << c.spec << ": " << choice.reason;
    if (c.wall_m > 0) {
      EXPECT_NEAR(choice.wall_m, c.wall_m, 1e-6 * c.wall_m) << c.spec;
    }
  }
}

// The automatic order meshes a thin box for Tet10 at twice the Tet4 edge (kTet10EdgeFactor): about
// the unknowns of its Tet4 mesh, not the ~8x of Tet10 on that mesh, and still far closer than Tet4
// (8-16% high here, locked). Checked against Timoshenko's free-free bending modes (pairs of the
// square section) and against the bank's own error estimate.
TEST(ElementOrder, AThinBoxGetsACoarserTet10MeshThatStillMeetsItsEstimate) {
  const std::string spec = "box:0.3,0.02,0.02";
  Result<LoadedMesh> tet4 = loadTetMesh(spec, MeshOptions{});
  ASSERT_TRUE(tet4.ok()) << tet4.error().message;
  const double tet4_dofs = 3.0 * static_cast<double>(tet4->mesh.nodes.rows());
  const double promoted_dofs = 3.0 * static_cast<double>(promoteToTet10(tet4->mesh).nodes.rows());
  const PrecomputeResult r = compute(spec, kAutoOrder, steel(), 7000.0, 12);
  const ModeBank& bank = r.bank;
  EXPECT_EQ(bank.element_order, 2u);
  const double dofs = static_cast<double>(r.report.dofs);
  std::printf("bar auto: %.0f DOF (Tet4 mesh %.0f, Tet10 on it %.0f), estimate %s\n", dofs, tet4_dofs, promoted_dofs,
              r.report.error_estimate_method.c_str());
  EXPECT_LE(dofs, tet4_dofs);
  EXPECT_LE(dofs, 0.25 * promoted_dofs);
  ASSERT_EQ(bank.frequency_error_estimate.size(), bank.modeCount());
  const test::BarProperties bar{2.0e11, 0.29, 7850, 0.3, 0.02, 0.02};
  for (double ref : test::timoshenkoFreeFreeHz(bar, 3)) {
    std::vector<std::pair<double, size_t>> near;
    for (size_t i = 0; i < bank.modeCount(); ++i) near.push_back({std::abs(bank.frequencyHz(i) - ref), i});
    std::sort(near.begin(), near.end());
    for (int k = 0; k < 2; ++k) {
      const size_t i = near[static_cast<size_t>(k)].second;
      const double truth = std::abs(bank.frequencyHz(i) - ref) / ref, est = bank.frequency_error_estimate[i];
      std::printf("bar auto %8.1f Hz ref %8.1f true %.3f%% est %.3f%%\n", bank.frequencyHz(i), ref, 100 * truth,
                  100 * est);
      EXPECT_LE(truth, est) << "mode " << i << " at " << bank.frequencyHz(i) << " Hz";
      EXPECT_LT(truth, 0.01) << "mode " << i << " at " << bank.frequencyHz(i) << " Hz";
    }
  }
}

}  // namespace
}  // namespace strike
