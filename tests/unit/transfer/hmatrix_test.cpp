// SPDX-License-Identifier: MIT
// The hierarchical collocation matrix (src/transfer/hmatrix.cpp) against the dense rows of the
// same system on a thin wall (a 4 mm disc, both faces): its product and right-hand side within
// the cross approximation's tolerance, its compression real, its bits independent of the thread
// count; and a transfer solved through it against the dense solve.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdlib>
#include <vector>

#include "strike/bank/bank.hpp"
#include "strike/mesh/mesh.hpp"
#include "strike/precompute/precompute.hpp"
#include "strike/transfer/transfer_solver.hpp"
#include "transfer/assembly.hpp"
#include "transfer/hmatrix.hpp"

namespace strike {
namespace {

using transfer::cd;

ModeBank discBank(double radius, double height, double edge) {
  Result<SurfaceMesh> mesh = makeCylinderSurface(radius, height, edge);
  EXPECT_TRUE(mesh) << mesh.error().message;
  ModeBank bank;
  for (Eigen::Index v = 0; v < mesh->V.rows(); ++v)
    for (int c = 0; c < 3; ++c) bank.surface_positions.push_back(mesh->V(v, c));
  bank.surface_normals.assign(bank.surface_positions.size(), 0.0f);
  for (Eigen::Index f = 0; f < mesh->F.rows(); ++f)
    for (int c = 0; c < 3; ++c) bank.surface_triangles.push_back(static_cast<uint32_t>(mesh->F(f, c)));
  return bank;
}

/// The system of a disc (radius 0.1 m, 4 mm thick) at k: the dense rows (assembleRow) and the
/// hierarchical matrix, for the boundary data of a rigid broadside motion and of a bending-like
/// pattern (two right-hand sides).
struct Systems {
  transfer::Surface surface;
  transfer::Cut cut;
  std::vector<std::vector<cd>> dense;  // rows
  std::vector<cd> dense_b;             // n x rhs
  transfer::HSystem h;
};

Systems systemsAt(double k, double aca_tolerance, bool two_threads, double eta = 2.0) {
  Systems out;
  ModeBank bank = discBank(0.1, 0.004, 0.006);
  Result<transfer::Surface> made = transfer::makeSurface(bank);
  EXPECT_TRUE(made);
  out.surface = std::move(*made);
  const transfer::Surface& s = out.surface;
  out.cut = transfer::cutWithCount(s, 700);
  const size_t n = out.cut.nodes.size();
  std::vector<transfer::NodeData> data(2);
  for (size_t t = 0; t < s.tris.size(); ++t) {
    const transfer::V3& c = s.tris[t].centroid;
    data[0].q.push_back(-1.2 * s.tris[t].normal[2]);
    data[1].q.push_back(-1.2 * s.tris[t].normal[2] * std::cos(40.0 * c[0]) * (1.0 + 10.0 * c[1]));
  }
  for (auto& d : data) transfer::nodeData(s, d);
  const transfer::NearCache near = transfer::buildNearCache(s, out.cut, k);
  const transfer::Pieces pieces = transfer::makePieces(s, out.cut, k);
  const transfer::PieceData piece_data = transfer::pieceData(s, pieces, data);
  const transfer::BigTriangles big = transfer::bigTriangles(s, pieces, k);
  transfer::RowScratch w;
  out.dense.assign(n, std::vector<cd>(n));
  out.dense_b.assign(2 * n, cd(0.0));
  for (size_t r = 0; r < n; ++r) {
    std::vector<cd> M(n, cd(0.0)), lq(2, cd(0.0));
    const transfer::V3 x = s.tris[s.nodes[out.cut.nodes[r]].rep].centroid;
    transfer::assembleRow(s, out.cut, pieces, piece_data, big, data, near, r, k, x, M.data(), lq.data(), w);
    for (size_t c = 0; c < n; ++c) out.dense[r][c] = -M[c] + (c == r ? 0.5 : 0.0);
    for (size_t q = 0; q < 2; ++q) out.dense_b[q * n + r] = -lq[q];
  }
  transfer::HMatrixOptions options;
  options.aca_tolerance = aca_tolerance;
  options.eta = eta;
  TwoParts parts(two_threads);
  out.h = transfer::assembleHSystem(s, out.cut, pieces, piece_data, big, data, near, k, options, parts);
  return out;
}

double relativeDifference(const std::vector<cd>& a, const std::vector<cd>& b) {
  double wrong = 0.0, total = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    wrong += std::norm(a[i] - b[i]);
    total += std::norm(b[i]);
  }
  return std::sqrt(wrong / total);
}

TEST(HMatrix, ProductAndRightHandSideAreTheDenseOnesWithinTheCrossApproximationsTolerance) {
  const double k = 3.0 / 0.1;  // ka = 3: 3.5 wavelengths across the disc's two faces
  for (const double tolerance : {1e-3, 1e-5}) {
    const Systems sys = systemsAt(k, tolerance, false);
    const size_t n = sys.cut.nodes.size();
    ASSERT_GT(n, 500u);
    const transfer::HMatrix& A = sys.h.A;
    // The compression is real: well-separated blocks of low rank, fewer values than dense.
    EXPECT_GT(A.lowRankBlocks(), 0u);
    EXPECT_LT(A.bytes(), n * n * sizeof(cd));
    // A fixed pseudo-random vector (an LCG), and the two faces' opposite pressures.
    std::vector<cd> x(n);
    uint64_t state = 12345;
    for (size_t i = 0; i < n; ++i) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      const double u = static_cast<double>(state >> 11) / 9007199254740992.0;
      x[i] = cd(std::cos(6.0 * u), std::sin(2.0 * u) - 0.3);
    }
    std::vector<cd> dense_y(n, cd(0.0)), h_y;
    for (size_t r = 0; r < n; ++r)
      for (size_t c = 0; c < n; ++c) dense_y[r] += sys.dense[r][c] * x[c];
    A.multiply(x, h_y);
    const double product_error = relativeDifference(h_y, dense_y);
    const double rhs_error = relativeDifference(sys.h.b, sys.dense_b);
    EXPECT_LT(product_error, 10 * tolerance) << tolerance;
    EXPECT_LT(rhs_error, 10 * tolerance) << tolerance;
    // The diagonal (the preconditioner) is the dense one's.
    const std::vector<cd> d = A.diagonal();
    for (size_t i = 0; i < n; i += 37) EXPECT_LT(std::abs(d[i] - sys.dense[i][i]), 1e-9 * std::abs(sys.dense[i][i]));
    std::printf(
        "  tolerance %.0e: %zu unknowns, %zu blocks (%zu low rank), %.1f MB against %.1f MB dense; product %.2e, "
        "b %.2e off\n",
        tolerance, n, A.blocks.size(), A.lowRankBlocks(), A.bytes() / 1e6, n * n * sizeof(cd) / 1e6, product_error,
        rhs_error);
  }
}

TEST(HMatrix, SameBitsOnOneThreadAndOnTwo) {
  const Systems one = systemsAt(30.0, 1e-5, false);
  const Systems two = systemsAt(30.0, 1e-5, true);
  ASSERT_EQ(one.h.A.blocks.size(), two.h.A.blocks.size());
  for (size_t b = 0; b < one.h.A.blocks.size(); ++b) {
    const transfer::HBlock& p = one.h.A.blocks[b];
    const transfer::HBlock& q = two.h.A.blocks[b];
    ASSERT_EQ(p.rank, q.rank);
    ASSERT_EQ(p.dense, q.dense);
    ASSERT_EQ(p.u, q.u);
    ASSERT_EQ(p.v, q.v);
  }
  ASSERT_EQ(one.h.b, two.h.b);
}

// A transfer solved with the hierarchical matrix (budget above direct_max_elements: GMRES over
// its product) against the same solve with the dense matrix: the far fields agree to the
// solver's residual, the estimates (the coarse system: the hierarchical one restricted) too.
TEST(HMatrix, ATransferThroughItIsTheDenseSolvesWithinTheTolerance) {
  ModeBank bank = discBank(0.1, 0.004, 0.006);
  const double c_air = 343.0;
  const size_t vertices = bank.surfaceVertexCount();
  for (const double ka : {1.0, 4.0}) {
    bank.eigenvalues.push_back(std::pow(ka / 0.1 * c_air, 2));
    for (size_t v = 0; v < vertices; ++v) {  // broadside, rising toward +x
      const double xv = bank.surface_positions[3 * v];
      for (int c = 0; c < 3; ++c) bank.shapes.push_back(c == 2 ? static_cast<float>(1.0 + 5.0 * xv) : 0.0f);
    }
  }
  TransferSettings settings;
  settings.fixed_elements = 900;
  settings.direct_max_elements = 300;
  std::vector<AcousticTransfer> runs;
  for (const bool hierarchical : {false, true}) {
    settings.hierarchical = hierarchical;
    Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings);
    ASSERT_TRUE(t) << t.error().message;
    runs.push_back(*t);
  }
  for (size_t i = 0; i < 2; ++i) {
    ASSERT_EQ(runs[0].order[i], runs[1].order[i]);
    double wrong = 0.0, total = 0.0;
    for (uint64_t j = runs[0].offset[i]; j < runs[0].offset[i + 1]; ++j) {
      wrong += std::norm(cd(runs[1].coefficients[j]) - cd(runs[0].coefficients[j]));
      total += std::norm(cd(runs[0].coefficients[j]));
    }
    EXPECT_LT(std::sqrt(wrong / total), 1e-4) << i;
    EXPECT_NEAR(runs[1].relative_error[i], runs[0].relative_error[i], 1e-3 * runs[0].relative_error[i]) << i;
  }
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(runs[1].translation_dipole_m3[i * 4], runs[0].translation_dipole_m3[i * 4],
                1e-4 * std::abs(runs[0].translation_dipole_m3[8]));
}

// The transfer's memory forecast (transferMemoryForecastBytes, checked before a solve against
// --max-memory) against what the solver counts it holds (TransferModeStats: the fine matrix and
// the near quadrature caches): at least that, and within 4x of it, on the thin disc solved
// through the hierarchical matrix and through dense LU (ka 4, the forecast's top frequency
// the mode's).
TEST(HMatrix, TheMemoryForecastBoundsWhatTheSolverHolds) {
  const double c_air = 343.0, ka = 4.0, k = ka / 0.1;
  for (const uint32_t direct_max : {300u, 1000u}) {
    ModeBank bank = discBank(0.1, 0.004, 0.006);
    bank.eigenvalues.push_back(std::pow(k * c_air, 2));
    bank.max_freq_hz = k * c_air / (2 * M_PI);
    for (size_t v = 0; v < bank.surfaceVertexCount(); ++v)
      for (int c = 0; c < 3; ++c) bank.shapes.push_back(c == 2 ? 1.0f : 0.0f);
    TransferSettings settings;
    settings.speed_of_sound_m_s = c_air;
    settings.max_elements = 900;
    settings.direct_max_elements = direct_max;
    std::vector<TransferModeStats> stats;
    Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings, {}, &stats);
    ASSERT_TRUE(t) << t.error().message;
    const double held = static_cast<double>(stats[0].matrix_bytes + stats[0].near_cache_bytes);
    const double forecast = transferMemoryForecastBytes(bank, settings);
    std::printf("  direct max %u: %u unknowns, matrix %.1f MB, near %.1f MB; forecast %.1f MB (%.2fx)\n", direct_max,
                stats[0].elements, stats[0].matrix_bytes / 1e6, stats[0].near_cache_bytes / 1e6, forecast / 1e6,
                forecast / held);
    EXPECT_GT(stats[0].matrix_bytes, 0u);
    EXPECT_GE(forecast, held);
    EXPECT_LE(forecast, 4.0 * held);
  }
}

// Development aid, not run by ctest: STRIKE_TRANSFER_BANK=path.modes prints the forecast.
TEST(HMatrix, DISABLED_PrintsTheForecastOfABankFromTheEnvironment) {
  const char* path = std::getenv("STRIKE_TRANSFER_BANK");
  ASSERT_NE(path, nullptr);
  Result<ModeBank> bank = readBank(path);
  ASSERT_TRUE(bank) << bank.error().message;
  TransferSettings settings;
  if (const char* max = std::getenv("STRIKE_TRANSFER_MAX_ELEMENTS")) settings.max_elements = std::atoi(max);
  std::printf("forecast %.1f MB\n", transferMemoryForecastBytes(*bank, settings) / 1e6);
}

}  // namespace
}  // namespace strike
