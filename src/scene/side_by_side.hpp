// SPDX-License-Identifier: MIT
// Solves side by side: the banks a render computes, each on a thread of its own, as many at once
// as the machine has cores and the memory forecast allows. Nothing a solve computes depends on
// what runs beside it (the eigen-solve and the transfer give the same bits on one thread or two,
// and no solve reads another's results), so the banks are those of a serial solve; ARPACK's
// eigen-solves still take turns (exclusive_solve.hpp), while one object's meshing, assembly and
// acoustic transfer run beside another's eigen-solve.
#pragma once

#include <cstddef>
#include <functional>

namespace strike {

/// Runs job(0) .. job(count - 1), starting them in that order, at most `threads` at a time. A job
/// starts only once its forecast_bytes(i) and those of the jobs running fit in `budget_bytes`
/// (0: no budget); one whose forecast alone exceeds the budget runs alone, as a serial solve
/// would. Returns when every job has finished.
void runSideBySide(size_t count, unsigned threads, double budget_bytes,
                   const std::function<double(size_t)>& forecast_bytes, const std::function<void(size_t)>& job);

/// The memory this machine has available now (MemAvailable of /proc/meminfo), bytes; 0 when unknown.
double availableMemoryBytes();

}  // namespace strike
