// SPDX-License-Identifier: MIT
// The collocation system as a hierarchical matrix over the cluster tree: blocks of well
// separated clusters compressed by adaptive cross approximation, the others dense
// [Hackbusch, "Hierarchical matrices", 2015; Bebendorf, "Approximation of boundary element
// matrices", Numer. Math. 86, 2000; Rjasanow & Steinbach, "The fast solution of boundary
// integral equations", 2007, ch. 3].
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "../modal/two_parts.hpp"
#include "clusters.hpp"
#include "kernels.hpp"
#include "near_quadrature.hpp"
#include "pieces.hpp"
#include "surface.hpp"

namespace strike::transfer {

/// One block of the matrix: rows [row_begin, row_end) x columns [col_begin, col_end) of the
/// clusters (the clusters under a node of the tree are consecutive, cutAt's order). Either
/// dense (rows x cols, column-major) or low rank, u (rows x rank, column-major) times v
/// (cols x rank, row-major) transposed.
struct HBlock {
  uint32_t row_begin = 0, row_end = 0, col_begin = 0, col_end = 0;
  bool low_rank = false;
  uint32_t rank = 0;
  std::vector<cd> dense;  // rows x cols, column-major
  std::vector<cd> u, v;   // rows x rank column-major, cols x rank row-major
  /// A block of a restricted matrix (HMatrix::restricted): its rows and columns listed (then the
  /// ranges above are unused).
  std::vector<uint32_t> row_index, col_index;
  size_t rows() const { return row_index.empty() ? row_end - row_begin : row_index.size(); }
  size_t cols() const { return col_index.empty() ? col_end - col_begin : col_index.size(); }
};

/// The square collocation matrix A = 1/2 I - M (M[i][j] = int over cluster j of dG/dn from
/// cluster i's collocation point) in blocks.
struct HMatrix {
  size_t n = 0;
  std::vector<HBlock> blocks;  // in the order of the block tree's walk: every sum follows it

  /// y = A x: each block's product in its own fixed order, the blocks added row by row in
  /// their order (the same bits on every machine and thread count).
  void multiply(const std::vector<cd>& x, std::vector<cd>& y) const;
  /// The diagonal (the Jacobi preconditioner's).
  std::vector<cd> diagonal() const;
  /// R A P: the rows `rows` of A (row j of the result is row rows[j]), its columns summed into
  /// `columns` groups (column c into column_of[c]); the blocks stay blocks (a low-rank one keeps
  /// its rank), so the error estimate's coarse system costs a fraction of the fine one.
  HMatrix restricted(const std::vector<int32_t>& rows, const std::vector<int32_t>& column_of, size_t columns) const;
  /// The bytes its blocks hold (values only).
  size_t bytes() const;
  size_t lowRankBlocks() const;
};

/// How the matrix is compressed.
struct HMatrixOptions {
  double aca_tolerance = 1e-5;  ///< a block's cross approximation stops at this relative size
  size_t leaf_clusters = 16;    ///< a cluster-tree node of at most this many clusters is a leaf
  double eta = 2.0;             ///< admissible: the smaller box's diagonal <= eta x their distance
};

/// The assembled system: A as an HMatrix and the right-hand sides b = - int G q (rows x rhs,
/// column-major), the same equation as solveSystem's dense rows for the cut's own collocation
/// points (no interior points).
struct HSystem {
  HMatrix A;
  std::vector<cd> b;  // n x rhs, column-major
  size_t rhs = 0;
};

/// Assembles the square system of `cut` at k: near blocks dense (the cached near quadrature
/// for the near triangles, the rest walked down the tree), admissible blocks by adaptive cross
/// approximation with partial pivoting of the matrix stacked with the right-hand sides' own
/// per-cluster integrals (int over cluster j of G q_r, scaled to the matrix's size), so that
/// b = - sum_j of them costs the same entries as the matrix. Blocks in two fixed halves
/// (`parts`), each computed the same whoever computes it.
HSystem assembleHSystem(const Surface& s, const Cut& cut, const Pieces& pieces, const PieceData& piece_data,
                        const BigTriangles& big, const std::vector<NodeData>& data, const NearCache& near, double k,
                        const HMatrixOptions& options, TwoParts& parts);

}  // namespace strike::transfer
