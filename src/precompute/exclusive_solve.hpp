// SPDX-License-Identifier: MIT
// solveModes() one at a time per process. ARPACK keeps its iteration state in Fortran SAVE
// variables, so two threads inside dsaupd at once corrupt each other's solve (found by the Python
// package, which releases the GIL: python/tests/test_threads.py; scipy locks ARPACK the same way,
// scipy PR 5848). Processes are unaffected: batch workers are processes and solve in parallel.
#pragma once

#include <mutex>

#include "strike/modal/modal.hpp"

namespace strike {

inline Result<ModalResult> solveModesExclusive(const Eigen::SparseMatrix<double>& K,
                                               const Eigen::SparseMatrix<double>& M, const ModalSettings& settings) {
  // Process-wide on purpose: it guards ARPACK's process-wide state.
  static std::mutex arpack_state;
  std::lock_guard<std::mutex> lock(arpack_state);
  return solveModes(K, M, settings);
}

}  // namespace strike
