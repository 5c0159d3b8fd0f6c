// SPDX-License-Identifier: MIT
// The near triangles' quadrature of every collocation point, chosen once per cut and reused
// for every wavenumber (only e^{ikr} is evaluated per mode).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

#include "clusters.hpp"
#include "quadrature.hpp"
#include "surface.hpp"

namespace strike::transfer {

/// Is triangle t (centroid c, longest edge d) near x: too close for one point with its moments
/// (integrateTriangle's test), so integrated by a finer rule or subdivided. One expression for
/// every caller, so that they agree to the bit.
inline bool nearLeaf(const V3& x, const V3& c, double d) {
  const double dx = c[0] - x[0], dy = c[1] - x[1], dz = c[2] - x[2];
  return !(std::sqrt(dx * dx + dy * dy + dz * dz) > kFarRatio * d);
}

/// The quadrature of the near triangles of each collocation point, which does not depend on the
/// wavenumber once its rules are chosen: chosen once per cut at a wavenumber k_ref at least the
/// solve's (a rule fine enough at k_ref is at every lower k), then every mode only evaluates
/// e^{ikr} at the stored distances. Per point: int G += w_g G(r), int dG/dn += w_dn dG/dr / r.
struct NearCache {
  std::vector<size_t> begin;                // per row: its points are [begin[row], begin[row + 1])
  std::vector<double> r, inv_r, w_g, w_dn;  // per point
  std::vector<uint32_t> tri;                // per point: the triangle (its cluster and data)
  std::vector<size_t> near_begin;           // per row: its near triangles
  std::vector<uint32_t> near_tris;          // their points: [near_first[i], near_first[i + 1])
  std::vector<size_t> near_first;
};

/// The bytes the caches hold (their vectors' capacities).
size_t nearCacheBytes(const NearCache& cache);
size_t nearCacheBytes(const std::map<size_t, NearCache>& caches);

/// The near quadrature of every row of `cut`, then of every interior candidate, at k_ref.
NearCache buildNearCache(const Surface& s, const Cut& cut, double k_ref);

/// Whether a node's triangles are all far from x (none of them near, nearLeaf), with a margin
/// that rounding cannot cross.
/// (Pieces::clear_of_near holds the same bound.)
inline bool noNearLeaf(const Node& n, double dist) { return dist > 1.001 * (n.radius + kFarRatio * n.max_edge); }

}  // namespace strike::transfer
