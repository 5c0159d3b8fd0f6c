// SPDX-License-Identifier: MIT
// What a render rebuilds from identical inputs each time, kept between the renders of one
// process: a batch worker renders thousands of scenes made of the same few shapes, and each
// render would otherwise build every body's convex hull and every struck bank's surface locator
// anew (~3 ms of a 40 ms render of three small objects).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "strike/sim/sim.hpp"

namespace strike {

struct ModeBank;
class BankFile;
class SurfaceLocator;

/// A memory of derived data for the renders of one caller, passed to each through
/// RenderSettings::session. Owned by the caller (no global state), safe to share between
/// threads. Every entry is keyed by the content it was built from (the points of a hull, byte for
/// byte; a bank file's content key), so a render gives the same bytes with or without a session,
/// warm or cold. Bounded: when its entries exceed max_bytes, the least recently used go.
class RenderSession {
 public:
  static constexpr uint64_t kDefaultMaxBytes = uint64_t(64) << 20;  ///< 64 MiB
  explicit RenderSession(uint64_t max_bytes = kDefaultMaxBytes);
  ~RenderSession();
  RenderSession(const RenderSession&) = delete;
  RenderSession& operator=(const RenderSession&) = delete;

  /// A bank file's header (its sharedBank(): everything but the shapes, not copied), and the surface
  /// locator built for that object (SurfaceLocator keeps a pointer to its bank: a voice given this
  /// locator must be given this bank). Built on first use of the file's content.
  struct BankSurface {
    std::shared_ptr<const ModeBank> bank;
    std::shared_ptr<const SurfaceLocator> locator;
  };
  BankSurface bankSurface(const BankFile& file);

  /// The hull of these points (SimHullMemo): remembered, or computed with `compute` now.
  std::shared_ptr<const SimHull> hull(const std::vector<double>& points_xyz, double shrink_m, double shrink_clamp,
                                      const std::function<SimHull()>& compute);
  /// hull() as SimSettings::hull_memo takes it; the session must outlive the simulation.
  SimHullMemo hullMemo();

  struct Stats {
    size_t entries = 0;
    uint64_t bytes = 0;  ///< estimated memory of the entries
    uint64_t max_bytes = 0;
    /// hits: lookups that found their entry; misses: lookups that built it (threads that miss the
    /// same key together each build and count a miss, and all get the entry of the first to
    /// finish: one entry per key); evicted: entries dropped to stay under max_bytes.
    uint64_t hits = 0, misses = 0, evicted = 0;
  };
  Stats stats() const;
  void clear();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace strike
