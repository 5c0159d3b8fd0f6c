// SPDX-License-Identifier: MIT
// Boundary data per node, the pieces of a solve and their data.
#include "pieces.hpp"

#include "quadrature.hpp"

namespace strike::transfer {

void nodeData(const Surface& s, NodeData& data) {
  data.Q.assign(s.nodes.size(), 0.0);
  data.D.assign(s.nodes.size(), V3::Zero());
  for (size_t i = s.nodes.size(); i-- > 0;) {
    const Node& n = s.nodes[i];
    if (n.leaf()) {
      const uint32_t t = s.order[n.begin];
      data.Q[i] = data.q[t] * s.tris[t].area;
      continue;
    }
    data.Q[i] = data.Q[n.left] + data.Q[n.right];
    data.D[i] = data.D[n.left] + (s.nodes[n.left].centroid - n.centroid) * data.Q[n.left] + data.D[n.right] +
                (s.nodes[n.right].centroid - n.centroid) * data.Q[n.right];
  }
}

Pieces makePieces(const Surface& s, const Cut& cut, double k) {
  Pieces p;
  auto add = [&](int32_t node, int32_t col, bool one_point, int8_t quarter, const V3& centroid, const V3& vector_area,
                 const Eigen::Matrix3d& cov, double diameter) {
    p.node.push_back(node);
    p.col.push_back(col);
    p.one_point.push_back(one_point ? 1 : 0);
    p.quarter.push_back(quarter);
    const Node& n = s.nodes[node];
    p.leaf_tri.push_back(n.leaf() ? static_cast<int64_t>(s.order[n.begin]) : -1);
    p.clear_of_near.push_back(1.001 * (n.radius + kFarRatio * n.max_edge));
    p.x.push_back(centroid[0]);
    p.y.push_back(centroid[1]);
    p.z.push_back(centroid[2]);
    p.ax.push_back(vector_area[0]);
    p.ay.push_back(vector_area[1]);
    p.az.push_back(vector_area[2]);
    p.cxx.push_back(cov(0, 0));
    p.cxy.push_back(cov(0, 1));
    p.cxz.push_back(cov(0, 2));
    p.cyy.push_back(cov(1, 1));
    p.cyz.push_back(cov(1, 2));
    p.czz.push_back(cov(2, 2));
    p.trace.push_back(cov.trace());
    p.diameter.push_back(diameter);
  };
  std::vector<int32_t> stack{0};
  while (!stack.empty()) {
    const int32_t i = stack.back();
    stack.pop_back();
    const Node& n = s.nodes[i];
    const int32_t col = cut.cluster_of_node[i];
    if (n.leaf()) {
      // A single triangle's size is its longest edge (as integrateTriangle judges it); one too
      // large for one point is four quarters (each with its own moments) while they are small
      // enough, else integrated by integrateTriangle's rules.
      const Triangle& t = s.tris[s.order[n.begin]];
      if (k * t.diameter <= kPointPhase || k * t.diameter > 2.0 * kPointPhase) {
        add(i, col, k * t.diameter <= kPointPhase, 0, n.centroid, n.vector_area, n.cov, t.diameter);
        continue;
      }
      const V3 ab = 0.5 * (t.v[0] + t.v[1]), bc = 0.5 * (t.v[1] + t.v[2]), ca = 0.5 * (t.v[2] + t.v[0]);
      const V3 centroids[4] = {(t.v[0] + ab + ca) / 3.0, (ab + t.v[1] + bc) / 3.0, (ca + bc + t.v[2]) / 3.0,
                               (ab + bc + ca) / 3.0};
      for (int8_t q = 0; q < 4; ++q)
        add(i, col, true, static_cast<int8_t>(q + 1), centroids[q], 0.25 * n.vector_area, 0.25 * n.cov,
            0.5 * t.diameter);
      continue;
    }
    const double diameter = 2.0 * n.radius;
    if (col >= 0 && k * diameter <= kPointPhase && diameter <= s.max_piece_m) {
      add(i, col, true, 0, n.centroid, n.vector_area, n.cov, diameter);
      continue;
    }
    stack.push_back(n.right);
    stack.push_back(n.left);
  }
  return p;
}

BigTriangles bigTriangles(const Surface& s, const Pieces& p, double k) {
  BigTriangles big;
  big.of_piece.assign(p.size(), -1);
  big.first.push_back(0);
  for (size_t j = 0; j < p.size(); ++j) {
    if (p.one_point[j] || p.leaf_tri[j] < 0) continue;
    const uint32_t t = static_cast<uint32_t>(p.leaf_tri[j]);
    const Triangle& tri = s.tris[t];
    const V3 &a = tri.v[0], &b = tri.v[1], &c = tri.v[2];
    big.of_piece[j] = static_cast<int32_t>(big.tri.size());
    big.tri.push_back(t);
    big.centroid.push_back((a + b + c) / 3.0);
    big.edge.push_back(longestEdge(a, b, c));
    const RuleChoice far = ruleFor(1e300, big.edge.back(), k, 0);
    big.rule.push_back(far.rule);
    for (int i = 0; far.rule && i < far.points; ++i) {
      big.point.push_back(V3(far.rule[i][0] * a + far.rule[i][1] * b + far.rule[i][2] * c));
      big.weight.push_back(far.rule[i][3] * tri.area);
    }
    big.first.push_back(big.point.size());
  }
  return big;
}

PieceData pieceData(const Surface& s, const Pieces& p, const std::vector<NodeData>& data) {
  PieceData out;
  const size_t count = p.size();
  out.Q.resize(data.size() * count);
  out.Dx.resize(data.size() * count);
  out.Dy.resize(data.size() * count);
  out.Dz.resize(data.size() * count);
  for (size_t r = 0; r < data.size(); ++r)
    for (size_t j = 0; j < count; ++j) {
      const int32_t node = p.node[j];
      if (p.quarter[j] > 0) {  // q is constant on a triangle: a quarter's first moment is 0
        const uint32_t t = s.order[s.nodes[node].begin];
        out.Q[r * count + j] = 0.25 * data[r].q[t] * s.tris[t].area;
        out.Dx[r * count + j] = out.Dy[r * count + j] = out.Dz[r * count + j] = 0.0;
        continue;
      }
      out.Q[r * count + j] = data[r].Q[node];
      out.Dx[r * count + j] = data[r].D[node][0];
      out.Dy[r * count + j] = data[r].D[node][1];
      out.Dz[r * count + j] = data[r].D[node][2];
    }
  return out;
}

}  // namespace strike::transfer
