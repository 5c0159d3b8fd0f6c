// SPDX-License-Identifier: MIT
// Cutting the tree into clusters, and the coarse partition of the error estimate.
#include "clusters.hpp"

namespace strike::transfer {

Cut cutAt(const Surface& s, double r) {
  Cut cut;
  cut.cluster_of_node.assign(s.nodes.size(), -1);
  std::vector<int32_t> stack{0};
  while (!stack.empty()) {
    const int32_t i = stack.back();
    stack.pop_back();
    const Node& n = s.nodes[i];
    if (n.leaf() || n.radius <= r) {
      cut.cluster_of_node[i] = static_cast<int32_t>(cut.nodes.size());
      cut.nodes.push_back(i);
      continue;
    }
    stack.push_back(n.right);
    stack.push_back(n.left);
  }
  // Descendants inherit (children come after parents in `nodes`).
  for (size_t i = 1; i < s.nodes.size(); ++i)
    if (cut.cluster_of_node[i] < 0 && cut.cluster_of_node[s.nodes[i].parent] >= 0)
      cut.cluster_of_node[i] = cut.cluster_of_node[s.nodes[i].parent];
  return cut;
}

namespace {

size_t clusterCount(const Surface& s, double r) {
  size_t count = 0;
  std::vector<int32_t> stack{0};
  while (!stack.empty()) {
    const Node& n = s.nodes[stack.back()];
    stack.pop_back();
    if (n.leaf() || n.radius <= r) {
      ++count;
      continue;
    }
    stack.push_back(n.left);
    stack.push_back(n.right);
  }
  return count;
}

}  // namespace

Cut cutWithCount(const Surface& s, size_t wanted) {
  double lo = 0.0, hi = s.nodes[0].radius * 1.0001;
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (clusterCount(s, mid) > wanted)
      lo = mid;
    else
      hi = mid;
  }
  return cutAt(s, hi);
}

Coarse coarsen(const Surface& s, const Cut& cut) {
  std::vector<char> is_parent(s.nodes.size(), 0);
  for (int32_t node : cut.nodes) is_parent[s.nodes[node].parent >= 0 ? s.nodes[node].parent : node] = 1;
  // Keep the outermost: a marked node with a marked ancestor is dropped (parents come first).
  std::vector<int32_t> owner(s.nodes.size(), -1);
  Coarse coarse;
  std::vector<int32_t> coarse_node;
  for (size_t i = 0; i < s.nodes.size(); ++i) {
    const int32_t parent = s.nodes[i].parent;
    if (parent >= 0 && owner[parent] >= 0) {
      owner[i] = owner[parent];
    } else if (is_parent[i]) {
      owner[i] = static_cast<int32_t>(coarse_node.size());
      coarse_node.push_back(static_cast<int32_t>(i));
    }
  }
  coarse.count = coarse_node.size();
  coarse.of_cluster.resize(cut.nodes.size());
  coarse.row_cluster.assign(coarse.count, -1);
  std::vector<double> best(coarse.count, 1e300);
  for (size_t c = 0; c < cut.nodes.size(); ++c) {
    const int32_t j = owner[cut.nodes[c]];
    coarse.of_cluster[c] = j;
    const double d = (s.tris[s.nodes[cut.nodes[c]].rep].centroid - s.nodes[coarse_node[j]].centroid).squaredNorm();
    if (d < best[j]) {
      best[j] = d;
      coarse.row_cluster[j] = static_cast<int32_t>(c);
    }
  }
  return coarse;
}

}  // namespace strike::transfer
