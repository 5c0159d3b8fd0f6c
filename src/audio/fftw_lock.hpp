// SPDX-License-Identifier: MIT
// Private helper of strike_fftw. FFTW's planner (fftw_plan_*, fftw_destroy_plan) is not
// thread-safe; fftw_execute is (FFTW 3.3 manual, section 5.2 "Thread safety"). Every plan this
// module makes or destroys holds this one lock.
#pragma once

#include <mutex>

namespace strike::detail {

inline std::mutex& fftwPlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace strike::detail
