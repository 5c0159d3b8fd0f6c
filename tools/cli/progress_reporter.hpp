// SPDX-License-Identifier: MIT
// Progress on stderr for steps longer than about a second: a single updating line on a
// terminal, nothing when stderr is not a terminal (logs and CI stay clean).
#pragma once

#include <chrono>
#include <string>

#include "strike/progress.hpp"

namespace strike::cli {

class ProgressReporter {
 public:
  explicit ProgressReporter(bool quiet);
  ~ProgressReporter();
  /// A ProgressFn that reports to this object (which must outlive it).
  ProgressFn callback();
  void update(std::string_view phase, double fraction);
  void finish();  ///< clears the line

 private:
  bool enabled_;
  bool line_open_ = false;
  std::string phase_;
  std::chrono::steady_clock::time_point phase_start_, last_print_;
};

}  // namespace strike::cli
