// SPDX-License-Identifier: MIT
// The acoustic transfer solver: collocation BEM on clusters of the bank's surface triangles,
// CHIEF points, spherical-harmonic far field (src/include/strike/transfer_solver.hpp).
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <string>
#include <vector>

#include "strike/transfer_solver.hpp"

namespace strike {
namespace {

using cd = std::complex<double>;
using V3 = Eigen::Vector3d;
constexpr double kFourPi = 4.0 * M_PI;

// Accuracy knobs of the quadrature (checked by the analytic-sphere tests).
constexpr double kFarRatio = 3.0;       // a cell is "far" from x beyond this many diameters
constexpr double kCellPhase = 0.6;      // a triangle's 1-point rule: k D at most this (3-point: twice)
constexpr double kPointPhase = 2.0;     // a far piece as one point with its phase spread: k D at most this
constexpr double kNearRatio = 2.5;      // a triangle's 3-point rule: this many diameters away
constexpr int kNearMaxDepth = 7;        // subdivision levels at most (4^7 pieces)
constexpr double kFarFieldPhase = 0.5;  // far-field projection cells: kappa D at most this

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// 8-point Gauss-Legendre on [0, 1].
constexpr double kGaussX[8] = {0.019855071751231856, 0.10166676129318664, 0.2372337950418355, 0.4082826787521751,
                               0.5917173212478249,   0.7627662049581645,  0.8983332387068134, 0.9801449282487681};
constexpr double kGaussW[8] = {0.05061426814518813, 0.11119051722668724, 0.15685332293894363, 0.18134189168918100,
                               0.18134189168918100, 0.15685332293894363, 0.11119051722668724, 0.05061426814518813};

struct Triangle {
  V3 v[3];
  V3 centroid;
  V3 normal;  // unit, outward
  double area = 0.0;
  double diameter = 0.0;                          // longest edge
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  // covariance of the points of the triangle
};

// A node of the bounding-volume tree over the triangles: a contiguous range of `order`.
struct Node {
  uint32_t begin = 0, end = 0;
  int32_t left = -1, right = -1, parent = -1;
  V3 centroid = V3::Zero();     // area-weighted
  V3 vector_area = V3::Zero();  // sum of area * normal
  double area = 0.0;
  double radius = 0.0;  // every point of its triangles lies within this of the centroid
  uint32_t rep = 0;     // triangle whose centroid is nearest the node's: its collocation point
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  // covariance of its points about the centroid
  bool leaf() const { return left < 0; }
};

struct Surface {
  std::vector<Triangle> tris;
  std::vector<uint32_t> order;  // triangles in tree order
  std::vector<Node> nodes;      // nodes[0] is the root; children after parents
  V3 centre = V3::Zero();
  double radius = 0.0;  // of the surface about centre
  double area = 0.0;
  double volume = 0.0;
  std::vector<V3> chief_candidates;  // interior points, deepest kind first
  double inner_radius = 0.0;         // largest distance of a candidate from the surface
};

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
      continue;
    }
    const Node& a = s.nodes[n.left];
    const Node& b = s.nodes[n.right];
    n.area = a.area + b.area;
    n.centroid = n.area > 0 ? V3((a.area * a.centroid + b.area * b.centroid) / n.area) : V3(a.centroid);
    n.vector_area = a.vector_area + b.vector_area;
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
  buildTree(s);
  findInteriorPoints(s);
  return s;
}

// ---- kernels ---------------------------------------------------------------------------------

struct Kernel {
  cd g;      // G(x, y)
  cd dg_dr;  // dG/dr divided by r: grad_y G = dg_dr * (y - x)
};

inline Kernel kernel(double k, double r) {
  const cd e = std::polar(1.0, k * r);
  const double inv_r = 1.0 / r;
  const cd g = e * (inv_r / kFourPi);
  return {g, g * cd(-inv_r * inv_r, k * inv_r)};  // e^{ikr}(ikr - 1) / (4 pi r^3)
}

// Symmetric rules on a triangle (barycentric weights, weights summing to 1): 3 points of
// degree 2 (Strang & Fix) and 7 points of degree 5 (Dunavant 1985).
constexpr double kRule3[3][4] = {
    {2.0 / 3, 1.0 / 6, 1.0 / 6, 1.0 / 3}, {1.0 / 6, 2.0 / 3, 1.0 / 6, 1.0 / 3}, {1.0 / 6, 1.0 / 6, 2.0 / 3, 1.0 / 3}};
constexpr double kA1 = 0.059715871789770, kB1 = 0.470142064105115, kW1 = 0.132394152788506;
constexpr double kA2 = 0.797426985353087, kB2 = 0.101286507323456, kW2 = 0.125939180544827;
constexpr double kRule7[7][4] = {{1.0 / 3, 1.0 / 3, 1.0 / 3, 0.225},
                                 {kA1, kB1, kB1, kW1},
                                 {kB1, kA1, kB1, kW1},
                                 {kB1, kB1, kA1, kW1},
                                 {kA2, kB2, kB2, kW2},
                                 {kB2, kA2, kB2, kW2},
                                 {kB2, kB2, kA2, kW2}};

/// The mean of e^{ik(r(y) - r(c))} over a piece with centroid c and covariance C, seen from x at
/// distance r along rhat: to second order, 1 - k^2 rhat.C.rhat / 2 (the phase's spread across the
/// piece) + ik (tr C - rhat.C.rhat) / (2r) (the wavefront's curvature). It lets one point stand
/// for a piece up to k D ~ 2 (the next term, k^4 <(rhat.d)^4> / 24, is ~0.3% there).
inline cd phaseSpread(double k, const Eigen::Matrix3d& cov, const V3& yx, double r) {
  const V3 rhat = yx / r;
  const double along = rhat.dot(cov * rhat);
  return cd(1.0 - 0.5 * k * k * along, k * (cov.trace() - along) / (2.0 * r));
}

/// int_T G dS and int_T dG/dn_y dS for x not on T: a rule of the degree that T's size in
/// wavelengths and its distance from x ask for, or four halves when x is too near.
void integrateTriangle(const V3& x, const V3& a, const V3& b, const V3& c, const V3& normal, double area, double k,
                       int depth, cd& int_g, cd& int_dg) {
  if (depth == 0) {  // a far whole triangle: one point with its phase spread
    const V3 m = (a + b + c) / 3.0, yx = m - x;
    const double d = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()}), r = yx.norm();
    if (r > kFarRatio * d && k * d <= kPointPhase) {
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (const V3* v : {&a, &b, &c}) cov += (*v - m) * (*v - m).transpose() / 12.0;
      const Kernel kr = kernel(k, r);
      const cd spread = phaseSpread(k, cov, yx, r);
      int_g += area * kr.g * spread;
      int_dg += area * kr.dg_dr * yx.dot(normal) * spread;
      return;
    }
  }
  const V3 m = (a + b + c) / 3.0;
  const double d = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  const double dist = (x - m).norm();
  const double kd = k * d;
  const double(*rule)[4] = nullptr;
  int points = 0;
  if (dist > kFarRatio * d && kd <= kCellPhase) {
    points = 1;
  } else if (dist > kNearRatio * d && kd <= 2.0 * kCellPhase) {
    rule = kRule3;
    points = 3;
  } else if ((dist > 2.0 * d && kd <= 2.5) || depth >= kNearMaxDepth) {
    rule = kRule7;
    points = 7;
  }
  if (points == 0) {
    const V3 ab = 0.5 * (a + b), bc = 0.5 * (b + c), ca = 0.5 * (c + a);
    const double quarter = 0.25 * area;
    integrateTriangle(x, a, ab, ca, normal, quarter, k, depth + 1, int_g, int_dg);
    integrateTriangle(x, ab, b, bc, normal, quarter, k, depth + 1, int_g, int_dg);
    integrateTriangle(x, ca, bc, c, normal, quarter, k, depth + 1, int_g, int_dg);
    integrateTriangle(x, ab, bc, ca, normal, quarter, k, depth + 1, int_g, int_dg);
    return;
  }
  for (int i = 0; i < points; ++i) {
    const V3 y = rule ? V3(rule[i][0] * a + rule[i][1] * b + rule[i][2] * c) : m;
    const double w = rule ? rule[i][3] * area : area;
    const V3 yx = y - x;
    const double r = yx.norm();
    if (!(r > 0)) continue;
    const Kernel kr = kernel(k, r);
    int_g += w * kr.g;
    int_dg += w * kr.dg_dr * yx.dot(normal);
  }
}

/// int_T G dS for x the centroid of T (weakly singular): three Duffy-transformed pieces.
cd selfTriangle(const Triangle& t, double k) {
  const V3 x = t.centroid;
  cd sum = 0.0;
  for (int e = 0; e < 3; ++e) {
    const V3 a = t.v[e] - x, ab = t.v[(e + 1) % 3] - t.v[e];
    const double jacobian = a.cross(ab).norm();  // 2 * area of the piece
    for (int iv = 0; iv < 8; ++iv) {
      const double rho = (a + kGaussX[iv] * ab).norm();  // r = u rho
      cd inner = 0.0;
      for (int iu = 0; iu < 8; ++iu) inner += kGaussW[iu] * std::polar(1.0, k * kGaussX[iu] * rho);
      sum += kGaussW[iv] * inner * (jacobian / (kFourPi * rho));
    }
  }
  return sum;
}

// ---- one mode: boundary data, the system, the far field -------------------------------------

/// Per-node integrals of the boundary data q = dp/dn (real: the shapes are real): Q = int q dS
/// and the first moment D = int (y - centroid) q dS.
struct NodeData {
  std::vector<double> q;  // per triangle
  std::vector<double> Q;  // per node
  std::vector<V3> D;      // per node
};

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

/// The cut of the tree into clusters of radius at most r (or single triangles).
struct Cut {
  std::vector<int32_t> cluster_of_node;  // -1 above the cut
  std::vector<int32_t> nodes;            // per cluster: its node
};

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

/// The cut with about `wanted` clusters (bisection on the radius; the count falls as r grows).
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

/// Coarse partition for the error estimate: each cluster goes to its parent node, keeping only
/// the outermost of nested parents. coarse[c] is cluster c's coarse index; rows[j] is the fine
/// cluster whose collocation point serves coarse cluster j (the one nearest its centroid).
struct Coarse {
  std::vector<int32_t> of_cluster;
  std::vector<int32_t> row_cluster;
  size_t count = 0;
};

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

/// One row of the system at x: M[col] += int_cluster dG/dn_y, and int G q over the surface.
/// host: the triangle x is the centroid of (-1 for interior points).
void assembleRow(const Surface& s, const Cut& cut, const NodeData& data, double k, const V3& x, int64_t host, cd* M,
                 cd& lq, std::vector<int32_t>& stack) {
  stack.clear();
  stack.push_back(0);
  while (!stack.empty()) {
    const int32_t i = stack.back();
    stack.pop_back();
    const Node& n = s.nodes[i];
    const int32_t col = cut.cluster_of_node[i];
    const V3 yx = n.centroid - x;
    const double dist = yx.norm();
    const double diameter = 2.0 * n.radius;
    if (col >= 0 && dist > kFarRatio * diameter && k * diameter <= kPointPhase) {
      const Kernel kr = kernel(k, dist);
      const cd spread = phaseSpread(k, n.cov, yx, dist);
      M[col] += kr.dg_dr * yx.dot(n.vector_area) * spread;
      lq += (kr.g * data.Q[i] + kr.dg_dr * yx.dot(data.D[i])) * spread;
      continue;
    }
    if (!n.leaf()) {
      stack.push_back(n.left);
      stack.push_back(n.right);
      continue;
    }
    const uint32_t t = s.order[n.begin];
    const Triangle& tri = s.tris[t];
    if (static_cast<int64_t>(t) == host) {
      lq += selfTriangle(tri, k) * data.q[t];  // int dG/dn_y over a flat triangle through x is 0
      continue;
    }
    cd int_g = 0.0, int_dg = 0.0;
    integrateTriangle(x, tri.v[0], tri.v[1], tri.v[2], tri.normal, tri.area, k, 0, int_g, int_dg);
    M[col] += int_dg;
    lq += int_g * data.q[t];
  }
}

/// Spherical Bessel j_0..j_n at x (Miller's downward recurrence, normalized by j_0 or j_1).
void sphericalBessel(int n, double x, double* out) {
  if (x < 1e-12) {
    out[0] = 1.0;
    for (int i = 1; i <= n; ++i) out[i] = 0.0;
    return;
  }
  const int start = std::max(n, static_cast<int>(x)) + 16 + static_cast<int>(std::sqrt(40.0 * std::max<double>(n, x)));
  double next = 0.0, cur = 1e-300;
  for (int i = start; i > 0; --i) {
    const double prev = (2.0 * i + 1.0) / x * cur - next;
    next = cur;
    cur = prev;
    if (i - 1 <= n) out[i - 1] = cur;
    if (i <= n) out[i] = next;
    if (std::abs(cur) > 1e200) {
      cur *= 1e-200;
      next *= 1e-200;
      for (int j = i - 1; j <= n; ++j)
        if (j >= 0) out[j] *= 1e-200;
    }
  }
  const double j0 = std::sin(x) / x, j1 = std::sin(x) / (x * x) - std::cos(x) / x;
  const double scale = std::abs(j0) >= std::abs(j1) ? j0 / out[0] : j1 / out[1];
  for (int i = 0; i <= n; ++i) out[i] *= scale;
}

/// A point of the far-field quadrature.
struct FarPoint {
  V3 y;
  V3 vector_area;  // for the p term: int p dG_inf/dn ~= p grad f . vector_area
  double Q;        // int q over the piece (first moment folded in by small pieces)
  int32_t cluster;
};

void farFieldPoints(const Surface& s, const Cut& cut, const NodeData& data, double kappa,
                    std::vector<FarPoint>& points) {
  points.clear();
  std::vector<int32_t> stack{0};
  while (!stack.empty()) {
    const int32_t i = stack.back();
    stack.pop_back();
    const Node& n = s.nodes[i];
    const int32_t cluster = cut.cluster_of_node[i];
    if (cluster >= 0 && 2.0 * n.radius * kappa <= kFarFieldPhase) {
      points.push_back({n.centroid, n.vector_area, data.Q[i], cluster});
      continue;
    }
    if (!n.leaf()) {
      stack.push_back(n.left);
      stack.push_back(n.right);
      continue;
    }
    const Triangle& t = s.tris[s.order[n.begin]];
    const double q = data.q[s.order[n.begin]] * t.area / 3.0;
    const V3 va = t.normal * (t.area / 3.0);
    points.push_back({(4.0 * t.v[0] + t.v[1] + t.v[2]) / 6.0, va, q, cluster});
    points.push_back({(t.v[0] + 4.0 * t.v[1] + t.v[2]) / 6.0, va, q, cluster});
    points.push_back({(t.v[0] + t.v[1] + 4.0 * t.v[2]) / 6.0, va, q, cluster});
  }
}

/// Spherical-harmonic coefficients of the far field, c_nm = (-i)^n int (p d/dn - q) f_nm dS with
/// f_nm(y) = j_n(k |y - c|) Y_nm(y - c) (the plane wave's expansion, Colton & Kress 2013, 2.46),
/// for two pressure vectors at once (the solution and the coarse solve's difference).
void projectFarField(const Surface& s, const std::vector<FarPoint>& points, double k, int n_cap,
                     const Eigen::VectorXcd& p, const Eigen::VectorXcd& dp, std::vector<cd>& coef,
                     std::vector<cd>& dcoef) {
  const size_t count = static_cast<size_t>((n_cap + 1) * (n_cap + 1));
  coef.assign(count, 0.0);
  dcoef.assign(count, 0.0);
  std::vector<double> f0(count), fp(count), fm(count), j(n_cap + 1), jp(n_cap + 1), jm(n_cap + 1);
  const double kappa = std::max(k, (n_cap + 1.0) / s.radius);
  const double eps = 1e-4 / kappa;
  auto evaluate = [&](const V3& y, double* f, double* jn) {
    const V3 r = y - s.centre;
    const double d[3] = {r[0], r[1], r[2]};
    realSphericalHarmonics(static_cast<uint32_t>(n_cap), d, f);
    sphericalBessel(n_cap, k * r.norm(), jn);
    for (int n = 0; n <= n_cap; ++n)
      for (int m = -n; m <= n; ++m) f[n * n + n + m] *= jn[n];
  };
  for (const FarPoint& pt : points) {
    const double area = pt.vector_area.norm();
    evaluate(pt.y, f0.data(), j.data());
    const cd pc = p[pt.cluster], dpc = dp[pt.cluster];
    if (area > 0) {
      const V3 step = pt.vector_area * (eps / area);
      evaluate(pt.y + step, fp.data(), jp.data());
      evaluate(pt.y - step, fm.data(), jm.data());
      const double scale = area / (2.0 * eps);
      for (size_t i = 0; i < count; ++i) {
        const double df = (fp[i] - fm[i]) * scale;
        coef[i] += pc * df - pt.Q * f0[i];
        dcoef[i] += dpc * df;
      }
    } else {
      for (size_t i = 0; i < count; ++i) coef[i] -= pt.Q * f0[i];
    }
  }
  cd phase = 1.0;  // (-i)^n
  for (int n = 0; n <= n_cap; ++n) {
    for (int m = -n; m <= n; ++m) {
      coef[n * n + n + m] *= phase;
      dcoef[n * n + n + m] *= phase;
    }
    phase *= cd(0.0, -1.0);
  }
}

struct ModeSolve {
  Eigen::VectorXcd p;       // per cluster
  Eigen::VectorXcd p_diff;  // p minus the coarse solve's, per cluster
  size_t elements = 0, chief = 0;
  Cut cut;
};

/// Solves the exterior Neumann problem for boundary data `data` at wavenumber k with `elements`
/// unknowns (about) and `chief` interior points; several right-hand sides are not needed here.
ModeSolve solveSystem(const Surface& s, const NodeData& data, double k, size_t elements, size_t chief) {
  ModeSolve out;
  out.cut = cutWithCount(s, elements);
  const Cut& cut = out.cut;
  const size_t n = cut.nodes.size();
  chief = std::min(chief, s.chief_candidates.size());
  const size_t rows = n + chief;
  Eigen::MatrixXcd A = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(n));
  Eigen::VectorXcd b(static_cast<Eigen::Index>(rows));
  std::vector<cd> M(n);
  std::vector<int32_t> stack;
  for (size_t r = 0; r < rows; ++r) {
    std::fill(M.begin(), M.end(), cd(0.0));
    cd lq = 0.0;
    if (r < n) {
      const uint32_t host = s.nodes[cut.nodes[r]].rep;
      assembleRow(s, cut, data, k, s.tris[host].centroid, host, M.data(), lq, stack);
    } else {
      assembleRow(s, cut, data, k, s.chief_candidates[r - n], -1, M.data(), lq, stack);
    }
    // 1/2 p(x) - int p dG/dn = - int G q (x on S); 0 - int p dG/dn = - int G q (x inside).
    for (size_t c = 0; c < n; ++c) A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = -M[c];
    if (r < n) A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(r)) += 0.5;
    b[static_cast<Eigen::Index>(r)] = -lq;
  }
  auto solve = [](const Eigen::MatrixXcd& matrix, const Eigen::VectorXcd& rhs) -> Eigen::VectorXcd {
    if (matrix.rows() == matrix.cols()) return matrix.partialPivLu().solve(rhs);
    return matrix.householderQr().solve(rhs);
  };
  out.p = solve(A, b);
  out.elements = n;
  out.chief = chief;

  // The coarse solve: clusters merged with their siblings, rows a subset, columns summed.
  const Coarse coarse = coarsen(s, cut);
  const size_t nc = coarse.count;
  if (nc < n && nc > 0) {
    Eigen::MatrixXcd Ac = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(nc + chief), static_cast<Eigen::Index>(nc));
    Eigen::VectorXcd bc(static_cast<Eigen::Index>(nc + chief));
    for (size_t j = 0; j < nc + chief; ++j) {
      const size_t fine_row = j < nc ? static_cast<size_t>(coarse.row_cluster[j]) : n + (j - nc);
      for (size_t c = 0; c < n; ++c) {
        cd m = A(static_cast<Eigen::Index>(fine_row), static_cast<Eigen::Index>(c));
        if (fine_row < n && c == fine_row) m -= 0.5;  // the free term goes to the coarse diagonal
        Ac(static_cast<Eigen::Index>(j), coarse.of_cluster[c]) += m;
      }
      if (j < nc) Ac(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)) += 0.5;
      bc[static_cast<Eigen::Index>(j)] = b[static_cast<Eigen::Index>(fine_row)];
    }
    const Eigen::VectorXcd pc = solve(Ac, bc);
    out.p_diff.resize(static_cast<Eigen::Index>(n));
    for (size_t c = 0; c < n; ++c)
      out.p_diff[static_cast<Eigen::Index>(c)] = out.p[static_cast<Eigen::Index>(c)] - pc[coarse.of_cluster[c]];
  } else {
    out.p_diff = Eigen::VectorXcd::Zero(static_cast<Eigen::Index>(n));
  }
  return out;
}

/// Unknowns the target error asks for at wavenumber k, within the budget.
size_t elementsFor(const Surface& s, const TransferSettings& settings, double k) {
  if (settings.fixed_elements > 0) return std::min<size_t>(settings.fixed_elements, s.tris.size());
  // Constant elements: far-field error ~ h^2, so elements per wavelength ~ 1/sqrt(target);
  // 6 per wavelength at 5%.
  const double per_wavelength = 6.0 * std::sqrt(0.05 / std::max(settings.target_relative_error, 1e-4));
  const double h = 2.0 * M_PI / std::max(k, 1e-30) / per_wavelength;
  const double wanted = s.area / (h * h);
  const size_t lo = settings.min_elements, hi = std::max<size_t>(settings.max_elements, lo);
  return std::min(std::clamp(static_cast<size_t>(std::ceil(wanted)), lo, hi), s.tris.size());
}

/// Interior points used at wavenumber k: none below the interior resonance range. The lowest
/// interior Dirichlet eigenvalue of a domain containing a ball of radius r_in is at most
/// pi / r_in (domain monotonicity), and is about that for chunky bodies; thin walls have none in
/// the audible band. Points are added from 0.5 pi / r_in on.
size_t chiefPointsFor(const Surface& s, const TransferSettings& settings, double k, size_t elements) {
  if (!settings.chief || s.chief_candidates.empty() || !(s.inner_radius > 0)) return 0;
  if (k * s.inner_radius < 0.5 * M_PI) return 0;
  return std::min(s.chief_candidates.size(), std::max<size_t>(8, elements / 10));
}

}  // namespace

Result<AcousticTransfer> solveAcousticTransfer(const ModeBank& bank, const TransferSettings& settings,
                                               const ProgressFn& progress, std::vector<TransferModeStats>* stats) {
  const auto start = std::chrono::steady_clock::now();
  if (!(settings.air_density_kg_m3 > 0) || !std::isfinite(settings.air_density_kg_m3))
    return badInput("transfer air density = " + std::to_string(settings.air_density_kg_m3) + " (must be > 0)");
  if (!(settings.speed_of_sound_m_s > 0) || !std::isfinite(settings.speed_of_sound_m_s))
    return badInput("transfer speed of sound = " + std::to_string(settings.speed_of_sound_m_s) + " (must be > 0)");
  if (!(settings.target_relative_error > 0))
    return badInput("transfer target error = " + std::to_string(settings.target_relative_error) + " (must be > 0)");
  const size_t modes = bank.modeCount();
  const size_t vertices = bank.surfaceVertexCount();
  if (bank.shapes.size() != modes * vertices * 3) return badInput("the bank's shapes are not loaded: no transfer");
  Result<Surface> made = makeSurface(bank);
  if (!made) return made.error();
  const Surface& s = *made;
  const double rho = settings.air_density_kg_m3, c_air = settings.speed_of_sound_m_s;

  AcousticTransfer out;
  out.centre_m = bank.centre_m;
  out.air_density_kg_m3 = rho;
  out.speed_of_sound_m_s = c_air;
  out.offset.push_back(0);
  if (stats) stats->assign(modes, {});

  // Triangle -> its three vertex indices (degenerate ones were dropped: match them up again).
  std::vector<std::array<uint32_t, 3>> corners;
  corners.reserve(s.tris.size());
  for (size_t t = 0; t < bank.surface_triangles.size() / 3; ++t) {
    const uint32_t* v = &bank.surface_triangles[3 * t];
    const V3 p0(&bank.surface_positions[3 * v[0]]), p1(&bank.surface_positions[3 * v[1]]),
        p2(&bank.surface_positions[3 * v[2]]);
    if ((p1 - p0).cross(p2 - p0).norm() > 0) corners.push_back({v[0], v[1], v[2]});
  }

  NodeData data;
  std::vector<FarPoint> points;
  std::vector<cd> coef, dcoef;
  for (size_t mode = 0; mode < modes; ++mode) {
    const auto mode_start = std::chrono::steady_clock::now();
    const double omega = std::sqrt(std::max(bank.eigenvalues[mode], 0.0));
    const double k = omega / c_air;
    // q = dp/dn = -rho a_n, a_n the normal component of the shape (per unit modal acceleration).
    data.q.resize(s.tris.size());
    for (size_t t = 0; t < s.tris.size(); ++t) {
      V3 shape = V3::Zero();
      for (uint32_t v : corners[t]) {
        const float* u = bank.shapeAt(mode, v);
        shape += V3(u[0], u[1], u[2]);
      }
      data.q[t] = -rho * s.tris[t].normal.dot(shape / 3.0);
    }
    nodeData(s, data);
    const double kr = k * s.radius;
    const int n_cap = std::min(120, static_cast<int>(std::ceil(kr + 4.0 * std::cbrt(kr))) + 6);
    const double kappa = std::max(k, (n_cap + 1.0) / s.radius);
    // Refine while the estimate exceeds the target and the budget allows: the mode's pattern
    // (not only the wavelength) sets the resolution, and the estimate sees it.
    size_t elements = elementsFor(s, settings, k);
    const size_t cap = settings.fixed_elements > 0 ? elements : std::min<size_t>(settings.max_elements, s.tris.size());
    ModeSolve solved;
    std::vector<double> energy;
    double total = 0.0, diff = 0.0;
    while (true) {
      const size_t chief = chiefPointsFor(s, settings, k, elements);
      solved = solveSystem(s, data, k, elements, chief);
      farFieldPoints(s, solved.cut, data, kappa, points);
      projectFarField(s, points, k, n_cap, solved.p, solved.p_diff, coef, dcoef);
      energy.assign(n_cap + 1, 0.0);
      total = 0.0;
      diff = 0.0;
      for (int n = 0; n <= n_cap; ++n)
        for (int m = -n; m <= n; ++m) {
          energy[n] += std::norm(coef[n * n + n + m]);
          diff += std::norm(dcoef[n * n + n + m]);
        }
      for (double e : energy) total += e;
      if (!(diff > std::pow(settings.target_relative_error, 2) * total) || elements >= cap) break;
      elements = std::min(cap, elements * 5 / 2);
    }

    // Order: the smallest whose tail holds at most 1e-8 of the energy (-80 dB), far below the
    // target, so that the modes of a degenerate pair, truncated apart, still sum basis-free.
    const double tail_allowed = 1e-8 * total;
    int order = n_cap;
    double tail = 0.0;
    while (order > 0 && tail + energy[order] <= tail_allowed) tail += energy[order--];
    // Error: the coarse solve's difference, the dropped tail, and what the last computed orders
    // still hold (a series not yet converged at n_cap).
    const double unresolved = energy[n_cap] + (n_cap > 0 ? energy[n_cap - 1] : 0.0);
    const double relative = total > 0 ? std::sqrt((diff + tail + (order == n_cap ? unresolved : 0.0)) / total) : 0.0;

    out.order.push_back(static_cast<uint32_t>(order));
    for (int i = 0; i < (order + 1) * (order + 1); ++i)
      out.coefficients.push_back(
          std::complex<float>(static_cast<float>(coef[i].real()), static_cast<float>(coef[i].imag())));
    out.offset.push_back(out.coefficients.size());
    out.relative_error.push_back(static_cast<float>(relative));
    if (stats) {
      TransferModeStats& st = (*stats)[mode];
      st.ka = kr;
      st.elements = static_cast<uint32_t>(solved.elements);
      st.chief_points = static_cast<uint32_t>(solved.chief);
      st.order = static_cast<uint32_t>(order);
      st.relative_error = relative;
      st.seconds = secondsSince(mode_start);
    }
    if (progress) progress("transfer", static_cast<double>(mode + 1) / static_cast<double>(modes + 1));
  }

  // Rigid translation in the compact limit: the Laplace problem (k = 0) with dp/dn = -n_j
  // (rho factored out). M_ij = V delta_ij + int n_i p_j dS (docs: from the far field's first
  // order in k, the volume term by the divergence theorem).
  {
    Eigen::Matrix3d dipole = Eigen::Matrix3d::Identity() * s.volume;
    const size_t elements = std::min<size_t>(settings.max_elements, s.tris.size());
    for (int j = 0; j < 3; ++j) {
      data.q.resize(s.tris.size());
      for (size_t t = 0; t < s.tris.size(); ++t) data.q[t] = -s.tris[t].normal[j];
      nodeData(s, data);
      const ModeSolve solved = solveSystem(s, data, 0.0, elements, 0);
      for (size_t c = 0; c < solved.cut.nodes.size(); ++c) {
        const V3 va = s.nodes[solved.cut.nodes[c]].vector_area;
        for (int i = 0; i < 3; ++i) dipole(i, j) += va[i] * solved.p[static_cast<Eigen::Index>(c)].real();
      }
    }
    const Eigen::Matrix3d symmetric = 0.5 * (dipole + dipole.transpose());
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out.translation_dipole_m3[i * 3 + j] = symmetric(i, j);
  }
  if (progress) progress("transfer", 1.0);
  out.solve_seconds = secondsSince(start);
  char method[160];
  std::snprintf(method, sizeof method,
                "bem collocation, clustered constant elements (%u-%u), chief, target %.3g, %zu triangles",
                settings.min_elements, settings.max_elements, settings.target_relative_error, s.tris.size());
  out.method = method;
  return out;
}

}  // namespace strike
