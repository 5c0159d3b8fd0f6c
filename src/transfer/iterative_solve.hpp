// SPDX-License-Identifier: MIT
// The collocation system solved iteratively: restarted GMRES (Saad & Schultz 1986) with a
// fixed order of every sum, for square systems too large for a dense LU's N^3.
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <cstddef>
#include <functional>
#include <vector>

#include "../modal/two_parts.hpp"

namespace strike::transfer {

/// What an iterative solve did.
struct IterativeReport {
  size_t iterations = 0;        ///< most over the right-hand sides
  double worst_residual = 0.0;  ///< largest |b - A x| / |b| reached
};

/// A x = B for a square A by restarted GMRES with a diagonal (Jacobi) preconditioner, each
/// column of B on its own, to a relative residual of `tolerance` or `max_iterations`. The
/// products A v are explicit loops in a fixed order, rows in two fixed halves (`parts`): the
/// same bits on one thread or two and whatever the cache sizes.
Eigen::MatrixXcd solveGmres(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B, double tolerance,
                            size_t max_iterations, TwoParts& parts, IterativeReport* report = nullptr);

/// y = A x for an operator given by its product (which must sum in a fixed order).
using MatrixProduct =
    std::function<void(const std::vector<std::complex<double>>& x, std::vector<std::complex<double>>& y)>;

/// The same GMRES for an A given by its product and its diagonal (the preconditioner).
Eigen::MatrixXcd solveGmres(const MatrixProduct& product, const std::vector<std::complex<double>>& diagonal,
                            const Eigen::MatrixXcd& B, double tolerance, size_t max_iterations,
                            IterativeReport* report = nullptr);

}  // namespace strike::transfer
