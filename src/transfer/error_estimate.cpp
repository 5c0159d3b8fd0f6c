// SPDX-License-Identifier: MIT
// The series' convergence test.
#include "error_estimate.hpp"

namespace strike::transfer {

bool seriesConverged(const std::vector<std::vector<cd>>& coef, const std::vector<char>& done, int n_top) {
  for (size_t r = 0; r < coef.size(); ++r) {
    if (done[r]) continue;
    double total = 0.0, top = 0.0;
    for (int n = 0; n <= n_top; ++n)
      for (int m = -n; m <= n; ++m) {
        const double e = std::norm(coef[r][static_cast<size_t>(n * n + n + m)]);
        total += e;
        if (n >= n_top - 1) top += e;
      }
    if (!(top <= kTailEnergy * total)) return false;
  }
  return true;
}

}  // namespace strike::transfer
