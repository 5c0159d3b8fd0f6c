// SPDX-License-Identifier: MIT
// `strike cache list|size|prune`: the bank cache of `strike render` (strike/cache/bank_cache.hpp).
#include <algorithm>
#include <cstdio>
#include <ctime>

#include "args.hpp"
#include "commands.hpp"
#include "strike/bank/bank.hpp"
#include "strike/cache/bank_cache.hpp"
#include "strike/scene/render.hpp"

namespace strike::cli {
namespace {

CommandSpec cacheSpec() {
  CommandSpec spec;
  spec.usage = "strike cache list|size|prune [--cache DIR] [--older-than AGE] [--max-size SIZE] [--dry-run]";
  spec.summary =
      "The mode bank cache of `strike render`: one file per distinct object (mesh, material, order, size,\n"
      "cut-off), named by its content hash. `list` shows each bank (size, last use, mesh, material, modes),\n"
      "least recently used first; `size` prints the total; `prune` removes banks last used longer ago than\n"
      "--older-than, then the least recently used until the rest fit in --max-size. A render marks the banks\n"
      "it reads as used, and after each render the cache is pruned to 2 GiB (`strike render --cache-max-size`).\n"
      "Removal is safe while renders run: a render reading a bank keeps its open file; one that finds it gone\n"
      "computes it again.";
  spec.options = {
      {"--cache", "DIR", "cache folder; default $STRIKE_CACHE_DIR, else $XDG_CACHE_HOME/strike, else ~/.cache/strike"},
      {"--older-than", "AGE",
       "prune: remove banks last used longer ago than AGE (30d, 12h, 90m, 45s; a number is days)"},
      {"--max-size", "SIZE", "prune: then remove the least recently used until the cache fits in SIZE (500M, 2G)"},
      {"--dry-run", "", "prune: say what would be removed, remove nothing"},
  };
  spec.examples =
      "  strike cache list\n  strike cache size --cache /tmp/strike-cache\n  strike cache prune --older-than 30d\n"
      "  strike cache prune --max-size 500M --dry-run\n";
  spec.min_positional = 1;
  spec.max_positional = 1;
  return spec;
}

std::string megabytes(uint64_t bytes) {
  char text[32];
  if (bytes < 100000)
    std::snprintf(text, sizeof text, "%.1f KB", double(bytes) / 1e3);
  else
    std::snprintf(text, sizeof text, "%.1f MB", double(bytes) / 1e6);
  return text;
}

std::string age(std::time_t then, std::time_t now) {
  const double s = std::difftime(now, then);
  char text[32];
  if (s < 3600)
    std::snprintf(text, sizeof text, "%.0f min ago", s / 60);
  else if (s < 86400 * 2)
    std::snprintf(text, sizeof text, "%.1f h ago", s / 3600);
  else
    std::snprintf(text, sizeof text, "%.0f days ago", s / 86400);
  return text;
}

}  // namespace

int runCache(const std::vector<std::string>& raw_args) {
  const CommandSpec spec = cacheSpec();
  if (wantsHelp(raw_args)) {
    std::fputs(helpText(spec).c_str(), stdout);
    return 0;
  }
  Result<ParsedArgs> parsed = parseArgs(spec, raw_args);
  if (!parsed) return reportError("cache", parsed.error());
  const ParsedArgs& args = *parsed;
  const std::string action = args.positional[0];
  const std::string dir = args.text("--cache", defaultCacheDir());
  if (dir.empty())
    return reportError("cache", badInput("no cache folder: set HOME or STRIKE_CACHE_DIR, or give --cache DIR"));
  const std::time_t now = std::time(nullptr);
  if (action == "list" || action == "size") {
    if (args.has("--older-than") || args.has("--max-size") || args.has("--dry-run"))
      return reportError("cache",
                         badInput("--older-than, --max-size and --dry-run are options of `strike cache prune`"));
    Result<std::vector<CacheEntry>> entries = listCache(dir);
    if (!entries) return reportError("cache", entries.error());
    uint64_t total = 0;
    for (const CacheEntry& e : *entries) total += e.bytes;
    if (action == "list") {
      std::printf("%-24s %10s  %-14s  %s\n", "bank", "size", "last used", "mesh, material, modes");
      // Hulls are many and tiny (a few hundred bytes each, one per distinct body): one row for all.
      size_t hulls = 0;
      uint64_t hull_bytes = 0;
      std::time_t hull_last_used = 0;
      for (const CacheEntry& e : *entries) {
        const std::string name = e.path.substr(e.path.find_last_of('/') + 1);
        if (name.size() > 5 && name.compare(name.size() - 5, 5, ".hull") == 0) {
          ++hulls;
          hull_bytes += e.bytes;
          hull_last_used = std::max(hull_last_used, e.last_used);
        }
      }
      if (hulls > 0)
        std::printf("%-24s %10s  %-14s  %s\n", ("(" + std::to_string(hulls) + " x .hull)").c_str(),
                    megabytes(hull_bytes).c_str(), age(hull_last_used, now).c_str(),
                    "convex hulls of bodies' surfaces, one per distinct body (docs/contact.md)");
      for (const CacheEntry& e : *entries) {
        const std::string name = e.path.substr(e.path.find_last_of('/') + 1);
        if (name.size() > 5 && name.compare(name.size() - 5, 5, ".hull") == 0) continue;
        if (name.size() > 7 && name.compare(name.size() - 7, 7, ".pieces") == 0) {
          std::printf("%-24s %10s  %-14s  %s\n", name.c_str(), megabytes(e.bytes).c_str(),
                      age(e.last_used, now).c_str(), "convex pieces of a concave moving body (docs/contact.md)");
          continue;
        }
        Result<BankFile> bank = BankFile::open(e.path);  // the header only: shapes are not read
        std::string what = "(unreadable: " + (bank ? std::string() : bank.error().message) + ")";
        const bool transfer = name.size() > 9 && name.compare(name.size() - 9, 9, ".transfer") == 0;
        if (bank && transfer) {
          char text[512];
          std::snprintf(text, sizeof text, "acoustic transfer of %s at unit size, %zu modes (render --similar)",
                        bank->bank().mesh_source.c_str(), bank->bank().modeCount());
          what = text;
        } else if (bank) {
          char text[512];
          std::snprintf(text, sizeof text, "%s, %s, Tet%d, %zu modes", bank->bank().mesh_source.c_str(),
                        bank->bank().material.name.c_str(), bank->bank().element_order == 2 ? 10 : 4,
                        bank->bank().modeCount());
          what = text;
        }
        std::printf("%-24s %10s  %-14s  %s\n", name.c_str(), megabytes(e.bytes).c_str(), age(e.last_used, now).c_str(),
                    what.c_str());
      }
    }
    std::printf("%s: %zu files, %s (%llu bytes)\n", dir.c_str(), entries->size(), megabytes(total).c_str(),
                static_cast<unsigned long long>(total));
    return 0;
  }
  if (action != "prune")
    return reportError("cache", badInput("unknown action '" + action + "' (known: list, size, prune)"));
  if (!args.has("--older-than") && !args.has("--max-size"))
    return reportError("cache", badInput("prune needs --older-than AGE and/or --max-size SIZE"));
  double max_age_s = -1.0;
  uint64_t max_bytes = 0;
  if (args.has("--older-than")) {
    Result<double> a = parseAgeSeconds(args.text("--older-than"), "--older-than");
    if (!a) return reportError("cache", a.error());
    max_age_s = *a;
  }
  if (args.has("--max-size")) {
    Result<uint64_t> m = parseByteSize(args.text("--max-size"), "--max-size");
    if (!m) return reportError("cache", m.error());
    if (*m == 0)
      return reportError("cache", badInput("--max-size = 0 would empty the cache; remove the folder instead"));
    max_bytes = *m;
  }
  const bool dry_run = args.has("--dry-run");
  Result<PruneReport> pruned = pruneCache(dir, max_bytes, max_age_s, now, dry_run);
  if (!pruned) return reportError("cache", pruned.error());
  for (const std::string& path : pruned->removed_paths)
    std::printf("%s %s\n", dry_run ? "would remove" : "removed", path.c_str());
  std::printf("%s: %s %zu banks (%s), kept %zu (%s)\n", dir.c_str(), dry_run ? "would remove" : "removed",
              pruned->removed, megabytes(pruned->bytes_removed).c_str(), pruned->kept,
              megabytes(pruned->bytes_kept).c_str());
  return 0;
}

}  // namespace strike::cli
