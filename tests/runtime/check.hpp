// SPDX-License-Identifier: MIT
// A check harness for plain test programs (tests/runtime): the runtime-only build
// (STRIKE_RUNTIME_ONLY) needs nothing but a compiler and CMake, so no GoogleTest there. A failed
// check prints file:line, the expression and the values, and the program goes on; main returns
// checkExitCode(), non-zero when any check failed, which ctest reports.
#pragma once

#include <cmath>
#include <cstdio>

#include "strike/strike.h"

namespace strike::check {

inline int& failures() {
  static int count = 0;
  return count;
}

inline void fail(const char* file, int line, const char* what) {
  std::fprintf(stderr, "%s:%d: check failed: %s\n", file, line, what);
  ++failures();
}

/// Prints a summary line; the exit code for main.
inline int checkExitCode(const char* program) {
  if (failures() == 0) {
    std::printf("%s: all checks passed\n", program);
    return 0;
  }
  std::fprintf(stderr, "%s: %d check(s) failed\n", program, failures());
  return 1;
}

}  // namespace strike::check

#define CHECK(cond)                                              \
  do {                                                           \
    if (!(cond)) strike::check::fail(__FILE__, __LINE__, #cond); \
  } while (0)

/// |actual - expected| <= tolerance, printing both when not.
#define CHECK_NEAR(actual, expected, tolerance)                                                                    \
  do {                                                                                                             \
    const double a_ = (actual), e_ = (expected), t_ = (tolerance);                                                 \
    if (!(std::fabs(a_ - e_) <= t_)) {                                                                             \
      std::fprintf(stderr, "%s:%d: check failed: %s = %.9g, expected %s = %.9g within %.3g\n", __FILE__, __LINE__, \
                   #actual, a_, #expected, e_, t_);                                                                \
      ++strike::check::failures();                                                                                 \
    }                                                                                                              \
  } while (0)

/// A C API call returns the expected status code.
#define CHECK_STATUS(expr, expected)                                                                                  \
  do {                                                                                                                \
    const strike_status s_ = (expr), x_ = (expected);                                                                 \
    if (s_ != x_) {                                                                                                   \
      std::fprintf(stderr, "%s:%d: check failed: %s returned %d (%s), expected %d (%s)\n", __FILE__, __LINE__, #expr, \
                   static_cast<int>(s_), strike_status_string(s_), static_cast<int>(x_), strike_status_string(x_));   \
      ++strike::check::failures();                                                                                    \
    }                                                                                                                 \
  } while (0)

#define CHECK_OK(expr) CHECK_STATUS(expr, STRIKE_OK)
