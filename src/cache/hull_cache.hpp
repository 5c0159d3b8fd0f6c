// SPDX-License-Identifier: MIT
// Bodies' convex hulls (SimHull, strike/sim/sim.hpp) cached beside the mode banks, keyed by a hash
// of the points they are the hull of: Bullet's hull of a plate's 14,000 surface points costs
// ~3 ms every render, reading it back ~0.05 ms. The same points give the same hull, bit for bit,
// so a render is the same bytes with the cache cold or warm. Internal to strike_scene.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "strike/core/result.hpp"
#include "strike/sim/sim.hpp"

namespace strike {

/// Content key of a hull: its points, the shrink and its clamp, and the simulator's hull recipe
/// (simHullRecipe: Bullet's version).
uint64_t hullKey(const std::vector<double>& points_xyz, double shrink_m, double shrink_clamp);

/// "<cache_dir>/<16 hex digits>.hull".
std::string hullPath(const std::string& cache_dir, uint64_t key);

/// Reads a hull file written for this key; an error if it is missing, damaged (checksum) or for
/// another key: the caller then computes the hull again.
Result<SimHull> readHull(const std::string& path, uint64_t key);

/// Writes a hull file atomically. Format (little-endian): "STRKHUL1", u64 key, f64 shrink_m,
/// f64 volume_m3, u32 vertex count and 3 f64 per vertex, then u64 FNV-1a of all before.
Status writeHull(const std::string& path, uint64_t key, const SimHull& hull);

/// The simulator's memory of hulls through the cache folder: a hull found there is read, one
/// that is not is computed (through `inner` when given, a RenderSession's) and written.
SimHullMemo cachedHullMemo(const std::string& cache_dir, SimHullMemo inner);

}  // namespace strike
