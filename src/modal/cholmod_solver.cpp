// SPDX-License-Identifier: MIT
// CHOLMOD factorization and solves of the eigen-solver (cholmod_solver.hpp).
#include "cholmod_solver.hpp"

#include <cstring>
#include <new>
#include <sstream>
#include <string>

namespace strike::detail {

using SpMat = Eigen::SparseMatrix<double>;

CholmodSolver::CholmodSolver() {
  cholmod_start(&common_);
  common_.print = 0;  // we report errors ourselves, on stderr, through Status
  common_.supernodal = CHOLMOD_SUPERNODAL;
}

CholmodSolver::~CholmodSolver() {
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

namespace {

cholmod_sparse viewOf(const SpMat& A) {
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
  return view;
}

}  // namespace

Result<double> CholmodSolver::analyze(const SpMat& A) {
  cholmod_sparse view = viewOf(A);
  // METIS nested dissection gives less fill than AMD on 3D solid meshes (George, SIAM J.
  // Numer. Anal. 10, 1973); the factor's size is what every solve streams from memory.
  common_.nmethods = 1;
  common_.method[0].ordering = CHOLMOD_METIS;
  common_.postorder = 1;
  factor_ = cholmod_analyze(&view, &common_);
  if (factor_ == nullptr)
    return internalError("eigensolver: CHOLMOD analysis failed (status " + std::to_string(common_.status) + ")");
  // The numeric factor's real and integer parts, and the largest supernode's dense update
  // matrix, the factorization's own workspace (CHOLMOD User Guide, cholmod_factor).
  if (factor_->is_super)
    return 8.0 * static_cast<double>(factor_->xsize + factor_->maxcsize) +
           4.0 * static_cast<double>(factor_->ssize + 4 * factor_->n);
  return 12.0 * common_.lnz + 32.0 * static_cast<double>(factor_->n);
}

Status CholmodSolver::factorize(const SpMat& A) {
  if (factor_ == nullptr) {
    Result<double> analyzed = analyze(A);
    if (!analyzed) return analyzed.error();
  }
  cholmod_sparse view = viewOf(A);
  const int ok = cholmod_factorize(&view, factor_, &common_);
  if (common_.status == CHOLMOD_NOT_POSDEF || factor_->minor < factor_->n) {
    std::ostringstream s;
    s << "eigensolver: K - sigma M is not positive definite (pivot " << factor_->minor << " of " << factor_->n
      << "): the mass matrix is singular or the mesh has degenerate or inverted elements";
    return internalError(s.str());
  }
  if (!ok || common_.status < CHOLMOD_OK) {
    if (common_.status == CHOLMOD_OUT_OF_MEMORY) throw std::bad_alloc();
    return internalError("eigensolver: CHOLMOD factorization failed (status " + std::to_string(common_.status) + ")");
  }
  return {};
}

bool CholmodSolver::solve(const double* b, double* x, int ncols, TwoParts* parts) {
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

bool CholmodSolver::solveColumns(const double* b, double* x, int ncols, cholmod_common& common, cholmod_dense*& x_work,
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

}  // namespace strike::detail
