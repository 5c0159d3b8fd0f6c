// SPDX-License-Identifier: MIT
// The acoustic transfer solver (src/transfer/) against closed forms:
// a sphere's surface acceleration Y_nm radiates A h_n(kr) Y_nm exactly, a rigid sphere's
// translation has the dipole tensor 2 pi a^3 I, and the transfer is linear in the mode shape.
#include <gtest/gtest.h>
#include <Eigen/Core>

#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

#include "references/axisymmetric_dipole.hpp"
#include "strike/mesh/mesh.hpp"
#include "strike/precompute/similar_bank.hpp"
#include "strike/transfer/transfer_solver.hpp"

namespace strike {
namespace {

using cd = std::complex<double>;

/// A bank on a geodesic sphere of radius a (edge ~ edge_m), no modes yet.
ModeBank sphereBank(double a, double edge_m) {
  Result<SurfaceMesh> mesh = makeSphereSurface(a, edge_m);
  EXPECT_TRUE(mesh);
  ModeBank bank;
  for (Eigen::Index v = 0; v < mesh->V.rows(); ++v)
    for (int c = 0; c < 3; ++c) {
      bank.surface_positions.push_back(mesh->V(v, c));
      bank.surface_normals.push_back(static_cast<float>(mesh->V.row(v).normalized()[c]));
    }
  for (Eigen::Index f = 0; f < mesh->F.rows(); ++f)
    for (int c = 0; c < 3; ++c) bank.surface_triangles.push_back(static_cast<uint32_t>(mesh->F(f, c)));
  return bank;
}

/// Adds a "mode" at wavenumber k whose surface acceleration is Y_nm(v) along the radius.
void addYnmMode(ModeBank& bank, int n, int m, double k, double c_air) {
  bank.eigenvalues.push_back(std::pow(k * c_air, 2));
  const size_t vertices = bank.surfaceVertexCount();
  std::vector<double> Y((n + 1) * (n + 1));
  for (size_t v = 0; v < vertices; ++v) {
    const double* p = &bank.surface_positions[3 * v];
    realSphericalHarmonics(static_cast<uint32_t>(n), p, Y.data());
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int c = 0; c < 3; ++c) bank.shapes.push_back(static_cast<float>(Y[n * n + n + m] * p[c] / r));
  }
}

/// The exact coefficient of Y_nm: F = -rho (-i)^{n+1} Y_nm / (k^2 h_n'(ka)), with e^{-i omega t}
/// and h_n = j_n + i y_n (outgoing); from p = A h_n(kr) Y_nm, dp/dr(a) = -rho Y_nm.
cd exactCoefficient(int n, double k, double a, double rho) {
  const double x = k * a;
  auto h = [&](int order) { return cd(std::sph_bessel(order, x), std::sph_neumann(order, x)); };
  const cd dh = n == 0 ? -h(1) : h(n - 1) - (n + 1.0) / x * h(n);
  return -rho * std::pow(cd(0, -1), n + 1) / (k * k * dh);
}

struct SphereError {
  double relative = 0, level_db = 0, phase_deg = 0, estimate = 0;
};

SphereError compare(const AcousticTransfer& t, size_t mode, int n, int m, double k, double a, double rho) {
  const cd exact = exactCoefficient(n, k, a, rho);
  double wrong = 0.0;
  cd got = 0.0;
  for (uint64_t j = t.offset[mode]; j < t.offset[mode + 1]; ++j) {
    const cd c(t.coefficients[j].real(), t.coefficients[j].imag());
    const uint64_t index = j - t.offset[mode];
    const bool main = index == static_cast<uint64_t>(n * n + n + m);
    if (main) got = c;
    wrong += std::norm(main ? c - exact : c);
  }
  SphereError e;
  e.relative = std::sqrt(wrong) / std::abs(exact);
  e.level_db = 20 * std::log10(std::abs(got) / std::abs(exact));
  e.phase_deg = std::arg(got / exact) * 180 / M_PI;
  e.estimate = t.relative_error[mode];
  return e;
}

/// A bank of the surface mesh (V, F) with no modes yet.
ModeBank surfaceBank(const SurfaceMesh& mesh) {
  ModeBank bank;
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v)
    for (int c = 0; c < 3; ++c) bank.surface_positions.push_back(mesh.V(v, c));
  bank.surface_normals.assign(bank.surface_positions.size(), 0.0f);
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
    for (int c = 0; c < 3; ++c) bank.surface_triangles.push_back(static_cast<uint32_t>(mesh.F(f, c)));
  return bank;
}

// The analytic case: n = 0..4, ka 0.1 to 20, on a sphere of 2420 triangles (edge a / 10,
// so ka = 20 has 3 edges per wavelength). Error = rms over directions of the far field's error
// relative to the exact one's rms; level and phase of the Y_nm coefficient itself.
TEST(TransferSolver, SphereWithYnmAccelerationGivesTheExactExteriorSolution) {
  const double a = 0.1, c_air = 343.0, rho = 1.2;
  const double kas[] = {0.1, 1.0, 5.0, 10.0, 20.0};
  ModeBank bank = sphereBank(a, 0.01);
  std::vector<std::array<int, 2>> nm;
  std::vector<double> ks;
  for (double ka : kas)
    for (int n = 0; n <= 4; ++n) {
      const int m = n % 2 == 0 ? n / 2 : -n;  // a mix of zonal, tesseral and sectoral
      addYnmMode(bank, n, m, ka / a, c_air);
      nm.push_back({n, m});
      ks.push_back(ka / a);
    }
  TransferSettings settings;
  settings.air_density_kg_m3 = rho;
  settings.speed_of_sound_m_s = c_air;
  std::vector<TransferModeStats> stats;
  Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings, {}, &stats);
  ASSERT_TRUE(t) << t.error().message;
  EXPECT_EQ(t->checkConsistency(bank.modeCount()), "");
  std::printf("sphere of %zu triangles\n   ka  n  elems chief order    error       dB     deg  estimate  seconds\n",
              bank.surface_triangles.size() / 3);
  for (size_t i = 0; i < bank.modeCount(); ++i) {
    const int n = nm[i][0];
    const double ka = ks[i] * a;
    const SphereError e = compare(*t, i, n, nm[i][1], ks[i], a, rho);
    std::printf("%5.1f  %d  %5u %5u %5u  %9.4f  %7.3f  %6.2f  %8.4f  %7.3f\n", ka, n, stats[i].elements,
                stats[i].chief_points, stats[i].order, e.relative, e.level_db, e.phase_deg, e.estimate,
                stats[i].seconds);
    // At low ka the order n radiates ~(ka)^n / (2n-1)!! as much as a monopole of the same
    // strength (1e-7 for n = 4 at ka = 0.1, 1e-2 at ka = 1): the discretized data's residual
    // monopole and dipole (O(h^2)) outweigh it. The coefficient itself is still right (level);
    // the estimate says the rest.
    const bool swamped = (ka < 0.5 && n >= 3) || (ka < 2 && n >= 4);
    if (!swamped) {
      EXPECT_LT(e.relative, ka <= 10 ? 0.06 : 0.12) << "ka " << ka << " n " << n;
      EXPECT_LT(std::abs(e.level_db), 0.6) << "ka " << ka << " n " << n;
      EXPECT_LT(std::abs(e.phase_deg), 2.0) << "ka " << ka << " n " << n;
    }
    // The estimate is honest where it matters: at least half the actual error (or "over 100%").
    if (e.relative > 0.01) {
      EXPECT_GE(e.estimate, std::min(0.5 * e.relative, 1.0)) << "ka " << ka << " n " << n;
    }
  }
  // The rigid translation's dipole tensor: M = 2 pi a^3 I (volume + added mass; Lamb,
  // Hydrodynamics, sec. 92).
  const double sphere = 2 * M_PI * a * a * a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(t->translation_dipole_m3[i * 3 + j], i == j ? sphere : 0.0, 0.01 * sphere) << i << "," << j;
}

// Modes of nearly one frequency share one solve at the first one's wavenumber while the gap's
// effect on the far field, gap x (1 + ka), is at most a tenth of the target; the estimate says
// what it costs. Three modes of the same shape: the second 0.5x that gap above the first (shared:
// the same coefficients to the bit), the third 2x (solved at its own wavenumber). Each is within
// the sphere's error of the exact field at its own frequency.
TEST(TransferSolver, ModesOfNearlyOneFrequencyShareASolveWhileTheGapCostsATenthOfTheTarget) {
  const double a = 0.05, c_air = 343.0, rho = 1.2, ka = 3.0;
  ModeBank bank = sphereBank(a, 0.01);
  double radius = 0.0;  // of the surface about its centre (the solver's ka)
  for (size_t v = 0; v < bank.surfaceVertexCount(); ++v)
    radius = std::max(
        radius, std::sqrt(std::pow(bank.surface_positions[3 * v], 2) + std::pow(bank.surface_positions[3 * v + 1], 2) +
                          std::pow(bank.surface_positions[3 * v + 2], 2)));
  TransferSettings settings;
  settings.air_density_kg_m3 = rho;
  settings.speed_of_sound_m_s = c_air;
  settings.fixed_elements = 300;
  const double k = ka / a, shared_gap = 0.1 * settings.target_relative_error / (1.0 + k * radius);
  const double ks[] = {k, k * (1.0 + 0.5 * shared_gap), k * (1.0 + 2.0 * shared_gap)};
  for (double kk : ks) addYnmMode(bank, 1, 0, kk, c_air);
  Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings);
  ASSERT_TRUE(t) << t.error().message;
  const size_t count = t->offset[1] - t->offset[0];
  ASSERT_EQ(t->offset[2] - t->offset[1], count);
  EXPECT_EQ(
      std::memcmp(&t->coefficients[t->offset[0]], &t->coefficients[t->offset[1]], count * sizeof(t->coefficients[0])),
      0);
  ASSERT_EQ(t->offset[3] - t->offset[2], count);
  EXPECT_NE(
      std::memcmp(&t->coefficients[t->offset[0]], &t->coefficients[t->offset[2]], count * sizeof(t->coefficients[0])),
      0);
  // The shared mode's estimate holds its gap's effect (added in quadrature).
  const double gap_effect = 0.5 * shared_gap * (1.0 + k * radius);
  EXPECT_NEAR(std::pow(t->relative_error[1], 2), std::pow(t->relative_error[0], 2) + gap_effect * gap_effect,
              1e-3 * std::pow(t->relative_error[0], 2));
  for (size_t i = 0; i < 3; ++i) {
    const SphereError e = compare(*t, i, 1, 0, ks[i], a, rho);
    EXPECT_LT(e.relative, 0.06) << i;
    EXPECT_LT(std::abs(e.level_db), 0.6) << i;
  }
}

// Eigen sizes the blocks of the products inside its LU and QR from the cache sizes it reads off
// the CPU; were a sum split by them, an Intel and an AMD machine would solve other last bits. The
// transfer must not depend on them (docs/determinism.md): here L1 256 B against 256 kB (also
// checked at 1000 unknowns: the same bits; the LU's panels are narrower than any split).
TEST(TransferSolver, SameBitsWhateverCacheSizesEigenReads) {
  const double a = 0.05, c_air = 343.0;
  ModeBank bank = sphereBank(a, 0.01);
  addYnmMode(bank, 1, 0, 3.0 / a, c_air);
  addYnmMode(bank, 2, 1, 6.0 / a, c_air);  // ka 6: CHIEF points, a least-squares (QR) solve
  TransferSettings settings;
  settings.fixed_elements = 400;
  std::ptrdiff_t l1 = 0, l2 = 0, l3 = 0;
  Eigen::internal::manage_caching_sizes(Eigen::GetAction, &l1, &l2, &l3);
  std::vector<std::vector<std::complex<float>>> runs;
  for (const std::ptrdiff_t scale : {std::ptrdiff_t(1), std::ptrdiff_t(32)}) {
    Eigen::setCpuCacheSizes(256 * scale * scale, 1024 * scale * scale, 4096 * scale * scale);
    Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings);
    ASSERT_TRUE(t) << t.error().message;
    runs.push_back(t->coefficients);
  }
  Eigen::setCpuCacheSizes(l1, l2, l3);
  ASSERT_EQ(runs[0].size(), runs[1].size());
  EXPECT_EQ(std::memcmp(runs[0].data(), runs[1].data(), runs[0].size() * sizeof(runs[0][0])), 0);
}

// The system's rows, and the far field's directions, are computed in two fixed halves, the
// second on a helper thread when the machine has two cores: the same bits as on one thread
// (docs/determinism.md), with a square (LU) and a least-squares (CHIEF, QR) system. The far
// field's coefficients, its error estimate (the coarse solve's far field) and the kept orders
// all come from the split sums over directions.
TEST(TransferSolver, SameBitsOnOneThreadAndOnTwo) {
  const double a = 0.05, c_air = 343.0;
  ModeBank bank = sphereBank(a, 0.01);
  addYnmMode(bank, 1, 0, 3.0 / a, c_air);
  addYnmMode(bank, 2, 1, 6.0 / a, c_air);
  addYnmMode(bank, 3, -2, 9.0 / a, c_air);  // projected to order 19: 441 directions (and their opposites)
  TransferSettings settings;
  settings.fixed_elements = 400;
  std::vector<AcousticTransfer> runs;
  for (const int threads : {1, 2, 2}) {
    settings.threads = threads;
    Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings);
    ASSERT_TRUE(t) << t.error().message;
    runs.push_back(*t);
  }
  for (size_t i = 1; i < runs.size(); ++i) {
    const AcousticTransfer &one = runs[0], &two = runs[i];
    ASSERT_EQ(one.coefficients.size(), two.coefficients.size());
    EXPECT_EQ(std::memcmp(one.coefficients.data(), two.coefficients.data(),
                          one.coefficients.size() * sizeof(one.coefficients[0])),
              0)
        << "run " << i;
    EXPECT_EQ(one.order, two.order) << "run " << i;
    ASSERT_EQ(one.relative_error.size(), two.relative_error.size());
    EXPECT_EQ(std::memcmp(one.relative_error.data(), two.relative_error.data(),
                          one.relative_error.size() * sizeof(one.relative_error[0])),
              0)
        << "run " << i;
    EXPECT_EQ(std::memcmp(one.translation_dipole_m3.data(), two.translation_dipole_m3.data(),
                          sizeof(one.translation_dipole_m3)),
              0)
        << "run " << i;
  }
}

// A group's transfer depends on its own modes and the settings alone (transferGroups): a bank of
// some of the groups gives them the same bits as the bank of them all, so a bank can be extended
// by the groups it lacks with the bits of a cold solve. Here a degenerate pair (one group, split
// by 1e-5), a mode below it and one above, the pair solved alone and with the others; the
// refinement runs (no fixed resolution), as the defaults do.
TEST(TransferSolver, AGroupSolvedAloneHasTheBitsItHasAmongOthers) {
  const double a = 0.05, c_air = 343.0;
  ModeBank all = sphereBank(a, 0.012);
  ModeBank pair = sphereBank(a, 0.012);
  addYnmMode(all, 1, 0, 1.5 / a, c_air);
  for (ModeBank* bank : {&all, &pair}) {
    addYnmMode(*bank, 2, 1, 4.0 / a, c_air);
    addYnmMode(*bank, 2, -1, 4.0 * (1.0 + 1e-5) / a, c_air);
  }
  addYnmMode(all, 3, 2, 9.0 / a, c_air);
  TransferSettings settings;
  settings.max_elements = 400;
  const std::vector<size_t> groups = transferGroups(all, settings);
  ASSERT_EQ(groups, (std::vector<size_t>{0, 1, 3, 4}));
  EXPECT_EQ(transferGroups(pair, settings), (std::vector<size_t>{0, 2}));
  Result<AcousticTransfer> with_others = solveAcousticTransfer(all, settings);
  Result<AcousticTransfer> alone = solveAcousticTransfer(pair, settings);
  ASSERT_TRUE(with_others) << with_others.error().message;
  ASSERT_TRUE(alone) << alone.error().message;
  for (size_t i = 0; i < 2; ++i) {
    const size_t mode = 1 + i;
    ASSERT_EQ(alone->order[i], with_others->order[mode]) << i;
    const size_t count = alone->offset[i + 1] - alone->offset[i];
    EXPECT_EQ(std::memcmp(&alone->coefficients[alone->offset[i]], &with_others->coefficients[with_others->offset[mode]],
                          count * sizeof(alone->coefficients[0])),
              0)
        << i;
    EXPECT_EQ(alone->relative_error[i], with_others->relative_error[mode]) << i;
  }
}

// A square system above direct_max_elements is solved by GMRES: the same far field as the LU's
// to well within the residual it stops at (1e-5), and the estimate (the coarse system, by GMRES
// too) the same. Below ka ~ 2 the sphere has no interior points: square systems.
TEST(TransferSolver, GmresGivesTheFarFieldOfTheLu) {
  const double a = 0.05, c_air = 343.0, rho = 1.2;
  ModeBank bank = sphereBank(a, 0.01);
  addYnmMode(bank, 1, 0, 1.0 / a, c_air);
  addYnmMode(bank, 2, -1, 1.5 / a, c_air);
  TransferSettings settings;
  settings.air_density_kg_m3 = rho;
  settings.fixed_elements = 400;
  std::vector<AcousticTransfer> runs;
  std::vector<TransferModeStats> stats;
  for (const uint32_t direct_max : {700u, 100u}) {
    settings.direct_max_elements = direct_max;
    Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings, {}, &stats);
    ASSERT_TRUE(t) << t.error().message;
    runs.push_back(*t);
  }
  EXPECT_GT(stats[0].iterations, 0u);  // the second run's: GMRES
  for (size_t i = 0; i < 2; ++i) {
    ASSERT_EQ(runs[0].order[i], runs[1].order[i]);
    double wrong = 0.0, total = 0.0;
    for (uint64_t j = runs[0].offset[i]; j < runs[0].offset[i + 1]; ++j) {
      wrong += std::norm(cd(runs[1].coefficients[j]) - cd(runs[0].coefficients[j]));
      total += std::norm(cd(runs[0].coefficients[j]));
    }
    EXPECT_LT(std::sqrt(wrong / total), 1e-4) << i;
    EXPECT_NEAR(runs[1].relative_error[i], runs[0].relative_error[i], 1e-3 * runs[0].relative_error[i]) << i;
    const SphereError e = compare(runs[1], i, i == 0 ? 1 : 2, i == 0 ? 0 : -1, (i == 0 ? 1.0 : 1.5) / a, a, rho);
    EXPECT_LT(e.relative, 0.05) << i;
  }
}

TEST(TransferSolver, IsLinearInTheShapeSoSignsAndDegenerateBasesCancel) {
  const double a = 0.05, c_air = 343.0, k = 3.0 / a;
  ModeBank bank = sphereBank(a, 0.01);
  // Two modes of a degenerate pair at one frequency (Y_1,-1 and Y_1,1 with a tangential part),
  // then the same pair rotated by 0.7 rad, then the first with its sign flipped.
  addYnmMode(bank, 1, -1, k, c_air);
  addYnmMode(bank, 1, 1, k, c_air);
  const size_t values = bank.surfaceVertexCount() * 3;
  for (size_t v = 0; v < values; v += 3) bank.shapes[v] += 0.3f * bank.shapes[values + v + 2];
  const std::vector<float> A(bank.shapes.begin(), bank.shapes.begin() + values);
  const std::vector<float> B(bank.shapes.begin() + values, bank.shapes.end());
  const double angle = 0.7, cs = std::cos(angle), sn = std::sin(angle);
  for (int mode = 0; mode < 3; ++mode) {
    bank.eigenvalues.push_back(k * k * c_air * c_air);
    for (size_t v = 0; v < values; ++v)
      bank.shapes.push_back(mode == 0   ? static_cast<float>(cs * A[v] + sn * B[v])
                            : mode == 1 ? static_cast<float>(-sn * A[v] + cs * B[v])
                                        : -A[v]);
  }
  Result<AcousticTransfer> t = solveAcousticTransfer(bank);
  ASSERT_TRUE(t) << t.error().message;
  // Sign: exactly the negated coefficients.
  ASSERT_EQ(t->order[4], t->order[0]);
  for (uint64_t j = 0; j < t->offset[1]; ++j) EXPECT_EQ(t->coefficients[t->offset[4] + j], -t->coefficients[j]);
  // Basis: sum_i F_i(d) phi_i(p) . J is the same for both bases, at any vertex and direction.
  std::vector<double> Y((t->maxOrder() + 1) * (t->maxOrder() + 1));
  std::vector<cd> F(5);
  double worst = 0.0, scale = 0.0;
  for (size_t v = 0; v < bank.surfaceVertexCount(); v += 97) {
    const double d[3] = {0.3, -0.4, 0.5};
    const double J[3] = {0.2, 1.0, -0.5};
    realSphericalHarmonics(t->maxOrder(), d, Y.data());
    evaluateFarField(*t, Y.data(), F.data());
    cd sums[2] = {0.0, 0.0};
    for (int mode = 0; mode < 4; ++mode) {
      const float* u = bank.shapeAt(mode, v);
      sums[mode / 2] += F[mode] * (u[0] * J[0] + u[1] * J[1] + u[2] * J[2]);
    }
    worst = std::max(worst, std::abs(sums[0] - sums[1]));
    scale = std::max(scale, std::abs(sums[0]));
  }
  EXPECT_LT(worst, 3e-4 * scale);  // -70 dB: float storage and the order's -80 dB tail
}

// The tolerance converges: at --transfer-tolerance 10%, 5% and 2% the solve takes more unknowns,
// and both its estimate and its true error fall at the order the method promises. Constant
// elements on clusters of size h: far-field error ~ h^2 ~ 1 / unknowns, and the unknowns chosen
// ~ 1 / target (elements per wavelength ~ 1 / sqrt(target)), so error ~ target. The true error
// is taken against a solve of the same surface with every triangle an unknown (the surface's own
// faceting is common to both; against the exact sphere it is a floor of ~1-1.5% that flattens
// the order), and the order in unknowns is held within 0.6-1.6 per step. The solver's floor of
// unknowns is lowered to 16 so that the tolerance alone chooses them (at 160, 10% and 5% would
// both be met by the first solve).
TEST(TransferSolver, TheToleranceConvergesAtTheOrderOfConstantElements) {
  const double a = 0.1, c_air = 343.0, rho = 1.2;
  ModeBank bank = sphereBank(a, 0.014);
  struct Case {
    int n, m;
    double ka;
  };
  const Case cases[] = {{2, 1, 1.5}, {2, -2, 2.5}};
  for (const Case& c : cases) addYnmMode(bank, c.n, c.m, c.ka / a, c_air);
  const uint32_t triangles = static_cast<uint32_t>(bank.surface_triangles.size() / 3);
  TransferSettings settings;
  settings.air_density_kg_m3 = rho;
  settings.speed_of_sound_m_s = c_air;
  settings.min_elements = 16;
  settings.max_elements = triangles;
  settings.direct_max_elements = triangles;
  TransferSettings every = settings;
  every.fixed_elements = triangles;
  Result<AcousticTransfer> reference = solveAcousticTransfer(bank, every);
  ASSERT_TRUE(reference) << reference.error().message;
  auto distance = [&](const AcousticTransfer& t, size_t mode) {
    const AcousticTransfer& r = *reference;
    double wrong = 0.0, total = 0.0;
    const uint64_t na = t.offset[mode + 1] - t.offset[mode], nb = r.offset[mode + 1] - r.offset[mode];
    for (uint64_t j = 0; j < std::max(na, nb); ++j) {
      const cd x = j < na ? cd(t.coefficients[t.offset[mode] + j]) : cd(0.0);
      const cd y = j < nb ? cd(r.coefficients[r.offset[mode] + j]) : cd(0.0);
      wrong += std::norm(x - y);
      total += std::norm(y);
    }
    return std::sqrt(wrong / total);
  };
  std::vector<std::vector<double>> estimate(2), truth(2), unknowns(2);
  for (double target : {0.10, 0.05, 0.02}) {
    settings.target_relative_error = target;
    std::vector<TransferModeStats> stats;
    Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings, {}, &stats);
    ASSERT_TRUE(t) << t.error().message;
    for (size_t i = 0; i < 2; ++i) {
      const SphereError exact = compare(*t, i, cases[i].n, cases[i].m, cases[i].ka / a, a, rho);
      std::printf("target %4.0f%%: n %d ka %.1f: %4u unknowns, estimate %6.2f%%, error %6.2f%% (exact %.2f%%)\n",
                  100 * target, cases[i].n, cases[i].ka, stats[i].elements, 100 * stats[i].relative_error,
                  100 * distance(*t, i), 100 * exact.relative);
      EXPECT_LE(stats[i].relative_error, target) << "met at every tolerance";
      estimate[i].push_back(stats[i].relative_error);
      truth[i].push_back(distance(*t, i));
      unknowns[i].push_back(stats[i].elements);
    }
  }
  for (size_t i = 0; i < 2; ++i)
    for (size_t step = 1; step < 3; ++step) {
      EXPECT_GT(unknowns[i][step], unknowns[i][step - 1]) << i << " " << step;
      EXPECT_LT(estimate[i][step], estimate[i][step - 1]) << i << " " << step;
      EXPECT_LT(truth[i][step], truth[i][step - 1]) << i << " " << step;
      const double more = std::log(unknowns[i][step] / unknowns[i][step - 1]);
      const double order_estimate = -std::log(estimate[i][step] / estimate[i][step - 1]) / more;
      const double order_truth = -std::log(truth[i][step] / truth[i][step - 1]) / more;
      std::printf("mode %zu, step %zu: order in unknowns %.2f (estimate), %.2f (error)\n", i, step, order_estimate,
                  order_truth);
      EXPECT_GT(order_truth, 0.6) << i << " " << step;
      EXPECT_LT(order_truth, 1.6) << i << " " << step;
      // The estimate (a difference with the solve of half the unknowns) follows the same order
      // from the solver's floor of 160 unknowns on; below it, on a pattern resolved by a few
      // dozen clusters, it under-reads (40 unknowns: 4.3% against a true 6.8%).
      if (unknowns[i][step - 1] >= TransferSettings{}.min_elements) {
        EXPECT_GT(order_estimate, 0.6) << i << " " << step;
        EXPECT_LT(order_estimate, 1.6) << i << " " << step;
      }
    }
}

// A thin body: a disc 4 mm thick and 200 mm across, its two faces 4 mm apart (near-singular
// integrals between them). Its broadside translation's dipole M_zz = V + (added mass) / rho is
// 8/3 R^3 for the infinitely thin disc (Lamb, Hydrodynamics, sec. 108); at H/R = 0.04 the rim adds
// 5.4% of that beyond the volume's 4.7%: 1.1005 x 8/3 R^3 (the disc's value is not the thin
// disc's plus its volume, 1.047 x, which read as +3.6% here before). The reference is an
// axisymmetric solve on the generating curve, graded to the rim (references/axisymmetric_dipole.hpp),
// checked here against Lamb's closed forms: the sphere, 2 pi a^3, and an oblate spheroid as thin
// as the disc (c/a = 0.02: 1.0255 x 8/3 R^3). The transfer must give that dipole both from its
// rigid translation and from a mode's far field at low ka, on the disc's mesh at two sizes; at
// ka ~ 3 it must stay finite with a sane estimate.
TEST(TransferSolver, ThinDiscRadiatesTheDipoleOfItsAddedMass) {
  const double R = 0.1, H = 0.004, c_air = 343.0, rho = 1.2;
  const double thin = 8.0 / 3.0 * R * R * R;
  // The reference against the closed forms (converging as h^2: errors 4x smaller at twice the segments).
  const double sphere = test::axialDipole(test::spheroidCurve(R, R, 40)) / (2 * M_PI * R * R * R) - 1;
  const double flat =
      test::axialDipole(test::spheroidCurve(R, 0.02 * R, 80)) / test::oblateSpheroidAxialDipole(R, 0.02 * R) - 1;
  EXPECT_LT(std::abs(sphere), 2e-3);
  EXPECT_LT(std::abs(flat), 1e-2);
  EXPECT_NEAR(test::oblateSpheroidAxialDipole(R, 0.02 * R) / thin, 1.0255, 1e-4);  // Lamb's limit, 8/3 R^3
  // The disc: two gradings, extrapolated (h^2).
  const double coarse = test::axialDipole(test::cylinderCurve(R, H, 30, 4));
  const double fine = test::axialDipole(test::cylinderCurve(R, H, 60, 8));
  const double reference = fine + (fine - coarse) / 3.0;
  std::printf("reference: sphere %+.3f%%, oblate c/a 0.02 %+.3f%%; disc M_zz %.5f x 8/3 R^3 (%.5f, %.5f)\n",
              100 * sphere, 100 * flat, reference / thin, coarse / thin, fine / thin);
  EXPECT_LT(std::abs(fine / reference - 1), 3e-3);
  for (double edge : {0.016, 0.008}) {
    Result<SurfaceMesh> disc = makeCylinderSurface(R, H, edge);
    ASSERT_TRUE(disc) << disc.error().message;
    ModeBank bank = surfaceBank(*disc);
    const double ks[] = {0.05 / R, 3.0 / R};
    for (double k : ks) {
      bank.eigenvalues.push_back(k * k * c_air * c_air);
      for (size_t v = 0; v < bank.surfaceVertexCount(); ++v)
        for (int c = 0; c < 3; ++c) bank.shapes.push_back(c == 2 ? 1.0f : 0.0f);  // rigid, along z
    }
    TransferSettings settings;
    settings.air_density_kg_m3 = rho;
    settings.speed_of_sound_m_s = c_air;
    std::vector<TransferModeStats> stats;
    Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings, {}, &stats);
    ASSERT_TRUE(t) << t.error().message;
    const double Mzz = t->translation_dipole_m3[8];
    // Low ka: c_10 = -(i k rho / 4 pi) M_zz sqrt(4 pi / 3) (d_z = sqrt(4 pi / 3) Y_10).
    ASSERT_GE(t->order[0], 1u);
    const cd c10(t->coefficients[t->offset[0] + 2].real(), t->coefficients[t->offset[0] + 2].imag());
    const cd per_m3 = cd(0, -ks[0] * rho / (4 * M_PI)) * std::sqrt(4 * M_PI / 3);
    const double far_field_dipole = std::abs(c10 / per_m3);
    std::printf(
        "disc of %zu triangles (edge %g m): M_zz %+.2f%%, from the far field %+.2f%% (phase %.2f deg); M_xx %.3g\n",
        bank.surface_triangles.size() / 3, edge, 100 * (Mzz / reference - 1), 100 * (far_field_dipole / reference - 1),
        std::arg(c10 / per_m3) * 180 / M_PI, t->translation_dipole_m3[0] / Mzz);
    EXPECT_LT(std::abs(Mzz / reference - 1), 0.02) << edge;
    EXPECT_LT(std::abs(far_field_dipole / reference - 1), 0.02) << edge;
    EXPECT_LT(std::abs(std::arg(c10 / per_m3)), 0.01) << edge;
    EXPECT_LT(t->translation_dipole_m3[0], 0.2 * Mzz);  // edgewise: little more than the volume
    for (size_t i = 0; i < 2; ++i) {
      std::printf("  ka %.2f: %u elements, order %u, rms %.4g Pa m, estimate %.4f, %.3f s\n", stats[i].ka,
                  stats[i].elements, stats[i].order, t->rmsFarField(i), stats[i].relative_error, stats[i].seconds);
      EXPECT_TRUE(std::isfinite(t->rmsFarField(i)));
      // (On the coarse mesh every triangle is an unknown at ka 3 and the estimate reads 13%.)
      if (edge < 0.01) {
        EXPECT_LT(stats[i].relative_error, 0.1);
      }
    }
  }
}

}  // namespace
}  // namespace strike

namespace strike {
namespace {
// Development aid, not run by ctest: STRIKE_TRANSFER_BANK=path.modes prints each mode's solve.
TEST(TransferSolver, DISABLED_PrintsTheSolveOfABankFromTheEnvironment) {
  const char* path = std::getenv("STRIKE_TRANSFER_BANK");
  ASSERT_NE(path, nullptr);
  Result<ModeBank> bank = readBank(path);
  ASSERT_TRUE(bank) << bank.error().message;
  TransferSettings settings;
  if (const char* max = std::getenv("STRIKE_TRANSFER_MAX_ELEMENTS")) settings.max_elements = std::atoi(max);
  if (const char* max = std::getenv("STRIKE_TRANSFER_DIRECT_MAX")) settings.direct_max_elements = std::atoi(max);
  if (const char* target = std::getenv("STRIKE_TRANSFER_TARGET")) settings.target_relative_error = std::atof(target);
  if (const char* dense = std::getenv("STRIKE_TRANSFER_DENSE")) settings.hierarchical = std::atoi(dense) == 0;
  if (const char* first = std::getenv("STRIKE_TRANSFER_FIRST")) {  // the first N modes only
    const size_t n = std::min<size_t>(std::max(1, std::atoi(first)), bank->modeCount());
    bank->eigenvalues.resize(n);
    bank->shapes.resize(n * bank->surfaceVertexCount() * 3);
  }
  if (const char* every = std::getenv("STRIKE_TRANSFER_EVERY")) {  // every N-th mode only (N-1, 2N-1, ...)
    const size_t n = std::max(1, std::atoi(every)), vertices = bank->surfaceVertexCount();
    ModeBank kept = *bank;
    kept.eigenvalues.clear();
    kept.shapes.clear();
    for (size_t i = n - 1; i < bank->modeCount(); i += n) {
      kept.eigenvalues.push_back(bank->eigenvalues[i]);
      kept.shapes.insert(kept.shapes.end(), bank->shapes.begin() + i * vertices * 3,
                         bank->shapes.begin() + (i + 1) * vertices * 3);
    }
    *bank = std::move(kept);
  }
  std::vector<TransferModeStats> stats;
  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();  // processor time: steadier than the wall on a shared machine
  Result<AcousticTransfer> t = solveAcousticTransfer(*bank, settings, {}, &stats);
  ASSERT_TRUE(t) << t.error().message;
  std::printf("%zu triangles, eigen-solve %.2f s (factorize + Lanczos), transfer %.2f s (processor %.2f s)\n",
              bank->surface_triangles.size() / 3, bank->factorize_seconds + bank->lanczos_seconds,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
              static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
  for (size_t i = 0; i < stats.size(); ++i)
    std::printf(
        "%3zu %8.1f Hz ka %6.2f elements %4u chief %3u order %3u estimate %7.4f %6.3f s (solves %u, assembly %.3f, "
        "factor %.3f, far field %.3f, iterations %u, matrix %.1f MB, near %.1f MB)\n",
        i, bank->frequencyHz(i), stats[i].ka, stats[i].elements, stats[i].chief_points, stats[i].order,
        stats[i].relative_error, stats[i].seconds, stats[i].solves, stats[i].assembly_seconds, stats[i].factor_seconds,
        stats[i].far_field_seconds, stats[i].iterations, stats[i].matrix_bytes / 1e6, stats[i].near_cache_bytes / 1e6);
  // Against a reference transfer of the same modes (a bank solved tighter): the true error of
  // each mode's far field (rms over directions, Parseval), beside its estimate.
  // (STRIKE_TRANSFER_REFERENCE: a bank file holding it; STRIKE_TRANSFER_REFERENCE_ELEMENTS: solved
  // here with that budget and a tenth of the target.)
  AcousticTransfer solved_reference;
  if (const char* elements = std::getenv("STRIKE_TRANSFER_REFERENCE_ELEMENTS")) {
    TransferSettings tighter = settings;
    tighter.max_elements = std::atoi(elements);
    tighter.target_relative_error = 0.1 * settings.target_relative_error;
    const std::clock_t reference_start = std::clock();
    Result<AcousticTransfer> r = solveAcousticTransfer(*bank, tighter);
    ASSERT_TRUE(r) << r.error().message;
    std::printf("reference: %d elements, processor %.2f s\n", tighter.max_elements,
                static_cast<double>(std::clock() - reference_start) / CLOCKS_PER_SEC);
    solved_reference = *r;
  }
  const char* reference_path = std::getenv("STRIKE_TRANSFER_REFERENCE");
  if (reference_path || !solved_reference.empty()) {
    ModeBank reference;
    if (reference_path) {
      Result<ModeBank> read = readBank(reference_path);
      ASSERT_TRUE(read) << read.error().message;
      reference = std::move(*read);
    } else {
      reference.transfer = solved_reference;
    }
    const AcousticTransfer& r = reference.transfer;
    ASSERT_EQ(r.modeCount(), t->modeCount());
    size_t within = 0, over3 = 0;
    for (size_t i = 0; i < t->modeCount(); ++i) {
      double wrong = 0.0, total = 0.0;
      const uint64_t a = t->offset[i + 1] - t->offset[i], b = r.offset[i + 1] - r.offset[i];
      for (uint64_t j = 0; j < std::max(a, b); ++j) {
        const cd x = j < a ? cd(t->coefficients[t->offset[i] + j]) : cd(0.0);
        const cd y = j < b ? cd(r.coefficients[r.offset[i] + j]) : cd(0.0);
        wrong += std::norm(x - y);
        total += std::norm(y);
      }
      const double truth = std::sqrt(wrong / total), estimate = t->relative_error[i];
      within += truth <= estimate ? 1 : 0;
      over3 += truth > 3.0 * estimate ? 1 : 0;
      std::printf("%3zu true error %7.4f estimate %7.4f ratio %.2f\n", i, truth, estimate, truth / estimate);
    }
    std::printf("true error within the estimate: %zu of %zu; over 3x the estimate: %zu\n", within, t->modeCount(),
                over3);
  }
}
}  // namespace
}  // namespace strike

namespace strike {
namespace {
// similarBank() scales the transfer when ka is unchanged (E/rho unchanged): F' = F s^2 / sqrt((rho'/rho)
// s^3). Checked against a direct solve of the scaled bank.
TEST(TransferSolver, ASimilarBankScalesItsTransferAsADirectSolveFindsIt) {
  const double a = 0.05, k = 2.0 / a;
  ModeBank bank = sphereBank(a, 0.01);
  bank.material = {"m", 1e10, 0.3, 1000.0, 0, 0};
  bank.max_freq_hz = 1e9;
  bank.max_modes = 1;  // capped: every mode up to the cut-off is there
  addYnmMode(bank, 1, 1, k, kSpeedOfSoundAir_m_s);
  Result<AcousticTransfer> t = solveAcousticTransfer(bank);
  ASSERT_TRUE(t) << t.error().message;
  bank.transfer = *t;
  const double s = 2.0;
  const Material heavier{"m2", 3e10, 0.3, 3000.0, 0, 0};  // E/rho unchanged: ka unchanged
  Result<ModeBank> scaled = similarBank(bank, s, heavier, 1e9, "scaled");
  ASSERT_TRUE(scaled) << scaled.error().message;
  ModeBank direct_bank = *scaled;
  direct_bank.transfer = {};
  Result<AcousticTransfer> direct = solveAcousticTransfer(direct_bank);
  ASSERT_TRUE(direct) << direct.error().message;
  const AcousticTransfer& by_scaling = scaled->transfer;
  ASSERT_EQ(by_scaling.modeCount(), 1u);
  double diff = 0, norm = 0;
  for (uint64_t j = 0; j < std::min(by_scaling.offset[1], direct->offset[1]); ++j) {
    diff += std::norm(std::complex<double>(by_scaling.coefficients[j]) - std::complex<double>(direct->coefficients[j]));
    norm += std::norm(std::complex<double>(direct->coefficients[j]));
  }
  EXPECT_LT(std::sqrt(diff / norm), 1e-5);
  EXPECT_NEAR(by_scaling.translation_dipole_m3[0], direct->translation_dipole_m3[0],
              1e-6 * direct->translation_dipole_m3[0]);
  // Another E/rho changes ka: solved again when asked, left empty when not.
  const Material stiffer{"m3", 4e10, 0.3, 1000.0, 0, 0};
  TransferSettings settings;
  Result<ModeBank> solved = similarBank(bank, s, stiffer, 1e9, "stiffer", &settings);
  ASSERT_TRUE(solved) << solved.error().message;
  EXPECT_EQ(solved->transfer.checkConsistency(1), "");
  Result<ModeBank> without = similarBank(bank, s, stiffer, 1e9, "stiffer");
  ASSERT_TRUE(without);
  EXPECT_TRUE(without->transfer.empty());
}
}  // namespace
}  // namespace strike
