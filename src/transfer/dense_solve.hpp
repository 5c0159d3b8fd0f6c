// SPDX-License-Identifier: MIT
// Dense solves of the collocation system: single precision, refined in double.
#pragma once

#include <Eigen/Dense>

namespace strike::transfer {

/// A x = B for a square A: LU in single precision (half the time of double), then iterative
/// refinement with the residual in double (Wilkinson; Moler 1967, "Iterative refinement in
/// floating point", J. ACM 14), which recovers double accuracy while cond(A) eps_float << 1 (these
/// second-kind systems: cond ~ 10-1000). The residual is an explicit loop (fixed order).
Eigen::MatrixXcd solveSquare(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B);

/// min |A x - B| for a tall A (the interior points' rows under the surface's): Householder QR
/// in single precision (half the time of double), then iterative refinement of the augmented
/// system [I A; A^H 0] [r; x] = [B; 0] with its residuals in double (Bjorck 1967, "Iterative
/// refinement of linear least squares solutions I", BIT 7), which converges to the double-
/// precision solution at a rate ~ cond(A) eps_float per step whatever the residual's size.
/// Each correction: h = R^-H g, [f1; f2] = Q^H f, dx = R^-1 (f1 - h), dr = Q [h; f2], for the
/// residuals f = B - r - A x and g = -A^H r. The residuals are explicit loops (fixed order).
Eigen::MatrixXcd solveLeastSquares(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B);

}  // namespace strike::transfer
