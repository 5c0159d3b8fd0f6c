// SPDX-License-Identifier: MIT
// The generalized eigenproblem K x = lambda M x: lowest elastic modes of a free solid by
// shift-invert Lanczos (ARPACK dsaupd/dseupd mode 3) on a CHOLMOD factorization of K - sigma M.
// Target strike_arpack.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>

#include "strike/core/progress.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// How the Lanczos work is split (both use one CHOLMOD factorization of K - sigma M).
enum class ModalMethod {
  /// Small requests (a few modes): ARPACK alone. Larger ones: block shift-invert Lanczos
  /// (multi-right-hand-side solves, BLAS-3 Gram-Schmidt). The fast default.
  Hybrid,
  /// ARPACK alone, single-vector solves: the reference the hybrid is checked against.
  ArpackOnly,
};

struct ModalSettings {
  double max_freq_hz = 20000.0;  ///< keep every elastic mode with sqrt(lambda)/2pi <= this
  int max_modes = 200;           ///< but at most this many (lowest first)
  /// Modes with sqrt(|lambda|)/2pi below this are rigid-body modes (a free solid has 6).
  double rigid_freq_hz = 1.0;
  ProgressFn progress;  ///< optional
  ModalMethod method = ModalMethod::Hybrid;
  /// Right-hand sides per block solve in the block Lanczos stage (Hybrid); 0 = default (16).
  int block_size = 0;
  /// Threads of our own in the block Lanczos stage and the refinement: 2 (on a machine of two
  /// cores or more) splits each block solve and dense product in two fixed halves, the second
  /// on a helper thread that sleeps between parts and is used only when it starts promptly;
  /// 1 does both halves in the calling thread. The result is the same bits either way, and
  /// whatever the load (tests/unit/modal/determinism_test.cpp). OpenBLAS itself runs
  /// single-threaded during the solve whatever OPENBLAS_NUM_THREADS says (its results depend on
  /// its thread count); that setting is process-wide, so it is restored
  /// afterwards, and other BLAS work should not run concurrently with a solve. What does change
  /// the bits: the BLAS kernels
  /// OpenBLAS picks for the CPU (docs/determinism.md).
  int threads = 2;
  /// Memory budget of the solve, bytes; 0: none. The solve forecasts what it will hold before it
  /// takes it: K, M, the factorization (exact, from CHOLMOD's symbolic analysis) and the first
  /// Lanczos basis before it factors, then the larger basis each time the basis must grow (it
  /// grows only while the band still holds modes, so a --max-modes beyond what the band holds
  /// costs nothing). A forecast above the budget ends the solve with a bad-input error that says
  /// the forecast and what to change, before the memory is taken.
  double max_bytes = 0.0;
  /// For tests: the helper thread sleeps this long before it picks up each part (a part it
  /// has not picked up within 300 us is done by the calling thread). Never changes the bits.
  int helper_delay_us = 0;
};

struct ModalResult {
  Eigen::VectorXd eigenvalues;       ///< lambda_i, rad^2/s^2, ascending, elastic modes only
  Eigen::MatrixXd shapes;            ///< 3N by #modes, M-orthonormal: shapes^T M shapes = I
  int rigid_modes_dropped = 0;       ///< normally 6 for a free body
  int above_cutoff_dropped = 0;      ///< converged modes found above max_freq_hz and not kept
  bool capped_by_max_modes = false;  ///< true when more modes lie below max_freq_hz
  double factorize_seconds = 0.0;
  double lanczos_seconds = 0.0;
  int operator_applications = 0;  ///< solves with the factorization (a block of k counts k)
  /// Largest relative residual ||K x - lambda M x|| / (lambda ||M x||) of a kept mode: the
  /// error estimate that precompute reports (eigenvalue error is about its square).
  double max_relative_residual = 0.0;
  double sigma = 0.0;           ///< the shift used (rad^2/s^2, negative)
  double refine_seconds = 0.0;  ///< Rayleigh-Ritz and residuals after Lanczos
  // Parts of lanczos_seconds:
  double solve_seconds = 0.0;          ///< CHOLMOD solves
  double orthogonalize_seconds = 0.0;  ///< block Lanczos recurrence, reorthogonalization, M products
  double ritz_seconds = 0.0;           ///< projected eigen-solves (block Lanczos convergence checks)
  int block_size = 0;                  ///< block Lanczos block size used (0: ARPACK only)
  int lanczos_basis = 0;               ///< largest block Krylov basis built
  int reorthogonalizations = 0;        ///< extra (DGKS) Gram-Schmidt passes in block Lanczos
  double forecast_bytes = 0.0;         ///< the largest memory forecast the solve made (ModalSettings::max_bytes)
};

/// What the eigen-solve of an n-DOF problem holds besides its factor: K, M (and the pruned M, the
/// shifted matrix) of nnz_k nonzeros each, and a Lanczos basis of `basis` vectors with the
/// projection and the modes it finds (at most `modes`). Bytes; the solver's own forecast.
double modalWorkspaceBytes(double n, double nnz_k, double basis, double modes);

/// "1.23 GB" / "312 MB": memory in the words of the forecasts' messages.
std::string memoryText(double bytes);

Result<ModalResult> solveModes(const Eigen::SparseMatrix<double>& K, const Eigen::SparseMatrix<double>& M,
                               const ModalSettings& settings);

/// OpenBLAS on one thread for the rest of the process, and its idle worker threads ended. A
/// threaded OpenBLAS starts a worker per extra core when it loads, before main, and each spins
/// (sched_yield) ~0.1 s before it sleeps: CPU burnt at every start of a program that links it,
/// although solveModes uses one BLAS thread anyway (bit-identical banks whatever the core count,
/// docs/determinism.md). For programs that own their process (the strike CLI), never for a
/// library loaded into someone else's (numpy may share this OpenBLAS). No-op for another BLAS.
void useOneBlasThread();

}  // namespace strike
