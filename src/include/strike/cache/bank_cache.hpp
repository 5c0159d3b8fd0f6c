// SPDX-License-Identifier: MIT
// The bank cache folder (`--cache DIR`, default ~/.cache/strike): list, measure and prune it
// (`strike cache`), and the size cap a render applies after writing to it.
//
// Entries are the files "<16 hex digits>.modes" (bankCacheKey's content hash, as the render's bank
// source looks banks up: src/scene/bank_source_direct.cpp), ".pieces" (convex pieces) and
// ".transfer" (the unit transfers of `--similar` renders with the acoustic transfer: a bank file of
// eigenvalues and transfer, no surface; normalized_problem.hpp);
// nothing else in the folder is touched except write temporaries ("*.modes.tmp-*") left behind
// by a crash more than a day ago. A render marks an entry it reads as used (its modification
// time), so pruning removes the least recently used first. Removal is an unlink: a render that
// has the bank open keeps reading it through its descriptor (BankFile reads with pread), and a
// render that opens it after the unlink misses the cache and recomputes. Two prunes at once are
// safe: an entry already gone is skipped.
#pragma once

#include <cstdint>
#include <ctime>
#include <string>
#include <vector>

#include "strike/core/parse_size.hpp"  // the --cache-max-size and --older-than spellings
#include "strike/core/result.hpp"

namespace strike {

/// Default size cap of the cache, applied after every render that wrote to it: 2 GiB (about 80
/// banks of a 137-mode plate). `strike render --cache-max-size` changes it; 0 turns it off.
constexpr uint64_t kDefaultCacheMaxBytes = uint64_t(2) << 30;

struct CacheEntry {
  std::string path;
  uint64_t bytes = 0;
  std::time_t last_used = 0;  ///< modification time: written, or last read by a render
};

/// The cache's entries, least recently used first (ties by name). A missing folder is empty.
Result<std::vector<CacheEntry>> listCache(const std::string& dir);

/// Marks an entry as just used (so the size cap removes it last). Failure is harmless.
void touchCacheEntry(const std::string& path);

struct PruneReport {
  size_t removed = 0, kept = 0;
  uint64_t bytes_removed = 0, bytes_kept = 0;
  std::vector<std::string> removed_paths;
};

/// Removes entries last used more than `max_age_s` before `now` (max_age_s < 0: no age limit),
/// then the least recently used until the rest fit in `max_bytes` (0: no size limit), and stale
/// write temporaries. `dry_run` reports what would go without removing it.
Result<PruneReport> pruneCache(const std::string& dir, uint64_t max_bytes, double max_age_s, std::time_t now,
                               bool dry_run = false);

}  // namespace strike
