// SPDX-License-Identifier: MIT
// One row of the collocation system: int dG/dn per cluster and int G q per right-hand side.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "clusters.hpp"
#include "kernels.hpp"
#include "near_quadrature.hpp"
#include "pieces.hpp"
#include "surface.hpp"

namespace strike::transfer {

/// Scratch of assembleRow.
struct RowScratch {
  std::vector<double> r, phase, sin_kr, cos_kr;  // per piece, then per near point
  std::vector<double> far, dx, dy, dz;           // per piece: 1 if summed as one point, 0 if not
  std::vector<double> g_re, g_im, dg_re, dg_im;  // G and dG/dr / r (times the spread, the weight)
  std::vector<double> m_re, m_im;                // the contribution to M[col]
  std::vector<int32_t> stack;
  std::vector<uint32_t> near_stamp;  // per triangle: the row that found it near (+1)
  uint32_t stamp = 0;
  // The big triangles (BigTriangles): per point, then per triangle.
  std::vector<double> big_r, big_w, big_dn, big_phase, big_sin, big_cos, big_g_re, big_g_im, big_dg_re, big_dg_im;
  std::vector<size_t> big_first;  // per big triangle: its first point, or SIZE_MAX (integrateTriangle)
  std::vector<cd> big_g, big_dg;  // per big triangle: int G, int dG/dn
};

/// One row of the system at x (row `row` of the cut, or an interior point after them):
/// M[col] += int_cluster dG/dn_y, and lq[r] += int G q_r over the surface. The near triangles
/// from the cache's points; pieces far from x as one point with their phase spread
/// (phaseSpread); the rest walked down the tree (assembleNear). The sums are split into
/// passes over arrays (distances, exponentials, kernels, then the sums) that vectorize, with
void assembleRow(const Surface& s, const Cut& cut, const Pieces& p, const PieceData& pd, const BigTriangles& big,
                 const std::vector<NodeData>& data, const NearCache& near, size_t row, double k, const V3& x, cd* M,
                 cd* lq, RowScratch& w);

}  // namespace strike::transfer
