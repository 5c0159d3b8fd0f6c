// SPDX-License-Identifier: MIT
// Single-precision LU and QR with iterative refinement in double.
#include "dense_solve.hpp"

#include <complex>

#include "kernels.hpp"

namespace strike::transfer {

Eigen::MatrixXcd solveSquare(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B) {
  using MatrixCf = Eigen::Matrix<std::complex<float>, Eigen::Dynamic, Eigen::Dynamic>;
  const Eigen::PartialPivLU<MatrixCf> lu(A.cast<std::complex<float>>());
  Eigen::MatrixXcd X = lu.solve(B.cast<std::complex<float>>()).cast<cd>();
  const Eigen::Index n = A.rows();
  Eigen::MatrixXcd R(n, B.cols());
  for (int step = 0; step < 2; ++step) {
    for (Eigen::Index c = 0; c < B.cols(); ++c) {
      for (Eigen::Index i = 0; i < n; ++i) R(i, c) = B(i, c);
      for (Eigen::Index j = 0; j < n; ++j) {
        const cd x = X(j, c);
        for (Eigen::Index i = 0; i < n; ++i) R(i, c) -= A(i, j) * x;
      }
    }
    X += lu.solve(R.cast<std::complex<float>>()).cast<cd>();
  }
  return X;
}

Eigen::MatrixXcd solveLeastSquares(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B) {
  using cf = std::complex<float>;
  using MatrixCf = Eigen::Matrix<cf, Eigen::Dynamic, Eigen::Dynamic>;
  const Eigen::Index m = A.rows(), n = A.cols(), cols = B.cols();
  const Eigen::HouseholderQR<MatrixCf> qr(A.cast<cf>());
  const auto R = qr.matrixQR().topLeftCorner(n, n).triangularView<Eigen::Upper>();
  Eigen::MatrixXcd X = qr.solve(B.cast<cf>()).cast<cd>();
  Eigen::MatrixXcd r(m, cols), f(m, cols), g(n, cols);
  auto residualOfX = [&](Eigen::MatrixXcd& out, const Eigen::MatrixXcd& start) {  // start - A X
    for (Eigen::Index c = 0; c < cols; ++c) {
      for (Eigen::Index i = 0; i < m; ++i) out(i, c) = start(i, c);
      for (Eigen::Index j = 0; j < n; ++j) {
        const cd x = X(j, c);
        for (Eigen::Index i = 0; i < m; ++i) out(i, c) -= A(i, j) * x;
      }
    }
  };
  residualOfX(r, B);
  for (int step = 0; step < 2; ++step) {
    residualOfX(f, B - r);
    for (Eigen::Index c = 0; c < cols; ++c)
      for (Eigen::Index j = 0; j < n; ++j) {
        cd sum = 0.0;
        for (Eigen::Index i = 0; i < m; ++i) sum += std::conj(A(i, j)) * r(i, c);
        g(j, c) = -sum;
      }
    const MatrixCf h = R.adjoint().solve(g.cast<cf>());
    MatrixCf qf = qr.householderQ().adjoint() * f.cast<cf>();
    X += R.solve(qf.topRows(n) - h).cast<cd>();
    qf.topRows(n) = h;
    r += (qr.householderQ() * qf).cast<cd>();
  }
  return X;
}

}  // namespace strike::transfer
