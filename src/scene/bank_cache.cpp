// SPDX-License-Identifier: MIT
#include "strike/bank_cache.hpp"

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

/// A cache entry: 16 hex digits and .modes (a bank) or .pieces (a body's convex pieces, written
/// beside its bank by the render; pruned like banks, and recomputed when missing).
bool isEntryName(const std::string& name) {
  if (name.size() < 17) return false;
  const std::string suffix = name.substr(16);
  if (suffix != ".modes" && suffix != ".pieces") return false;
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

Result<PruneReport> pruneCache(const std::string& dir, uint64_t max_bytes, double max_age_s, std::time_t now, bool dry_run) {
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

Result<uint64_t> parseByteSize(const std::string& text, const std::string& what) {
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  std::string unit(end ? end : "");
  for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (unit.size() > 1 && unit.back() == 'B') unit.pop_back();  // "MB", "GiB" -> "M", "Gi"
  if (unit.size() == 2 && unit[1] == 'I') unit.pop_back();
  double scale = 0;
  if (unit.empty()) scale = 1;
  else if (unit == "K") scale = 1024.0;
  else if (unit == "M") scale = 1024.0 * 1024;
  else if (unit == "G") scale = 1024.0 * 1024 * 1024;
  else if (unit == "T") scale = 1024.0 * 1024 * 1024 * 1024;
  if (text.empty() || end == text.c_str() || scale == 0 || !std::isfinite(value) || value < 0 || errno == ERANGE ||
      value * scale > 1.8e19)
    return badInput(what + " = '" + text + "' (expected a size such as 500M, 2G or a number of bytes)");
  return static_cast<uint64_t>(std::llround(value * scale));
}

Result<double> parseAgeSeconds(const std::string& text, const std::string& what) {
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  const std::string unit(end ? end : "");
  double scale = 0;
  if (unit.empty() || unit == "d") scale = 86400;
  else if (unit == "h") scale = 3600;
  else if (unit == "m") scale = 60;
  else if (unit == "s") scale = 1;
  if (text.empty() || end == text.c_str() || scale == 0 || !std::isfinite(value) || value < 0 || errno == ERANGE)
    return badInput(what + " = '" + text + "' (expected an age such as 30d, 12h, 90m or 45s)");
  return value * scale;
}

}  // namespace strike
