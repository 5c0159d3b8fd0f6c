// SPDX-License-Identifier: MIT
// The ARPACK stage of the eigen-solver: implicitly restarted Lanczos, one vector at a time,
// in shift-invert mode (Lehoucq, Sorensen & Yang, "ARPACK Users' Guide", SIAM 1998, sec.
// 3.2.3, mode 3), for small requests and the ModalMethod::ArpackOnly reference.
#include <arpack/arpack.h>

#include <algorithm>
#include <random>
#include <sstream>
#include <string>

#include "lanczos.hpp"

namespace strike::detail {

namespace {

std::string arpackMessage(const char* routine, a_int info) {
  std::ostringstream s;
  s << "eigensolver: ARPACK " << routine << " failed with info = " << info;
  switch (info) {
    case 3: s << " (no shifts could be applied; ncv too small)"; break;
    case -8: s << " (LAPACK tridiagonal eigenvalue error)"; break;
    case -9: s << " (starting vector is zero)"; break;
    case -9999: s << " (could not build a Lanczos factorization)"; break;
    case -14: s << " (no eigenvalue converged to the requested accuracy)"; break;
    default: break;
  }
  return s.str();
}

}  // namespace

/// One ARPACK run for `nev` eigenpairs of OP deflated against `found`; appends the converged
/// pairs to `found`. Returns the number appended.
Result<int> lanczosChunk(Context& ctx, Found& found, int nev, double tol, uint64_t seed, double progress_base,
                         double progress_span) {
  const a_int n = static_cast<a_int>(ctx.K.rows());
  const int locked = static_cast<int>(found.lambdas.size());
  const a_int max_ncv = n - locked;
  if (nev >= max_ncv) nev = static_cast<int>(max_ncv) - 1;
  if (nev <= 0) return 0;
  // ncv ~ 1.6 nev: fewer restarts than nev + 20, less reorthogonalization than 2 nev
  // (measured on box meshes; see tests/bench/modal).
  a_int ncv = std::min<a_int>(max_ncv, std::max<a_int>(nev + 24, (8 * nev) / 5));
  const a_int lworkl = ncv * (ncv + 8);
  std::vector<double> resid(static_cast<size_t>(n));
  std::vector<double> v(static_cast<size_t>(n) * static_cast<size_t>(ncv));
  std::vector<double> workd(3 * static_cast<size_t>(n));
  std::vector<double> workl(static_cast<size_t>(lworkl));
  a_int iparam[11] = {};
  a_int ipntr[11] = {};
  iparam[0] = 1;    // exact shifts
  iparam[2] = 300;  // max restarts
  iparam[6] = 3;    // shift-invert mode

  // Deterministic start vector (ARPACK's own random start depends on how often it was called
  // before in this process), projected away from the modes already found.
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (double& r : resid) r = uniform(rng);
  Eigen::Map<Eigen::VectorXd> resid_vec(resid.data(), n);
  auto deflate = [&](Eigen::Map<Eigen::VectorXd>& y) {
    if (locked > 0) y.noalias() -= found.vectors * (found.m_vectors.transpose() * y);
  };
  deflate(resid_vec);

  Eigen::VectorXd mx(n);
  a_int ido = 0;
  a_int info = 1;  // use resid as the start vector
  const int expected_applications = static_cast<int>(ncv + 2 * (ncv - nev));
  int chunk_applications = 0;
  while (true) {
    dsaupd_c(&ido, "G", n, "LM", nev, tol, resid.data(), ncv, v.data(), n, iparam, ipntr, workd.data(), workl.data(),
             lworkl, &info);
    if (ido == -1 || ido == 1) {
      const double* x = workd.data() + ipntr[0] - 1;
      double* y = workd.data() + ipntr[1] - 1;
      const double* bx = nullptr;
      if (ido == 1) {
        bx = workd.data() + ipntr[2] - 1;
      } else {
        mx.noalias() = ctx.M * Eigen::Map<const Eigen::VectorXd>(x, n);
        bx = mx.data();
      }
      const auto t_solve = Clock::now();
      if (!ctx.solver.solve(bx, y, 1)) return internalError("eigensolver: CHOLMOD solve failed");
      ctx.solve_seconds += secondsSince(t_solve);
      Eigen::Map<Eigen::VectorXd> y_vec(y, n);
      deflate(y_vec);
      ++ctx.applications;
      ++chunk_applications;
      if (ctx.settings.progress && chunk_applications % 16 == 0) {
        const double f = std::min(0.95, static_cast<double>(chunk_applications) / expected_applications);
        ctx.settings.progress("lanczos", progress_base + progress_span * f);
      }
    } else if (ido == 2) {
      Eigen::Map<Eigen::VectorXd>(workd.data() + ipntr[1] - 1, n).noalias() =
          ctx.M * Eigen::Map<const Eigen::VectorXd>(workd.data() + ipntr[0] - 1, n);
    } else {
      break;
    }
  }
  if (info < 0 || info == 3) return internalError(arpackMessage("dsaupd", info));
  const a_int nconv = iparam[4];
  if (nconv <= 0) return 0;

  std::vector<a_int> select(static_cast<size_t>(ncv), 1);
  std::vector<double> d(static_cast<size_t>(nev));
  Eigen::MatrixXd z(n, nev);
  a_int einfo = 0;
  dseupd_c(1, "A", select.data(), d.data(), z.data(), n, ctx.sigma, "G", n, "LM", nev, tol, resid.data(), ncv, v.data(),
           n, iparam, ipntr, workd.data(), workl.data(), lworkl, &einfo);
  if (einfo != 0) return internalError(arpackMessage("dseupd", einfo));
  const int got = static_cast<int>(std::min<a_int>(iparam[4], nev));
  const int total = locked + got;
  found.vectors.conservativeResize(n, total);
  found.m_vectors.conservativeResize(n, total);
  for (int k = 0; k < got; ++k) {
    found.lambdas.push_back(d[static_cast<size_t>(k)]);
    found.vectors.col(locked + k) = z.col(k);
    found.m_vectors.col(locked + k) = ctx.M * z.col(k);
  }
  return got;
}

}  // namespace strike::detail
