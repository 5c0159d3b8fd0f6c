// SPDX-License-Identifier: MIT
// A free elastic sphere struck radially, heard at several angles (issue 17). A radial impulse at
// the pole excites, of each spheroidal multiplet of degree n (Lamb 1882), the combination that is
// axisymmetric about the strike axis; its surface normal velocity is proportional to
// P_n(cos theta), and a sphere radiates a normal velocity Y_n exactly as h_n(kr) / h_n'(ka) Y_n,
// so the multiplet is heard at angle theta from the strike point in proportion to
// |P_n(cos theta)| whatever ka [Morse & Ingard 1968, 7.2]. For n = 2 that is 1, 0.625 and 0.5 at
// 0, 30 and 90 degrees, and nothing at 54.7 degrees, where P_2 = 0. The FEM multiplet comes in
// five modes with whatever basis the eigen-solver picked: only a far field linear in the shape
// (the acoustic transfer) sums them to the pattern. The absolute level of such a far field is
// checked against the exact sphere in TransferSolver.*.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

#include "references/lamb_sphere.hpp"
#include "strike/hit.hpp"
#include "strike/precompute.hpp"

namespace strike {
namespace {

/// Energy of x within [f_lo, f_hi] Hz (direct DFT on the bins there).
double bandEnergy(const std::vector<float>& x, double rate, double f_lo, double f_hi) {
  const size_t n = x.size();
  double e = 0.0;
  for (size_t k = static_cast<size_t>(f_lo * n / rate); k <= static_cast<size_t>(f_hi * n / rate); ++k) {
    std::complex<double> sum = 0.0;
    const double w = 2.0 * M_PI * static_cast<double>(k) / static_cast<double>(n);
    std::complex<double> turn = std::polar(1.0, -w), phase = 1.0;
    for (size_t j = 0; j < n; ++j, phase *= turn) sum += static_cast<double>(x[j]) * phase;
    e += std::norm(sum);
  }
  return e;
}

TEST(SphereDirectivity, TheQuadrupoleMultipletFollowsP2AndVanishesAt547Degrees) {
  // A soft sphere (shear wave 62 m/s) keeps ka of its n = 2 multiplet at 0.5, so the solve is
  // cheap; the pattern does not depend on ka. No damping: the multiplet's line stays narrow.
  const double radius = 0.1, nu = 0.3, rho = 1000.0, youngs = 1e7;
  PrecomputeSettings s;
  s.mesh_spec = "sphere:0.1";
  s.material.name = "soft";
  s.material.youngs_pa = youngs;
  s.material.poisson = nu;
  s.material.density_kg_m3 = rho;
  s.order = 2;
  s.target_edge_m = 0.025;
  s.max_modes = 12;
  s.acoustic_transfer = true;
  Result<PrecomputeResult> r = computeModeBank(s);
  ASSERT_TRUE(r) << r.error().message;
  const ModeBank& bank = r->bank;
  ASSERT_FALSE(bank.transfer.empty());

  const double c_s = std::sqrt(youngs / (2.0 * (1.0 + nu)) / rho);
  const double c_l = std::sqrt(youngs * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)) / rho);
  const std::vector<double> roots =
      test::scanRoots([&](double eta) { return test::lambSpheroidal(2, eta, c_l / c_s); }, 1.0, 4.0, 0.01);
  ASSERT_FALSE(roots.empty());
  const double f2 = roots[0] * c_s / (2.0 * M_PI * radius);  // Lamb's S2, ~260 Hz

  const double rate = 8000.0, distance = 2.0;
  auto level = [&](double theta_deg) {
    const double t = theta_deg * M_PI / 180.0;
    HitSettings h;
    h.at_m = std::array<double, 3>{0.0, 0.0, radius};
    h.impulse_n_s = std::array<double, 3>{0.0, 0.0, -0.01};
    h.contact_time_s = 0.0;
    h.duration_s = 1.0;
    h.sample_rate_hz = rate;
    h.listener_m = std::array<double, 3>{distance * std::sin(t), 0.0, distance * std::cos(t)};
    Result<HitResult> hit = renderHit(bank, h);
    EXPECT_TRUE(hit) << (hit ? "" : hit.error().message);
    return hit ? bandEnergy(hit->audio.samples, rate, 0.95 * f2, 1.05 * f2) : 0.0;
  };
  const double at0 = level(0.0);
  ASSERT_GT(at0, 0.0);
  for (double theta : {30.0, 90.0, 150.0}) {
    const double c = std::cos(theta * M_PI / 180.0), p2 = 0.5 * (3.0 * c * c - 1.0);
    const double db = 10.0 * std::log10(level(theta) / at0), expected = 20.0 * std::log10(std::fabs(p2));
    std::printf("S2 (%.1f Hz) at %5.1f deg: %+6.2f dB re the pole, P_2 says %+6.2f dB\n", f2, theta, db, expected);
    EXPECT_NEAR(db, expected, 1.0) << theta;
  }
  const double null_db = 10.0 * std::log10(level(std::acos(1.0 / std::sqrt(3.0)) * 180.0 / M_PI) / at0);
  std::printf("S2 at 54.7 deg: %+.1f dB re the pole\n", null_db);
  EXPECT_LT(null_db, -20.0);
}

}  // namespace
}  // namespace strike
