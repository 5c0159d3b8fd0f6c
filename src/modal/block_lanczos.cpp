// SPDX-License-Identifier: MIT
// The block stage of the eigen-solver: block shift-invert Lanczos with multi-right-hand-side
// solves, BLAS-3 Gram-Schmidt and top-Ritz-pair checks by LAPACK dsyevr.
#include <algorithm>
#include <cmath>
#include <random>

#include "lanczos.hpp"

extern "C" void dsyevr_(const char* jobz, const char* range, const char* uplo, const int* n, double* a, const int* lda,
                        const double* vl, const double* vu, const int* il, const int* iu, const double* abstol, int* m,
                        double* w, double* z, const int* ldz, int* isuppz, double* work, const int* lwork, int* iwork,
                        const int* liwork, int* info, size_t jobz_len, size_t range_len, size_t uplo_len);

namespace strike::detail {

namespace {

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

/// The Krylov basis Q, M Q and the block tridiagonal projection T of one run, with room for
/// capacity_steps + 1 blocks. It is taken as it is needed: first enough for what a cut-off
/// usually leaves, then twice as much each time it fills, each growth forecast against the
/// budget first. A request for more modes than the band holds then costs no more than one for
/// fewer (the cut-off ends the run before the basis grows). Q and M Q grow by columns (a
/// realloc: no copy of the big blocks where the allocator can move pages); T, small, is copied.
struct Basis {
  Eigen::MatrixXd Q, MQ, T;
  Eigen::Index capacity_steps = 0;
};

Status firstBasis(Context& ctx, Eigen::Index n, Eigen::Index b, int want, Eigen::Index max_steps, Basis& basis) {
  basis.capacity_steps = std::min<Eigen::Index>(max_steps, std::max<Eigen::Index>(2, kFirstBasisVectors / b));
  const Eigen::Index capacity_steps = basis.capacity_steps;
  if (Status fits =
          checkMemoryForecast(ctx, static_cast<double>((capacity_steps + 1) * b),
                              std::min<double>(want, (capacity_steps + 1) * b / 3.0), "for its first Lanczos basis");
      !fits)
    return fits.error();
  basis.Q.resize(n, (capacity_steps + 1) * b);
  basis.MQ.resize(n, (capacity_steps + 1) * b);
  basis.T = Eigen::MatrixXd::Zero((capacity_steps + 1) * b, (capacity_steps + 1) * b);
  return {};
}

Status growBasis(Context& ctx, Eigen::Index b, int want, Eigen::Index max_steps, Basis& basis) {
  const Eigen::Index steps = std::min<Eigen::Index>(max_steps, 2 * basis.capacity_steps);
  const Eigen::Index columns = (steps + 1) * b;
  if (Status fits = checkMemoryForecast(ctx, static_cast<double>(columns), std::min<double>(want, columns / 3.0),
                                        "to grow its Lanczos basis to " + std::to_string(columns) +
                                            " vectors (the band holds more modes than the basis has found)");
      !fits)
    return fits;
  basis.Q.conservativeResize(Eigen::NoChange, columns);
  basis.MQ.conservativeResize(Eigen::NoChange, columns);
  Eigen::MatrixXd bigger = Eigen::MatrixXd::Zero(columns, columns);
  bigger.topLeftCorner(basis.T.rows(), basis.T.cols()) = basis.T;
  basis.T = std::move(bigger);
  basis.capacity_steps = steps;
  return {};
}

/// W minus its components along the modes already found (in the M inner product).
void deflate(const Found& found, Eigen::MatrixXd& W) {
  if (!found.lambdas.empty()) W.noalias() -= found.vectors * (found.m_vectors.transpose() * W);
}

/// M-orthonormalizes W in place by Cholesky QR; MW is updated alongside. R accumulates the
/// triangular factor so that W_in = W_out R. One pass leaves ||W^T M W - I|| ~ eps cond(W)^2
/// (Yamamoto et al., ETNA 44, 2015), so a second pass (CholQR2) runs only when the first
/// factor's diagonal spread says cond(W) may exceed ~30. Returns false on (numerical) rank
/// deficiency.
bool orthonormalize(Eigen::MatrixXd& W, Eigen::MatrixXd& MW, Eigen::MatrixXd& R) {
  const Eigen::Index b = W.cols();
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
}

/// One classical Gram-Schmidt pass against basis columns [first, first + width):
/// h = (M Q)^T W, W -= Q h, both products split by rows in two halves over two threads
/// (each thread streams half of Q and M Q; h is the sum of the two halves' products). The
/// halves are the same whoever computes them (ctx.parts runs them in turn without a helper).
class GramSchmidt {
 public:
  GramSchmidt(TwoParts& parts, Eigen::Index b) : parts_(parts), b_(b) {}
  void operator()(const Basis& basis, Eigen::MatrixXd& W, Eigen::Index first, Eigen::Index width,
                  Eigen::MatrixXd& h_out) {
    const Eigen::Index n = W.rows(), half = n / 2;
    for (Eigen::MatrixXd& part : h_parts_) part.resize(width, b_);
    parts_.run(n, half, [&](Eigen::Index r0, Eigen::Index r1, int part) {
      h_parts_[part].noalias() = basis.MQ.block(r0, first, r1 - r0, width).transpose() * W.middleRows(r0, r1 - r0);
    });
    h_out = h_parts_[0] + h_parts_[1];
    parts_.run(n, half, [&](Eigen::Index r0, Eigen::Index r1, int) {
      W.middleRows(r0, r1 - r0).noalias() -= basis.Q.block(r0, first, r1 - r0, width) * h_out;
    });
  }

 private:
  TwoParts& parts_;
  Eigen::Index b_;
  Eigen::MatrixXd h_parts_[2];
};

/// The start block: random (seeded), deflated, M-orthonormal, as the basis' first columns.
Status startBlock(Context& ctx, const Found& found, Eigen::Index b, uint64_t seed, Basis& basis, Eigen::MatrixXd& W,
                  Eigen::MatrixXd& MW, Eigen::MatrixXd& R) {
  const Eigen::Index n = ctx.K.rows();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  W.resize(n, b);
  for (Eigen::Index j = 0; j < b; ++j) {
    for (Eigen::Index i = 0; i < n; ++i) W(i, j) = uniform(rng);
  }
  deflate(found, W);
  symmetricTimesBlock(ctx.M, W, MW);
  if (!orthonormalize(W, MW, R))
    return internalError("eigensolver: block Lanczos could not start (degenerate start block)");
  basis.Q.leftCols(b) = W;
  basis.MQ.leftCols(b) = MW;
  return {};
}

/// Full reorthogonalization of W against the k basis vectors, adding the coefficients to H:
/// one classical Gram-Schmidt pass (two BLAS-3 products), a second one only where the DGKS test
/// says the pass cancelled (Daniel, Gragg, Kaufman & Stewart, Math. Comp. 30, 1976). MW = M W
/// is recomputed after each pass (the sparse product costs less than updating it with M Q), and
/// the norm before a pass follows from Pythagoras: Q is M-orthonormal.
void reorthogonalize(Context& ctx, const Basis& basis, GramSchmidt& gramSchmidt, Eigen::Index k, Eigen::MatrixXd& W,
                     Eigen::MatrixXd& MW, Eigen::MatrixXd& H, Eigen::MatrixXd& h) {
  for (int pass = 0; pass < 3; ++pass) {
    gramSchmidt(basis, W, 0, k, h);
    H += h;
    symmetricTimesBlock(ctx.M, W, MW, ctx.parts);
    const Eigen::ArrayXd after = W.cwiseProduct(MW).colwise().sum().transpose().array();
    const Eigen::ArrayXd removed = h.colwise().squaredNorm().transpose().array();
    // ||w_after||_M < 0.717 ||w_before||_M: the pass cancelled, rounding may remain.
    if (!((after < 0.514 * (after + removed)).any())) break;
    ++ctx.reorthogonalizations;
  }
}

/// The converged Ritz values' eigenvalues (largest theta first = smallest lambda first), from
/// the top m pairs of the k x k projection: a pair converges when its residual
/// ||R s_last|| <= tol theta.
std::vector<double> convergedPairs(const Context& ctx, const Eigen::VectorXd& ritz_values,
                                   const Eigen::MatrixXd& ritz_vectors, const Eigen::MatrixXd& R, Eigen::Index k,
                                   Eigen::Index b, int m, double tol) {
  std::vector<double> converged;
  for (Eigen::Index i = m - 1; i >= 0; --i) {
    const double theta = ritz_values[i];
    const double residual = (R * ritz_vectors.block(k - b, i, b, 1)).norm();
    if (!(theta > 0.0) || residual > tol * theta) break;
    converged.push_back(ctx.sigma + 1.0 / theta);
  }
  return converged;
}

/// How far: the basis against its cap, the pairs against the request, or the highest converged
/// eigenvalue against the cut-off's (Lanczos converges from the lowest up), whichever is
/// furthest.
void reportProgress(const Context& ctx, const std::vector<double>& converged, Eigen::Index k, int max_basis, int want) {
  if (!ctx.settings.progress) return;
  const double lambda_cut = std::pow(2.0 * M_PI * ctx.settings.max_freq_hz, 2);
  const double top = converged.empty() ? 0.0 : std::max(0.0, converged.back() / lambda_cut);
  const double done = std::max({static_cast<double>(k) / max_basis, static_cast<double>(converged.size()) / want, top});
  ctx.settings.progress("lanczos", std::min(0.95, done));
}

/// Appends the converged Ritz vectors Q S (and M Q S, by the sparse product) to `found`,
/// releasing the basis first.
void appendConverged(Context& ctx, Found& found, Basis& basis, const Eigen::MatrixXd& S, Eigen::Index kb,
                     const std::vector<double>& converged) {
  const Eigen::Index n = ctx.K.rows();
  const Eigen::Index locked = static_cast<Eigen::Index>(found.lambdas.size());
  const Eigen::Index num_converged = static_cast<Eigen::Index>(converged.size());
  const Eigen::Index total = locked + num_converged;
  found.vectors.conservativeResize(n, total);
  found.m_vectors.conservativeResize(n, total);
  ctx.parts->run(n, n / 2, [&](Eigen::Index r0, Eigen::Index r1, int) {
    found.vectors.block(r0, locked, r1 - r0, num_converged).noalias() =
        basis.Q.block(r0, 0, r1 - r0, kb) * S.topRows(kb);
  });
  basis.Q.resize(0, 0);  // the basis is not needed any more: release it before the temporaries below
  basis.MQ.resize(0, 0);
  // M (Q S) by the sparse product, not (M Q) S: 2 nnz(M) p flops instead of 2 n kb p (M has
  // at most a few tens of nonzeros per row, against kb ~ 450 basis vectors), and the
  // refinement reuses it.
  Eigen::MatrixXd m_fresh;
  symmetricTimesBlock(ctx.M, found.vectors.rightCols(num_converged), m_fresh, ctx.parts);
  found.m_vectors.rightCols(num_converged) = m_fresh;
  for (double l : converged) found.lambdas.push_back(l);
}

}  // namespace

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
  const Eigen::Index b = block;
  const Eigen::Index max_steps = std::max<Eigen::Index>(2, max_basis / b);
  Basis basis;
  if (Status fits = firstBasis(ctx, ctx.K.rows(), b, want, max_steps, basis); !fits) return fits.error();
  Eigen::MatrixXd W, MW, R;
  if (Status started = startBlock(ctx, found, b, seed, basis, W, MW, R); !started) return started.error();
  GramSchmidt gramSchmidt(*ctx.parts, b);

  Eigen::Index steps = 0;
  std::vector<double> converged;
  Eigen::MatrixXd S;
  Eigen::MatrixXd H, h, Tk, ritz_vectors;
  Eigen::VectorXd ritz_values;
  Eigen::Index next_check = 0;
  for (Eigen::Index j = 0; j < max_steps; ++j) {
    const Eigen::Index k = (j + 1) * b;  // basis size after this step's block
    if (j + 1 > basis.capacity_steps) {
      if (Status grown = growBasis(ctx, b, want, max_steps, basis); !grown) return grown.error();
    }
    auto t0 = Clock::now();
    if (!ctx.solver.solve(basis.MQ.middleCols(j * b, b).data(), W.data(), static_cast<int>(b), ctx.parts)) {
      return internalError("eigensolver: CHOLMOD block solve failed");
    }
    ctx.solve_seconds += secondsSince(t0);
    t0 = Clock::now();
    ctx.applications += static_cast<int>(b);
    deflate(found, W);
    H.setZero(k, b);
    // Three-term recurrence, W -= Q_j A_j + Q_{j-1} B_{j-1}^T, with the coefficients
    // measured (local Gram-Schmidt against the two latest blocks, one product each way).
    {
      const Eigen::Index first = j > 0 ? (j - 1) * b : 0;
      const Eigen::Index width = j > 0 ? 2 * b : b;
      gramSchmidt(basis, W, first, width, h);
      H.middleRows(first, width) = h;
    }
    reorthogonalize(ctx, basis, gramSchmidt, k, W, MW, H, h);
    basis.T.block(0, j * b, k, b) = H;
    const bool ok = orthonormalize(W, MW, R);
    steps = j + 1;
    if (ok) {
      basis.Q.middleCols(k, b) = W;
      basis.MQ.middleCols(k, b) = MW;
      basis.T.block(k, j * b, b, b) = R;
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
    Tk = basis.T.topLeftCorner(k, k);
    Tk = 0.5 * (Tk + Tk.transpose()).eval();
    const int m = static_cast<int>(std::min<Eigen::Index>(k, want + b));
    if (!topEigenpairs(Tk, m, ritz_values, ritz_vectors)) {
      return internalError("eigensolver: block Lanczos projection eigen-solve failed");
    }
    ctx.ritz_seconds += secondsSince(t0);
    converged = convergedPairs(ctx, ritz_values, ritz_vectors, R, k, b, m, tol);
    const Eigen::Index num_converged = static_cast<Eigen::Index>(converged.size());
    reportProgress(ctx, converged, k, max_basis, want);
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
  const Eigen::Index num_converged = static_cast<Eigen::Index>(converged.size());
  if (num_converged == 0 || S.cols() != num_converged) return 0;
  appendConverged(ctx, found, basis, S, kb, converged);
  return static_cast<int>(num_converged);
}

}  // namespace strike::detail
