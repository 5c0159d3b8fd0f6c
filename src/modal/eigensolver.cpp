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
//
// This file is the driver (steps 1, 2 and 5 and the choice between 3 and 4); the stages are
// cholmod_solver.cpp, arpack_lanczos.cpp, block_lanczos.cpp and symmetric_times_block.cpp.
#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cholmod_solver.hpp"
#include "lanczos.hpp"
#include "strike/modal/modal.hpp"
#include "two_parts.hpp"

// OpenBLAS thread control, weak so that another BLAS (no such functions) still links.
extern "C" __attribute__((weak)) void openblas_set_num_threads(int num_threads);
extern "C" __attribute__((weak)) int openblas_get_num_threads(void);
// Ends OpenBLAS's worker threads (its pthread_atfork handler); the next set_num_threads or
// multi-threaded call starts them again.
extern "C" __attribute__((weak)) int blas_thread_shutdown_(void);

namespace strike {

namespace {

using detail::blockLanczos;
using detail::checkMemoryForecast;
using detail::CholmodSolver;
using detail::Clock;
using detail::Context;
using detail::Found;
using detail::kFirstBasisVectors;
using detail::lanczosChunk;
using detail::secondsSince;
using detail::SpMat;
using detail::symmetricTimesBlock;

/// Sets OpenBLAS's thread count for a scope and restores it (no-op for 0 or another BLAS).
/// Already that count: no call at all (a call would start again the threads that
/// useOneBlasThread ended).
class BlasThreadsScope {
 public:
  explicit BlasThreadsScope(int threads) {
    if (threads <= 0 || openblas_set_num_threads == nullptr || openblas_get_num_threads == nullptr) return;
    const int previous = openblas_get_num_threads();
    if (previous == threads) return;
    previous_ = previous;
    openblas_set_num_threads(threads);
  }
  ~BlasThreadsScope() {
    if (previous_ > 0) openblas_set_num_threads(previous_);
  }
  BlasThreadsScope(const BlasThreadsScope&) = delete;
  BlasThreadsScope& operator=(const BlasThreadsScope&) = delete;

 private:
  int previous_ = 0;
};

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

/// Shift from the problem's own scale: median of diag(K)/diag(M) is ~ (c/h)^2, the squared
/// angular frequency of one element, whatever the units or material. A tiny fraction of it
/// keeps K - sigma M well conditioned (cond ~ lambda_max / |sigma| ~ 1e5) while staying far
/// below the wanted eigenvalues, where the shift would slow Lanczos convergence down.
double medianDiagonalRatio(const SpMat& K, const SpMat& M) {
  std::vector<double> ratio;
  ratio.reserve(static_cast<size_t>(K.rows()));
  const Eigen::VectorXd dk = K.diagonal();
  const Eigen::VectorXd dm = M.diagonal();
  for (Eigen::Index i = 0; i < K.rows(); ++i) {
    if (dk[i] > 0.0 && dm[i] > 0.0) ratio.push_back(dk[i] / dm[i]);
  }
  if (ratio.empty()) return 0.0;
  std::nth_element(ratio.begin(), ratio.begin() + static_cast<std::ptrdiff_t>(ratio.size() / 2), ratio.end());
  return ratio[ratio.size() / 2];
}

double chooseShift(double scale, double lambda_cut) {
  if (!(scale > 0.0)) return -1.0;
  double shift = 1e-4 * scale;
  if (std::isfinite(lambda_cut)) shift = std::min(shift, 0.05 * lambda_cut);
  shift = std::max(shift, 1e-9 * scale);
  return -shift;
}

std::string memoryFrequencyText(double hz) {
  char text[32];
  std::snprintf(text, sizeof text, "%g Hz", hz);
  return text;
}

double sparseBytes(const SpMat& A) {
  return 12.0 * static_cast<double>(A.nonZeros()) + 4.0 * static_cast<double>(A.cols() + 1);
}

Result<ModalResult> solveDense(const SpMat& K, const SpMat& M, ModalResult out, Eigen::VectorXd& lambdas,
                               Eigen::MatrixXd& vectors) {
  const Eigen::MatrixXd Kd(K);
  const Eigen::MatrixXd Md(M);
  if (Eigen::LLT<Eigen::MatrixXd>(Md).info() != Eigen::Success)
    return internalError("eigensolver: the mass matrix is not positive definite");
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Kd, Md);
  if (es.info() != Eigen::Success)
    return internalError("eigensolver: dense generalized eigen-solve failed (is M positive definite?)");
  lambdas = es.eigenvalues();
  vectors = es.eigenvectors();
  return out;
}

/// Why K, M or the settings cannot be solved; nothing when they can.
Status checkProblem(const SpMat& K, const SpMat& M, const ModalSettings& settings) {
  const Eigen::Index n = K.rows();
  if (n == 0 || K.cols() != n || M.rows() != n || M.cols() != n) {
    std::ostringstream s;
    s << "eigensolver: K (" << K.rows() << "x" << K.cols() << ") and M (" << M.rows() << "x" << M.cols()
      << ") must be square, non-empty and of the same size";
    return badInput(s.str());
  }
  if (!(settings.max_freq_hz > 0.0))
    return badInput("eigensolver: max_freq_hz must be > 0, got " + std::to_string(settings.max_freq_hz));
  if (settings.max_modes <= 0)
    return badInput("eigensolver: max_modes must be > 0, got " + std::to_string(settings.max_modes));
  if (!(settings.rigid_freq_hz >= 0.0))
    return badInput("eigensolver: rigid_freq_hz must be >= 0, got " + std::to_string(settings.rigid_freq_hz));

  for (Eigen::Index i = 0; i < n; ++i) {
    const double m_ii = M.coeff(i, i);
    const double k_ii = K.coeff(i, i);
    if (!(m_ii > 0.0) || !std::isfinite(m_ii) || !std::isfinite(k_ii)) {
      std::ostringstream s;
      s << "eigensolver: the mass matrix must be positive definite and K, M finite; degree of freedom " << i
        << " has M = " << m_ii << ", K = " << k_ii << " (is the density positive and the mesh valid?)";
      return internalError(s.str());
    }
  }
  return {};
}

/// Which eigenvalues are rigid (|lambda| <= lambda_zero), which are in the band, and when the
/// Lanczos rounds have found enough.
struct Bands {
  double lambda_zero = 0.0, lambda_cut = 0.0;
  int max_modes = 0;
  /// True when what was found and `extra` reach past the cut-off or the cap; the elastic
  /// eigenvalues in the band and the largest of all.
  bool enough(const Found& found, const std::vector<double>& extra, int& elastic_below, double& top) const {
    elastic_below = 0;
    top = -INFINITY;
    for (const std::vector<double>* list : {static_cast<const std::vector<double>*>(&found.lambdas), &extra}) {
      for (double l : *list) {
        top = std::max(top, l);
        if (std::abs(l) > lambda_zero && l <= lambda_cut) ++elastic_below;
      }
    }
    return top > lambda_cut || elastic_below > max_modes;
  }
};

/// Where the Lanczos rounds stand: done, and how many rounds found modes.
struct Rounds {
  bool done = false;
  int with_modes = 0;
  /// All modes from one block Lanczos run: M-orthonormal and ascending by construction.
  bool single_block = false;
};

/// Checks the memory forecast of the factorization and the first Lanczos basis, before either is
/// taken. A cut-off above the elements' own frequency leaves every mode the mesh has in the
/// band: then the request is all the cap asks for, and its whole basis is forecast at once.
Status checkFactorAndFirstBasis(Context& ctx, Eigen::Index n, double element_scale, double lambda_cut) {
  const ModalSettings& settings = ctx.settings;
  const double wanted = settings.max_modes + 7.0;
  const double full_basis = std::min<double>(n - 1, kBasisFactor * wanted + 2 * kBlockSize);
  const bool band_holds_the_mesh = lambda_cut >= element_scale;
  const double first_basis =
      band_holds_the_mesh ? full_basis : std::min<double>(full_basis, kFirstBasisVectors + kBlockSize);
  return checkMemoryForecast(
      ctx, first_basis, band_holds_the_mesh ? std::min<double>(wanted, n) : std::min(wanted, first_basis / 3.0),
      band_holds_the_mesh ? "for the factorization and the Lanczos basis of every mode up to " +
                                memoryFrequencyText(settings.max_freq_hz) +
                                " (above the mesh's own element frequency: the band holds all its modes)"
                          : std::string("for the factorization and its first Lanczos basis"));
}

/// A small request (at most kArpackModes pairs): ARPACK alone, to full accuracy, in one round.
/// ModalMethod::ArpackOnly grows ARPACK requests instead, round after round.
Status arpackRounds(Context& ctx, Found& found, const Bands& bands, Eigen::Index n, Rounds& rounds) {
  const ModalSettings& settings = ctx.settings;
  const bool arpack_only = settings.method == ModalMethod::ArpackOnly;
  const int wanted_total = settings.max_modes + 7;
  int chunk = arpack_only ? std::min(wanted_total, 400) : std::min(wanted_total, kArpackModes);
  const bool block_only = !arpack_only && wanted_total > kArpackModes;
  for (int round = 0; round < 64 && !rounds.done && !block_only; ++round) {
    auto got = lanczosChunk(ctx, found, chunk, 1e-10, 0x5eed0000ULL + static_cast<uint64_t>(round), 0.0, 1.0);
    if (!got) return got.error();
    if (*got > 0) ++rounds.with_modes;
    int elastic_below = 0;
    double top = 0.0;
    rounds.done = bands.enough(found, {}, elastic_below, top);
    const bool exhausted = static_cast<Eigen::Index>(found.lambdas.size()) + 2 >= n;
    if (*got == 0 || exhausted) rounds.done = true;
    if (!arpack_only) break;
    chunk = std::min(std::max(chunk, 16), settings.max_modes + 7 - elastic_below);
  }
  return {};
}

/// A larger request: block Lanczos from scratch (rigid modes included), then, only if it fell
/// short, further block rounds on the operator deflated against what was found.
Status blockRounds(Context& ctx, Found& found, const Bands& bands, Eigen::Index n, Rounds& rounds) {
  const ModalSettings& settings = ctx.settings;
  const bool arpack_only = settings.method == ModalMethod::ArpackOnly;
  for (int round = 0; !rounds.done && !arpack_only && round < 16; ++round) {
    int elastic_below = 0;
    double top = 0.0;
    bands.enough(found, {}, elastic_below, top);
    // A free body has 6 rigid modes: when the block stage starts from scratch it finds them too.
    const int rigid_found = static_cast<int>(std::count_if(found.lambdas.begin(), found.lambdas.end(),
                                                           [&](double l) { return std::abs(l) <= bands.lambda_zero; }));
    const int needed = settings.max_modes + 1 - elastic_below + std::max(0, 6 - rigid_found);
    const Eigen::Index room = n - static_cast<Eigen::Index>(found.lambdas.size()) - 1;
    const int block_pref = settings.block_size > 0 ? settings.block_size : kBlockSize;
    const int block = static_cast<int>(std::min<Eigen::Index>(room / 3, block_pref));
    if (block < 1) break;
    const int max_basis =
        static_cast<int>(std::min<Eigen::Index>(room, std::max(kBasisFactor * needed, 4 * block) + 2 * block));
    auto got = blockLanczos(ctx, found, block, needed, needed + block, max_basis, kBlockTol,
                            0xb10c0000ULL + static_cast<uint64_t>(round), [&](const std::vector<double>& extra) {
                              int e = 0;
                              double t = 0.0;
                              return bands.enough(found, extra, e, t);
                            });
    if (!got) return got.error();
    if (*got > 0) {
      ++rounds.with_modes;
      rounds.single_block = rounds.with_modes == 1;
    }
    rounds.done = bands.enough(found, {}, elastic_below, top) || *got == 0;
  }
  return {};
}

/// The Lanczos path (n > 600): one factorization of K - sigma M after its memory forecast, then
/// ARPACK or block Lanczos rounds until the band or the cap is passed. Fills `found`, the
/// stages' timings and tallies in `out`, and whether all came from one block round.
Status lanczosStages(const SpMat& K, const SpMat& M, const SpMat& M_pruned, const ModalSettings& settings,
                     double element_scale, const Bands& bands, TwoParts& parts, ModalResult& out, Found& found,
                     bool& single_block_round) {
  const Eigen::Index n = K.rows();
  auto solver = std::make_unique<CholmodSolver>();
  const auto t_factor = Clock::now();
  if (settings.progress) settings.progress("factorize", 0.0);
  SpMat A = K - out.sigma * M;
  // Forecast before the factor and the basis are taken: the factor's size is exact once the
  // symbolic analysis has ordered A (a small fraction of the factorization's time).
  Result<double> factor_bytes = solver->analyze(A);
  if (!factor_bytes) return factor_bytes.error();
  Context ctx{K, M_pruned, *solver, out.sigma, settings};
  ctx.matrices_bytes = sparseBytes(K) + sparseBytes(M) + sparseBytes(M_pruned) + sparseBytes(A);
  ctx.factor_bytes = *factor_bytes;
  if (Status fits = checkFactorAndFirstBasis(ctx, n, element_scale, bands.lambda_cut); !fits) return fits.error();
  Status st = solver->factorize(A);
  if (!st) return st.error();
  ctx.matrices_bytes -= sparseBytes(A);
  A = SpMat();
  out.factorize_seconds = secondsSince(t_factor);
  if (settings.progress) settings.progress("factorize", 1.0);

  const auto t_lanczos = Clock::now();
  ctx.parts = &parts;
  Rounds rounds;
  if (Status ok = arpackRounds(ctx, found, bands, n, rounds); !ok) return ok.error();
  if (Status ok = blockRounds(ctx, found, bands, n, rounds); !ok) return ok.error();
  single_block_round = rounds.single_block;
  out.lanczos_seconds = secondsSince(t_lanczos);
  out.operator_applications = ctx.applications;
  out.solve_seconds = ctx.solve_seconds;
  out.orthogonalize_seconds = ctx.orthogonalize_seconds;
  out.ritz_seconds = ctx.ritz_seconds;
  out.block_size = ctx.block_size;
  out.lanczos_basis = ctx.basis;
  out.reorthogonalizations = ctx.reorthogonalizations;
  out.forecast_bytes = ctx.forecast_bytes;
  return {};
}

/// The eigenvalues kept (indices into all_lambdas, ascending, at most max_modes); counts the
/// rigid ones, those above the cut-off and whether the cap cut the band.
std::vector<int> keptModes(const Eigen::VectorXd& all_lambdas, const Bands& bands, ModalResult& out) {
  std::vector<int> order(static_cast<size_t>(all_lambdas.size()));
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return all_lambdas[a] < all_lambdas[b]; });
  std::vector<int> kept;
  for (int i : order) {
    const double l = all_lambdas[i];
    if (std::abs(l) <= bands.lambda_zero) {
      ++out.rigid_modes_dropped;
    } else if (l > bands.lambda_cut) {
      ++out.above_cutoff_dropped;
    } else if (static_cast<int>(kept.size()) < bands.max_modes) {
      kept.push_back(i);
    } else {
      out.capped_by_max_modes = true;
    }
  }
  return kept;
}

/// The Ritz vectors Q S of one block Lanczos run are M-orthonormal to round-off and ordered:
/// the eigenvalues are their Rayleigh quotients (as accurate as a Rayleigh-Ritz step, both
/// second order in the residual), with no p x p products or rotations of the n x p blocks
/// (measured 0.6 s of 1.0 s at 86k DOF). Sorted when round-off reordered two.
void rayleighQuotients(Eigen::MatrixXd& X, Eigen::MatrixXd& KX, Eigen::MatrixXd& MX, ModalResult& out) {
  const Eigen::Index n = X.rows(), p = X.cols();
  out.eigenvalues =
      X.cwiseProduct(KX).colwise().sum().transpose().cwiseQuotient(X.cwiseProduct(MX).colwise().sum().transpose());
  std::vector<Eigen::Index> rank(static_cast<size_t>(p));
  for (Eigen::Index k = 0; k < p; ++k) rank[static_cast<size_t>(k)] = k;
  std::stable_sort(rank.begin(), rank.end(),
                   [&](Eigen::Index a, Eigen::Index c) { return out.eigenvalues[a] < out.eigenvalues[c]; });
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
}

/// Rayleigh-Ritz on the kept vectors: exact M-orthonormality and ascending order.
Status rayleighRitz(const Eigen::MatrixXd& X, Eigen::MatrixXd& KX, Eigen::MatrixXd& MX, ModalResult& out) {
  Eigen::MatrixXd Kr = X.transpose() * KX;
  Eigen::MatrixXd Mr = X.transpose() * MX;
  Kr = 0.5 * (Kr + Kr.transpose()).eval();
  Mr = 0.5 * (Mr + Mr.transpose()).eval();
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> rr(Kr, Mr);
  if (rr.info() != Eigen::Success)
    return internalError("eigensolver: Rayleigh-Ritz failed: the computed modes are not independent");
  const Eigen::MatrixXd& Q = rr.eigenvectors();
  out.eigenvalues = rr.eigenvalues();
  out.shapes.noalias() = X * Q;
  KX = KX * Q;
  MX = MX * Q;
  return {};
}

/// The kept modes' eigenvalues and M-orthonormal shapes in ascending order, and the largest
/// relative residual ||K x - lambda M x|| / (|lambda| ||M x||). Frees the candidates' vectors.
Status refine(const SpMat& K, const SpMat& M_pruned, const std::vector<int>& kept, const Eigen::VectorXd& all_lambdas,
              Eigen::MatrixXd& all_vectors, Eigen::MatrixXd& all_m_vectors, bool single_block_round, TwoParts& parts,
              ModalResult& out) {
  const Eigen::Index n = K.rows();
  const Eigen::Index p = static_cast<Eigen::Index>(kept.size());
  Eigen::MatrixXd X(n, p);
  for (Eigen::Index k = 0; k < p; ++k) X.col(k) = all_vectors.col(kept[static_cast<size_t>(k)]);
  all_vectors = Eigen::MatrixXd();
  if (p == 0) {
    out.eigenvalues.resize(0);
    out.shapes.resize(n, 0);
    return {};
  }
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
    rayleighQuotients(X, KX, MX, out);
  } else if (Status ok = rayleighRitz(X, KX, MX, out); !ok) {
    return ok.error();
  }
  for (Eigen::Index k = 0; k < p; ++k) {
    const double l = out.eigenvalues[k];
    const double r = (KX.col(k) - l * MX.col(k)).norm() / (std::abs(l) * MX.col(k).norm());
    out.max_relative_residual = std::max(out.max_relative_residual, r);
  }
  return {};
}

Result<ModalResult> solveModesImpl(const SpMat& K, const SpMat& M, const ModalSettings& settings) {
  if (Status ok = checkProblem(K, M, settings); !ok) return ok.error();
  const Eigen::Index n = K.rows();
  Bands bands;
  bands.lambda_cut = std::pow(kTwoPi * settings.max_freq_hz, 2);
  bands.max_modes = settings.max_modes;
  const double lambda_rigid = std::pow(kTwoPi * settings.rigid_freq_hz, 2);
  ModalResult out;
  const double element_scale = medianDiagonalRatio(K, M);
  out.sigma = chooseShift(element_scale, bands.lambda_cut);
  // A rigid mode's computed eigenvalue is round-off, ~eps * |sigma| * cond: count anything
  // below a tiny fraction of the shift as rigid too, whatever rigid_freq_hz says.
  bands.lambda_zero = std::max(lambda_rigid, 1e-6 * std::abs(out.sigma));

  // The assembled M stores the 3x3 pattern of K, but a consistent mass matrix couples only
  // equal directions: two thirds of its entries are exact zeros. Dropping them makes every
  // M product up to 3x cheaper (block Lanczos does one or two per step).
  SpMat M_pruned = M;
  M_pruned.prune(0.0, 0.0);
  Eigen::VectorXd all_lambdas;
  Eigen::MatrixXd all_vectors, all_m_vectors;  // all_m_vectors = M all_vectors, if known
  bool single_block_round = false;
  // OpenBLAS single-threaded for the whole solve, factorization included: with two threads
  // the same matrix's CHOLMOD factor has other bits than with one (so the core count and
  // OPENBLAS_NUM_THREADS would change the bank), and its idle threads spin (sched_yield): under
  // two busy processes a solve took 30-55 s instead of 2.5 s. It costs the factorization ~1.7x
  // on an idle 2-core machine (tests/bench/modal). The parallelism is ours instead (two_parts.hpp): a helper thread for the
  // block stage and the refinement when the machine has two cores or more, with the work cut
  // in the same two parts whether it takes part or not.
  const BlasThreadsScope one_blas_thread(1);
  const bool block_stage =
      n > 600 && settings.method != ModalMethod::ArpackOnly && settings.max_modes + 7 > kArpackModes;
  TwoParts parts(block_stage && settings.threads >= 2 && std::thread::hardware_concurrency() >= 2,
                 std::chrono::microseconds(settings.helper_delay_us));
  if (n <= 600) {
    // Tiny problems (a few cells): LAPACK on dense matrices is exact and faster than setting
    // up Lanczos, and ARPACK needs ncv < n anyway.
    auto dense = solveDense(K, M, out, all_lambdas, all_vectors);
    if (!dense) return dense.error();
  } else {
    Found found;
    if (Status ok =
            lanczosStages(K, M, M_pruned, settings, element_scale, bands, parts, out, found, single_block_round);
        !ok)
      return ok.error();
    all_lambdas = Eigen::Map<Eigen::VectorXd>(found.lambdas.data(), static_cast<Eigen::Index>(found.lambdas.size()));
    all_vectors = std::move(found.vectors);
    all_m_vectors = std::move(found.m_vectors);
  }

  const std::vector<int> kept = keptModes(all_lambdas, bands, out);
  const auto t_refine = Clock::now();
  if (Status ok = refine(K, M_pruned, kept, all_lambdas, all_vectors, all_m_vectors, single_block_round, parts, out);
      !ok)
    return ok.error();
  out.refine_seconds = secondsSince(t_refine);
  if (settings.progress) settings.progress("lanczos", 1.0);
  return out;
}

}  // namespace

namespace detail {

Status checkMemoryForecast(Context& ctx, double basis_vectors, double modes, const std::string& when) {
  const double n = static_cast<double>(ctx.K.rows());
  const double basis_bytes = modalWorkspaceBytes(n, 0.0, basis_vectors, modes);
  const double total = ctx.matrices_bytes + ctx.factor_bytes + basis_bytes;
  ctx.forecast_bytes = std::max(ctx.forecast_bytes, total);
  const double budget = ctx.settings.max_bytes;
  if (!(budget > 0.0) || total <= budget) return {};
  char text[640];
  std::snprintf(text, sizeof text,
                "the eigen-solve of %.0f DOF would need about %s %s (K and M %s, the factorization %s, a Lanczos "
                "basis of %.0f vectors with the modes it finds %s): more than the memory budget of %s. Raise "
                "--max-memory (default: the memory available), or ask for less: a coarser mesh (--size) or fewer "
                "modes (--max-modes, --max-freq)",
                n, memoryText(total).c_str(), when.c_str(), memoryText(ctx.matrices_bytes).c_str(),
                memoryText(ctx.factor_bytes).c_str(), basis_vectors, memoryText(basis_bytes).c_str(),
                memoryText(budget).c_str());
  return badInput(text);
}

}  // namespace detail

double modalWorkspaceBytes(double n, double nnz_k, double basis, double modes) {
  // K, M, M with its zeros pruned (a third of K's entries) and the shifted matrix: 12 bytes a
  // nonzero (value and row index).
  const double matrices = 12.0 * nnz_k * (1.0 + 1.0 + 1.0 / 3.0 + 1.0);
  // The basis Q and M Q (n x basis), the projection T and its working copy, the Ritz vectors,
  // the block's own vectors (a few n x 16 blocks), and the pairs found with M times them.
  const double lanczos = 8.0 * (2.0 * n * basis + 3.0 * basis * basis + 8.0 * n * 16.0);
  const double found = 8.0 * 2.0 * n * modes;
  return matrices + lanczos + found;
}

std::string memoryText(double bytes) {
  char text[32];
  if (bytes >= 1e9)
    std::snprintf(text, sizeof text, "%.2f GB", bytes / 1e9);
  else
    std::snprintf(text, sizeof text, "%.0f MB", std::ceil(bytes / 1e6));
  return text;
}

void useOneBlasThread() {
  if (openblas_set_num_threads == nullptr || blas_thread_shutdown_ == nullptr) return;
  openblas_set_num_threads(1);  // before the shutdown: with the pool down, a set would restart it
  blas_thread_shutdown_();
}

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
