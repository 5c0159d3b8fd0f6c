// SPDX-License-Identifier: MIT
// Lowest elastic modes of a free solid: K x = lambda M x by shift-invert Lanczos.
//
// The operator is OP = (K - sigma M)^{-1} M with a NEGATIVE shift sigma, so K - sigma M is
// symmetric positive definite even though a free body's K is singular (6 rigid modes), and a
// supernodal Cholesky (CHOLMOD) can factor it without pivoting. ARPACK's implicitly restarted
// Lanczos (Lehoucq, Sorensen & Yang, "ARPACK Users' Guide", SIAM 1998, sec. 3.2.3, mode 3)
// finds the largest |mu| of OP, mu = 1 / (lambda - sigma), i.e. the lambdas nearest sigma: the
// rigid modes and then the lowest elastic modes (Ericsson & Ruhe, Math. Comp. 35, 1980).
//
// Pipeline:
//  1. sigma from the problem's own scale (diag K / diag M), so units never matter;
//  2. one CHOLMOD supernodal factorization (METIS ordering), reused for every solve;
//  3. a small request (at most kArpackModes pairs, rigid ones included): ARPACK (tol 1e-10);
//  4. otherwise block shift-invert Lanczos from scratch (it finds the rigid modes too), with
//     multi-right-hand-side solves, the three-term recurrence plus one BLAS-3 Gram-Schmidt
//     pass against the basis, and top-Ritz-pair checks by LAPACK dsyevr, until the cut-off or
//     the cap is passed; a second round, deflated against what was found, if the first falls
//     short (ModalMethod::ArpackOnly instead grows ARPACK requests, single-vector). OpenBLAS
//     runs single-threaded for the whole solve, and the block solves, Gram-Schmidt products
//     and M products are split in two fixed halves over two threads of our own
//     (two_parts.hpp; the bits do not depend on the split happening);
//  5. Rayleigh-Ritz on the kept vectors: exact M-orthonormality and ascending order (modes
//     from a single block Lanczos run already are: Rayleigh quotients only); the residuals
//     ||K x - lambda M x|| are measured and reported.
#include <arpack/arpack.h>
#include <cholmod.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <new>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "strike/modal.hpp"
#include "two_parts.hpp"

extern "C" void dsyevr_(const char* jobz, const char* range, const char* uplo, const int* n, double* a, const int* lda,
                        const double* vl, const double* vu, const int* il, const int* iu, const double* abstol, int* m,
                        double* w, double* z, const int* ldz, int* isuppz, double* work, const int* lwork, int* iwork,
                        const int* liwork, int* info, size_t jobz_len, size_t range_len, size_t uplo_len);

// OpenBLAS thread control, weak so that another BLAS (no such functions) still links.
extern "C" __attribute__((weak)) void openblas_set_num_threads(int num_threads);
extern "C" __attribute__((weak)) int openblas_get_num_threads(void);

namespace strike {

namespace {

/// Sets OpenBLAS's thread count for a scope and restores it (no-op for 0 or another BLAS).
class BlasThreadsScope {
 public:
  explicit BlasThreadsScope(int threads) {
    if (threads <= 0 || openblas_set_num_threads == nullptr || openblas_get_num_threads == nullptr) return;
    previous_ = openblas_get_num_threads();
    if (previous_ != threads) openblas_set_num_threads(threads);
  }
  ~BlasThreadsScope() {
    if (previous_ > 0) openblas_set_num_threads(previous_);
  }
  BlasThreadsScope(const BlasThreadsScope&) = delete;
  BlasThreadsScope& operator=(const BlasThreadsScope&) = delete;

 private:
  int previous_ = 0;
};

using SpMat = Eigen::SparseMatrix<double>;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Y = A X for a SYMMETRIC sparse A (K or M) and a block X of a few to a few hundred columns.
/// Column j of A is row j, so each row of Y gathers rows of X: with X and Y row-major the
/// inner loop runs over the block's columns, contiguous, and A is read once instead of once
/// per column (Eigen's sparse * dense product; measured 2x faster at 16 and 100 columns).
/// Rows of Y are independent and each is summed by this loop in one order, so with `parts` two
/// threads may fill one half each and the bits do not depend on the cut.
void symmetricTimesBlock(const SpMat& A, const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::MatrixXd& Y,
                         TwoParts* parts = nullptr) {
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

// Stage sizes (measured on box meshes, tests/bench/modal): ARPACK's single-vector solves are
// memory bound (and its stage cost ~1.4 s for the first 20 of 106 pairs at 29k DOF), so it
// serves only small requests; block solves of 16 right-hand sides cost ~1/3 as much per
// vector as single ones. Block 16 beat 24 and 32 at 29k and 86k DOF (fewer vectors needed,
// less Gram-Schmidt work) with OpenBLAS single-threaded.
constexpr int kArpackModes = 20;
constexpr int kBlockSize = 16;
// Largest block Krylov basis, in multiples of the modes still wanted: block Lanczos needs a
// bigger basis than single-vector Lanczos (measured ~4.5x the wanted count at b = 16).
constexpr int kBasisFactor = 6;
// Block Lanczos residual ||OP x - theta x||_M relative to theta. Eigenvalues come out about
// tol^2 accurate (measured: 1e-12 relative to the ARPACK-only solve at 1e-6). The reported
// ||K x - lambda M x|| residual is larger, as (K - sigma M) amplifies the high-frequency part
// of the Lanczos residual, most when a cut-off stops a small basis early: 1e-7 keeps it
// below 1e-6 on the steel-bar test (4e-4 at 1e-6) and ~4e-6 at 100 modes, 29k DOF, for a
// basis only 4% bigger.
constexpr double kBlockTol = 1e-7;

constexpr double kTwoPi = 6.283185307179586476925286766559;

/// RAII owner of a CHOLMOD workspace and factor of an SPD matrix.
class CholmodSolver {
 public:
  CholmodSolver() {
    cholmod_start(&common_);
    common_.print = 0;  // we report errors ourselves, on stderr, through Status
    common_.supernodal = CHOLMOD_SUPERNODAL;
  }
  ~CholmodSolver() {
    if (factor_ != nullptr) cholmod_free_factor(&factor_, &common_);
    if (x_ != nullptr) cholmod_free_dense(&x_, &common_);
    if (y_ != nullptr) cholmod_free_dense(&y_, &common_);
    if (e_ != nullptr) cholmod_free_dense(&e_, &common_);
    cholmod_finish(&common_);
    if (helper_started_) {
      if (helper_x_ != nullptr) cholmod_free_dense(&helper_x_, &helper_common_);
      if (helper_y_ != nullptr) cholmod_free_dense(&helper_y_, &helper_common_);
      if (helper_e_ != nullptr) cholmod_free_dense(&helper_e_, &helper_common_);
      cholmod_finish(&helper_common_);
    }
  }
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  /// Factors A (both triangles stored; CHOLMOD reads the lower one).
  Status factorize(const SpMat& A) {
    cholmod_sparse view{};
    view.nrow = static_cast<size_t>(A.rows());
    view.ncol = static_cast<size_t>(A.cols());
    view.nzmax = static_cast<size_t>(A.nonZeros());
    view.p = const_cast<int*>(A.outerIndexPtr());
    view.i = const_cast<int*>(A.innerIndexPtr());
    view.x = const_cast<double*>(A.valuePtr());
    view.stype = -1;
    view.itype = CHOLMOD_INT;
    view.xtype = CHOLMOD_REAL;
    view.dtype = CHOLMOD_DOUBLE;
    view.sorted = 1;
    view.packed = 1;
    // METIS nested dissection gives less fill than AMD on 3D solid meshes (George, SIAM J.
    // Numer. Anal. 10, 1973); the factor's size is what every solve streams from memory.
    common_.nmethods = 1;
    common_.method[0].ordering = CHOLMOD_METIS;
    common_.postorder = 1;
    factor_ = cholmod_analyze(&view, &common_);
    if (factor_ == nullptr) return internalError("eigensolver: CHOLMOD analysis failed (status " + std::to_string(common_.status) + ")");
    const int ok = cholmod_factorize(&view, factor_, &common_);
    if (common_.status == CHOLMOD_NOT_POSDEF || factor_->minor < factor_->n) {
      std::ostringstream s;
      s << "eigensolver: K - sigma M is not positive definite (pivot " << factor_->minor << " of "
        << factor_->n << "): the mass matrix is singular or the mesh has degenerate or inverted elements";
      return internalError(s.str());
    }
    if (!ok || common_.status < CHOLMOD_OK) {
      if (common_.status == CHOLMOD_OUT_OF_MEMORY) throw std::bad_alloc();
      return internalError("eigensolver: CHOLMOD factorization failed (status " + std::to_string(common_.status) + ")");
    }
    return {};
  }

  double factorNonZeros() const { return common_.lnz; }

  /// x = A^{-1} b for ncols right-hand sides stored column-major with leading dimension n.
  /// With `parts`, the columns are solved in two halves, ALWAYS: the second by the helper
  /// thread when it is free, with its own CHOLMOD workspace (cholmod_solve2 only reads the
  /// factor), else by this thread after the first. The halves are never merged into one call
  /// when the helper is late: OpenBLAS's AVX-512 kernels give other last bits for 16
  /// right-hand sides than for 2 x 8. Two threads of 8 right-hand sides each take ~70% of the
  /// time of one thread of 16 (per-thread cost 3.7 vs 2.6 ms per right-hand side at 29k DOF,
  /// tests/bench/modal).
  bool solve(const double* b, double* x, int ncols, TwoParts* parts = nullptr) {
    if (parts == nullptr) return solveColumns(b, x, ncols, common_, x_, y_, e_);
    if (!helper_started_) {
      cholmod_start(&helper_common_);
      helper_common_.print = 0;
      helper_started_ = true;
    }
    const size_t n = factor_->n;
    bool ok[2] = {true, true};
    parts->run(ncols, ncols / 2, [&](int first, int end, int part) {
      ok[part] = solveColumns(b + n * static_cast<size_t>(first), x + n * static_cast<size_t>(first), end - first,
                              part == 0 ? common_ : helper_common_, part == 0 ? x_ : helper_x_,
                              part == 0 ? y_ : helper_y_, part == 0 ? e_ : helper_e_);
    });
    return ok[0] && ok[1];
  }

 private:
  bool solveColumns(const double* b, double* x, int ncols, cholmod_common& common, cholmod_dense*& x_work,
                    cholmod_dense*& y_work, cholmod_dense*& e_work) {
    cholmod_dense rhs{};
    rhs.nrow = factor_->n;
    rhs.ncol = static_cast<size_t>(ncols);
    rhs.nzmax = rhs.nrow * rhs.ncol;
    rhs.d = rhs.nrow;
    rhs.x = const_cast<double*>(b);
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    if (!cholmod_solve2(CHOLMOD_A, factor_, &rhs, nullptr, &x_work, nullptr, &y_work, &e_work, &common)) return false;
    std::memcpy(x, x_work->x, sizeof(double) * rhs.nzmax);
    return true;
  }

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

/// Eigenpairs found so far (M-orthonormal columns), used to deflate later Lanczos chunks.
struct Found {
  std::vector<double> lambdas;
  Eigen::MatrixXd vectors;   // n x k
  Eigen::MatrixXd m_vectors; // M * vectors
};

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

struct Context {
  const SpMat& K;
  const SpMat& M;
  CholmodSolver& solver;
  double sigma;
  const ModalSettings& settings;
  TwoParts* parts = nullptr;  // block stage: solves and products in two fixed parts (two_parts.hpp)
  int applications = 0;
  double solve_seconds = 0.0;
  double orthogonalize_seconds = 0.0;
  double ritz_seconds = 0.0;
  int block_size = 0;
  int basis = 0;
  int reorthogonalizations = 0;
};

/// One ARPACK run for `nev` eigenpairs of OP deflated against `found`; appends the converged
/// pairs to `found`. Returns the number appended.
Result<int> lanczosChunk(Context& ctx, Found& found, int nev, double tol, uint64_t seed,
                         double progress_base, double progress_span) {
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
  iparam[0] = 1;      // exact shifts
  iparam[2] = 300;    // max restarts
  iparam[6] = 3;      // shift-invert mode

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
    dsaupd_c(&ido, "G", n, "LM", nev, tol, resid.data(), ncv, v.data(), n, iparam, ipntr,
             workd.data(), workl.data(), lworkl, &info);
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
  dseupd_c(1, "A", select.data(), d.data(), z.data(), n, ctx.sigma, "G", n, "LM", nev, tol,
           resid.data(), ncv, v.data(), n, iparam, ipntr, workd.data(), workl.data(), lworkl, &einfo);
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


/// Top `m` eigenpairs of the symmetric k x k matrix A (lower triangle read; destroyed) by
/// LAPACK dsyevr (Householder tridiagonalization + MRRR for the selected pairs only): far
/// cheaper than a full dense eigen-solve when m << k. Eigenvalues ascending.
bool topEigenpairs(Eigen::MatrixXd& A, int m, Eigen::VectorXd& values, Eigen::MatrixXd& vectors) {
  const int k = static_cast<int>(A.rows());
  m = std::min(m, k);
  const int il = k - m + 1, iu = k;
  const double vl = 0.0, vu = 0.0, abstol = 0.0;
  int found_m = 0, info = 0;
  values.resize(k);
  vectors.resize(k, m);
  std::vector<int> isuppz(2 * static_cast<size_t>(m));
  int lwork = -1, liwork = -1, iwork_query = 0;
  double work_query = 0.0;
  dsyevr_("V", "I", "L", &k, A.data(), &k, &vl, &vu, &il, &iu, &abstol, &found_m, values.data(), vectors.data(), &k,
          isuppz.data(), &work_query, &lwork, &iwork_query, &liwork, &info, 1, 1, 1);
  if (info != 0) return false;
  lwork = static_cast<int>(work_query);
  liwork = iwork_query;
  std::vector<double> work(static_cast<size_t>(lwork));
  std::vector<int> iwork(static_cast<size_t>(liwork));
  dsyevr_("V", "I", "L", &k, A.data(), &k, &vl, &vu, &il, &iu, &abstol, &found_m, values.data(), vectors.data(), &k,
          isuppz.data(), work.data(), &lwork, iwork.data(), &liwork, &info, 1, 1, 1);
  if (info != 0 || found_m != m) return false;
  values.conservativeResize(m);
  return true;
}

/// Block shift-invert Lanczos on OP deflated against `found` (Grimes, Lewis & Simon, "A
/// shifted block Lanczos algorithm for solving sparse symmetric generalized eigenproblems",
/// SIAM J. Matrix Anal. Appl. 15, 1994). Each step applies OP to a whole block with one
/// multi-right-hand-side CHOLMOD solve (BLAS 3: the factor is read once per block, not once
/// per vector), subtracts the three-term recurrence (the two latest blocks), then
/// reorthogonalizes against the whole basis in the M inner product with one classical
/// Gram-Schmidt pass as two BLAS-3 products, repeated only when the DGKS test says the pass
/// cancelled too much (Daniel, Gragg, Kaufman & Stewart, Math. Comp. 30, 1976; as ARPACK's
/// dsaitr does), and M-orthonormalizes the block by Cholesky QR applied twice. Ritz pairs
/// come from the block tridiagonal projection T (only its top pairs, by dsyevr); the residual
/// of Ritz pair (theta, Q s) is ||B_j s_last|| (Parlett, "The Symmetric Eigenvalue Problem",
/// 1998, sec. 13.2). Converged pairs are appended to `found`. `want` is how many pairs the
/// caller expects to need; `enough(lambdas_converged_in_order)` says when to stop. Returns the
/// number appended. Its vectors are M-orthonormal to round-off (Q is, and S is orthonormal).
Result<int> blockLanczos(Context& ctx, Found& found, int block, int want, int min_basis, int max_basis, double tol,
                         uint64_t seed, const std::function<bool(const std::vector<double>&)>& enough) {
  const Eigen::Index n = ctx.K.rows();
  const Eigen::Index locked = static_cast<Eigen::Index>(found.lambdas.size());
  const Eigen::Index b = block;
  const Eigen::Index max_steps = std::max<Eigen::Index>(2, max_basis / b);
  Eigen::MatrixXd Q(n, (max_steps + 1) * b);
  Eigen::MatrixXd MQ(n, (max_steps + 1) * b);
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero((max_steps + 1) * b, (max_steps + 1) * b);

  auto deflate = [&](Eigen::MatrixXd& W) {
    if (locked > 0) W.noalias() -= found.vectors * (found.m_vectors.transpose() * W);
  };
  // M-orthonormalizes W in place by Cholesky QR; MW is updated alongside. R accumulates the
  // triangular factor so that W_in = W_out R. One pass leaves ||W^T M W - I|| ~ eps cond(W)^2
  // (Yamamoto et al., ETNA 44, 2015), so a second pass (CholQR2) runs only when the first
  // factor's diagonal spread says cond(W) may exceed ~30. Returns false on (numerical) rank
  // deficiency.
  auto orthonormalize = [&](Eigen::MatrixXd& W, Eigen::MatrixXd& MW, Eigen::MatrixXd& R) {
    R = Eigen::MatrixXd::Identity(b, b);
    for (int pass = 0; pass < 2; ++pass) {
      Eigen::MatrixXd G = W.transpose() * MW;
      G = 0.5 * (G + G.transpose()).eval();
      Eigen::LLT<Eigen::MatrixXd> llt(G);
      if (llt.info() != Eigen::Success) return false;
      const Eigen::MatrixXd U = llt.matrixU();
      const double spread = U.diagonal().maxCoeff() / U.diagonal().minCoeff();
      if (pass == 0 && !(spread < 1e10)) return false;
      const Eigen::MatrixXd Uinv = U.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(b, b));
      W = W * Uinv;
      MW = MW * Uinv;
      R = (U * R).eval();
      if (spread < 30.0) break;
    }
    return true;
  };

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::MatrixXd W(n, b);
  for (Eigen::Index j = 0; j < b; ++j) {
    for (Eigen::Index i = 0; i < n; ++i) W(i, j) = uniform(rng);
  }
  deflate(W);
  Eigen::MatrixXd MW;
  symmetricTimesBlock(ctx.M, W, MW);
  Eigen::MatrixXd R;
  if (!orthonormalize(W, MW, R)) return internalError("eigensolver: block Lanczos could not start (degenerate start block)");
  Q.leftCols(b) = W;
  MQ.leftCols(b) = MW;

  // One classical Gram-Schmidt pass against basis columns [first, first + width):
  // h = (M Q)^T W, W -= Q h, both products split by rows in two halves over two threads
  // (each thread streams half of Q and M Q; h is the sum of the two halves' products). The
  // halves are the same whoever computes them (ctx.parts runs them in turn without a helper).
  Eigen::MatrixXd h_parts[2];
  const Eigen::Index half = n / 2;
  auto gramSchmidt = [&](Eigen::Index first, Eigen::Index width, Eigen::MatrixXd& h_out) {
    for (Eigen::MatrixXd& part : h_parts) part.resize(width, b);
    ctx.parts->run(n, half, [&](Eigen::Index r0, Eigen::Index r1, int part) {
      h_parts[part].noalias() = MQ.block(r0, first, r1 - r0, width).transpose() * W.middleRows(r0, r1 - r0);
    });
    h_out = h_parts[0] + h_parts[1];
    ctx.parts->run(n, half, [&](Eigen::Index r0, Eigen::Index r1, int) {
      W.middleRows(r0, r1 - r0).noalias() -= Q.block(r0, first, r1 - r0, width) * h_out;
    });
  };

  Eigen::Index steps = 0;
  std::vector<double> converged;
  Eigen::MatrixXd S;
  Eigen::Index num_converged = 0;
  Eigen::MatrixXd H, h, Tk, ritz_vectors;
  Eigen::VectorXd ritz_values;
  Eigen::Index next_check = 0;
  for (Eigen::Index j = 0; j < max_steps; ++j) {
    const Eigen::Index k = (j + 1) * b;  // basis size after this step's block
    auto t0 = Clock::now();
    if (!ctx.solver.solve(MQ.middleCols(j * b, b).data(), W.data(), static_cast<int>(b), ctx.parts)) {
      return internalError("eigensolver: CHOLMOD block solve failed");
    }
    ctx.solve_seconds += secondsSince(t0);
    t0 = Clock::now();
    ctx.applications += static_cast<int>(b);
    deflate(W);
    H.setZero(k, b);
    // Three-term recurrence, W -= Q_j A_j + Q_{j-1} B_{j-1}^T, with the coefficients
    // measured (local Gram-Schmidt against the two latest blocks, one product each way).
    {
      const Eigen::Index first = j > 0 ? (j - 1) * b : 0;
      const Eigen::Index width = j > 0 ? 2 * b : b;
      gramSchmidt(first, width, h);
      H.middleRows(first, width) = h;
    }
    // Full reorthogonalization: one classical Gram-Schmidt pass (two BLAS-3 products), a
    // second one only where the DGKS test says the pass cancelled (Daniel, Gragg, Kaufman &
    // Stewart, Math. Comp. 30, 1976). MW = M W is recomputed after each pass (the sparse
    // product costs less than updating it with M Q), and the norm before a pass follows from
    // Pythagoras: Q is M-orthonormal.
    for (int pass = 0; pass < 3; ++pass) {
      gramSchmidt(0, k, h);
      H += h;
      symmetricTimesBlock(ctx.M, W, MW, ctx.parts);
      const Eigen::ArrayXd after = W.cwiseProduct(MW).colwise().sum().transpose().array();
      const Eigen::ArrayXd removed = h.colwise().squaredNorm().transpose().array();
      // ||w_after||_M < 0.717 ||w_before||_M: the pass cancelled, rounding may remain.
      if (!((after < 0.514 * (after + removed)).any())) break;
      ++ctx.reorthogonalizations;
    }
    T.block(0, j * b, k, b) = H;
    const bool ok = orthonormalize(W, MW, R);
    steps = j + 1;
    if (ok) {
      Q.middleCols(k, b) = W;
      MQ.middleCols(k, b) = MW;
      T.block(k, j * b, b, b) = R;
    } else {
      R = Eigen::MatrixXd::Zero(b, b);  // invariant subspace found: residuals are exact zeros
    }
    ctx.orthogonalize_seconds += secondsSince(t0);
    // Ritz pairs of the k x k projection (symmetrized: full reorthogonalization keeps the
    // entries above the block tridiagonal at round-off level); only the top `want + b` pairs.
    // A cap-limited request needs a basis of several times `want` (measured 4x), but a
    // cut-off may end it much earlier: checks start small and come every third step while
    // few pairs have converged, then every other step, then every step.
    const bool last = !ok || j + 1 == max_steps;
    if (!last && (k < std::min<Eigen::Index>(min_basis, 3 * b) || j < next_check)) continue;
    t0 = Clock::now();
    Tk = T.topLeftCorner(k, k);
    Tk = 0.5 * (Tk + Tk.transpose()).eval();
    const int m = static_cast<int>(std::min<Eigen::Index>(k, want + b));
    if (!topEigenpairs(Tk, m, ritz_values, ritz_vectors)) {
      return internalError("eigensolver: block Lanczos projection eigen-solve failed");
    }
    ctx.ritz_seconds += secondsSince(t0);
    // Largest theta first = smallest lambda first.
    converged.clear();
    num_converged = 0;
    for (Eigen::Index i = m - 1; i >= 0; --i) {
      const double theta = ritz_values[i];
      const double residual = (R * ritz_vectors.block(k - b, i, b, 1)).norm();
      if (!(theta > 0.0) || residual > tol * theta) break;
      converged.push_back(ctx.sigma + 1.0 / theta);
      ++num_converged;
    }
    if (ctx.settings.progress) ctx.settings.progress("lanczos", std::min(0.95, static_cast<double>(k) / max_basis));
    // Few converged yet: the next check can wait a step or two (each costs O(k^3)).
    next_check = j + (num_converged < want / 2 ? 3 : num_converged < (4 * want) / 5 ? 2 : 1);
    if (last || enough(converged)) {
      S = ritz_vectors.rightCols(num_converged).rowwise().reverse();
      break;
    }
  }
  const Eigen::Index kb = steps * b;
  ctx.block_size = static_cast<int>(b);
  ctx.basis = std::max(ctx.basis, static_cast<int>(kb));
  if (num_converged == 0 || S.cols() != num_converged) return 0;
  const Eigen::Index total = locked + num_converged;
  found.vectors.conservativeResize(n, total);
  found.m_vectors.conservativeResize(n, total);
  ctx.parts->run(n, n / 2, [&](Eigen::Index r0, Eigen::Index r1, int) {
    found.vectors.block(r0, locked, r1 - r0, num_converged).noalias() = Q.block(r0, 0, r1 - r0, kb) * S.topRows(kb);
  });
  Q.resize(0, 0);  // the basis is not needed any more: release it before the temporaries below
  MQ.resize(0, 0);
  // M (Q S) by the sparse product, not (M Q) S: 2 nnz(M) p flops instead of 2 n kb p (M has
  // at most a few tens of nonzeros per row, against kb ~ 450 basis vectors), and the
  // refinement reuses it.
  Eigen::MatrixXd m_fresh;
  symmetricTimesBlock(ctx.M, found.vectors.rightCols(num_converged), m_fresh, ctx.parts);
  found.m_vectors.rightCols(num_converged) = m_fresh;
  for (double l : converged) found.lambdas.push_back(l);
  return static_cast<int>(num_converged);
}

/// Shift from the problem's own scale: median of diag(K)/diag(M) is ~ (c/h)^2, the squared
/// angular frequency of one element, whatever the units or material. A tiny fraction of it
/// keeps K - sigma M well conditioned (cond ~ lambda_max / |sigma| ~ 1e5) while staying far
/// below the wanted eigenvalues, where the shift would slow Lanczos convergence down.
double chooseShift(const SpMat& K, const SpMat& M, double lambda_cut) {
  std::vector<double> ratio;
  ratio.reserve(static_cast<size_t>(K.rows()));
  const Eigen::VectorXd dk = K.diagonal();
  const Eigen::VectorXd dm = M.diagonal();
  for (Eigen::Index i = 0; i < K.rows(); ++i) {
    if (dk[i] > 0.0 && dm[i] > 0.0) ratio.push_back(dk[i] / dm[i]);
  }
  if (ratio.empty()) return -1.0;
  std::nth_element(ratio.begin(), ratio.begin() + static_cast<std::ptrdiff_t>(ratio.size() / 2), ratio.end());
  const double scale = ratio[ratio.size() / 2];
  double shift = 1e-4 * scale;
  if (std::isfinite(lambda_cut)) shift = std::min(shift, 0.05 * lambda_cut);
  shift = std::max(shift, 1e-9 * scale);
  return -shift;
}

Result<ModalResult> solveDense(const SpMat& K, const SpMat& M, ModalResult out, Eigen::VectorXd& lambdas,
                               Eigen::MatrixXd& vectors) {
  const Eigen::MatrixXd Kd(K);
  const Eigen::MatrixXd Md(M);
  if (Eigen::LLT<Eigen::MatrixXd>(Md).info() != Eigen::Success) return internalError("eigensolver: the mass matrix is not positive definite");
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Kd, Md);
  if (es.info() != Eigen::Success) return internalError("eigensolver: dense generalized eigen-solve failed (is M positive definite?)");
  lambdas = es.eigenvalues();
  vectors = es.eigenvectors();
  return out;
}

Result<ModalResult> solveModesImpl(const SpMat& K, const SpMat& M, const ModalSettings& settings) {
  const Eigen::Index n = K.rows();
  if (n == 0 || K.cols() != n || M.rows() != n || M.cols() != n) {
    std::ostringstream s;
    s << "eigensolver: K (" << K.rows() << "x" << K.cols() << ") and M (" << M.rows() << "x"
      << M.cols() << ") must be square, non-empty and of the same size";
    return badInput(s.str());
  }
  if (!(settings.max_freq_hz > 0.0)) return badInput("eigensolver: max_freq_hz must be > 0, got " + std::to_string(settings.max_freq_hz));
  if (settings.max_modes <= 0) return badInput("eigensolver: max_modes must be > 0, got " + std::to_string(settings.max_modes));
  if (!(settings.rigid_freq_hz >= 0.0)) return badInput("eigensolver: rigid_freq_hz must be >= 0, got " + std::to_string(settings.rigid_freq_hz));

  for (Eigen::Index i = 0; i < n; ++i) {
    const double m_ii = M.coeff(i, i);
    const double k_ii = K.coeff(i, i);
    if (!(m_ii > 0.0) || !std::isfinite(m_ii) || !std::isfinite(k_ii)) {
      std::ostringstream s;
      s << "eigensolver: the mass matrix must be positive definite and K, M finite; degree of freedom "
        << i << " has M = " << m_ii << ", K = " << k_ii << " (is the density positive and the mesh valid?)";
      return internalError(s.str());
    }
  }
  const double lambda_cut = std::pow(kTwoPi * settings.max_freq_hz, 2);
  const double lambda_rigid = std::pow(kTwoPi * settings.rigid_freq_hz, 2);
  ModalResult out;
  out.sigma = chooseShift(K, M, lambda_cut);
  // A rigid mode's computed eigenvalue is round-off, ~eps * |sigma| * cond: count anything
  // below a tiny fraction of the shift as rigid too, whatever rigid_freq_hz says.
  const double lambda_zero = std::max(lambda_rigid, 1e-6 * std::abs(out.sigma));

  // The assembled M stores the 3x3 pattern of K, but a consistent mass matrix couples only
  // equal directions: two thirds of its entries are exact zeros. Dropping them makes every
  // M product up to 3x cheaper (block Lanczos does one or two per step).
  SpMat M_pruned = M;
  M_pruned.prune(0.0, 0.0);
  Eigen::VectorXd all_lambdas;
  Eigen::MatrixXd all_vectors, all_m_vectors;  // all_m_vectors = M all_vectors, if known
  // All modes from one block Lanczos run: M-orthonormal and ascending by construction.
  bool single_block_round = false;
  std::unique_ptr<CholmodSolver> solver;
  // OpenBLAS single-threaded for the whole solve, factorization included: with two threads
  // the same matrix's CHOLMOD factor has other bits than with one (so the core count and
  // OPENBLAS_NUM_THREADS would change the bank), and its idle threads spin (sched_yield): under
  // two busy processes a solve took 30-55 s instead of 2.5 s. It costs the factorization ~1.7x
  // on an idle 2-core machine (tests/bench/modal). The parallelism is ours instead (two_parts.hpp): a helper thread for the
  // block stage and the refinement when the machine has two cores or more, with the work cut
  // in the same two parts whether it takes part or not.
  const BlasThreadsScope one_blas_thread(1);
  const bool block_stage = n > 600 && settings.method != ModalMethod::ArpackOnly && settings.max_modes + 7 > kArpackModes;
  TwoParts parts(block_stage && settings.threads >= 2 && std::thread::hardware_concurrency() >= 2,
                 std::chrono::microseconds(settings.helper_delay_us));
  if (n <= 600) {
    // Tiny problems (a few cells): LAPACK on dense matrices is exact and faster than setting
    // up Lanczos, and ARPACK needs ncv < n anyway.
    auto dense = solveDense(K, M, out, all_lambdas, all_vectors);
    if (!dense) return dense.error();
  } else {
    solver = std::make_unique<CholmodSolver>();
    const auto t_factor = Clock::now();
    if (settings.progress) settings.progress("factorize", 0.0);
    SpMat A = K - out.sigma * M;
    Status st = solver->factorize(A);
    if (!st) return st.error();
    A = SpMat();
    out.factorize_seconds = secondsSince(t_factor);
    if (settings.progress) settings.progress("factorize", 1.0);

    const auto t_lanczos = Clock::now();
    Context ctx{K, M_pruned, *solver, out.sigma, settings};
    ctx.parts = &parts;
    Found found;
    // A small request (at most kArpackModes pairs): ARPACK alone, to full accuracy. A larger
    // one: block Lanczos from scratch (rigid modes included), then, only if it fell short,
    // further block rounds on the operator deflated against what was found.
    // ModalMethod::ArpackOnly grows ARPACK requests instead.
    auto status = [&](const std::vector<double>& extra, int& elastic_below, double& top) {
      elastic_below = 0;
      top = -INFINITY;
      for (const std::vector<double>* list : {static_cast<const std::vector<double>*>(&found.lambdas), &extra}) {
        for (double l : *list) {
          top = std::max(top, l);
          if (std::abs(l) > lambda_zero && l <= lambda_cut) ++elastic_below;
        }
      }
      return top > lambda_cut || elastic_below > settings.max_modes;
    };
    const bool arpack_only = settings.method == ModalMethod::ArpackOnly;
    int rounds_with_modes = 0;
    const int wanted_total = settings.max_modes + 7;
    int chunk = arpack_only ? std::min(wanted_total, 400) : std::min(wanted_total, kArpackModes);
    bool done = false;
    const bool block_only = !arpack_only && wanted_total > kArpackModes;
    for (int round = 0; round < 64 && !done && !block_only; ++round) {
      auto got = lanczosChunk(ctx, found, chunk, 1e-10, 0x5eed0000ULL + static_cast<uint64_t>(round),
                              0.0, 1.0);
      if (!got) return got.error();
      if (*got > 0) ++rounds_with_modes;
      int elastic_below = 0;
      double top = 0.0;
      done = status({}, elastic_below, top);
      const bool exhausted = static_cast<Eigen::Index>(found.lambdas.size()) + 2 >= n;
      if (*got == 0 || exhausted) done = true;
      if (!arpack_only) break;
      chunk = std::min(std::max(chunk, 16), settings.max_modes + 7 - elastic_below);
    }
    for (int round = 0; !done && !arpack_only && round < 16; ++round) {
      int elastic_below = 0;
      double top = 0.0;
      status({}, elastic_below, top);
      // A free body has 6 rigid modes: when the block stage starts from scratch it finds them too.
      const int rigid_found = static_cast<int>(std::count_if(found.lambdas.begin(), found.lambdas.end(),
                                                              [&](double l) { return std::abs(l) <= lambda_zero; }));
      const int needed = settings.max_modes + 1 - elastic_below + std::max(0, 6 - rigid_found);
      const Eigen::Index room = n - static_cast<Eigen::Index>(found.lambdas.size()) - 1;
      const int block_pref = settings.block_size > 0 ? settings.block_size : kBlockSize;
      const int block = static_cast<int>(std::min<Eigen::Index>(room / 3, block_pref));
      if (block < 1) break;
      const int max_basis = static_cast<int>(std::min<Eigen::Index>(room, std::max(kBasisFactor * needed, 4 * block) + 2 * block));
      auto got = blockLanczos(ctx, found, block, needed, needed + block, max_basis, kBlockTol, 0xb10c0000ULL + static_cast<uint64_t>(round),
                              [&](const std::vector<double>& extra) {
                                int e = 0;
                                double t = 0.0;
                                return status(extra, e, t);
                              });
      if (!got) return got.error();
      if (*got > 0) {
        ++rounds_with_modes;
        single_block_round = rounds_with_modes == 1;
      }
      done = status({}, elastic_below, top) || *got == 0;
    }
    out.lanczos_seconds = secondsSince(t_lanczos);
    out.operator_applications = ctx.applications;
    out.solve_seconds = ctx.solve_seconds;
    out.orthogonalize_seconds = ctx.orthogonalize_seconds;
    out.ritz_seconds = ctx.ritz_seconds;
    out.block_size = ctx.block_size;
    out.lanczos_basis = ctx.basis;
    out.reorthogonalizations = ctx.reorthogonalizations;
    all_lambdas = Eigen::Map<Eigen::VectorXd>(found.lambdas.data(), static_cast<Eigen::Index>(found.lambdas.size()));
    all_vectors = std::move(found.vectors);
    all_m_vectors = std::move(found.m_vectors);
  }

  // Classify: rigid, kept elastic (ascending, capped), above the cut-off.
  std::vector<int> order(static_cast<size_t>(all_lambdas.size()));
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return all_lambdas[a] < all_lambdas[b]; });
  std::vector<int> kept;
  for (int i : order) {
    const double l = all_lambdas[i];
    if (std::abs(l) <= lambda_zero) {
      ++out.rigid_modes_dropped;
    } else if (l > lambda_cut) {
      ++out.above_cutoff_dropped;
    } else if (static_cast<int>(kept.size()) < settings.max_modes) {
      kept.push_back(i);
    } else {
      out.capped_by_max_modes = true;
    }
  }

  const auto t_refine = Clock::now();
  const Eigen::Index p = static_cast<Eigen::Index>(kept.size());
  Eigen::MatrixXd X(n, p);
  for (Eigen::Index k = 0; k < p; ++k) X.col(k) = all_vectors.col(kept[static_cast<size_t>(k)]);
  all_vectors = Eigen::MatrixXd();
  if (p > 0) {
    Eigen::MatrixXd KX, MX;
    symmetricTimesBlock(K, X, KX, &parts);
    if (all_m_vectors.cols() == all_lambdas.size()) {
      MX.resize(n, p);
      for (Eigen::Index k = 0; k < p; ++k) MX.col(k) = all_m_vectors.col(kept[static_cast<size_t>(k)]);
    } else {
      symmetricTimesBlock(M_pruned, X, MX, &parts);
    }
    all_m_vectors = Eigen::MatrixXd();
    if (single_block_round) {
      // The Ritz vectors Q S of one block Lanczos run are M-orthonormal to round-off and
      // ordered: the eigenvalues are their Rayleigh quotients (as accurate as a Rayleigh-Ritz
      // step, both second order in the residual), with no p x p products or rotations of the
      // n x p blocks (measured 0.6 s of 1.0 s at 86k DOF).
      out.eigenvalues = X.cwiseProduct(KX).colwise().sum().transpose().cwiseQuotient(
          X.cwiseProduct(MX).colwise().sum().transpose());
      std::vector<Eigen::Index> rank(static_cast<size_t>(p));
      for (Eigen::Index k = 0; k < p; ++k) rank[static_cast<size_t>(k)] = k;
      std::stable_sort(rank.begin(), rank.end(), [&](Eigen::Index a, Eigen::Index c) { return out.eigenvalues[a] < out.eigenvalues[c]; });
      bool sorted = true;
      for (Eigen::Index k = 0; k < p; ++k) sorted = sorted && rank[static_cast<size_t>(k)] == k;
      if (sorted) {
        out.shapes = std::move(X);
      } else {
        const Eigen::VectorXd values = out.eigenvalues;
        out.shapes.resize(n, p);
        Eigen::MatrixXd KX2(n, p), MX2(n, p);
        for (Eigen::Index k = 0; k < p; ++k) {
          const Eigen::Index from = rank[static_cast<size_t>(k)];
          out.eigenvalues[k] = values[from];
          out.shapes.col(k) = X.col(from);
          KX2.col(k) = KX.col(from);
          MX2.col(k) = MX.col(from);
        }
        KX = std::move(KX2);
        MX = std::move(MX2);
      }
    } else {
      // Rayleigh-Ritz on the kept vectors: exact M-orthonormality and ascending order.
      Eigen::MatrixXd Kr = X.transpose() * KX;
      Eigen::MatrixXd Mr = X.transpose() * MX;
      Kr = 0.5 * (Kr + Kr.transpose()).eval();
      Mr = 0.5 * (Mr + Mr.transpose()).eval();
      Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> rr(Kr, Mr);
      if (rr.info() != Eigen::Success) return internalError("eigensolver: Rayleigh-Ritz failed: the computed modes are not independent");
      const Eigen::MatrixXd& Q = rr.eigenvectors();
      out.eigenvalues = rr.eigenvalues();
      out.shapes.noalias() = X * Q;
      KX = KX * Q;
      MX = MX * Q;
    }
    for (Eigen::Index k = 0; k < p; ++k) {
      const double l = out.eigenvalues[k];
      const double r = (KX.col(k) - l * MX.col(k)).norm() / (std::abs(l) * MX.col(k).norm());
      out.max_relative_residual = std::max(out.max_relative_residual, r);
    }
  } else {
    out.eigenvalues.resize(0);
    out.shapes.resize(n, 0);
  }
  out.refine_seconds = secondsSince(t_refine);
  if (settings.progress) settings.progress("lanczos", 1.0);
  return out;
}

}  // namespace

Result<ModalResult> solveModes(const SpMat& K, const SpMat& M, const ModalSettings& settings) {
  // No exception escapes the core: allocation failures (Eigen, std::vector) and anything a
  // third-party library throws become Errors here.
  try {
    return solveModesImpl(K, M, settings);
  } catch (const std::bad_alloc&) {
    return internalError("eigensolver: out of memory (" + std::to_string(K.rows()) + " degrees of freedom)");
  } catch (const std::exception& e) {
    return internalError(std::string("eigensolver: ") + e.what());
  }
}

}  // namespace strike
