// SPDX-License-Identifier: MIT
// One solve: assemble the collocation system of a cut at a wavenumber, solve it and its
// coarse version (the error estimate).
#pragma once

#include <map>
#include <vector>

#include "../modal/two_parts.hpp"
#include "clusters.hpp"
#include "hmatrix.hpp"
#include "near_quadrature.hpp"
#include "pieces.hpp"
#include "surface.hpp"

namespace strike::transfer {

struct ModeSolve {
  std::vector<Eigen::VectorXcd> p;       // per right-hand side, per cluster
  std::vector<Eigen::VectorXcd> p_diff;  // p minus the coarse solve's, per cluster
  size_t elements = 0, chief = 0;
  Cut cut;
  Pieces pieces;
  PieceData piece_data;
  double assembly_seconds = 0.0, factor_seconds = 0.0;
  size_t iterations = 0;                   ///< GMRES iterations of the fine solve (0: a direct solve)
  size_t matrix_bytes = 0;                 ///< what the fine system's matrix held (dense, or its blocks)
  size_t low_rank_blocks = 0, blocks = 0;  ///< of a hierarchical matrix (0: dense)
};

/// How the systems are solved.
struct SystemOptions {
  /// Square systems with more unknowns than this are solved by GMRES (iterative_solve.hpp), the
  /// others by single-precision LU refined in double (dense_solve.hpp).
  size_t direct_max_elements = 700;
  double iterative_tolerance = 1e-5;  ///< GMRES's relative residual
  /// The iterative systems as hierarchical matrices (hmatrix.hpp: near-linear memory and
  /// products); false: dense, as below direct_max_elements.
  bool hierarchical = true;
  HMatrixOptions hmatrix;
};

/// Solves the exterior Neumann problem for the boundary data `data` (one right-hand side each:
/// modes of one frequency share the matrix and its factorization) at wavenumber k with
/// `elements` unknowns (about) and `chief` interior points. The near quadrature's rules are
/// chosen at k_rule >= k; `near_caches` (per number of unknowns) must all be of that k_rule.
ModeSolve solveSystem(const Surface& s, const std::vector<NodeData>& data, double k, size_t elements, size_t chief,
                      double k_rule, std::map<size_t, NearCache>& near_caches, TwoParts& parts,
                      const SystemOptions& options = {});

}  // namespace strike::transfer
