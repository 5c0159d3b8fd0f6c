// SPDX-License-Identifier: MIT
// The acoustic transfer solver: collocation BEM on clusters of the bank's surface triangles,
// CHIEF points, spherical-harmonic far field (src/include/strike/transfer_solver.hpp).
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "../modal/two_parts.hpp"
#include "strike/transfer_solver.hpp"

namespace strike {
namespace {

using cd = std::complex<double>;
using V3 = Eigen::Vector3d;
constexpr double kFourPi = 4.0 * M_PI;

// Accuracy knobs of the quadrature (checked by the analytic-sphere tests).
constexpr double kFarRatio = 3.0;    // a cell is "far" from x beyond this many diameters
constexpr double kCellPhase = 0.6;   // a triangle's 1-point rule: k D at most this (3-point: twice)
constexpr double kPointPhase = 2.0;  // a far piece as one point with its phase spread: k D at most this
constexpr double kNearRatio = 2.5;   // a triangle's 3-point rule: this many diameters away
constexpr int kNearMaxDepth = 7;     // subdivision levels at most (4^7 pieces)
constexpr double kPieceEdges = 4.0;  // a row's pieces: at most this many median triangle edges across

// The loops over arrays below write arrays that GCC cannot prove apart from what they read:
// this tells it they are (GCC only; other compilers ignore the hint's absence).
#if defined(__GNUC__) && !defined(__clang__)
#define STRIKE_IVDEP _Pragma("GCC ivdep")
#else
#define STRIKE_IVDEP
#endif

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
  double radius = 0.0;    // every point of its triangles lies within this of the centroid
  double max_edge = 0.0;  // the longest edge of its triangles
  uint32_t rep = 0;       // triangle whose centroid is nearest the node's: its collocation point
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
  std::vector<int32_t> leaf_of_tri;  // the leaf node of each triangle
  double max_piece_m = 1e300;        // pieces of a row's sum: at most this across (makePieces)
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

// ---- kernels ---------------------------------------------------------------------------------

/// sin and cos of a phase (|x| < 2^30; ours are below ~1e4): Cody & Waite's range reduction by
/// pi/2 in three parts, then the minimax polynomials of Cephes (S. Moshier, sin.c) on
/// [-pi/4, pi/4]; within 1 ulp of 1 absolute. Plain branch-free arithmetic (rounding by the
/// 1.5 * 2^52 trick, no floor()), so loops over it vectorize with the baseline instruction set,
/// and the same bits on every x86-64 (no FMA: -ffp-contract=off; libm picks FMA code at run time).
inline void sinCos(double x, double& sin_out, double& cos_out) {
  constexpr double kTwoOverPi = 0.63661977236758134308;
  constexpr double kRound = 6755399441055744.0;   // 1.5 * 2^52: (v + kRound) - kRound rounds v
  constexpr double kP1 = 1.5707963267341256e+00;  // pi/2 = kP1 + kP2 + kP3 (kP1, kP2: 24 bits)
  constexpr double kP2 = 6.0771005065061922e-11;
  constexpr double kP3 = 2.0222662487959506e-21;
  const double q = (x * kTwoOverPi + kRound) - kRound;
  const double r = ((x - q * kP1) - q * kP2) - q * kP3;
  const double z = r * r;
  const double sr = r + r * z *
                            (-1.66666666666666307295e-1 +
                             z * (8.33333333332211858878e-3 +
                                  z * (-1.98412698295895385996e-4 +
                                       z * (2.75573136213857245213e-6 +
                                            z * (-2.50507477628578072866e-8 + z * 1.58962301576546568060e-10)))));
  const double cr = 1.0 - 0.5 * z +
                    z * z *
                        (4.16666666666665929218e-2 +
                         z * (-1.38888888888730564116e-3 +
                              z * (2.48015872888517045348e-5 +
                                   z * (-2.75573141792967388112e-7 +
                                        z * (2.08757008419747316778e-9 - z * 1.13585365213876817300e-11)))));
  const int32_t quadrant = static_cast<int32_t>(q) & 3;
  const double sv = (quadrant & 1) ? cr : sr, cv = (quadrant & 1) ? sr : cr;
  sin_out = (quadrant & 2) ? -sv : sv;
  cos_out = ((quadrant + 1) & 2) ? -cv : cv;
}

inline cd unitPhase(double x) {  // e^{ix}
  double s = 0.0, c = 0.0;
  sinCos(x, s, c);
  return {c, s};
}

void sinCosArray(const double* x, double* sin_out, double* cos_out, size_t n) {
  for (size_t i = 0; i < n; ++i) sinCos(x[i], sin_out[i], cos_out[i]);
}

/// sum_j a_j w_j and sum_j b_j w_j in four fixed interleaved partial sums (vectorizable without
/// reassociating: the same order on every machine).
void dotTwo(const double* a, const double* b, const double* w, size_t n, double& sum_a, double& sum_b) {
  double pa[4] = {0, 0, 0, 0}, pb[4] = {0, 0, 0, 0};
  size_t j = 0;
  for (; j + 4 <= n; j += 4)
    for (int l = 0; l < 4; ++l) {
      pa[l] += a[j + l] * w[j + l];
      pb[l] += b[j + l] * w[j + l];
    }
  for (int l = 0; j < n; ++j, ++l) {
    pa[l] += a[j] * w[j];
    pb[l] += b[j] * w[j];
  }
  sum_a = (pa[0] + pa[1]) + (pa[2] + pa[3]);
  sum_b = (pb[0] + pb[1]) + (pb[2] + pb[3]);
}

struct Kernel {
  cd g;      // G(x, y)
  cd dg_dr;  // dG/dr divided by r: grad_y G = dg_dr * (y - x)
};

inline Kernel kernel(double k, double r) {
  const cd e = unitPhase(k * r);
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

/// The rule for triangle (a, b, c) with centroid m seen from x at wavenumber k, `depth`
/// subdivisions down: 1 point (far and small in wavelengths), the 3- or 7-point rule, or none
/// (points == 0: split into four quarters, at most kNearMaxDepth times). integrateTriangle and
/// the near cache (nearRule) both choose here, so the cached points are the ones it would use.
struct RuleChoice {
  const double (*rule)[4] = nullptr;  // null with one point: the centroid
  int points = 0;
};

/// The choice for a triangle of longest edge d whose centroid is `dist` from x.
inline RuleChoice ruleFor(double dist, double d, double k, int depth) {
  const double kd = k * d;
  if (dist > kFarRatio * d && kd <= kCellPhase) return {nullptr, 1};
  if (dist > kNearRatio * d && kd <= 2.0 * kCellPhase) return {kRule3, 3};
  if ((dist > 2.0 * d && kd <= 2.5) || depth >= kNearMaxDepth) return {kRule7, 7};
  return {nullptr, 0};
}

/// The longest edge of triangle (a, b, c), as chooseRule measures it.
inline double longestEdge(const V3& a, const V3& b, const V3& c) {
  return std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
}

inline RuleChoice chooseRule(const V3& x, const V3& a, const V3& b, const V3& c, const V3& m, double k, int depth) {
  return ruleFor((x - m).norm(), longestEdge(a, b, c), k, depth);
}

/// The four quarters of triangle (a, b, c) (split at its edges' midpoints), in the order that
/// integrateTriangle and nearRule both visit them (the cache's points are summed in its order).
using Corners = std::array<V3, 3>;
inline std::array<Corners, 4> quarters(const V3& a, const V3& b, const V3& c) {
  const V3 ab = 0.5 * (a + b), bc = 0.5 * (b + c), ca = 0.5 * (c + a);
  return {Corners{a, ab, ca}, Corners{ab, b, bc}, Corners{ca, bc, c}, Corners{ab, bc, ca}};
}

/// int_T G dS and int_T dG/dn_y dS for x not on T: a rule of the degree that T's size in
/// wavelengths and its distance from x ask for (chooseRule), or its four quarters when x is too near.
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
  const RuleChoice choice = chooseRule(x, a, b, c, m, k, depth);
  const double(*rule)[4] = choice.rule;
  const int points = choice.points;
  if (points == 0) {
    const double quarter = 0.25 * area;
    for (const Corners& q : quarters(a, b, c))
      integrateTriangle(x, q[0], q[1], q[2], normal, quarter, k, depth + 1, int_g, int_dg);
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

/// The pieces of a solve at wavenumber k: the largest nodes inside one cluster that one point
/// with its moments can stand for (k D <= kPointPhase), or single triangles too large for that.
/// They are the same for every collocation point, so each row is one flat loop over them
/// (structure of arrays), and the far field is summed over them too.
struct Pieces {
  std::vector<int32_t> node, col;
  std::vector<char> one_point;                              // k D <= kPointPhase: one point with its moments will do
  std::vector<int8_t> quarter;                              // 1-4: a quarter of the leaf triangle (0: the whole node)
  std::vector<int64_t> leaf_tri;                            // the triangle of a leaf node (-1: a larger node)
  std::vector<double> clear_of_near;                        // a larger node: beyond this none of its triangles is near
  std::vector<double> x, y, z;                              // centroid
  std::vector<double> ax, ay, az;                           // vector area
  std::vector<double> cxx, cxy, cxz, cyy, cyz, czz, trace;  // covariance of the piece's points
  std::vector<double> diameter;
  size_t size() const { return node.size(); }
};

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

/// The triangles too large in wavelengths for one point or for their quarters as points
/// (k D > 2 kPointPhase: the plate's 2 cm triangles at its top modes), which integrateTriangle
/// integrates row by row. It always splits them in four at the first level (k D > 2.5), and
/// then gives each quarter the 7-point rule whenever the quarter is more than two of its edges
/// from x (their k d is above the 3-point rule's): those quarters' points do not depend on x, so
/// they are laid out here once per solve, and a row evaluates their kernels in vectorized passes
/// with integrateTriangle's own arithmetic, in its order (the same bits). A triangle with a
/// quarter that needs more (x nearer) goes through integrateTriangle as before.
struct BigTriangles {
  std::vector<int32_t> of_piece;  // per piece: its index here, or -1
  std::vector<uint32_t> tri;      // per big triangle
  std::vector<V3> quarter_centroid;
  std::vector<double> quarter_edge;  // longest edge (chooseRule's d)
  std::vector<V3> point;             // 7 per quarter, 28 per triangle, in integrateTriangle's order
  std::vector<double> weight;
  size_t size() const { return tri.size(); }
};
constexpr int kBigPoints = 28;  // 4 quarters x 7 points

BigTriangles bigTriangles(const Surface& s, const Pieces& p) {
  BigTriangles big;
  big.of_piece.assign(p.size(), -1);
  for (size_t j = 0; j < p.size(); ++j) {
    if (p.one_point[j] || p.leaf_tri[j] < 0) continue;
    const uint32_t t = static_cast<uint32_t>(p.leaf_tri[j]);
    const Triangle& tri = s.tris[t];
    big.of_piece[j] = static_cast<int32_t>(big.tri.size());
    big.tri.push_back(t);
    const double quarter = 0.25 * tri.area;  // as integrateTriangle passes it down
    for (const Corners& q : quarters(tri.v[0], tri.v[1], tri.v[2])) {
      big.quarter_centroid.push_back((q[0] + q[1] + q[2]) / 3.0);
      big.quarter_edge.push_back(longestEdge(q[0], q[1], q[2]));
      for (int i = 0; i < 7; ++i) {
        big.point.push_back(V3(kRule7[i][0] * q[0] + kRule7[i][1] * q[1] + kRule7[i][2] * q[2]));
        big.weight.push_back(kRule7[i][3] * quarter);
      }
    }
  }
  return big;
}

/// The boundary data of several modes at one wavenumber, per piece: Q = int q dS and the first
/// moment D = int (y - centroid) q dS (index rhs * pieces + piece).
struct PieceData {
  std::vector<double> Q, Dx, Dy, Dz;
};

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

/// Is triangle t (centroid c, longest edge d) near x: too close for one point with its moments
/// (integrateTriangle's test), so integrated by a finer rule or subdivided. One expression for
/// every caller, so that they agree to the bit.
inline bool nearLeaf(const V3& x, const V3& c, double d) {
  const double dx = c[0] - x[0], dy = c[1] - x[1], dz = c[2] - x[2];
  return !(std::sqrt(dx * dx + dy * dy + dz * dz) > kFarRatio * d);
}

/// The quadrature of the near triangles of each collocation point, which does not depend on the
/// wavenumber once its rules are chosen: chosen once per cut at the bank's largest wavenumber
/// k_ref (a rule fine enough at k_ref is at every lower k), then every mode only evaluates
/// e^{ikr} at the stored distances. Per point: int G += w_g G(r), int dG/dn += w_dn dG/dr / r.
struct NearCache {
  std::vector<size_t> begin;                // per row: its points are [begin[row], begin[row + 1])
  std::vector<double> r, inv_r, w_g, w_dn;  // per point
  std::vector<uint32_t> tri;                // per point: the triangle (its cluster and data)
  std::vector<size_t> near_begin;           // per row: its near triangles
  std::vector<uint32_t> near_tris;          // their points: [near_first[i], near_first[i + 1])
  std::vector<size_t> near_first;
};

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

/// The near quadrature of every row of `cut`, then of every interior candidate, at k_ref.
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

/// Whether a node's triangles are all far from x (none of them near, nearLeaf), with a margin
/// that rounding cannot cross.
/// (Pieces::clear_of_near holds the same bound.)
inline bool noNearLeaf(const Node& n, double dist) { return dist > 1.001 * (n.radius + kFarRatio * n.max_edge); }

/// Scratch of assembleRow.
struct RowScratch {
  std::vector<double> r, phase, sin_kr, cos_kr;  // per piece, then per near point
  std::vector<double> far, dx, dy, dz;           // per piece: 1 if summed as one point, 0 if not
  std::vector<double> g_re, g_im, dg_re, dg_im;  // G and dG/dr / r (times the spread, the weight)
  std::vector<double> m_re, m_im;                // the contribution to M[col]
  std::vector<int32_t> stack;
  std::vector<uint32_t> near_stamp;  // per triangle: the row that found it near (+1)
  uint32_t stamp = 0;
  // The big triangles (BigTriangles): per point, then per triangle.
  std::vector<double> big_r, big_w, big_dn, big_phase, big_sin, big_cos, big_g_re, big_g_im, big_dg_re, big_dg_im;
  std::vector<size_t> big_first;  // per big triangle: its first point, or SIZE_MAX (integrateTriangle)
  std::vector<cd> big_g, big_dg;  // per big triangle: int G, int dG/dn
};

/// int G and int dG/dn over the big triangles (BigTriangles) whose four quarters all take the
/// 7-point rule from x, into w.big_g and w.big_dg: integrateTriangle's points, weights and
/// arithmetic (kernel(): G = e^{ikr} (1/r / 4 pi), dG/dr / r = G (-1/r^2 + ik/r)), the sums
/// in its order. The others (and the near ones) are marked SIZE_MAX in w.big_first.
void integrateBigTriangles(const Surface& s, const BigTriangles& big, double k, const V3& x, RowScratch& w) {
  const size_t count = big.size();
  w.big_first.assign(count, SIZE_MAX);
  w.big_g.resize(count);
  w.big_dg.resize(count);
  for (auto* v : {&w.big_r, &w.big_w, &w.big_dn}) v->resize(count * kBigPoints);
  size_t points = 0;
  for (size_t b = 0; b < count; ++b) {
    const uint32_t t = big.tri[b];
    if (w.near_stamp[t] == w.stamp) continue;  // near: in the cache
    bool seven = true;
    for (size_t q = 4 * b; q < 4 * b + 4; ++q)
      seven = seven && ruleFor((x - big.quarter_centroid[q]).norm(), big.quarter_edge[q], k, 1).points == 7;
    if (!seven) continue;
    const V3& normal = s.tris[t].normal;
    bool finite = true;
    for (size_t i = 0; i < static_cast<size_t>(kBigPoints); ++i) {
      const V3 yx = big.point[b * kBigPoints + i] - x;
      const double r = yx.norm();
      finite = finite && r > 0;
      w.big_r[points + i] = r;
      w.big_w[points + i] = big.weight[b * kBigPoints + i];
      w.big_dn[points + i] = yx.dot(normal);
    }
    if (!finite) continue;  // (x on the triangle: integrateTriangle skips that point)
    w.big_first[b] = points;
    points += kBigPoints;
  }
  for (auto* v : {&w.big_phase, &w.big_sin, &w.big_cos, &w.big_g_re, &w.big_g_im, &w.big_dg_re, &w.big_dg_im})
    v->resize(points);
  for (size_t i = 0; i < points; ++i) w.big_phase[i] = k * w.big_r[i];
  sinCosArray(w.big_phase.data(), w.big_sin.data(), w.big_cos.data(), points);
  {
    const double* __restrict r_i = w.big_r.data();
    const double* __restrict w_i = w.big_w.data();
    const double* __restrict dn_i = w.big_dn.data();
    const double* __restrict sin_i = w.big_sin.data();
    const double* __restrict cos_i = w.big_cos.data();
    double* __restrict g_re_i = w.big_g_re.data();
    double* __restrict g_im_i = w.big_g_im.data();
    double* __restrict dg_re_i = w.big_dg_re.data();
    double* __restrict dg_im_i = w.big_dg_im.data();
    STRIKE_IVDEP
    for (size_t i = 0; i < points; ++i) {
      const double inv_r = 1.0 / r_i[i];
      const double scale = inv_r / kFourPi;
      const double g_re = cos_i[i] * scale, g_im = sin_i[i] * scale;
      const double a = -inv_r * inv_r, b = k * inv_r;
      const double dg_re = g_re * a - g_im * b, dg_im = g_re * b + g_im * a;
      g_re_i[i] = w_i[i] * g_re;
      g_im_i[i] = w_i[i] * g_im;
      dg_re_i[i] = (w_i[i] * dg_re) * dn_i[i];
      dg_im_i[i] = (w_i[i] * dg_im) * dn_i[i];
    }
  }
  for (size_t b = 0; b < count; ++b) {
    if (w.big_first[b] == SIZE_MAX) continue;
    double g_re = 0.0, g_im = 0.0, dg_re = 0.0, dg_im = 0.0;
    for (size_t i = w.big_first[b]; i < w.big_first[b] + kBigPoints; ++i) {
      g_re += w.big_g_re[i];
      g_im += w.big_g_im[i];
      dg_re += w.big_dg_re[i];
      dg_im += w.big_dg_im[i];
    }
    w.big_g[b] = cd(g_re, g_im);
    w.big_dg[b] = cd(dg_re, dg_im);
  }
}

/// The part of a row at x from the subtree of `start`, the triangles near x left out (the
/// NearCache has them): M[col] += int_cluster dG/dn_y, lq[r] += int G q_r.
void assembleNear(const Surface& s, const Cut& cut, const std::vector<NodeData>& data, double k, const V3& x,
                  int32_t start, cd* M, cd* lq, RowScratch& w) {
  const size_t rhs = data.size();
  w.stack.clear();
  w.stack.push_back(start);
  while (!w.stack.empty()) {
    const int32_t i = w.stack.back();
    w.stack.pop_back();
    const Node& n = s.nodes[i];
    const int32_t col = cut.cluster_of_node[i];
    const V3 yx = n.centroid - x;
    const double dist = yx.norm();
    const double diameter = 2.0 * n.radius;
    if (!n.leaf()) {
      if (col >= 0 && dist > kFarRatio * diameter && k * diameter <= kPointPhase && noNearLeaf(n, dist)) {
        const Kernel kr = kernel(k, dist);
        const cd spread = phaseSpread(k, n.cov, yx, dist);
        M[col] += kr.dg_dr * yx.dot(n.vector_area) * spread;
        for (size_t r = 0; r < rhs; ++r) lq[r] += (kr.g * data[r].Q[i] + kr.dg_dr * yx.dot(data[r].D[i])) * spread;
        continue;
      }
      w.stack.push_back(n.left);
      w.stack.push_back(n.right);
      continue;
    }
    const uint32_t t = s.order[n.begin];
    if (w.near_stamp[t] == w.stamp) continue;  // near: in the cache
    const Triangle& tri = s.tris[t];
    cd int_g = 0.0, int_dg = 0.0;
    integrateTriangle(x, tri.v[0], tri.v[1], tri.v[2], tri.normal, tri.area, k, 0, int_g, int_dg);
    M[col] += int_dg;
    for (size_t r = 0; r < rhs; ++r) lq[r] += int_g * data[r].q[t];
  }
}

/// sum_j (a_re_j + i a_im_j) w_j + (b_re_j + i b_im_j) v_j in four fixed interleaved partial
/// sums (vectorizable without reassociating: the same order on every machine). v may be null.
cd sumTwo(const double* a_re, const double* a_im, const double* w, const double* b_re, const double* b_im,
          const double* v, size_t n) {
  double re[4] = {0, 0, 0, 0}, im[4] = {0, 0, 0, 0};
  size_t j = 0;
  for (; j + 4 <= n; j += 4)
    for (int l = 0; l < 4; ++l) {
      re[l] += a_re[j + l] * w[j + l] + (v ? b_re[j + l] * v[j + l] : 0.0);
      im[l] += a_im[j + l] * w[j + l] + (v ? b_im[j + l] * v[j + l] : 0.0);
    }
  for (int l = 0; j < n; ++j, ++l) {
    re[l] += a_re[j] * w[j] + (v ? b_re[j] * v[j] : 0.0);
    im[l] += a_im[j] * w[j] + (v ? b_im[j] * v[j] : 0.0);
  }
  return {(re[0] + re[1]) + (re[2] + re[3]), (im[0] + im[1]) + (im[2] + im[3])};
}

/// One row of the system at x (row `row` of the cut, or an interior point after them):
/// M[col] += int_cluster dG/dn_y, and lq[r] += int G q_r over the surface. The near triangles
/// from the cache's points; pieces far from x as one point with their phase spread
/// (phaseSpread); the rest walked down the tree (assembleNear). The sums are split into
/// passes over arrays (distances, exponentials, kernels, then the sums) that vectorize, with
/// complex products written out (no library complex multiplication and its NaN checks).
void assembleRow(const Surface& s, const Cut& cut, const Pieces& p, const PieceData& pd, const BigTriangles& big,
                 const std::vector<NodeData>& data, const NearCache& near, size_t row, double k, const V3& x, cd* M,
                 cd* lq, RowScratch& w) {
  const size_t count = p.size(), rhs = data.size();
  const double x0 = x[0], x1 = x[1], x2 = x[2];
  const double inv_four_pi = 1.0 / kFourPi;
  // The near triangles.
  w.near_stamp.resize(s.tris.size(), 0);
  ++w.stamp;
  for (size_t i = near.near_begin[row]; i < near.near_begin[row + 1]; ++i) w.near_stamp[near.near_tris[i]] = w.stamp;
  const size_t first = near.begin[row], points = near.begin[row + 1] - first;
  const size_t size = std::max(points, count);
  for (auto* v : {&w.r, &w.phase, &w.sin_kr, &w.cos_kr, &w.far, &w.dx, &w.dy, &w.dz, &w.g_re, &w.g_im, &w.dg_re,
                  &w.dg_im, &w.m_re, &w.m_im})
    v->resize(size);
  {
    const double* r = near.r.data() + first;
    for (size_t i = 0; i < points; ++i) w.phase[i] = k * r[i];
    sinCosArray(w.phase.data(), w.sin_kr.data(), w.cos_kr.data(), points);
    const double* inv = near.inv_r.data() + first;
    const double* w_g = near.w_g.data() + first;
    const double* w_dn = near.w_dn.data() + first;
    STRIKE_IVDEP
    for (size_t i = 0; i < points; ++i) {
      const double inv_r = inv[i];
      const double g_re = w.cos_kr[i] * inv_r * inv_four_pi, g_im = w.sin_kr[i] * inv_r * inv_four_pi;
      const double a = -inv_r * inv_r, b = k * inv_r;  // dG/dr / r = G (-1/r^2 + ik/r)
      w.m_re[i] = w_dn[i] * (g_re * a - g_im * b);
      w.m_im[i] = w_dn[i] * (g_re * b + g_im * a);
      w.g_re[i] = w_g[i] * g_re;
      w.g_im[i] = w_g[i] * g_im;
    }
    // Per near triangle (its points are consecutive): one sum, then its cluster and data.
    for (size_t i = near.near_begin[row]; i < near.near_begin[row + 1]; ++i) {
      const uint32_t t = near.near_tris[i];
      double m_re = 0.0, m_im = 0.0, g_re = 0.0, g_im = 0.0;
      for (size_t at = near.near_first[i] - first; at < near.near_first[i + 1] - first; ++at) {
        m_re += w.m_re[at];
        m_im += w.m_im[at];
        g_re += w.g_re[at];
        g_im += w.g_im[at];
      }
      M[cut.cluster_of_node[s.leaf_of_tri[t]]] += cd(m_re, m_im);
      for (size_t rr = 0; rr < rhs; ++rr) lq[rr] += cd(g_re * data[rr].q[t], g_im * data[rr].q[t]);
    }
  }
  // The pieces: which are one point far from x (the others are done one by one below).
  STRIKE_IVDEP
  for (size_t j = 0; j < count; ++j) {
    w.dx[j] = p.x[j] - x0;
    w.dy[j] = p.y[j] - x1;
    w.dz[j] = p.z[j] - x2;
    w.r[j] = std::sqrt(w.dx[j] * w.dx[j] + w.dy[j] * w.dy[j] + w.dz[j] * w.dz[j]);
    w.phase[j] = k * w.r[j];
  }
  for (size_t j = 0; j < count; ++j) {
    bool far = p.one_point[j] != 0;
    if (p.leaf_tri[j] >= 0)
      far = far && w.near_stamp[p.leaf_tri[j]] != w.stamp;
    else
      far = far && w.r[j] > kFarRatio * p.diameter[j] && w.r[j] > p.clear_of_near[j];
    w.far[j] = far ? 1.0 : 0.0;
  }
  sinCosArray(w.phase.data(), w.sin_kr.data(), w.cos_kr.data(), count);
  const double half_kk = 0.5 * k * k;
  {
    // Restrict-qualified views (no aliasing between the arrays), so that this loop vectorizes.
    const double* __restrict far_j = w.far.data();
    const double* __restrict r_j = w.r.data();
    const double* __restrict cos_j = w.cos_kr.data();
    const double* __restrict sin_j = w.sin_kr.data();
    const double* __restrict dx_j = w.dx.data();
    const double* __restrict dy_j = w.dy.data();
    const double* __restrict dz_j = w.dz.data();
    const double* __restrict cxx = p.cxx.data();
    const double* __restrict cxy = p.cxy.data();
    const double* __restrict cxz = p.cxz.data();
    const double* __restrict cyy = p.cyy.data();
    const double* __restrict cyz = p.cyz.data();
    const double* __restrict czz = p.czz.data();
    const double* __restrict trace = p.trace.data();
    const double* __restrict ax = p.ax.data();
    const double* __restrict ay = p.ay.data();
    const double* __restrict az = p.az.data();
    double* __restrict g_re_j = w.g_re.data();
    double* __restrict g_im_j = w.g_im.data();
    double* __restrict dg_re_j = w.dg_re.data();
    double* __restrict dg_im_j = w.dg_im.data();
    double* __restrict m_re_j = w.m_re.data();
    double* __restrict m_im_j = w.m_im.data();
    STRIKE_IVDEP
    for (size_t j = 0; j < count; ++j) {
      const double far = far_j[j];
      const double r = far * r_j[j] + (1.0 - far);  // 1 for the others (no division by a near piece's 0)
      const double inv_r = 1.0 / r, inv_r2 = inv_r * inv_r;
      const double dx = dx_j[j], dy = dy_j[j], dz = dz_j[j];
      // G = e^{ikr} / (4 pi r); grad_y G = (y - x) G (ik/r - 1/r^2).
      const double g_re = far * cos_j[j] * inv_r * inv_four_pi, g_im = far * sin_j[j] * inv_r * inv_four_pi;
      const double a = -inv_r2, b = k * inv_r;
      const double dg_re = g_re * a - g_im * b, dg_im = g_re * b + g_im * a;
      // phaseSpread: 1 - k^2 rhat.C.rhat / 2 + ik (tr C - rhat.C.rhat) / (2r).
      const double along = (cxx[j] * dx * dx + cyy[j] * dy * dy + czz[j] * dz * dz +
                            2.0 * (cxy[j] * dx * dy + cxz[j] * dx * dz + cyz[j] * dy * dz)) *
                           inv_r2;
      const double sp_re = 1.0 - half_kk * along, sp_im = k * (trace[j] - along) * 0.5 * inv_r;
      g_re_j[j] = g_re * sp_re - g_im * sp_im;
      g_im_j[j] = g_re * sp_im + g_im * sp_re;
      const double ds_re = dg_re * sp_re - dg_im * sp_im, ds_im = dg_re * sp_im + dg_im * sp_re;
      dg_re_j[j] = ds_re;
      dg_im_j[j] = ds_im;
      const double along_va = dx * ax[j] + dy * ay[j] + dz * az[j];
      m_re_j[j] = ds_re * along_va;
      m_im_j[j] = ds_im * along_va;
    }
  }
  for (size_t j = 0; j < count; ++j) M[p.col[j]] += cd(w.m_re[j], w.m_im[j]);
  for (size_t rr = 0; rr < rhs; ++rr) {
    const double* Q = pd.Q.data() + rr * count;
    const double* Dx = pd.Dx.data() + rr * count;
    const double* Dy = pd.Dy.data() + rr * count;
    const double* Dz = pd.Dz.data() + rr * count;
    for (size_t j = 0; j < count; ++j) w.phase[j] = w.dx[j] * Dx[j] + w.dy[j] * Dy[j] + w.dz[j] * Dz[j];
    lq[rr] += sumTwo(w.g_re.data(), w.g_im.data(), Q, w.dg_re.data(), w.dg_im.data(), w.phase.data(), count);
  }
  // The pieces not summed as one point.
  if (big.size() > 0) integrateBigTriangles(s, big, k, x, w);
  for (size_t j = 0; j < count; ++j) {
    if (w.far[j] > 0) continue;
    const Node& n = s.nodes[p.node[j]];
    if (!n.leaf()) {
      assembleNear(s, cut, data, k, x, p.node[j], M, lq, w);
      continue;
    }
    const uint32_t t = s.order[n.begin];
    if (w.near_stamp[t] == w.stamp) continue;  // near: done above
    if (p.quarter[j] > 1) continue;            // (a quarter's triangle is done with its first)
    const Triangle& tri = s.tris[t];           // too large for one point at this k
    cd int_g = 0.0, int_dg = 0.0;
    const int32_t b = big.of_piece[j];
    if (b >= 0 && w.big_first[static_cast<size_t>(b)] != SIZE_MAX) {
      int_g = w.big_g[static_cast<size_t>(b)];
      int_dg = w.big_dg[static_cast<size_t>(b)];
    } else {
      integrateTriangle(x, tri.v[0], tri.v[1], tri.v[2], tri.normal, tri.area, k, 0, int_g, int_dg);
    }
    M[p.col[j]] += int_dg;
    for (size_t rr = 0; rr < rhs; ++rr) lq[rr] += int_g * data[rr].q[t];
  }
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n; symmetric by construction).
void gaussLegendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.assign(n, 0.0);
  w.assign(n, 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double t = unitPhase(M_PI * (i + 0.75) / (n + 0.5)).real(), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = t;  // P_0, P_1
      for (int j = 2; j <= n; ++j) {
        const double p2 = ((2.0 * j - 1.0) * t * p1 - (j - 1.0) * p0) / j;
        p0 = p1;
        p1 = p2;
      }
      const double pn = n == 0 ? 1.0 : p1, pn1 = n == 0 ? 0.0 : p0;
      dp = n * (t * pn - pn1) / (t * t - 1.0);
      const double step = pn / dp;
      t -= step;
      if (std::abs(step) < 1e-16) break;
    }
    double p0 = 1.0, p1 = t;  // the derivative at the converged node
    for (int j = 2; j <= n; ++j) {
      const double p2 = ((2.0 * j - 1.0) * t * p1 - (j - 1.0) * p0) / j;
      p0 = p1;
      p1 = p2;
    }
    dp = n * (t * p1 - p0) / (t * t - 1.0);
    x[i] = t;
    x[n - 1 - i] = -t;
    w[i] = w[n - 1 - i] = 2.0 / ((1.0 - t * t) * dp * dp);
  }
  if (n % 2 == 1) x[n / 2] = 0.0;
}

/// The far field's points, structure of arrays (projectFarField).
struct FarPoints {
  size_t count = 0;
  std::vector<double> y0, y1, y2;                    // position relative to the centre
  std::vector<double> cxx, cxy, cxz, cyy, cyz, czz;  // second moment C
  std::vector<double> vx, vy, vz;                    // vector area
  std::vector<double> Q, Dx, Dy, Dz;                 // per solution r and point j: [r * count + j]
  std::vector<size_t> segment_begin;                 // runs of one cluster: their begins, then count
  std::vector<int32_t> segment_col;                  // each run's cluster
};

/// One direction's far fields of one solution: F(d), F(-d), and the coarse difference's.
struct FarFields {
  cd F, G, Fd, Gd;
};

/// A thread's work arrays for farFieldsAt.
struct FarScratch {
  std::vector<double> phase, spread, sin_e, cos_e, dD, ex;
  std::vector<cd> U;  // per cluster run: d.U_c
  void resize(size_t points, size_t segments) {
    for (auto* v : {&phase, &spread, &sin_e, &cos_e, &dD, &ex}) v->resize(points);
    U.resize(segments);
  }
};

/// The far fields of every solution at the direction d (unit) and its opposite -d, into
/// out[r] (formulas in projectFarField). Reads only its arguments and writes only `w` and `out`.
void farFieldsAt(const FarPoints& pts, double k, const double* d, const std::vector<Eigen::VectorXcd>& p,
                 const std::vector<Eigen::VectorXcd>& p_diff, FarScratch& w, FarFields* out) {
  const size_t np = pts.count, segments = pts.segment_col.size(), rhs = p.size();
  const double d0 = d[0], d1 = d[1], d2 = d[2];
  const double kk = k * k;
  const cd ik(0.0, k);
  double* phase = w.phase.data();
  double* spread = w.spread.data();
  double* sin_e = w.sin_e.data();
  double* cos_e = w.cos_e.data();
  double* ex = w.ex.data();
  // The scratch's arrays and the points' never overlap (STRIKE_IVDEP: vectorized without the
  // run-time overlap tests, too many for the compiler to make).
  STRIKE_IVDEP
  for (size_t j = 0; j < np; ++j) {
    phase[j] = -k * (d0 * pts.y0[j] + d1 * pts.y1[j] + d2 * pts.y2[j]);
    const double along = pts.cxx[j] * d0 * d0 + pts.cyy[j] * d1 * d1 + pts.czz[j] * d2 * d2 +
                         2.0 * (pts.cxy[j] * d0 * d1 + pts.cxz[j] * d0 * d2 + pts.cyz[j] * d1 * d2);
    spread[j] = 1.0 - 0.5 * kk * along;
  }
  sinCosArray(phase, sin_e, cos_e, np);
  STRIKE_IVDEP
  for (size_t j = 0; j < np; ++j) {
    cos_e[j] *= spread[j];
    sin_e[j] *= spread[j];
    ex[j] = d0 * pts.vx[j] + d1 * pts.vy[j] + d2 * pts.vz[j];  // d.va
  }
  // Per cluster: d.U_c = sum E_j d.va_j (one complex number: d is known here).
  for (size_t c = 0; c < segments; ++c) {
    double re = 0.0, im = 0.0;
    for (size_t j = pts.segment_begin[c]; j < pts.segment_begin[c + 1]; ++j) {
      re += cos_e[j] * ex[j];
      im += sin_e[j] * ex[j];
    }
    w.U[c] = cd(re, im);
  }
  for (size_t r = 0; r < rhs; ++r) {
    const double* Dxr = &pts.Dx[r * np];
    const double* Dyr = &pts.Dy[r * np];
    const double* Dzr = &pts.Dz[r * np];
    double* dD = w.dD.data();
    STRIKE_IVDEP
    for (size_t j = 0; j < np; ++j) dD[j] = d0 * Dxr[j] + d1 * Dyr[j] + d2 * Dzr[j];
    double q_re = 0.0, q_im = 0.0, d_re = 0.0, d_im = 0.0;
    dotTwo(cos_e, sin_e, &pts.Q[r * np], np, q_re, q_im);
    dotTwo(cos_e, sin_e, dD, np, d_re, d_im);
    const cd SQ(q_re, q_im), SD(d_re, d_im);
    // sum_c p_c d.U_c and sum_c p_c conj(d.U_c), and the same with p_diff.
    double t_re = 0, t_im = 0, u_re = 0, u_im = 0, td_re = 0, td_im = 0, ud_re = 0, ud_im = 0;
    const cd* pr = p[r].data();
    const cd* dr = p_diff[r].data();
    for (size_t c = 0; c < segments; ++c) {
      const double a_re = pr[pts.segment_col[c]].real(), a_im = pr[pts.segment_col[c]].imag();
      const double b_re = dr[pts.segment_col[c]].real(), b_im = dr[pts.segment_col[c]].imag();
      const double x_re = w.U[c].real(), x_im = w.U[c].imag();
      t_re += a_re * x_re - a_im * x_im;
      t_im += a_re * x_im + a_im * x_re;
      u_re += a_re * x_re + a_im * x_im;  // a conj(x)
      u_im += a_im * x_re - a_re * x_im;
      td_re += b_re * x_re - b_im * x_im;
      td_im += b_re * x_im + b_im * x_re;
      ud_re += b_re * x_re + b_im * x_im;
      ud_im += b_im * x_re - b_re * x_im;
    }
    out[r].F = -SQ + ik * SD - ik * cd(t_re, t_im);
    out[r].G = -std::conj(SQ) - ik * std::conj(SD) + ik * cd(u_re, u_im);
    out[r].Fd = -ik * cd(td_re, td_im);
    out[r].Gd = ik * cd(ud_re, ud_im);
  }
}

/// Spherical-harmonic coefficients of the far fields of several solutions at one wavenumber.
/// F(d) = (1/4pi) int (p dE/dn - q E) dS with E = e^{-ik d.(y - c)} (c: the centre), summed
/// over the pieces with their moments (E over a piece ~ E(centroid) (1 - k^2 d.C.d / 2), and
/// int q E ~ E(centroid) (Q - ik d.D)), at the nodes of a product rule (Gauss-Legendre in
/// cos theta, uniform in phi) that integrates Y_nm Y_n'm' exactly up to n_cap + 1; then
/// c_nm = int F Y_nm dOmega. A direction d and its opposite share their exponentials
/// (E(-d) = conj E(d)). p[r], p_diff[r]: per cluster; coef[r], dcoef[r]: (n_cap + 1)^2 each.
/// The sums at the directions are done in two fixed halves of them (`parts`).
void projectFarField(const Surface& s, const Pieces& pc, const PieceData& pd, const std::vector<NodeData>& data,
                     double k, int n_cap, const std::vector<Eigen::VectorXcd>& p,
                     const std::vector<Eigen::VectorXcd>& p_diff, std::vector<std::vector<cd>>& coef,
                     std::vector<std::vector<cd>>& dcoef, TwoParts& parts) {
  const size_t rhs = data.size();
  const size_t count = static_cast<size_t>((n_cap + 1) * (n_cap + 1));
  coef.assign(rhs, std::vector<cd>(count, 0.0));
  dcoef.assign(rhs, std::vector<cd>(count, 0.0));
  // Points: the one-point pieces with their moments, and a 7-point rule on each larger triangle.
  struct Point {
    V3 y;   // relative to the centre
    V3 va;  // vector area
    double cxx, cxy, cxz, cyy, cyz, czz;
    int32_t col;
    int32_t piece;  // moments Q, D from the piece (-1: a rule point of triangle `tri`)
    uint32_t tri;
    double weight;  // of a rule point: its share of the triangle's area
  };
  std::vector<Point> points;
  points.reserve(pc.size());
  for (size_t j = 0; j < pc.size(); ++j) {
    if (pc.one_point[j] || pc.col[j] < 0) {
      points.push_back({V3(pc.x[j], pc.y[j], pc.z[j]) - s.centre, V3(pc.ax[j], pc.ay[j], pc.az[j]), pc.cxx[j],
                        pc.cxy[j], pc.cxz[j], pc.cyy[j], pc.cyz[j], pc.czz[j], pc.col[j], static_cast<int32_t>(j), 0,
                        1.0});
      continue;
    }
    // A triangle too large for one point: 3 points (degree 2) up to twice that, else 7 (degree 5).
    const uint32_t t = s.order[s.nodes[pc.node[j]].begin];
    const Triangle& tri = s.tris[t];
    const bool three = k * tri.diameter <= 2.0 * kPointPhase;
    const double(*rule)[4] = three ? kRule3 : kRule7;
    for (int i = 0; i < (three ? 3 : 7); ++i) {
      const V3 y = rule[i][0] * tri.v[0] + rule[i][1] * tri.v[1] + rule[i][2] * tri.v[2];
      points.push_back(
          {y - s.centre, tri.normal * (rule[i][3] * tri.area), 0, 0, 0, 0, 0, 0, pc.col[j], -1, t, rule[i][3]});
    }
  }
  // With E_j = e^{-ik d.y_j} (1 - k^2 d.C_j.d / 2) at point j (real weights after it):
  //   F(d)  = -S_Q + ik S_D - ik sum_c p_c d.U_c,   S_Q = sum_j E_j Q_j, S_D = sum_j E_j d.D_j,
  //   F(-d) = -conj(S_Q) - ik conj(S_D) + ik sum_c p_c d.conj(U_c),   U_c = sum_{j in c} E_j va_j,
  // and the coarse difference likewise with p_diff alone: the pressure's term is summed per
  // cluster (the points of a cluster are consecutive), shared by every solution.
  const size_t np = points.size();
  FarPoints fp;
  fp.count = np;
  for (auto* v : {&fp.y0, &fp.y1, &fp.y2, &fp.cxx, &fp.cxy, &fp.cxz, &fp.cyy, &fp.cyz, &fp.czz, &fp.vx, &fp.vy, &fp.vz})
    v->resize(np);
  for (size_t j = 0; j < np; ++j) {
    const Point& pt = points[j];
    fp.y0[j] = pt.y[0];
    fp.y1[j] = pt.y[1];
    fp.y2[j] = pt.y[2];
    fp.cxx[j] = pt.cxx;
    fp.cxy[j] = pt.cxy;
    fp.cxz[j] = pt.cxz;
    fp.cyy[j] = pt.cyy;
    fp.cyz[j] = pt.cyz;
    fp.czz[j] = pt.czz;
    fp.vx[j] = pt.va[0];
    fp.vy[j] = pt.va[1];
    fp.vz[j] = pt.va[2];
    if (j == 0 || pt.col != points[j - 1].col) {
      fp.segment_begin.push_back(j);
      fp.segment_col.push_back(pt.col);
    }
  }
  fp.segment_begin.push_back(np);
  for (auto* v : {&fp.Q, &fp.Dx, &fp.Dy, &fp.Dz}) v->resize(rhs * np);
  for (size_t r = 0; r < rhs; ++r)
    for (size_t j = 0; j < np; ++j) {
      const Point& pt = points[j];
      const size_t at = r * np + j;
      if (pt.piece >= 0) {
        const size_t from = r * pc.size() + static_cast<size_t>(pt.piece);
        fp.Q[at] = pd.Q[from];
        fp.Dx[at] = pd.Dx[from];
        fp.Dy[at] = pd.Dy[from];
        fp.Dz[at] = pd.Dz[from];
      } else {
        fp.Q[at] = data[r].q[pt.tri] * s.tris[pt.tri].area * pt.weight;
        fp.Dx[at] = fp.Dy[at] = fp.Dz[at] = 0.0;
      }
    }
  const int rings = n_cap + 2, around = 2 * n_cap + 4;
  std::vector<double> cos_theta, ring_weight;
  gaussLegendre(rings, cos_theta, ring_weight);
  const double dphi = 2.0 * M_PI / around;
  // The directions d of the rule's upper half (each with its opposite -d), in the order their
  // contributions are summed below.
  std::vector<int> direction_ring;
  std::vector<double> direction;  // d0, d1, d2 of each
  for (int i = 0; i < (rings + 1) / 2; ++i) {
    const double ct = cos_theta[i], st = std::sqrt(std::max(0.0, 1.0 - ct * ct));
    const bool middle = 2 * i + 1 == rings;  // its opposite directions are on the ring itself
    const int phis = middle ? around / 2 : around;
    for (int l = 0; l < phis; ++l) {
      const double phi = dphi * l;
      const cd around_z = unitPhase(phi);
      direction_ring.push_back(i);
      direction.insert(direction.end(), {st * around_z.real(), st * around_z.imag(), ct});
    }
  }
  const size_t directions = direction_ring.size();
  // Per direction and solution: F(d), F(-d), and the coarse difference's two (`FarFields`).
  // Each direction's values are sums over the points for that direction alone, so the two
  // halves of the directions (always the same halves) are computed at once, each with its own
  // scratch, into entries the other never touches; the projection on the harmonics then adds
  // them up in the directions' order, on this thread. The same bits with or without the helper
  // thread, and the same as revision 3's single loop (every operation and its order unchanged).
  std::vector<FarFields> fields(directions * rhs);
  std::array<FarScratch, 2> scratch;
  for (FarScratch& w : scratch) w.resize(np, fp.segment_col.size());
  parts.run(directions, directions / 2, [&](size_t begin, size_t end, int part) {
    FarScratch& w = scratch[static_cast<size_t>(part)];
    for (size_t t = begin; t < end; ++t) farFieldsAt(fp, k, &direction[3 * t], p, p_diff, w, &fields[t * rhs]);
  });

  std::vector<double> Y(count);
  for (size_t t = 0; t < directions; ++t) {
    const double d0 = direction[3 * t], d1 = direction[3 * t + 1], d2 = direction[3 * t + 2];
    const double weight = ring_weight[static_cast<size_t>(direction_ring[t])] * dphi / kFourPi;
    for (int side = 0; side < 2; ++side) {
      const double dd[3] = {side ? -d0 : d0, side ? -d1 : d1, side ? -d2 : d2};
      realSphericalHarmonics(static_cast<uint32_t>(n_cap), dd, Y.data());
      for (size_t r = 0; r < rhs; ++r) {
        const FarFields& v = fields[t * rhs + r];
        const cd f = (side ? v.G : v.F) * weight, fd = (side ? v.Gd : v.Fd) * weight;
        cd* co = coef[r].data();
        cd* dc = dcoef[r].data();
        for (size_t m = 0; m < count; ++m) {
          co[m] += f * Y[m];
          dc[m] += fd * Y[m];
        }
      }
    }
  }
}

/// The energy a mode's far field may leave beyond its kept order, relative to its total: 1e-8
/// (-80 dB), far below the target, so that the modes of a degenerate pair, truncated apart,
/// still sum basis-free.
constexpr double kTailEnergy = 1e-8;

/// Whether the far fields `coef` (up to order n_top) of the modes not yet done have converged
/// there: their two top orders hold at most kTailEnergy of their energy, so that the order kept
/// is below n_top - 1 and the orders beyond n_top (falling faster still past kR) hold less.
bool seriesConverged(const std::vector<std::vector<cd>>& coef, const std::vector<char>& done, int n_top) {
  for (size_t r = 0; r < coef.size(); ++r) {
    if (done[r]) continue;
    double total = 0.0, top = 0.0;
    for (int n = 0; n <= n_top; ++n)
      for (int m = -n; m <= n; ++m) {
        const double e = std::norm(coef[r][static_cast<size_t>(n * n + n + m)]);
        total += e;
        if (n >= n_top - 1) top += e;
      }
    if (!(top <= kTailEnergy * total)) return false;
  }
  return true;
}

/// A x = B for a square A: LU in single precision (half the time of double), then iterative
/// refinement with the residual in double (Wilkinson; Moler 1967, "Iterative refinement in
/// floating point", J. ACM 14), which recovers double accuracy while cond(A) eps_float << 1 (these
/// second-kind systems: cond ~ 10-1000). The residual is an explicit loop (fixed order).
Eigen::MatrixXcd solveSquare(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B) {
  using MatrixCf = Eigen::Matrix<std::complex<float>, Eigen::Dynamic, Eigen::Dynamic>;
  const Eigen::PartialPivLU<MatrixCf> lu(A.cast<std::complex<float>>());
  Eigen::MatrixXcd X = lu.solve(B.cast<std::complex<float>>()).cast<cd>();
  const Eigen::Index n = A.rows();
  Eigen::MatrixXcd R(n, B.cols());
  for (int step = 0; step < 2; ++step) {
    for (Eigen::Index c = 0; c < B.cols(); ++c) {
      for (Eigen::Index i = 0; i < n; ++i) R(i, c) = B(i, c);
      for (Eigen::Index j = 0; j < n; ++j) {
        const cd x = X(j, c);
        for (Eigen::Index i = 0; i < n; ++i) R(i, c) -= A(i, j) * x;
      }
    }
    X += lu.solve(R.cast<std::complex<float>>()).cast<cd>();
  }
  return X;
}

/// min |A x - B| for a tall A (the interior points' rows under the surface's): Householder QR
/// in single precision (half the time of double), then iterative refinement of the augmented
/// system [I A; A^H 0] [r; x] = [B; 0] with its residuals in double (Bjorck 1967, "Iterative
/// refinement of linear least squares solutions I", BIT 7), which converges to the double-
/// precision solution at a rate ~ cond(A) eps_float per step whatever the residual's size.
/// Each correction: h = R^-H g, [f1; f2] = Q^H f, dx = R^-1 (f1 - h), dr = Q [h; f2], for the
/// residuals f = B - r - A x and g = -A^H r. The residuals are explicit loops (fixed order).
Eigen::MatrixXcd solveLeastSquares(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B) {
  using cf = std::complex<float>;
  using MatrixCf = Eigen::Matrix<cf, Eigen::Dynamic, Eigen::Dynamic>;
  const Eigen::Index m = A.rows(), n = A.cols(), cols = B.cols();
  const Eigen::HouseholderQR<MatrixCf> qr(A.cast<cf>());
  const auto R = qr.matrixQR().topLeftCorner(n, n).triangularView<Eigen::Upper>();
  Eigen::MatrixXcd X = qr.solve(B.cast<cf>()).cast<cd>();
  Eigen::MatrixXcd r(m, cols), f(m, cols), g(n, cols);
  auto residualOfX = [&](Eigen::MatrixXcd& out, const Eigen::MatrixXcd& start) {  // start - A X
    for (Eigen::Index c = 0; c < cols; ++c) {
      for (Eigen::Index i = 0; i < m; ++i) out(i, c) = start(i, c);
      for (Eigen::Index j = 0; j < n; ++j) {
        const cd x = X(j, c);
        for (Eigen::Index i = 0; i < m; ++i) out(i, c) -= A(i, j) * x;
      }
    }
  };
  residualOfX(r, B);
  for (int step = 0; step < 2; ++step) {
    residualOfX(f, B - r);
    for (Eigen::Index c = 0; c < cols; ++c)
      for (Eigen::Index j = 0; j < n; ++j) {
        cd sum = 0.0;
        for (Eigen::Index i = 0; i < m; ++i) sum += std::conj(A(i, j)) * r(i, c);
        g(j, c) = -sum;
      }
    const MatrixCf h = R.adjoint().solve(g.cast<cf>());
    MatrixCf qf = qr.householderQ().adjoint() * f.cast<cf>();
    X += R.solve(qf.topRows(n) - h).cast<cd>();
    qf.topRows(n) = h;
    r += (qr.householderQ() * qf).cast<cd>();
  }
  return X;
}

struct ModeSolve {
  std::vector<Eigen::VectorXcd> p;       // per right-hand side, per cluster
  std::vector<Eigen::VectorXcd> p_diff;  // p minus the coarse solve's, per cluster
  size_t elements = 0, chief = 0;
  Cut cut;
  Pieces pieces;
  PieceData piece_data;
  double assembly_seconds = 0.0, factor_seconds = 0.0;
};

/// Solves the exterior Neumann problem for the boundary data `data` (one right-hand side each:
/// modes of one frequency share the matrix and its factorization) at wavenumber k with
/// `elements` unknowns (about) and `chief` interior points.
ModeSolve solveSystem(const Surface& s, const std::vector<NodeData>& data, double k, size_t elements, size_t chief,
                      double k_ref, std::map<size_t, NearCache>& near_caches, TwoParts& parts) {
  ModeSolve out;
  const auto assembly_start = std::chrono::steady_clock::now();
  out.cut = cutWithCount(s, elements);
  const Cut& cut = out.cut;
  auto cached = near_caches.find(elements);
  if (cached == near_caches.end()) cached = near_caches.emplace(elements, buildNearCache(s, cut, k_ref)).first;
  const NearCache& near = cached->second;
  out.pieces = makePieces(s, cut, k);
  out.piece_data = pieceData(s, out.pieces, data);
  const BigTriangles big = bigTriangles(s, out.pieces);
  const size_t n = cut.nodes.size(), rhs = data.size();
  chief = std::min(chief, s.chief_candidates.size());
  const size_t rows = n + chief;
  const auto R = static_cast<Eigen::Index>(rhs);
  Eigen::MatrixXcd A = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(n));
  Eigen::MatrixXcd b(static_cast<Eigen::Index>(rows), R);
  // Each row depends on its collocation point alone, so the two halves (always the same halves)
  // may be assembled at once, each with its own scratch, into rows of A and b the other never
  // touches: the same bits with or without the helper thread.
  std::array<RowScratch, 2> scratch;
  parts.run(rows, rows / 2, [&](size_t begin, size_t end, int part) {
    RowScratch& stack = scratch[static_cast<size_t>(part)];
    std::vector<cd> M(n), lq(rhs);
    for (size_t r = begin; r < end; ++r) {
      std::fill(M.begin(), M.end(), cd(0.0));
      std::fill(lq.begin(), lq.end(), cd(0.0));
      if (r < n) {
        const uint32_t host = s.nodes[cut.nodes[r]].rep;
        assembleRow(s, cut, out.pieces, out.piece_data, big, data, near, r, k, s.tris[host].centroid, M.data(),
                    lq.data(), stack);
      } else {
        assembleRow(s, cut, out.pieces, out.piece_data, big, data, near, r, k, s.chief_candidates[r - n], M.data(),
                    lq.data(), stack);
      }
      // 1/2 p(x) - int p dG/dn = - int G q (x on S); 0 - int p dG/dn = - int G q (x inside).
      for (size_t c = 0; c < n; ++c) A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = -M[c];
      if (r < n) A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(r)) += 0.5;
      for (size_t q = 0; q < rhs; ++q) b(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(q)) = -lq[q];
    }
  });
  auto solve = [](const Eigen::MatrixXcd& matrix, const Eigen::MatrixXcd& rhs_m) -> Eigen::MatrixXcd {
    if (matrix.rows() == matrix.cols()) return solveSquare(matrix, rhs_m);
    return solveLeastSquares(matrix, rhs_m);
  };
  out.assembly_seconds = secondsSince(assembly_start);
  const auto factor_start = std::chrono::steady_clock::now();
  // The coarse solve: clusters merged with their siblings, rows a subset, columns summed. It
  // reads A and b only, so it runs beside the fine solve, on the helper thread (each solve is
  // the same whoever computes it: the same bits with or without the helper).
  const Coarse coarse = coarsen(s, cut);
  const size_t nc = coarse.count;
  const bool coarse_solve = nc < n && nc > 0;
  Eigen::MatrixXcd P, pc;
  parts.run(size_t{2}, size_t{1}, [&](size_t begin, size_t, int) {
    if (begin == 0) {
      P = solve(A, b);
      return;
    }
    if (!coarse_solve) return;
    Eigen::MatrixXcd Ac = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(nc + chief), static_cast<Eigen::Index>(nc));
    Eigen::MatrixXcd bc(static_cast<Eigen::Index>(nc + chief), R);
    for (size_t j = 0; j < nc + chief; ++j) {
      const size_t fine_row = j < nc ? static_cast<size_t>(coarse.row_cluster[j]) : n + (j - nc);
      for (size_t c = 0; c < n; ++c) {
        cd m = A(static_cast<Eigen::Index>(fine_row), static_cast<Eigen::Index>(c));
        if (fine_row < n && c == fine_row) m -= 0.5;  // the free term goes to the coarse diagonal
        Ac(static_cast<Eigen::Index>(j), coarse.of_cluster[c]) += m;
      }
      if (j < nc) Ac(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)) += 0.5;
      bc.row(static_cast<Eigen::Index>(j)) = b.row(static_cast<Eigen::Index>(fine_row));
    }
    pc = solve(Ac, bc);
  });
  out.elements = n;
  out.chief = chief;
  out.p.resize(rhs);
  out.p_diff.resize(rhs);
  for (size_t q = 0; q < rhs; ++q) out.p[q] = P.col(static_cast<Eigen::Index>(q));
  if (coarse_solve) {
    for (size_t q = 0; q < rhs; ++q) {
      out.p_diff[q].resize(static_cast<Eigen::Index>(n));
      for (size_t c = 0; c < n; ++c)
        out.p_diff[q][static_cast<Eigen::Index>(c)] =
            out.p[q][static_cast<Eigen::Index>(c)] - pc(coarse.of_cluster[c], static_cast<Eigen::Index>(q));
    }
  } else {
    for (size_t q = 0; q < rhs; ++q) out.p_diff[q] = Eigen::VectorXcd::Zero(static_cast<Eigen::Index>(n));
  }
  out.factor_seconds = secondsSince(factor_start);
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
  // The assembly's helper thread, as the eigen-solve's block stage has (src/modal/two_parts.hpp).
  TwoParts parts(settings.threads >= 2 && std::thread::hardware_concurrency() >= 2);

  // Triangle -> its three vertex indices (degenerate ones were dropped: match them up again).
  std::vector<std::array<uint32_t, 3>> corners;
  corners.reserve(s.tris.size());
  for (size_t t = 0; t < bank.surface_triangles.size() / 3; ++t) {
    const uint32_t* v = &bank.surface_triangles[3 * t];
    const V3 p0(&bank.surface_positions[3 * v[0]]), p1(&bank.surface_positions[3 * v[1]]),
        p2(&bank.surface_positions[3 * v[2]]);
    if ((p1 - p0).cross(p2 - p0).norm() > 0) corners.push_back({v[0], v[1], v[2]});
  }

  // Modes of (nearly) one frequency, as degenerate pairs of symmetric bodies are (split by the
  // mesh's asymmetry), share the system and its factorization: solved at the first one's
  // wavenumber, which changes the others' far fields by about (relative frequency gap) x (1 + ka),
  // added to their estimates. Shared while that is at most a tenth of the target (in quadrature,
  // +0.5% of an estimate at the target).
  constexpr double kSharedGapShare = 0.1;
  std::vector<size_t> group_start;
  for (size_t mode = 0; mode < modes; ++mode) {
    const double omega = std::sqrt(std::max(bank.eigenvalues[mode], 0.0));
    const double first = group_start.empty() ? -1.0 : std::sqrt(std::max(bank.eigenvalues[group_start.back()], 0.0));
    const double allowed = kSharedGapShare * settings.target_relative_error / (1.0 + first / c_air * s.radius);
    if (group_start.empty() || !(std::abs(omega - first) <= allowed * first)) group_start.push_back(mode);
  }
  group_start.push_back(modes);

  // The near quadrature per cut, its rules chosen at the largest wavenumber.
  double k_ref = 0.0;
  for (size_t mode = 0; mode < modes; ++mode)
    k_ref = std::max(k_ref, std::sqrt(std::max(bank.eigenvalues[mode], 0.0)) / c_air);
  std::map<size_t, NearCache> near_caches;

  std::vector<NodeData> data;
  std::vector<std::vector<cd>> coef;
  std::vector<double> energy, diff;
  // The last group solved at the budget whose modes all missed the target there: its wavenumber
  // and its best mode's estimate (0: none yet).
  double missed_k = 0.0, missed_best = 0.0;
  for (size_t g = 0; g + 1 < group_start.size(); ++g) {
    const auto group_begin = std::chrono::steady_clock::now();
    const size_t first = group_start[g], last = group_start[g + 1], rhs = last - first;
    const double omega = std::sqrt(std::max(bank.eigenvalues[first], 0.0));
    const double k = omega / c_air;
    // q = dp/dn = -rho a_n, a_n the normal component of the shape (per unit modal acceleration).
    data.assign(rhs, {});
    for (size_t r = 0; r < rhs; ++r) {
      data[r].q.resize(s.tris.size());
      for (size_t t = 0; t < s.tris.size(); ++t) {
        V3 shape = V3::Zero();
        for (uint32_t v : corners[t]) {
          const float* u = bank.shapeAt(first + r, v);
          shape += V3(u[0], u[1], u[2]);
        }
        data[r].q[t] = -rho * s.tris[t].normal.dot(shape / 3.0);
      }
      nodeData(s, data[r]);
    }
    const double kr = k * s.radius;
    const int n_cap = std::min(120, static_cast<int>(std::ceil(kr + 4.0 * std::cbrt(kr))) + 6);
    // The far field is first projected to a lower order (the directions cost ~ order^2): enough
    // for every mode seen so far (the orders kept are ~kR + 3 (kR)^{1/3}); a mode whose top two
    // orders there still hold more than the tail allowed is projected again up to n_cap.
    const int n_try = std::min(n_cap, static_cast<int>(std::ceil(kr + 3.0 * std::cbrt(kr))) + 3);
    // Refine while an estimate exceeds the target and the budget allows: the mode's pattern
    // (not only the wavelength) sets the resolution, and the estimate sees it.
    size_t elements = elementsFor(s, settings, k);
    const size_t cap = settings.fixed_elements > 0 ? elements : std::min<size_t>(settings.max_elements, s.tris.size());
    // Straight to the budget when a lower frequency's modes all missed the target there: the error
    // of constant elements grows as (k h)^2, so these modes are predicted to miss it at the budget
    // too, and every step below it would be solved only to be dropped (the result is the
    // budget's solve either way).
    if (missed_k > 0 && missed_best * (k / missed_k) * (k / missed_k) > settings.target_relative_error) elements = cap;
    // Per mode: the far field of the first resolution that met the target (or the last).
    std::vector<double> total(rhs, 0.0);
    std::vector<char> done(rhs, 0);
    std::vector<uint32_t> mode_elements(rhs, 0), mode_chief(rhs, 0);
    std::vector<int> mode_cap(rhs, n_cap);  // the order up to which the mode's far field was projected
    diff.assign(rhs, 0.0);
    energy.assign(rhs * (n_cap + 1), 0.0);
    coef.assign(rhs, {});
    double assembly_seconds = 0.0, factor_seconds = 0.0, far_field_seconds = 0.0;
    uint32_t solves = 0;
    std::vector<std::vector<cd>> step_coef, step_dcoef;
    while (true) {
      const size_t chief = chiefPointsFor(s, settings, k, elements);
      const ModeSolve solved = solveSystem(s, data, k, elements, chief, k_ref, near_caches, parts);
      ++solves;
      assembly_seconds += solved.assembly_seconds;
      factor_seconds += solved.factor_seconds;
      const auto far_start = std::chrono::steady_clock::now();
      int projected = n_try;
      projectFarField(s, solved.pieces, solved.piece_data, data, k, projected, solved.p, solved.p_diff, step_coef,
                      step_dcoef, parts);
      if (n_try < n_cap && !seriesConverged(step_coef, done, n_try)) {
        projected = n_cap;
        projectFarField(s, solved.pieces, solved.piece_data, data, k, projected, solved.p, solved.p_diff, step_coef,
                        step_dcoef, parts);
      }
      far_field_seconds += secondsSince(far_start);
      const bool last_step = elements >= cap;
      for (size_t r = 0; r < rhs; ++r) {
        if (done[r]) continue;
        double* e = &energy[r * (n_cap + 1)];
        std::fill(e, e + n_cap + 1, 0.0);
        total[r] = 0.0;
        diff[r] = 0.0;
        for (int n = 0; n <= projected; ++n)
          for (int m = -n; m <= n; ++m) {
            e[n] += std::norm(step_coef[r][n * n + n + m]);
            diff[r] += std::norm(step_dcoef[r][n * n + n + m]);
          }
        for (int n = 0; n <= projected; ++n) total[r] += e[n];
        coef[r] = step_coef[r];
        mode_cap[r] = projected;
        mode_elements[r] = static_cast<uint32_t>(solved.elements);
        mode_chief[r] = static_cast<uint32_t>(solved.chief);
        done[r] = last_step || !(diff[r] > std::pow(settings.target_relative_error, 2) * total[r]);
      }
      if (std::all_of(done.begin(), done.end(), [](char d) { return d != 0; })) break;
      // Next: 2.5x the unknowns, or straight to the budget when even that is predicted to fall
      // short of the target (the error of constant elements falls as h^2, i.e. as 1 / unknowns):
      // the steps between would be solved only to be dropped.
      // (Of a shared solve: when every mode still refining is predicted to fall short.)
      double best = 1e300;
      for (size_t r = 0; r < rhs; ++r)
        if (!done[r]) best = std::min(best, total[r] > 0 ? std::sqrt(diff[r] / total[r]) : 0.0);
      const double asked = static_cast<double>(elements) * best / settings.target_relative_error;
      elements = asked >= static_cast<double>(cap) ? cap : std::min(cap, elements * 5 / 2);
    }
    const double group_seconds = secondsSince(group_begin);
    if (elements >= cap && settings.fixed_elements == 0) {
      double best = 1e300;
      for (size_t r = 0; r < rhs; ++r) best = std::min(best, total[r] > 0 ? std::sqrt(diff[r] / total[r]) : 0.0);
      if (best > settings.target_relative_error) {
        missed_k = k;
        missed_best = best;
      }
    }

    for (size_t r = 0; r < rhs; ++r) {
      const size_t mode = first + r;
      const double* e = &energy[r * (n_cap + 1)];
      // Order: the smallest whose tail holds at most kTailEnergy of the energy.
      const double tail_allowed = kTailEnergy * total[r];
      const int top = mode_cap[r];
      int order = top;
      double tail = 0.0;
      while (order > 0 && tail + e[order] <= tail_allowed) tail += e[order--];
      // Error: the coarse solve's difference, the dropped tail, what the last computed orders
      // still hold (a series not yet converged at n_cap), and a shared solve's frequency gap.
      const double unresolved = e[top] + (top > 0 ? e[top - 1] : 0.0);
      const double omega_mode = std::sqrt(std::max(bank.eigenvalues[mode], 0.0));
      const double gap = omega > 0 ? std::abs(omega_mode - omega) / omega * (1.0 + kr) : 0.0;
      const double relative =
          total[r] > 0 ? std::sqrt((diff[r] + tail + (order == top ? unresolved : 0.0)) / total[r] + gap * gap) : 0.0;

      out.order.push_back(static_cast<uint32_t>(order));
      for (int i = 0; i < (order + 1) * (order + 1); ++i)
        out.coefficients.push_back(
            std::complex<float>(static_cast<float>(coef[r][i].real()), static_cast<float>(coef[r][i].imag())));
      out.offset.push_back(out.coefficients.size());
      out.relative_error.push_back(static_cast<float>(relative));
      if (stats) {
        TransferModeStats& st = (*stats)[mode];
        st.ka = omega_mode / c_air * s.radius;
        st.elements = mode_elements[r];
        st.chief_points = mode_chief[r];
        st.order = static_cast<uint32_t>(order);
        st.relative_error = relative;
        // A shared solve's time is split evenly between its modes.
        st.seconds = group_seconds / static_cast<double>(rhs);
        st.assembly_seconds = assembly_seconds / static_cast<double>(rhs);
        st.factor_seconds = factor_seconds / static_cast<double>(rhs);
        st.far_field_seconds = far_field_seconds / static_cast<double>(rhs);
        st.solves = solves;
      }
    }
    if (progress) progress("transfer", static_cast<double>(last) / static_cast<double>(modes + 1));
  }

  // Rigid translation in the compact limit: the Laplace problem (k = 0) with dp/dn = -n_j
  // (rho factored out). M_ij = V delta_ij + int n_i p_j dS (docs: from the far field's first
  // order in k, the volume term by the divergence theorem).
  {
    Eigen::Matrix3d dipole = Eigen::Matrix3d::Identity() * s.volume;
    const size_t elements = std::min<size_t>(settings.max_elements, s.tris.size());
    data.assign(3, {});
    for (int j = 0; j < 3; ++j) {
      data[j].q.resize(s.tris.size());
      for (size_t t = 0; t < s.tris.size(); ++t) data[j].q[t] = -s.tris[t].normal[j];
      nodeData(s, data[j]);
    }
    const ModeSolve solved =
        solveSystem(s, data, 0.0, elements, 0, k_ref, near_caches, parts);  // the three right-hand sides at once
    for (int j = 0; j < 3; ++j)
      for (size_t c = 0; c < solved.cut.nodes.size(); ++c) {
        const V3 va = s.nodes[solved.cut.nodes[c]].vector_area;
        for (int i = 0; i < 3; ++i) dipole(i, j) += va[i] * solved.p[j][static_cast<Eigen::Index>(c)].real();
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
