// SPDX-License-Identifier: MIT
#include "progress_reporter.hpp"

#include <unistd.h>

#include <cstdio>

namespace strike::cli {

ProgressReporter::ProgressReporter(bool quiet) : enabled_(!quiet && isatty(STDERR_FILENO) != 0) {}
ProgressReporter::~ProgressReporter() { finish(); }

ProgressFn ProgressReporter::callback() {
  return [this](std::string_view phase, double fraction) { update(phase, fraction); };
}

void ProgressReporter::update(std::string_view phase, double fraction) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (phase != phase_) {
    phase_ = std::string(phase);
    phase_start_ = now;
  }
  // Only steps that take longer than a second are worth a line; redraw at most 10 times a second.
  const double elapsed = std::chrono::duration<double>(now - phase_start_).count();
  if (elapsed < 1.0 || std::chrono::duration<double>(now - last_print_).count() < 0.1) return;
  last_print_ = now;
  if (fraction >= 0.0)
    std::fprintf(stderr, "\r  %-16s %5.1f%%  %6.1f s   ", phase_.c_str(), 100.0 * fraction, elapsed);
  else
    std::fprintf(stderr, "\r  %-16s ...     %6.1f s   ", phase_.c_str(), elapsed);
  std::fflush(stderr);
  line_open_ = true;
}

void ProgressReporter::finish() {
  if (line_open_) std::fprintf(stderr, "\r%60s\r", "");
  line_open_ = false;
}

}  // namespace strike::cli
