// SPDX-License-Identifier: MIT
// The solver's surface: triangles, bounding-volume tree, interior (CHIEF) points.
#include "surface.hpp"

#include <algorithm>
#include <string>
#include <utility>

namespace strike::transfer {

namespace {

/// Splits triangles recursively: along the widest spread of centroids, or between normals when
/// they spread more than ~60 degrees (so the two faces of a thin plate never share a cluster).
void buildTree(Surface& s) {
  const uint32_t count = static_cast<uint32_t>(s.tris.size());
  s.order.resize(count);
  for (uint32_t i = 0; i < count; ++i) s.order[i] = i;
  s.nodes.clear();
  s.nodes.reserve(2 * count);
  s.nodes.push_back(Node{0, count});
  for (size_t at = 0; at < s.nodes.size(); ++at) {
    const uint32_t begin = s.nodes[at].begin, end = s.nodes[at].end;
    if (end - begin < 2) continue;
    V3 lo = V3::Constant(1e300), hi = V3::Constant(-1e300), nlo = lo, nhi = hi;
    for (uint32_t i = begin; i < end; ++i) {
      const Triangle& t = s.tris[s.order[i]];
      lo = lo.cwiseMin(t.centroid);
      hi = hi.cwiseMax(t.centroid);
      nlo = nlo.cwiseMin(t.normal);
      nhi = nhi.cwiseMax(t.normal);
    }
    const V3 spread = hi - lo, nspread = nhi - nlo;
    int axis = 0, naxis = 0;
    spread.maxCoeff(&axis);
    nspread.maxCoeff(&naxis);
    uint32_t* first = s.order.data() + begin;
    uint32_t* last = s.order.data() + end;
    uint32_t* middle = nullptr;
    if (nspread[naxis] > 1.0) {
      const double cut = 0.5 * (nlo[naxis] + nhi[naxis]);
      middle = std::partition(first, last, [&](uint32_t t) { return s.tris[t].normal[naxis] < cut; });
      if (middle == first || middle == last) middle = nullptr;
    }
    if (!middle) {
      middle = first + (end - begin) / 2;
      std::nth_element(first, middle, last, [&](uint32_t a, uint32_t b) {
        const double ca = s.tris[a].centroid[axis], cb = s.tris[b].centroid[axis];
        return ca < cb || (ca == cb && a < b);  // deterministic on ties
      });
    }
    const uint32_t split = begin + static_cast<uint32_t>(middle - first);
    const int32_t left = static_cast<int32_t>(s.nodes.size());
    s.nodes.push_back(Node{begin, split});
    s.nodes.push_back(Node{split, end});
    s.nodes[left].parent = s.nodes[left + 1].parent = static_cast<int32_t>(at);
    s.nodes[at].left = left;
    s.nodes[at].right = left + 1;
  }
  s.leaf_of_tri.assign(count, -1);
  for (size_t i = 0; i < s.nodes.size(); ++i)
    if (s.nodes[i].leaf()) s.leaf_of_tri[s.order[s.nodes[i].begin]] = static_cast<int32_t>(i);
  // Moments bottom-up (children come after parents).
  for (size_t i = s.nodes.size(); i-- > 0;) {
    Node& n = s.nodes[i];
    if (n.leaf()) {
      const Triangle& t = s.tris[s.order[n.begin]];
      n.centroid = t.centroid;
      n.area = t.area;
      n.vector_area = t.area * t.normal;
      n.radius = 0.0;
      for (const V3& v : t.v) n.radius = std::max(n.radius, (v - t.centroid).norm());
      n.rep = s.order[n.begin];
      n.cov = t.cov;
      n.max_edge = t.diameter;
      continue;
    }
    const Node& a = s.nodes[n.left];
    const Node& b = s.nodes[n.right];
    n.area = a.area + b.area;
    n.centroid = n.area > 0 ? V3((a.area * a.centroid + b.area * b.centroid) / n.area) : V3(a.centroid);
    n.vector_area = a.vector_area + b.vector_area;
    n.max_edge = std::max(a.max_edge, b.max_edge);
    n.radius = std::max((a.centroid - n.centroid).norm() + a.radius, (b.centroid - n.centroid).norm() + b.radius);
    const double da = (s.tris[a.rep].centroid - n.centroid).squaredNorm();
    const double db = (s.tris[b.rep].centroid - n.centroid).squaredNorm();
    n.rep = da <= db ? a.rep : b.rep;
    if (n.area > 0) {
      const V3 oa = a.centroid - n.centroid, ob = b.centroid - n.centroid;
      n.cov = (a.area * (a.cov + oa * oa.transpose()) + b.area * (b.cov + ob * ob.transpose())) / n.area;
    }
  }
}

/// First hit of the ray from `origin` along `dir` with a triangle other than `skip` (Moller-Trumbore).
double rayHit(const Surface& s, const V3& origin, const V3& dir, uint32_t skip) {
  double best = 1e300;
  for (uint32_t t = 0; t < s.tris.size(); ++t) {
    if (t == skip) continue;
    const Triangle& tri = s.tris[t];
    const V3 e1 = tri.v[1] - tri.v[0], e2 = tri.v[2] - tri.v[0];
    const V3 p = dir.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-300) continue;
    const V3 tv = origin - tri.v[0];
    const double u = tv.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const V3 q = tv.cross(e1);
    const double v = dir.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const double dist = e2.dot(q) / det;
    if (dist > 0 && dist < best) best = dist;
  }
  return best;
}

double distanceToSurface(const Surface& s, const V3& x) {
  // Distance to the nearest triangle, bounded below through centroids and radii (enough for
  // choosing interior points well inside).
  double best = 1e300;
  for (const Triangle& t : s.tris) {
    const double d = (x - t.centroid).norm() - 0.5 * t.diameter;
    best = std::min(best, d);
  }
  return best;
}

/// Interior points for CHIEF: along the inward normal of triangles spread over the tree, at
/// varied fractions of the chord to the far side, kept if well away from the surface.
void findInteriorPoints(Surface& s) {
  const size_t triangles = s.tris.size();
  const size_t tries = std::min<size_t>(triangles, 96);
  const double fractions[] = {0.5, 0.3, 0.7, 0.4, 0.6, 0.2, 0.8};
  std::vector<std::pair<double, V3>> found;
  for (size_t i = 0; i < tries; ++i) {
    const uint32_t t = s.order[(i * triangles) / tries + (triangles / tries) / 2];
    const Triangle& tri = s.tris[t];
    const V3 dir = -tri.normal;
    const double chord = rayHit(s, tri.centroid, dir, t);
    if (!(chord < 1e299)) continue;
    const V3 x = tri.centroid + fractions[i % 7] * chord * dir;
    const double depth = distanceToSurface(s, x);
    if (depth > 0.15 * chord && depth > 0) found.push_back({depth, x});
  }
  s.inner_radius = 0.0;
  for (const auto& f : found) s.inner_radius = std::max(s.inner_radius, f.first);
  // Deepest first (the most useful), deterministic.
  std::stable_sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  s.chief_candidates.clear();
  for (const auto& f : found) s.chief_candidates.push_back(f.second);
}

}  // namespace

double surfaceRadius(const ModeBank& bank) {
  const size_t vertices = bank.surfaceVertexCount();
  const V3 centre(bank.centre_m[0], bank.centre_m[1], bank.centre_m[2]);
  double radius = 0.0;
  for (size_t t = 0; t < bank.surface_triangles.size() / 3; ++t) {
    V3 v[3];
    bool valid = true;
    for (int c = 0; c < 3; ++c) {
      const uint32_t at = bank.surface_triangles[3 * t + c];
      valid = valid && at < vertices;
      if (valid)
        v[c] =
            V3(bank.surface_positions[3 * at], bank.surface_positions[3 * at + 1], bank.surface_positions[3 * at + 2]);
    }
    if (!valid || !(0.5 * (v[1] - v[0]).cross(v[2] - v[0]).norm() > 0)) continue;
    for (const V3& corner : v) radius = std::max(radius, (corner - centre).norm());
  }
  return radius;
}

Result<Surface> makeSurface(const ModeBank& bank) {
  Surface s;
  const size_t vertices = bank.surfaceVertexCount();
  const size_t triangles = bank.surface_triangles.size() / 3;
  if (triangles == 0) return badInput("the bank has no surface triangles: no acoustic transfer");
  s.tris.reserve(triangles);
  s.centre = V3(bank.centre_m[0], bank.centre_m[1], bank.centre_m[2]);
  for (size_t t = 0; t < triangles; ++t) {
    Triangle tri;
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = bank.surface_triangles[3 * t + c];
      if (v >= vertices)
        return badInput("surface triangle " + std::to_string(t) + " names vertex " + std::to_string(v));
      tri.v[c] =
          V3(bank.surface_positions[3 * v], bank.surface_positions[3 * v + 1], bank.surface_positions[3 * v + 2]);
    }
    const V3 cross = (tri.v[1] - tri.v[0]).cross(tri.v[2] - tri.v[0]);
    tri.area = 0.5 * cross.norm();
    if (!(tri.area > 0)) continue;  // a degenerate triangle carries nothing
    tri.normal = cross.normalized();
    tri.centroid = (tri.v[0] + tri.v[1] + tri.v[2]) / 3.0;
    tri.diameter = std::max({(tri.v[1] - tri.v[0]).norm(), (tri.v[2] - tri.v[1]).norm(), (tri.v[0] - tri.v[2]).norm()});
    for (const V3& v : tri.v) tri.cov += (v - tri.centroid) * (v - tri.centroid).transpose() / 12.0;
    s.area += tri.area;
    s.volume += tri.centroid.dot(cross) / 6.0;  // divergence theorem: V = 1/3 int y.n dS
    for (const V3& v : tri.v) s.radius = std::max(s.radius, (v - s.centre).norm());
    s.tris.push_back(tri);
  }
  if (s.tris.empty()) return badInput("the bank's surface triangles all have zero area");
  // Pieces at most a few triangles across, so that the near ones (walked down the tree, one
  // by one) stay few; the far ones are summed in vectorized loops.
  std::vector<double> edges;
  for (const Triangle& t : s.tris) edges.push_back(t.diameter);
  std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
  s.max_piece_m = kPieceEdges * edges[edges.size() / 2];
  buildTree(s);
  findInteriorPoints(s);
  return s;
}

}  // namespace strike::transfer
