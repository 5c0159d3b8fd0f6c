// SPDX-License-Identifier: MIT
// Sparse symmetric matrix times a dense block, row by row (the M and K products of the
// eigen-solver's block stage and refinement).
#include <algorithm>

#include "lanczos.hpp"

namespace strike::detail {

namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

}  // namespace

/// Y = A X for a SYMMETRIC sparse A (K or M) and a block X of a few to a few hundred columns.
/// Column j of A is row j, so each row of Y gathers rows of X: with X and Y row-major the
/// inner loop runs over the block's columns, contiguous, and A is read once instead of once
/// per column (Eigen's sparse * dense product; measured 2x faster at 16 and 100 columns).
/// Rows of Y are independent and each is summed by this loop in one order, so with `parts` two
/// threads may fill one half each and the bits do not depend on the cut.
void symmetricTimesBlock(const SpMat& A, const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::MatrixXd& Y,
                         TwoParts* parts) {
  const RowMajorMatrix Xr = X;
  RowMajorMatrix Yr(X.rows(), X.cols());
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* values = A.valuePtr();
  const int* nnz = A.innerNonZeroPtr();  // null when compressed
  const Eigen::Index b = X.cols();
  const Eigen::Index rows = A.outerSize();
  auto rowsOfY = [&](Eigen::Index begin, Eigen::Index end_row, int) {
    for (Eigen::Index j = begin; j < end_row; ++j) {
      double* y = Yr.data() + j * b;
      std::fill(y, y + b, 0.0);
      const int end = nnz != nullptr ? outer[j] + nnz[j] : outer[j + 1];
      for (int q = outer[j]; q < end; ++q) {
        const double a = values[q];
        const double* x = Xr.data() + static_cast<Eigen::Index>(inner[q]) * b;
        for (Eigen::Index c = 0; c < b; ++c) y[c] += a * x[c];
      }
    }
  };
  if (parts != nullptr) {
    parts->run(rows, rows / 2, rowsOfY);
  } else {
    rowsOfY(0, rows, 0);
  }
  Y = Yr;
}

}  // namespace strike::detail
