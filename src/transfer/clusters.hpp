// SPDX-License-Identifier: MIT
// The unknowns: the tree cut into clusters (one constant pressure each), and the coarser
// partition of the error estimate (each cluster merged with its sibling).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "surface.hpp"

namespace strike::transfer {

/// The cut of the tree into clusters of radius at most r (or single triangles).
struct Cut {
  std::vector<int32_t> cluster_of_node;  // -1 above the cut
  std::vector<int32_t> nodes;            // per cluster: its node
};

/// The cut into clusters of radius at most r (or single triangles).
Cut cutAt(const Surface& s, double r);

/// The cut with about `wanted` clusters (bisection on the radius; the count falls as r grows).

Cut cutWithCount(const Surface& s, size_t wanted);

/// Coarse partition for the error estimate: each cluster goes to its parent node, keeping only
/// the outermost of nested parents. coarse[c] is cluster c's coarse index; rows[j] is the fine
/// cluster whose collocation point serves coarse cluster j (the one nearest its centroid).
struct Coarse {
  std::vector<int32_t> of_cluster;
  std::vector<int32_t> row_cluster;
  size_t count = 0;
};

Coarse coarsen(const Surface& s, const Cut& cut);

}  // namespace strike::transfer
