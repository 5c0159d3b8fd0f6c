// SPDX-License-Identifier: MIT
// The acoustic transfer solver (src/precompute/acoustic_transfer.cpp) against closed forms:
// a sphere's surface acceleration Y_nm radiates A h_n(kr) Y_nm exactly, a rigid sphere's
// translation has the dipole tensor 2 pi a^3 I, and the transfer is linear in the mode shape.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <vector>

#include "strike/mesh.hpp"
#include "strike/transfer_solver.hpp"

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
  std::printf("triangles %zu\n  ka   n  elems chief order  error    dB     deg   estimate  seconds\n",
              bank.surface_triangles.size() / 3);
  for (size_t i = 0; i < bank.modeCount(); ++i) {
    const SphereError e = compare(*t, i, nm[i][0], nm[i][1], ks[i], a, rho);
    std::printf("%5.1f  %d  %5u %5u %5u  %7.4f  %6.3f  %6.2f  %7.4f  %6.3f\n", ks[i] * a, nm[i][0], stats[i].elements,
                stats[i].chief_points, stats[i].order, e.relative, e.level_db, e.phase_deg, e.estimate,
                stats[i].seconds);
  }
}

}  // namespace
}  // namespace strike
