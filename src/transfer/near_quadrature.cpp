// SPDX-License-Identifier: MIT
// Building the near quadrature (NearCache) of a cut.
#include "near_quadrature.hpp"

namespace strike::transfer {

namespace {

/// Records the points that integrateTriangle's rules and subdivisions use for a near triangle
/// (depth >= 0 past its one-point test) at wavenumber k.
void nearRule(const V3& x, const V3& a, const V3& b, const V3& c, const V3& normal, double area, double k, int depth,
              uint32_t t, NearCache& out) {
  const V3 m = (a + b + c) / 3.0;
  const RuleChoice choice = chooseRule(x, a, b, c, m, k, depth);
  const double(*rule)[4] = choice.rule;
  const int points = choice.points;
  if (points == 0) {
    const double quarter = 0.25 * area;
    for (const Corners& q : quarters(a, b, c)) nearRule(x, q[0], q[1], q[2], normal, quarter, k, depth + 1, t, out);
    return;
  }
  for (int i = 0; i < points; ++i) {
    const V3 y = rule ? V3(rule[i][0] * a + rule[i][1] * b + rule[i][2] * c) : m;
    const double w = rule ? rule[i][3] * area : area;
    const V3 yx = y - x;
    const double r = yx.norm();
    if (!(r > 0)) continue;
    out.r.push_back(r);
    out.w_g.push_back(w);
    out.w_dn.push_back(w * yx.dot(normal));
    out.tri.push_back(t);
  }
}

}  // namespace

size_t nearCacheBytes(const NearCache& c) {
  return (c.begin.capacity() + c.near_begin.capacity() + c.near_first.capacity()) * sizeof(size_t) +
         (c.r.capacity() + c.inv_r.capacity() + c.w_g.capacity() + c.w_dn.capacity()) * sizeof(double) +
         (c.tri.capacity() + c.near_tris.capacity()) * sizeof(uint32_t);
}

size_t nearCacheBytes(const std::map<size_t, NearCache>& caches) {
  size_t total = 0;
  for (const auto& entry : caches) total += nearCacheBytes(entry.second);
  return total;
}

NearCache buildNearCache(const Surface& s, const Cut& cut, double k_ref) {
  NearCache out;
  const size_t rows = cut.nodes.size() + s.chief_candidates.size();
  std::vector<int32_t> stack;
  for (size_t row = 0; row < rows; ++row) {
    out.begin.push_back(out.r.size());
    out.near_begin.push_back(out.near_tris.size());
    const bool on_surface = row < cut.nodes.size();
    const int64_t host = on_surface ? static_cast<int64_t>(s.nodes[cut.nodes[row]].rep) : -1;
    const V3 x = on_surface ? s.tris[host].centroid : s.chief_candidates[row - cut.nodes.size()];
    // Near triangles: walk down the nodes that may hold one (within 3 longest edges of x).
    stack.assign(1, 0);
    while (!stack.empty()) {
      const Node& n = s.nodes[stack.back()];
      stack.pop_back();
      if (!((n.centroid - x).norm() <= 1.01 * (n.radius + kFarRatio * n.max_edge))) continue;
      if (!n.leaf()) {
        stack.push_back(n.right);
        stack.push_back(n.left);
        continue;
      }
      const uint32_t t = s.order[n.begin];
      const Triangle& tri = s.tris[t];
      if (static_cast<int64_t>(t) != host && !nearLeaf(x, tri.centroid, tri.diameter)) continue;
      out.near_tris.push_back(t);
      out.near_first.push_back(out.r.size());
      if (static_cast<int64_t>(t) == host) {
        // int_T G dS for x the centroid of T (weakly singular): three Duffy-transformed pieces,
        // sum w_iv w_iu e^{ikr} J / (4 pi rho) with r = x_iu rho, i.e. w_g = w_iv w_iu J x_iu
        // against G = e^{ikr} / (4 pi r); int dG/dn_y over a flat triangle through x is 0.
        for (int e = 0; e < 3; ++e) {
          const V3 a = tri.v[e] - x, ab = tri.v[(e + 1) % 3] - tri.v[e];
          const double jacobian = a.cross(ab).norm();
          for (int iv = 0; iv < 8; ++iv) {
            const double rho = (a + kGaussX[iv] * ab).norm();
            for (int iu = 0; iu < 8; ++iu) {
              out.r.push_back(kGaussX[iu] * rho);
              out.w_g.push_back(kGaussW[iv] * kGaussW[iu] * jacobian * kGaussX[iu]);
              out.w_dn.push_back(0.0);
              out.tri.push_back(t);
            }
          }
        }
        continue;
      }
      nearRule(x, tri.v[0], tri.v[1], tri.v[2], tri.normal, tri.area, k_ref, 0, t, out);
    }
  }
  out.begin.push_back(out.r.size());
  out.near_begin.push_back(out.near_tris.size());
  out.near_first.push_back(out.r.size());
  out.inv_r.resize(out.r.size());
  for (size_t i = 0; i < out.r.size(); ++i) out.inv_r[i] = 1.0 / out.r[i];
  return out;
}

}  // namespace strike::transfer
