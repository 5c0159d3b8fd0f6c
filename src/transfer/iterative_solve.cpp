// SPDX-License-Identifier: MIT
// Restarted, right-preconditioned GMRES with modified Gram-Schmidt and Givens rotations
// [Saad & Schultz, "GMRES: a generalized minimal residual algorithm for solving nonsymmetric
// linear systems", SIAM J. Sci. Stat. Comput. 7, 1986; Saad, "Iterative methods for sparse linear
// systems", 2nd ed., 2003, alg. 6.9 and 9.5].
#include "iterative_solve.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

namespace strike::transfer {
namespace {

using cd = std::complex<double>;

constexpr size_t kRestart = 60;

/// y = A x, rows in two fixed halves; each row's sum in column order, walked column by column
/// (A is column-major: contiguous reads).
void multiply(const Eigen::MatrixXcd& A, const std::vector<cd>& x, std::vector<cd>& y, TwoParts& parts) {
  const size_t n = static_cast<size_t>(A.rows());
  y.assign(n, cd(0.0));
  parts.run(n, n / 2, [&](size_t begin, size_t end, int) {
    std::vector<double> re(end - begin, 0.0), im(end - begin, 0.0);
    for (size_t j = 0; j < n; ++j) {
      const cd* column = A.data() + j * n;
      const double x_re = x[j].real(), x_im = x[j].imag();
      for (size_t i = begin; i < end; ++i) {
        const double a_re = column[i].real(), a_im = column[i].imag();
        re[i - begin] += a_re * x_re - a_im * x_im;
        im[i - begin] += a_re * x_im + a_im * x_re;
      }
    }
    for (size_t i = begin; i < end; ++i) y[i] = cd(re[i - begin], im[i - begin]);
  });
}

cd dot(const std::vector<cd>& a, const std::vector<cd>& b) {  // sum conj(a) b
  double re = 0.0, im = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    re += a[i].real() * b[i].real() + a[i].imag() * b[i].imag();
    im += a[i].real() * b[i].imag() - a[i].imag() * b[i].real();
  }
  return {re, im};
}

double norm(const std::vector<cd>& a) { return std::sqrt(dot(a, a).real()); }

}  // namespace

Eigen::MatrixXcd solveGmres(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B, double tolerance,
                            size_t max_iterations, TwoParts& parts, IterativeReport* report) {
  const size_t n = static_cast<size_t>(A.rows());
  std::vector<cd> diagonal(n);
  for (size_t i = 0; i < n; ++i) diagonal[i] = A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i));
  return solveGmres([&](const std::vector<cd>& x, std::vector<cd>& y) { multiply(A, x, y, parts); }, diagonal, B,
                    tolerance, max_iterations, report);
}

Eigen::MatrixXcd solveGmres(const MatrixProduct& product, const std::vector<cd>& diagonal, const Eigen::MatrixXcd& B,
                            double tolerance, size_t max_iterations, IterativeReport* report) {
  const size_t n = diagonal.size();
  Eigen::MatrixXcd X = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(n), B.cols());
  // Right preconditioner M^-1 = diag(A)^-1: x = M^-1 u, solve A M^-1 u = b.
  std::vector<cd> inv_diag(n);
  for (size_t i = 0; i < n; ++i) {
    const cd d = diagonal[i];
    inv_diag[i] = std::abs(d) > 0 ? 1.0 / d : cd(1.0);
  }
  IterativeReport done;
  std::vector<std::vector<cd>> V(kRestart + 1, std::vector<cd>(n));
  std::vector<std::vector<cd>> H(kRestart + 1, std::vector<cd>(kRestart));
  std::vector<cd> cs(kRestart), sn(kRestart), g(kRestart + 1), w(n), z(n), x(n), r(n), b(n), ax(n);
  for (Eigen::Index col = 0; col < B.cols(); ++col) {
    for (size_t i = 0; i < n; ++i) b[i] = B(static_cast<Eigen::Index>(i), col);
    std::fill(x.begin(), x.end(), cd(0.0));
    const double b_norm = norm(b);
    if (!(b_norm > 0)) continue;
    size_t iterations = 0;
    double residual = 1.0;
    while (iterations < max_iterations) {
      product(x, ax);
      for (size_t i = 0; i < n; ++i) r[i] = b[i] - ax[i];
      const double beta = norm(r);
      residual = beta / b_norm;
      if (residual <= tolerance) break;
      for (size_t i = 0; i < n; ++i) V[0][i] = r[i] / beta;
      std::fill(g.begin(), g.end(), cd(0.0));
      g[0] = beta;
      size_t j = 0;
      for (; j < kRestart && iterations < max_iterations; ++j, ++iterations) {
        for (size_t i = 0; i < n; ++i) z[i] = inv_diag[i] * V[j][i];
        product(z, w);
        for (size_t l = 0; l <= j; ++l) {  // modified Gram-Schmidt
          const cd h = dot(V[l], w);
          H[l][j] = h;
          for (size_t i = 0; i < n; ++i) w[i] -= h * V[l][i];
        }
        const double h_next = norm(w);
        H[j + 1][j] = h_next;
        if (h_next > 0)
          for (size_t i = 0; i < n; ++i) V[j + 1][i] = w[i] / h_next;
        for (size_t l = 0; l < j; ++l) {  // the earlier rotations on the new column
          const cd t = cs[l] * H[l][j] + sn[l] * H[l + 1][j];
          H[l + 1][j] = -std::conj(sn[l]) * H[l][j] + cs[l] * H[l + 1][j];
          H[l][j] = t;
        }
        const double a = std::abs(H[j][j]), denom = std::sqrt(a * a + h_next * h_next);
        if (!(denom > 0)) break;  // (a zero column: the solve stops at what it has)
        cs[j] = a / denom;
        sn[j] = (a > 0 ? H[j][j] / a : cd(1.0)) * (h_next / denom);  // zeroes H[j + 1][j]
        H[j][j] = cs[j] * H[j][j] + sn[j] * h_next;
        H[j + 1][j] = 0.0;
        g[j + 1] = -std::conj(sn[j]) * g[j];
        g[j] = cs[j] * g[j];
        residual = std::abs(g[j + 1]) / b_norm;
        if (residual <= tolerance || h_next == 0) {
          ++j;
          ++iterations;
          break;
        }
      }
      // y = H^-1 g (upper triangular, j x j), x += M^-1 V y.
      std::vector<cd> y(j);
      for (size_t l = j; l-- > 0;) {
        cd sum = g[l];
        for (size_t m = l + 1; m < j; ++m) sum -= H[l][m] * y[m];
        y[l] = sum / H[l][l];
      }
      for (size_t i = 0; i < n; ++i) {
        cd sum = 0.0;
        for (size_t l = 0; l < j; ++l) sum += V[l][i] * y[l];
        x[i] += inv_diag[i] * sum;
      }
      if (residual <= tolerance) {
        product(x, ax);  // the true residual
        for (size_t i = 0; i < n; ++i) r[i] = b[i] - ax[i];
        residual = norm(r) / b_norm;
        if (residual <= tolerance) break;
      }
    }
    for (size_t i = 0; i < n; ++i) X(static_cast<Eigen::Index>(i), col) = x[i];
    done.iterations = std::max(done.iterations, iterations);
    done.worst_residual = std::max(done.worst_residual, residual);
  }
  if (report) *report = done;
  return X;
}

}  // namespace strike::transfer
