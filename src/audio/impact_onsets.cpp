// SPDX-License-Identifier: MIT
#include "impact_onsets.hpp"

#include <algorithm>
#include <cmath>
#include <deque>

namespace strike::detail {

std::vector<size_t> impactOnsets(const std::vector<double>& x, size_t first_onset, double peak, double rate_hz) {
  std::vector<size_t> onsets;
  if (first_onset >= x.size()) return onsets;
  onsets.push_back(first_onset);
  const size_t block = std::max<size_t>(1, static_cast<size_t>(std::lround(1e-3 * rate_hz)));
  const size_t history_blocks = 25;  // 25 ms: half a period of 20 Hz
  const double rise_ratio = 2.0;     // 6 dB
  const double floor = 1e-3 * peak;  // -60 dB, as the file's onset
  // Block peaks from the first onset on; a sliding maximum over the last history_blocks.
  std::deque<std::pair<size_t, double>> window;  // (block index, peak), decreasing peaks
  size_t index = 0;
  for (size_t start = first_onset; start < x.size(); start += block, ++index) {
    const size_t end = std::min(x.size(), start + block);
    double block_peak = 0.0;
    for (size_t n = start; n < end; ++n) block_peak = std::max(block_peak, std::fabs(x[n]));
    while (!window.empty() && window.front().first + history_blocks < index) window.pop_front();
    const double before = window.empty() ? 0.0 : window.front().second;
    // Only with a full history: in the first 25 ms a low mode's first half period is still
    // rising, and that is not a new impact.
    if (index >= history_blocks && block_peak > floor && block_peak > rise_ratio * before) {
      size_t n = start;
      while (n < end && !(std::fabs(x[n]) > before)) ++n;
      onsets.push_back(n);
    }
    while (!window.empty() && window.back().second <= block_peak) window.pop_back();
    window.emplace_back(index, block_peak);
  }
  return onsets;
}

}  // namespace strike::detail
