// SPDX-License-Identifier: MIT
#include "strike/cache/bank_cache.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace strike {
namespace {

namespace fs = std::filesystem;

// A crash can leave a write temporary behind; one older than this belongs to no live write.
constexpr double kStaleTemporarySeconds = 86400.0;

/// A cache entry: 16 hex digits and .modes (a bank), .pieces (a body's convex pieces, written
/// beside its bank by the render), .hull (a body's convex hull, likewise), .transfer (a unit
/// transfer of `--similar` with the transfer, normalized_problem.hpp) or .hrtf (a binaural
/// render's responses at its rate, hrtf_cache.hpp); all pruned alike, and recomputed when missing.
bool isEntryName(const std::string& name) {
  if (name.size() < 17) return false;
  const std::string suffix = name.substr(16);
  if (suffix != ".modes" && suffix != ".pieces" && suffix != ".hull" && suffix != ".transfer" && suffix != ".hrtf")
    return false;
  for (size_t i = 0; i < 16; ++i)
    if (!std::isxdigit(static_cast<unsigned char>(name[i]))) return false;
  return true;
}

bool isTemporaryName(const std::string& name) {
  const size_t tmp = name.find(".tmp-");
  return tmp != std::string::npos && isEntryName(name.substr(0, tmp));
}

}  // namespace

Result<std::vector<CacheEntry>> listCache(const std::string& dir) {
  std::vector<CacheEntry> entries;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return entries;
  if (!fs::is_directory(dir, ec)) return badInput(dir + ": error: the cache is not a folder");
  fs::directory_iterator it(dir, ec);
  if (ec) return badInput(dir + ": error: cannot read the cache folder: " + ec.message());
  for (const fs::directory_entry& file : it) {
    const std::string name = file.path().filename().string();
    if (!isEntryName(name)) continue;
    struct stat st {};
    if (::lstat(file.path().c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;  // removed meanwhile, or not a file
    entries.push_back({file.path().string(), static_cast<uint64_t>(st.st_size), st.st_mtime});
  }
  std::sort(entries.begin(), entries.end(), [](const CacheEntry& a, const CacheEntry& b) {
    return a.last_used != b.last_used ? a.last_used < b.last_used : a.path < b.path;
  });
  return entries;
}

void touchCacheEntry(const std::string& path) { (void)::utimensat(AT_FDCWD, path.c_str(), nullptr, 0); }

Result<PruneReport> pruneCache(const std::string& dir, uint64_t max_bytes, double max_age_s, std::time_t now,
                               bool dry_run) {
  Result<std::vector<CacheEntry>> listed = listCache(dir);
  if (!listed) return listed.error();
  PruneReport report;
  uint64_t total = 0;
  for (const CacheEntry& e : *listed) total += e.bytes;
  auto remove = [&](const CacheEntry& e) {
    // unlink: a reader holding the file open keeps its data until it closes it.
    if (!dry_run && ::unlink(e.path.c_str()) != 0 && errno != ENOENT) return false;
    ++report.removed;
    report.bytes_removed += e.bytes;
    report.removed_paths.push_back(e.path);
    total -= e.bytes;
    return true;
  };
  for (const CacheEntry& e : *listed) {  // least recently used first
    const bool too_old = max_age_s >= 0 && std::difftime(now, e.last_used) > max_age_s;
    const bool over_size = max_bytes > 0 && total > max_bytes;
    if ((too_old || over_size) && remove(e)) continue;
    ++report.kept;
    report.bytes_kept += e.bytes;
  }
  // Write temporaries abandoned by a crash (a live write renames its temporary within seconds).
  std::error_code ec;
  if (fs::is_directory(dir, ec))
    for (const fs::directory_entry& file : fs::directory_iterator(dir, ec)) {
      if (!isTemporaryName(file.path().filename().string())) continue;
      struct stat st {};
      if (::lstat(file.path().c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
      if (std::difftime(now, st.st_mtime) > kStaleTemporarySeconds && !dry_run) ::unlink(file.path().c_str());
    }
  return report;
}

}  // namespace strike
