// SPDX-License-Identifier: MIT
#include "progress_reporter.hpp"

#include <unistd.h>

#include <cstdio>

#include "strike/core/interrupt_cleanup.hpp"

namespace strike::cli {

ProgressReporter::ProgressReporter(std::string command, bool quiet, bool forced)
    : command_(std::move(command)),
      enabled_(!quiet && (forced || isatty(STDERR_FILENO) != 0)),
      terminal_(isatty(STDERR_FILENO) != 0) {
  say("interrupted; nothing was written");
}

ProgressReporter::~ProgressReporter() { finish(); }

ProgressFn ProgressReporter::callback() {
  return [this](std::string_view phase, double fraction) { update(phase, fraction); };
}

void ProgressReporter::update(std::string_view phase, double fraction) {
  const auto now = std::chrono::steady_clock::now();
  if (phase != phase_) {
    phase_ = std::string(phase);
    phase_start_ = now;
    shown_ = phase_;  // a render names each object's solve steps itself: "modes bowl: lanczos"
    say("interrupted during " + shown_ + "; nothing was written");
  }
  if (!enabled_) return;
  // Only steps that take longer than a second are worth a line; on a terminal the line is
  // redrawn at most 10 times a second, elsewhere a new one every 5 seconds.
  const double elapsed = std::chrono::duration<double>(now - phase_start_).count();
  const double since_print = std::chrono::duration<double>(now - last_print_).count();
  if (elapsed < 1.0 || since_print < (terminal_ ? 0.1 : 5.0)) return;
  last_print_ = now;
  char left[48] = "";
  // The time left, assuming the rest goes as fast as what is done (shown once 2% is done).
  if (fraction >= 0.02 && fraction < 1.0)
    std::snprintf(left, sizeof left, ", ~%.0f s left", elapsed * (1.0 - fraction) / fraction);
  char done[24] = "...";
  if (fraction >= 0.0) std::snprintf(done, sizeof done, "%5.1f%%", 100.0 * fraction);
  const std::string name = shown_.size() > 40 ? shown_.substr(0, 37) + "..." : shown_;
  std::fprintf(stderr, "%s  %-40s %s  %.0f s%s   %s", terminal_ ? "\r" : "", name.c_str(), done, elapsed, left,
               terminal_ ? "" : "\n");
  std::fflush(stderr);
  line_open_ = terminal_;
}

void ProgressReporter::finish() {
  if (line_open_) std::fprintf(stderr, "\r%90s\r", "");
  line_open_ = false;
}

void ProgressReporter::say(const std::string& what) {
  // On a terminal the line first clears a progress line that may be open.
  setInterruptMessage((terminal_ ? "\r\033[K" : "") + ("strike " + command_ + ": " + what));
}

void ProgressReporter::written(const std::string& path) {
  say("interrupted after writing " + path + " (nothing else was written)");
}

}  // namespace strike::cli
