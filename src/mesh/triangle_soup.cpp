// SPDX-License-Identifier: MIT
// Welding of a surface reader's triangle soup into a SurfaceMesh (triangle_soup.hpp).
#include "triangle_soup.hpp"

#include <algorithm>
#include <cstring>
#include <numeric>

namespace strike::detail {

SurfaceMesh finishSurface(Soup soup, const std::string& path, bool warn_on_weld, std::vector<MeshWarning>* warnings) {
  const size_t nv = soup.xyz.size() / 3;
  for (double& c : soup.xyz) c += 0.0;  // -0.0 -> +0.0, so that they weld
  std::vector<int> order(nv);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const double* pa = &soup.xyz[3 * static_cast<size_t>(a)];
    const double* pb = &soup.xyz[3 * static_cast<size_t>(b)];
    if (pa[0] != pb[0]) return pa[0] < pb[0];
    if (pa[1] != pb[1]) return pa[1] < pb[1];
    if (pa[2] != pb[2]) return pa[2] < pb[2];
    return a < b;
  });
  std::vector<int> representative(nv);
  size_t merged = 0;
  for (size_t i = 0; i < nv;) {
    size_t j = i + 1;
    const double* pi = &soup.xyz[3 * static_cast<size_t>(order[i])];
    while (j < nv && std::memcmp(pi, &soup.xyz[3 * static_cast<size_t>(order[j])], 3 * sizeof(double)) == 0) ++j;
    for (size_t k = i; k < j; ++k) representative[static_cast<size_t>(order[k])] = order[i];
    merged += j - i - 1;
    i = j;
  }
  std::vector<int> kept_tris;
  kept_tris.reserve(soup.tri.size());
  size_t collapsed = 0;
  for (size_t t = 0; t + 2 < soup.tri.size(); t += 3) {
    const int a = representative[static_cast<size_t>(soup.tri[t])];
    const int b = representative[static_cast<size_t>(soup.tri[t + 1])];
    const int c = representative[static_cast<size_t>(soup.tri[t + 2])];
    if (a == b || b == c || c == a) {
      ++collapsed;
      continue;
    }
    kept_tris.insert(kept_tris.end(), {a, b, c});
  }
  std::vector<int> new_id(nv, -1);
  int next = 0;
  for (int v : kept_tris) {
    if (new_id[static_cast<size_t>(v)] < 0) new_id[static_cast<size_t>(v)] = next++;
  }
  // Number vertices in their original order, not first use, to stay close to the file.
  next = 0;
  for (size_t v = 0; v < nv; ++v) {
    if (new_id[v] >= 0) new_id[v] = next++;
  }
  size_t dropped_vertices = 0;
  for (size_t v = 0; v < nv; ++v) {
    if (representative[v] == static_cast<int>(v) && new_id[v] < 0) ++dropped_vertices;
  }
  SurfaceMesh mesh;
  mesh.V.resize(next, 3);
  for (size_t v = 0; v < nv; ++v) {
    if (new_id[v] >= 0) {
      for (int c = 0; c < 3; ++c) mesh.V(new_id[v], c) = soup.xyz[3 * v + static_cast<size_t>(c)];
    }
  }
  mesh.F.resize(static_cast<Eigen::Index>(kept_tris.size() / 3), 3);
  for (size_t t = 0; t < kept_tris.size() / 3; ++t) {
    for (int c = 0; c < 3; ++c)
      mesh.F(static_cast<Eigen::Index>(t), c) = new_id[static_cast<size_t>(kept_tris[3 * t + static_cast<size_t>(c)])];
  }
  if (warnings) {
    if (merged > 0 && warn_on_weld) {
      warnings->push_back(
          {path + ": warning: merged " + std::to_string(merged) + " duplicate vertices (exactly equal coordinates)"});
    }
    if (collapsed > 0) {
      warnings->push_back(
          {path + ": warning: dropped " + std::to_string(collapsed) + " degenerate triangles (a repeated vertex)"});
    }
    if (dropped_vertices > 0) {
      warnings->push_back(
          {path + ": warning: dropped " + std::to_string(dropped_vertices) + " vertices that no triangle uses"});
    }
  }
  return mesh;
}

Error nonFinite(const std::string& where, const char* what, double value) {
  return badInput(where + what + " is " + formatNumber(value, 17) + ", expected a finite number");
}

}  // namespace strike::detail
