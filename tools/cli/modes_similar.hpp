// SPDX-License-Identifier: MIT
// `strike modes --similar`: the object's normalized solve (src/include/strike/precompute/normalized_problem.hpp)
// from the bank cache that `strike render --similar` fills, or solved and put there, then scaled.
#pragma once

#include <string>

#include "strike/precompute/precompute.hpp"

namespace strike::cli {

struct SimilarSource {
  std::string cache_entry;  ///< the cache file of the normalized solve (empty: no cache)
  bool from_cache = false;  ///< read from it rather than solved
};

/// The bank of `settings`' object, scaled from its normalized solve. With a cache folder the
/// solve is read from there when present (and, if an error estimate is asked for, has one), else
/// solved and written there; so is its unit transfer (KEY.transfer) with settings.acoustic_transfer.
/// The result's modes and transfer do not depend on which.
Result<PrecomputeResult> similarModeBank(const PrecomputeSettings& settings, const std::string& cache_dir,
                                         SimilarSource& source);

}  // namespace strike::cli
