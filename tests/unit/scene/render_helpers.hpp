// SPDX-License-Identifier: MIT
// Helpers of the end-to-end render tests (rolling_sound_test.cpp, spoon_scrape_test.cpp): a
// render with its own bank cache, and the level of a stretch of the output.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike::render_helpers {

/// renderScene with its banks cached in `cache_dir`; an empty result (and a failed expectation)
/// when it fails.
inline RenderResult renderCached(const Scene& scene, const std::string& cache_dir) {
  RenderSettings settings;
  settings.cache_dir = cache_dir;
  Result<RenderResult> out = renderScene(scene, settings);
  EXPECT_TRUE(out) << (out ? "" : out.error().message);
  return out ? *out : RenderResult{};
}

/// Root mean square of the samples x from t0 to t1 seconds (0 for an empty stretch).
inline double rms(const std::vector<float>& x, double t0, double t1, double rate) {
  double s = 0;
  size_t n = 0;
  for (size_t i = static_cast<size_t>(t0 * rate); i < static_cast<size_t>(t1 * rate) && i < x.size(); ++i, ++n)
    s += double(x[i]) * x[i];
  return n ? std::sqrt(s / n) : 0.0;
}

}  // namespace strike::render_helpers
