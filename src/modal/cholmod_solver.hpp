// SPDX-License-Identifier: MIT
// The eigen-solver's one factorization: CHOLMOD's supernodal Cholesky of K - sigma M (SPD for
// a negative shift), reused for every solve of the Lanczos stages. Internal to src/modal.
#pragma once

#include <cholmod.h>

#include <Eigen/SparseCore>

#include "strike/core/result.hpp"
#include "two_parts.hpp"

namespace strike::detail {

/// RAII owner of a CHOLMOD workspace and factor of an SPD matrix.
class CholmodSolver {
 public:
  CholmodSolver();
  ~CholmodSolver();
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  /// The symbolic analysis of A (fill-reducing ordering, supernodes): returns the bytes the
  /// numeric factorization will take, before it takes them.
  Result<double> analyze(const Eigen::SparseMatrix<double>& A);
  /// Factors A (both triangles stored; CHOLMOD reads the lower one), after analyze(A) or alone.
  Status factorize(const Eigen::SparseMatrix<double>& A);

  /// x = A^{-1} b for ncols right-hand sides stored column-major with leading dimension n.
  /// With `parts`, the columns are solved in two halves, ALWAYS: the second by the helper
  /// thread when it is free, with its own CHOLMOD workspace (cholmod_solve2 only reads the
  /// factor), else by this thread after the first. The halves are never merged into one call
  /// when the helper is late: OpenBLAS's AVX-512 kernels give other last bits for 16
  /// right-hand sides than for 2 x 8. Two threads of 8 right-hand sides each take ~70% of the
  /// time of one thread of 16 (per-thread cost 3.7 vs 2.6 ms per right-hand side at 29k DOF,
  /// tests/bench/modal).
  bool solve(const double* b, double* x, int ncols, TwoParts* parts = nullptr);

 private:
  bool solveColumns(const double* b, double* x, int ncols, cholmod_common& common, cholmod_dense*& x_work,
                    cholmod_dense*& y_work, cholmod_dense*& e_work);

  cholmod_common common_{};
  cholmod_factor* factor_ = nullptr;
  cholmod_dense* x_ = nullptr;
  cholmod_dense* y_ = nullptr;
  cholmod_dense* e_ = nullptr;
  // Workspace of the helper thread of a parallel solve (started on first use).
  bool helper_started_ = false;
  cholmod_common helper_common_{};
  cholmod_dense* helper_x_ = nullptr;
  cholmod_dense* helper_y_ = nullptr;
  cholmod_dense* helper_e_ = nullptr;
};

}  // namespace strike::detail
