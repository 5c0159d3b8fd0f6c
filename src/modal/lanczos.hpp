// SPDX-License-Identifier: MIT
// What the eigen-solver's stages share (eigensolver.cpp drives them): the Lanczos context,
// the pairs found so far, the two Lanczos kinds (arpack_lanczos.cpp, block_lanczos.cpp) and
// the sparse-times-block product (symmetric_times_block.cpp). Internal to src/modal.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cholmod_solver.hpp"
#include "strike/modal/modal.hpp"
#include "strike/core/result.hpp"
#include "two_parts.hpp"

namespace strike::detail {

using SpMat = Eigen::SparseMatrix<double>;
using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// Y = A X for a SYMMETRIC sparse A and a block X, optionally in two fixed halves of rows over
/// two threads (symmetric_times_block.cpp).
void symmetricTimesBlock(const SpMat& A, const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::MatrixXd& Y,
                         TwoParts* parts = nullptr);

/// Eigenpairs found so far (M-orthonormal columns), used to deflate later Lanczos chunks.
struct Found {
  std::vector<double> lambdas;
  Eigen::MatrixXd vectors;    // n x k
  Eigen::MatrixXd m_vectors;  // M * vectors
};

/// What a Lanczos stage works on (the operator's parts and settings) and its tallies.
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
  /// Bytes held through the Lanczos stage besides its basis (K, M, the factor); the basis
  /// forecasts each growth against the solve's budget (ModalSettings::max_bytes; 0: none).
  double matrices_bytes = 0.0, factor_bytes = 0.0;
  double forecast_bytes = 0.0;  ///< the largest forecast made
};

/// Checks a forecast of the whole solve against the budget: bad input naming the forecast, its
/// parts and what to change when it is over (eigensolver.cpp).
Status checkMemoryForecast(Context& ctx, double basis_vectors, double modes, const std::string& when);

/// The first block Lanczos basis, in vectors: enough for the modes a 20 kHz cut-off leaves on the
/// examples (the bar 144 vectors for its 29 pairs, the bowl 240 for 58); a request beyond them
/// grows the basis only when the band holds more.
constexpr int kFirstBasisVectors = 256;
/// Pairs a basis of k vectors converges, at most about k / 4 (measured: the two above, and the
/// 4.5x basis of a request the cap limits); the forecast counts k / 3.

/// One ARPACK run for `nev` eigenpairs of OP deflated against `found`; appends the converged
/// pairs to `found`. Returns the number appended (arpack_lanczos.cpp).
Result<int> lanczosChunk(Context& ctx, Found& found, int nev, double tol, uint64_t seed, double progress_base,
                         double progress_span);

/// Block shift-invert Lanczos on OP deflated against `found`; appends the converged pairs to
/// `found`, stops when `enough(lambdas_converged_in_order)`. Returns the number appended
/// (block_lanczos.cpp, which explains the parameters).
Result<int> blockLanczos(Context& ctx, Found& found, int block, int want, int min_basis, int max_basis, double tol,
                         uint64_t seed, const std::function<bool(const std::vector<double>&)>& enough);

}  // namespace strike::detail
