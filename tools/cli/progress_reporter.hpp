// SPDX-License-Identifier: MIT
// Progress on stderr for steps longer than about a second: the phase (per object in a render),
// how far it is and an estimate of the time left. A single updating line on a terminal; with
// --progress also when stderr is not a terminal (a line every few seconds); nothing under
// --quiet or in pipes (logs and CI stay clean). It also keeps the line an interruption prints
// (setInterruptMessage) up to date with the phase.
#pragma once

#include <chrono>
#include <string>

#include "strike/core/progress.hpp"

namespace strike::cli {

class ProgressReporter {
 public:
  /// `command` names the interruption's line ("render": "strike render: interrupted ...").
  ProgressReporter(std::string command, bool quiet, bool forced);
  ~ProgressReporter();
  /// A ProgressFn that reports to this object (which must outlive it).
  ProgressFn callback();
  void update(std::string_view phase, double fraction);
  void finish();  ///< clears the line
  /// From now on an interruption says that `path` was written and what was not done after it.
  void written(const std::string& path);

 private:
  void say(const std::string& what);  ///< sets the interruption's line

  std::string command_;
  bool enabled_;
  bool terminal_;
  bool line_open_ = false;
  std::string phase_;  ///< as the library named it ("modes bowl: lanczos" in a render)
  std::string shown_;  ///< the phase as shown
  std::chrono::steady_clock::time_point phase_start_, last_print_;
};

}  // namespace strike::cli
