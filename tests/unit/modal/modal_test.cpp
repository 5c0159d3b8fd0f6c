// SPDX-License-Identifier: MIT
// The eigen-solve against closed-form beam theory, its invariants (rigid modes, ordering,
// M-orthonormality), convergence under refinement, and independence of units.
//
// Material constants used throughout (steel): E = 2.0e11 Pa, nu = 0.29, rho = 7850 kg/m^3.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>

#include "strike/core/constants.hpp"
#include "strike/fem/fem.hpp"
#include "strike/modal/modal.hpp"

namespace strike {
namespace {

constexpr double kE = 2.0e11;
constexpr double kNu = 0.29;
constexpr double kRho = 7850.0;
const Material kSteel{"steel", kE, kNu, kRho, 0.0, 0.0};

struct Solved {
  TetMesh mesh;
  Eigen::SparseMatrix<double> K, M;
  ModalResult modes;
  Eigen::VectorXd freqs_hz;
};

Solved solveBox(double lx, double ly, double lz, int order, double edge_m, const Material& material,
                ModalSettings settings) {
  Solved s;
  MeshOptions options;
  options.order = order;
  options.target_edge_m = edge_m;
  auto mesh = makeBox(lx, ly, lz, options);
  EXPECT_TRUE(mesh.ok());
  s.mesh = std::move(mesh.value());
  assembleStiffnessAndMass(s.mesh, material, s.K, s.M);
  auto modes = solveModes(s.K, s.M, settings);
  EXPECT_TRUE(modes.ok()) << modes.error().message;
  s.modes = std::move(modes.value());
  s.freqs_hz = s.modes.eigenvalues.cwiseSqrt() / (2 * kPi);
  return s;
}

// Free-free Timoshenko beam: w'' - psi' + (rho w^2 / (k G)) w = 0 and
// E I psi'' + k G A (w' - psi) + rho I w^2 psi = 0, with free ends psi' = 0, w' - psi = 0.
// The general solution (cosh, sinh of alpha x; cos, sin of beta x) gives a 4x4 boundary
// determinant whose roots are the natural frequencies (Huang, J. Appl. Mech. 28, 1961;
// Han, Benaroya & Wei, J. Sound Vib. 225, 1999, sec. 5). Shear coefficient of a rectangle:
// k = 10 (1 + nu) / (12 + 11 nu) (Cowper, J. Appl. Mech. 33, 1966).
double timoshenkoDeterminant(double omega, double L, double h) {
  const double G = kE / (2 * (1 + kNu));
  const double k = 10 * (1 + kNu) / (12 + 11 * kNu);
  const double A = h * h, I = h * h * h * h / 12;
  const double w2 = omega * omega;
  const double a2 = k * G * A * kE * I;
  const double a1 = w2 * (k * G * A * kRho * I + kRho * A * kE * I);
  const double a0 = kRho * A * w2 * (kRho * I * w2 - k * G * A);
  const double disc = std::sqrt(a1 * a1 - 4 * a2 * a0);
  const double alpha = std::sqrt((-a1 + disc) / (2 * a2));
  const double beta = std::sqrt((a1 + disc) / (2 * a2));
  const double q = kRho * w2 / (k * G);
  const double a = (alpha * alpha + q) / alpha;
  const double b = (q - beta * beta) / beta;
  Eigen::Matrix4d D;
  auto rows = [&](int r, double x) {
    D.row(r) << a * alpha * std::cosh(alpha * x), a * alpha * std::sinh(alpha * x), b * beta * std::cos(beta * x),
        b * beta * std::sin(beta * x);
    D.row(r + 1) << (alpha - a) * std::sinh(alpha * x), (alpha - a) * std::cosh(alpha * x),
        -(beta + b) * std::sin(beta * x), (beta + b) * std::cos(beta * x);
  };
  rows(0, 0.0);
  rows(2, L);
  return D.determinant();
}

double eulerBernoulliHz(double bl, double L, double h) {
  return bl * bl / (2 * kPi * L * L) * std::sqrt(kE * h * h / 12 / kRho);
}

// First root of the Timoshenko determinant in [0.7, 1.01] x the Euler-Bernoulli frequency.
double timoshenkoHz(double bl, double L, double h) {
  const double f_eb = eulerBernoulliHz(bl, L, h);
  auto det = [&](double f) { return timoshenkoDeterminant(2 * kPi * f, L, h); };
  double lo = 0.7 * f_eb;
  const double step = 1e-3 * f_eb;
  double hi = lo + step;
  while (hi < 1.01 * f_eb && (det(lo) > 0) == (det(hi) > 0)) {
    lo = hi;
    hi += step;
  }
  EXPECT_LT(hi, 1.01 * f_eb) << "no root bracketed";
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((det(lo) > 0) == (det(mid) > 0) ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double maxOrthonormalityError(const Solved& s) {
  const Eigen::MatrixXd G = s.modes.shapes.transpose() * (s.M * s.modes.shapes);
  return (G - Eigen::MatrixXd::Identity(G.rows(), G.cols())).cwiseAbs().maxCoeff();
}

// Fraction of a mode's kinetic energy (M-norm) in axis-x motion.
double axialFraction(const Solved& s, Eigen::Index mode) {
  Eigen::VectorXd ux = Eigen::VectorXd::Zero(s.K.rows());
  for (Eigen::Index i = 0; i < s.mesh.nodes.rows(); ++i) ux[3 * i] = s.modes.shapes(3 * i, mode);
  return ux.dot(s.M * ux);
}

constexpr double kL = 0.3, kH = 0.02;

TEST(SteelBar, Tet10MatchesBeamTheory) {
  ModalSettings settings;
  settings.max_freq_hz = 9000.0;
  const Solved s = solveBox(kL, kH, kH, 2, 0.0, kSteel, settings);
  EXPECT_EQ(s.modes.rigid_modes_dropped, 6);
  ASSERT_GE(s.freqs_hz.size(), 8);
  EXPECT_GT(s.freqs_hz.minCoeff(), 1.0);
  for (Eigen::Index i = 1; i < s.freqs_hz.size(); ++i) EXPECT_LE(s.freqs_hz[i - 1], s.freqs_hz[i]);
  EXPECT_LE(s.freqs_hz.maxCoeff(), 9000.0);
  EXPECT_LT(maxOrthonormalityError(s), 1e-8);
  EXPECT_LT(s.modes.max_relative_residual, 1e-6);

  // Square section: bending modes come in degenerate pairs (two planes).
  const double t1 = timoshenkoHz(4.730041, kL, kH), t2 = timoshenkoHz(7.853205, kL, kH);
  const double e1 = eulerBernoulliHz(4.730041, kL, kH), e2 = eulerBernoulliHz(7.853205, kL, kH);
  for (int k : {0, 1}) {
    EXPECT_NEAR(s.freqs_hz[k], t1, 0.01 * t1) << "first bending pair, mode " << k;
    EXPECT_NEAR(s.freqs_hz[k], e1, 0.03 * e1);
    EXPECT_NEAR(s.freqs_hz[2 + k], t2, 0.01 * t2) << "second bending pair, mode " << 2 + k;
    EXPECT_NEAR(s.freqs_hz[2 + k], e2, 0.05 * e2);
  }
  // The Kuhn split is symmetric under the y<->z mirror but not under a 90 degree turn, so the
  // pairs are split by discretization error only (measured ~3e-5).
  EXPECT_NEAR(s.freqs_hz[1], s.freqs_hz[0], 1e-4 * s.freqs_hz[0]);
  EXPECT_NEAR(s.freqs_hz[3], s.freqs_hz[2], 1e-4 * s.freqs_hz[2]);

  // First longitudinal mode: the lowest mode whose energy is mostly axial.
  Eigen::Index longitudinal = -1;
  for (Eigen::Index i = 0; i < s.freqs_hz.size() && longitudinal < 0; ++i) {
    if (axialFraction(s, i) > 0.9) longitudinal = i;
  }
  ASSERT_GE(longitudinal, 0);
  const double f_long = std::sqrt(kE / kRho) / (2 * kL);
  EXPECT_NEAR(s.freqs_hz[longitudinal], f_long, 0.005 * f_long);
}

TEST(SteelBar, RefinementConvergesAndTet10BeatsTet4AtEqualNodes) {
  ModalSettings settings;
  settings.max_freq_hz = 2500.0;
  const double t1 = timoshenkoHz(4.730041, kL, kH);
  double previous_error = INFINITY;
  for (double edge : {kH / 2, kH / 4, kH / 6}) {
    const Solved s = solveBox(kL, kH, kH, 1, edge, kSteel, settings);
    ASSERT_GE(s.freqs_hz.size(), 1);
    const double error = std::abs(s.freqs_hz[0] - t1) / t1;
    EXPECT_LT(error, previous_error) << "edge " << edge;
    previous_error = error;
  }
  // Same node count (61 x 5 x 5 = 1525): Tet4 with 4 cells across, Tet10 with 2.
  const Solved tet4 = solveBox(kL, kH, kH, 1, kH / 4, kSteel, settings);
  const Solved tet10 = solveBox(kL, kH, kH, 2, kH / 2, kSteel, settings);
  ASSERT_EQ(tet4.mesh.nodes.rows(), tet10.mesh.nodes.rows());
  const double err4 = std::abs(tet4.freqs_hz[0] - t1) / t1;
  const double err10 = std::abs(tet10.freqs_hz[0] - t1) / t1;
  EXPECT_LT(err10, 0.25 * err4) << "Tet4 " << err4 << ", Tet10 " << err10;
}

// f L sqrt(rho / E) depends only on shape, Poisson ratio and mode number, so a tiny stiff
// cube and a soft rubber one must give the reference steel-like cube's numbers exactly.
Eigen::VectorXd dimensionlessCube(double L, const Material& material) {
  ModalSettings settings;
  settings.max_freq_hz = 1e12;
  settings.max_modes = 12;
  const Solved s = solveBox(L, L, L, 1, L / 6, material, settings);
  EXPECT_EQ(s.modes.rigid_modes_dropped, 6);
  EXPECT_LT(maxOrthonormalityError(s), 1e-8);
  return s.freqs_hz * L * std::sqrt(material.density_kg_m3 / material.youngs_pa);
}

TEST(Units, StiffAndSoftMaterialsGiveTheSameDimensionlessFrequencies) {
  const Eigen::VectorXd steel = dimensionlessCube(0.1, kSteel);
  const Eigen::VectorXd stiff = dimensionlessCube(0.005, Material{"stiff", 1e12, kNu, 19300.0, 0, 0});
  ASSERT_EQ(steel.size(), 12);
  ASSERT_EQ(stiff.size(), 12);
  EXPECT_LT(((stiff - steel).array() / steel.array()).abs().maxCoeff(), 1e-6);
  // Rubber has nu = 0.45, so it is compared with a steel-like cube of the same Poisson ratio.
  const Eigen::VectorXd ref45 = dimensionlessCube(0.1, Material{"ref", kE, 0.45, kRho, 0, 0});
  const Eigen::VectorXd rubber = dimensionlessCube(0.1, Material{"rubber", 1e6, 0.45, 1100.0, 0, 0});
  ASSERT_EQ(rubber.size(), 12);
  EXPECT_LT(((rubber - ref45).array() / ref45.array()).abs().maxCoeff(), 1e-6);
}

TEST(Settings, CapCutoffAndOrdering) {
  ModalSettings settings;
  settings.max_freq_hz = 1e9;
  settings.max_modes = 5;
  const Solved capped = solveBox(kL, kH, kH, 1, kH / 2, kSteel, settings);
  EXPECT_EQ(capped.freqs_hz.size(), 5);
  EXPECT_TRUE(capped.modes.capped_by_max_modes);
  EXPECT_EQ(capped.modes.shapes.cols(), 5);

  settings.max_modes = 200;
  settings.max_freq_hz = 0.5 * (capped.freqs_hz[3] + capped.freqs_hz[4]);  // between modes 4 and 5
  const Solved cut = solveBox(kL, kH, kH, 1, kH / 2, kSteel, settings);
  ASSERT_EQ(cut.freqs_hz.size(), 4);
  EXPECT_FALSE(cut.modes.capped_by_max_modes);
  EXPECT_LT(((cut.freqs_hz - capped.freqs_hz.head(4)).array() / cut.freqs_hz.array()).abs().maxCoeff(), 1e-9);
}

TEST(Settings, ManyModesBeyondTheFirstRequest) {
  // More modes than one Lanczos request asks for at first: the solve must grow and keep
  // ascending, M-orthonormal modes with no duplicates or gaps (compared with a dense solve).
  ModalSettings settings;
  settings.max_freq_hz = 1e9;
  settings.max_modes = 150;
  const Solved s = solveBox(0.1, 0.05, 0.04, 1, 0.01, kSteel, settings);  // 990 dofs: sparse path
  ASSERT_EQ(s.freqs_hz.size(), 150);
  EXPECT_LT(maxOrthonormalityError(s), 1e-8);
  const Eigen::MatrixXd Kd(s.K), Md(s.M);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> dense(Kd, Md, Eigen::EigenvaluesOnly);
  const Eigen::VectorXd expected = dense.eigenvalues().segment(6, 150);
  EXPECT_LT(((s.modes.eigenvalues - expected).array() / expected.array()).abs().maxCoeff(), 1e-9);
}

TEST(Settings, HybridMatchesArpackOnly) {
  // The block Lanczos stage against ARPACK alone on the same matrices.
  ModalSettings settings;
  settings.max_freq_hz = 1e9;
  settings.max_modes = 60;
  const Solved hybrid = solveBox(kL, kH, kH, 1, kH / 2, kSteel, settings);
  settings.method = ModalMethod::ArpackOnly;
  auto reference = solveModes(hybrid.K, hybrid.M, settings);
  ASSERT_TRUE(reference.ok()) << reference.error().message;
  ASSERT_EQ(reference->eigenvalues.size(), 60);
  ASSERT_EQ(hybrid.modes.eigenvalues.size(), 60);
  EXPECT_EQ(reference->rigid_modes_dropped, 6);
  EXPECT_LT(
      ((hybrid.modes.eigenvalues - reference->eigenvalues).array() / reference->eigenvalues.array()).abs().maxCoeff(),
      1e-9);
  EXPECT_LT(maxOrthonormalityError(hybrid), 1e-8);
}

TEST(Settings, BlockLanczosMatchesArpackOnlyOnAMediumSolidAndIsDeterministic) {
  // A 100-mode request (the block Lanczos path from scratch, rigid modes included) on a
  // medium solid, with two block sizes and with one thread, against ARPACK alone.
  ModalSettings settings;
  settings.max_freq_hz = 1e9;
  settings.max_modes = 100;
  const Solved s = solveBox(0.2, 0.1, 0.05, 1, 0.0125, kSteel, settings);
  ASSERT_GT(s.K.rows(), 2000);
  ASSERT_EQ(s.modes.eigenvalues.size(), 100);
  EXPECT_EQ(s.modes.rigid_modes_dropped, 6);
  EXPECT_EQ(s.modes.block_size, 16);
  EXPECT_LT(maxOrthonormalityError(s), 1e-8);
  ModalSettings reference_settings = settings;
  reference_settings.method = ModalMethod::ArpackOnly;
  auto reference = solveModes(s.K, s.M, reference_settings);
  ASSERT_TRUE(reference.ok()) << reference.error().message;
  ASSERT_EQ(reference->eigenvalues.size(), 100);
  EXPECT_LT(((s.modes.eigenvalues - reference->eigenvalues).array() / reference->eigenvalues.array()).abs().maxCoeff(),
            1e-8);

  ModalSettings other = settings;
  other.block_size = 32;
  other.threads = 1;
  auto wide = solveModes(s.K, s.M, other);
  ASSERT_TRUE(wide.ok()) << wide.error().message;
  ASSERT_EQ(wide->eigenvalues.size(), 100);
  EXPECT_EQ(wide->block_size, 32);
  EXPECT_LT(((wide->eigenvalues - reference->eigenvalues).array() / reference->eigenvalues.array()).abs().maxCoeff(),
            1e-8);

  // Fixed start blocks: the same request gives the same numbers (under hostile timing too:
  // determinism_test.cpp).
  auto again = solveModes(s.K, s.M, settings);
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE(again->eigenvalues == s.modes.eigenvalues);
  EXPECT_EQ(again->operator_applications, s.modes.operator_applications);
}

TEST(Errors, BadInputsBecomeErrorsNotCrashes) {
  Eigen::SparseMatrix<double> K(30, 30), M(31, 31);
  auto mismatched = solveModes(K, M, ModalSettings{});
  ASSERT_FALSE(mismatched.ok());
  EXPECT_EQ(mismatched.error().kind, ErrorKind::BadInput);

  // A mass matrix that is not positive definite: factorization or dense solve must fail cleanly.
  MeshOptions options;
  options.target_edge_m = 0.01;
  const TetMesh mesh = makeBox(0.1, 0.02, 0.02, options).value();
  Eigen::SparseMatrix<double> K2, M2;
  assembleStiffnessAndMass(mesh, kSteel, K2, M2);
  Eigen::SparseMatrix<double> negative_mass = -M2;
  auto failed = solveModes(K2, negative_mass, ModalSettings{});
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.error().message.find("eigensolver"), std::string::npos) << failed.error().message;

  ModalSettings bad;
  bad.max_modes = 0;
  EXPECT_FALSE(solveModes(K2, M2, bad).ok());
}

// Memory forecasts. A cap far beyond the modes the band holds must cost nothing: the Lanczos
// basis grows only while the band still has modes, so the solve (and its forecast) is the one of
// a cap the band fills. A budget below the forecast refuses the solve before it factors.
TEST(MemoryForecast, ACapBeyondTheBandCostsNothingAndABudgetBelowTheForecastRefuses) {
  MeshOptions options;
  options.order = 2;
  options.target_edge_m = 0.01;
  auto mesh = makeBox(0.3, 0.02, 0.02, options);
  ASSERT_TRUE(mesh.ok());
  Eigen::SparseMatrix<double> K, M;
  assembleStiffnessAndMass(*mesh, kSteel, K, M);
  ModalSettings settings;
  settings.max_freq_hz = 20000.0;
  settings.max_modes = 200;
  auto capped = solveModes(K, M, settings);
  ASSERT_TRUE(capped.ok()) << capped.error().message;
  ASSERT_GT(capped->eigenvalues.size(), 5);
  ASSERT_FALSE(capped->capped_by_max_modes) << "the band, not the cap, must end the solve";
  settings.max_modes = 10000;
  auto uncapped = solveModes(K, M, settings);
  ASSERT_TRUE(uncapped.ok()) << uncapped.error().message;
  EXPECT_EQ(uncapped->eigenvalues, capped->eigenvalues);
  EXPECT_EQ(uncapped->lanczos_basis, capped->lanczos_basis);
  EXPECT_LE(uncapped->forecast_bytes, 1.5 * capped->forecast_bytes);
  // The forecast holds at least the basis the solve built (Q and M Q, 8 bytes a number).
  EXPECT_GE(capped->forecast_bytes, 16.0 * K.rows() * capped->lanczos_basis);

  settings.max_modes = 200;
  settings.max_bytes = 0.5 * capped->forecast_bytes;
  auto refused = solveModes(K, M, settings);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().kind, ErrorKind::BadInput);
  EXPECT_NE(refused.error().message.find("more than the memory budget"), std::string::npos) << refused.error().message;
  EXPECT_NE(refused.error().message.find("--max-memory"), std::string::npos);
  settings.max_bytes = capped->forecast_bytes;
  auto fits = solveModes(K, M, settings);
  ASSERT_TRUE(fits.ok()) << fits.error().message;
  EXPECT_EQ(fits->eigenvalues, capped->eigenvalues);

  // A cut-off above the elements' own frequency: the band holds every mode of the mesh, and the
  // whole request's basis is forecast at once.
  settings.max_freq_hz = 1e7;
  settings.max_modes = 10000;
  settings.max_bytes = 4.0 * capped->forecast_bytes;
  auto everything = solveModes(K, M, settings);
  ASSERT_FALSE(everything.ok());
  EXPECT_NE(everything.error().message.find("the band holds all its modes"), std::string::npos)
      << everything.error().message;
}

}  // namespace
}  // namespace strike
