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
  std::vector<uint32_t> col_mark;  // per cluster: col_stamp when in the columns assembled
  uint32_t col_stamp = 0;
  // The big triangles (BigTriangles): per point, then per triangle.
  std::vector<double> big_r, big_w, big_dn, big_phase, big_sin, big_cos, big_g_re, big_g_im, big_dg_re, big_dg_im;
  std::vector<size_t> big_first;  // per big triangle: its first point, or SIZE_MAX (integrateTriangle)
  std::vector<cd> big_g, big_dg;  // per big triangle: int G, int dG/dn
};

/// The part of a row at x from the subtree of node `start`, the triangles stamped near x in
/// w.near_stamp (w.stamp) left out (the NearCache has them): M[col] += int_cluster dG/dn_y,
/// lq[r] += int G q_r. Nodes far from x as one point with their phase spread, the rest walked
/// down to triangles (integrateTriangle).
void assembleSubtree(const Surface& s, const Cut& cut, const std::vector<NodeData>& data, double k, const V3& x,
                     int32_t start, cd* M, cd* lq, RowScratch& w);

/// A part of a row: the columns [col_begin, col_end), whose pieces are [piece_begin, piece_end)
/// and big triangles [big_begin, big_end) (makePieces lists them cluster by cluster, in the
/// cut's order); `near`: the near cache's triangles of the row in those columns are taken from
/// it (false: the columns are known to hold none, as a well-separated block's).
struct RowRange {
  size_t piece_begin = 0, piece_end = 0;
  size_t col_begin = 0, col_end = 0;
  size_t big_begin = 0, big_end = 0;
  bool near = true;
};

/// Per cluster c: its first piece (and clusters + 1 entries: the last is the pieces' count).
std::vector<size_t> pieceBegin(const Pieces& p, size_t clusters);
RowRange rowRange(const BigTriangles& big, const std::vector<size_t>& piece_begin, size_t col_begin, size_t col_end,
                  bool near);

/// assembleRow restricted to a range of columns: the same sums in the same order (the whole
/// range is assembleRow itself).
void assembleRowRange(const Surface& s, const Cut& cut, const Pieces& p, const PieceData& pd, const BigTriangles& big,
                      const std::vector<NodeData>& data, const NearCache& near, size_t row, double k, const V3& x,
                      const RowRange& range, cd* M, cd* lq, RowScratch& w);

/// The same for several ranges of columns at once (their near triangles from one pass over the
/// row's near quadrature), the ranges in their order.
void assembleRowRanges(const Surface& s, const Cut& cut, const Pieces& p, const PieceData& pd, const BigTriangles& big,
                       const std::vector<NodeData>& data, const NearCache& near, size_t row, double k, const V3& x,
                       const RowRange* ranges, size_t range_count, cd* M, cd* lq, RowScratch& w);

/// One row of the system at x (row `row` of the cut, or an interior point after them):
/// M[col] += int_cluster dG/dn_y, and lq[r] += int G q_r over the surface. The near triangles
/// from the cache's points; pieces far from x as one point with their phase spread
/// (phaseSpread); the rest walked down the tree (assembleNear). The sums are split into
/// passes over arrays (distances, exponentials, kernels, then the sums) that vectorize, with
void assembleRow(const Surface& s, const Cut& cut, const Pieces& p, const PieceData& pd, const BigTriangles& big,
                 const std::vector<NodeData>& data, const NearCache& near, size_t row, double k, const V3& x, cd* M,
                 cd* lq, RowScratch& w);

}  // namespace strike::transfer
