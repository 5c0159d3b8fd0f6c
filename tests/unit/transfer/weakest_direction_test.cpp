// SPDX-License-Identifier: MIT
// Development aid, not run by ctest: the square collocation system's smallest singular values
// across a band, and where on the surface its weakest direction lies. A fictitious interior
// resonance, or a resonance of air the body encloses (a cup's inside), shows as a sharp dip;
// docs/acoustic-transfer.md ("Is the estimate honest?") reads the mug's with it.
//
//   STRIKE_PROBE_BANK=mug.modes STRIKE_PROBE_ELEMENTS=700 STRIKE_PROBE_HZ=13500,19000,250
//     strike_transfer_tests --gtest_also_run_disabled_tests --gtest_filter='WeakestDirection.*'
//
// (the bank from strike modes ... --no-transfer; STRIKE_PROBE_VECTOR=1 also prints the share of
// the weakest direction's energy on faces facing up, down, and sideways outward and inward.)
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "strike/bank/bank.hpp"
#include "transfer/assembly.hpp"

namespace strike {
namespace {

using transfer::cd;

TEST(WeakestDirection, DISABLED_PrintsTheSmallestSingularValuesOfABankFromTheEnvironment) {
  const char* path = std::getenv("STRIKE_PROBE_BANK");
  const char* elements_text = std::getenv("STRIKE_PROBE_ELEMENTS");
  const char* band = std::getenv("STRIKE_PROBE_HZ");
  ASSERT_TRUE(path && elements_text && band);
  double from_hz = 0.0, to_hz = 0.0, step_hz = 0.0;
  ASSERT_EQ(std::sscanf(band, "%lf,%lf,%lf", &from_hz, &to_hz, &step_hz), 3);
  ASSERT_GT(step_hz, 0.0);
  Result<ModeBank> bank = readBank(path);
  ASSERT_TRUE(bank) << bank.error().message;
  Result<transfer::Surface> made = transfer::makeSurface(*bank);
  ASSERT_TRUE(made) << made.error().message;
  const transfer::Surface& s = *made;
  const transfer::Cut cut = transfer::cutWithCount(s, static_cast<size_t>(std::atoi(elements_text)));
  const auto n = static_cast<Eigen::Index>(cut.nodes.size());
  const double c_air = 343.0;
  std::printf("%zu triangles, %td unknowns, %zu interior point candidates\n", s.tris.size(), n,
              s.chief_candidates.size());
  std::vector<transfer::NodeData> data(1);  // (the matrix does not depend on it)
  for (const transfer::Triangle& t : s.tris) data[0].q.push_back(t.normal[2]);
  transfer::nodeData(s, data[0]);
  for (double hz = from_hz; hz <= to_hz * (1 + 1e-12); hz += step_hz) {
    const double k = 2.0 * M_PI * hz / c_air;
    const transfer::NearCache near = transfer::buildNearCache(s, cut, k);
    const transfer::Pieces pieces = transfer::makePieces(s, cut, k);
    const transfer::PieceData piece_data = transfer::pieceData(s, pieces, data);
    const transfer::BigTriangles big = transfer::bigTriangles(s, pieces, k);
    transfer::RowScratch scratch;
    Eigen::MatrixXcd A(n, n);
    for (Eigen::Index r = 0; r < n; ++r) {
      std::vector<cd> M(static_cast<size_t>(n), cd(0.0)), lq(1, cd(0.0));
      const auto row = static_cast<size_t>(r);
      const transfer::V3 x = s.tris[s.nodes[cut.nodes[row]].rep].centroid;
      transfer::assembleRow(s, cut, pieces, piece_data, big, data, near, row, k, x, M.data(), lq.data(), scratch);
      for (Eigen::Index c = 0; c < n; ++c) A(r, c) = -M[static_cast<size_t>(c)] + (c == r ? 0.5 : 0.0);
    }
    const bool vector = std::getenv("STRIKE_PROBE_VECTOR") != nullptr;
    Eigen::BDCSVD<Eigen::MatrixXcd> svd(A, vector ? Eigen::ComputeThinV : 0);
    const Eigen::VectorXd& sv = svd.singularValues();
    std::printf("%8.1f Hz: smallest singular values %.4g %.4g %.4g, largest %.4g\n", hz, sv[n - 1], sv[n - 2],
                sv[n - 3], sv[0]);
    if (vector) {
      // Energy of the weakest direction by the collocation triangle's normal: up, down, and
      // sideways away from the z axis (outward) or toward it (inward).
      double up = 0.0, down = 0.0, outward = 0.0, inward = 0.0;
      for (Eigen::Index c = 0; c < n; ++c) {
        const transfer::Triangle& t = s.tris[s.nodes[cut.nodes[static_cast<size_t>(c)]].rep];
        const double e = std::norm(svd.matrixV()(c, n - 1));
        if (t.normal[2] > 0.7)
          up += e;
        else if (t.normal[2] < -0.7)
          down += e;
        else if (t.normal.head<2>().dot(t.centroid.head<2>()) > 0)
          outward += e;
        else
          inward += e;
      }
      std::printf("  weakest direction: up %.3f, down %.3f, outward %.3f, inward %.3f\n", up, down, outward, inward);
    }
    std::fflush(stdout);
  }
}

}  // namespace
}  // namespace strike
