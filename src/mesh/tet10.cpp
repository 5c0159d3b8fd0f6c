// SPDX-License-Identifier: MIT
// Tet4 -> Tet10 promotion: one new node at the midpoint of every edge, shared by all tets
// around that edge. Local mid-edge numbering follows Gmsh (element type 11):
// 4:(0,1) 5:(1,2) 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1).
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "strike/mesh/mesh.hpp"

namespace strike {

namespace {
constexpr int kTet10Edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
}  // namespace

TetMesh promoteToTet10(const TetMesh& tet4) {
  if (tet4.order == 2 && tet4.tets.cols() == 10) return tet4;
  const int64_t num_tets = tet4.tets.rows();
  const int64_t num_corner_nodes = tet4.nodes.rows();

  // Sort (edge key, slot) pairs so that equal edges are adjacent; new node ids are handed out
  // in edge-key order, which is deterministic and keeps neighbouring nodes close in memory.
  struct EdgeSlot {
    int64_t key;   // min * N + max
    int64_t slot;  // 6 * tet + local edge
  };
  std::vector<EdgeSlot> slots;
  slots.reserve(static_cast<size_t>(6 * num_tets));
  for (int64_t t = 0; t < num_tets; ++t) {
    for (int e = 0; e < 6; ++e) {
      int64_t a = tet4.tets(t, kTet10Edges[e][0]);
      int64_t b = tet4.tets(t, kTet10Edges[e][1]);
      if (a > b) std::swap(a, b);
      slots.push_back({a * num_corner_nodes + b, 6 * t + e});
    }
  }
  std::sort(slots.begin(), slots.end(),
            [](const EdgeSlot& x, const EdgeSlot& y) { return x.key != y.key ? x.key < y.key : x.slot < y.slot; });

  TetMesh out;
  out.order = 2;
  out.tets.resize(num_tets, 10);
  out.tets.leftCols(4) = tet4.tets.leftCols(4);
  int64_t num_edges = 0;
  for (size_t i = 0; i < slots.size(); ++i) {
    if (i == 0 || slots[i].key != slots[i - 1].key) ++num_edges;
  }
  out.nodes.resize(num_corner_nodes + num_edges, 3);
  out.nodes.topRows(num_corner_nodes) = tet4.nodes;
  int64_t next = num_corner_nodes - 1;
  for (size_t i = 0; i < slots.size(); ++i) {
    if (i == 0 || slots[i].key != slots[i - 1].key) {
      ++next;
      const int64_t a = slots[i].key / num_corner_nodes;
      const int64_t b = slots[i].key % num_corner_nodes;
      out.nodes.row(next) = 0.5 * (tet4.nodes.row(a) + tet4.nodes.row(b));
    }
    out.tets(slots[i].slot / 6, 4 + slots[i].slot % 6) = static_cast<int>(next);
  }
  out.surface = tet4.surface.rows() > 0 ? tet4.surface : extractSurface(out.tets.leftCols(4));
  return out;
}

}  // namespace strike
