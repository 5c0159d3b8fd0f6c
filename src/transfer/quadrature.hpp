// SPDX-License-Identifier: MIT
// Quadrature on the surface's triangles: the rules, their choice by distance and size in
// wavelengths, the adaptive integration of G and dG/dn over a triangle, and Gauss-Legendre.
#pragma once

#include <algorithm>
#include <array>
#include <vector>

#include "kernels.hpp"

namespace strike::transfer {

// Accuracy knobs of the quadrature (checked by the analytic-sphere tests).
constexpr double kFarRatio = 3.0;    // a cell is "far" from x beyond this many diameters
constexpr double kCellPhase = 0.6;   // a triangle's 1-point rule: k D at most this (3-point: twice)
constexpr double kPointPhase = 2.0;  // a far piece as one point with its phase spread: k D at most this
constexpr double kNearRatio = 2.5;   // a triangle's 3-point rule: this many diameters away
constexpr int kNearMaxDepth = 7;     // subdivision levels at most (4^7 pieces)

// 8-point Gauss-Legendre on [0, 1].
constexpr double kGaussX[8] = {0.019855071751231856, 0.10166676129318664, 0.2372337950418355, 0.4082826787521751,
                               0.5917173212478249,   0.7627662049581645,  0.8983332387068134, 0.9801449282487681};
constexpr double kGaussW[8] = {0.05061426814518813, 0.11119051722668724, 0.15685332293894363, 0.18134189168918100,
                               0.18134189168918100, 0.15685332293894363, 0.11119051722668724, 0.05061426814518813};

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

// Collapsed Gauss products (Stroud 1971, the conical product): n x n points on a triangle, exact
// to degree 2n - 1, for pieces too large in wavelengths for the 7-point rule (k d > 2.5) and at
// least two of their diameters from x. They replace subdividing for the oscillation alone: a
// triangle of k d = 6.4 takes 25-36 points instead of 112 (16 quarters of sixteenths x 7).
constexpr int kProductMaxOrder = 8;
// The largest k d each order n integrates (index n) within the 7-point rule's own error at its
// bound k d = 2.5 (2.5e-5 of area / r), when x is 2-3 diameters away; beyond kFarRatio within
// 1e-3 (below the 0.3% of a far piece's one point with its phase spread; orders 6-8 there at
// their near bounds, not measured at the far one). Measured against a 40 x 40 rule over x in 16
// directions, in plane and above, on a right, an equilateral and a skinny triangle; with a
// margin of 3% in k d.
constexpr double kProductNearKd[kProductMaxOrder + 1] = {0, 0, 0, 0, 3.5, 6.0, 8.7, 11.8, 14.9};
constexpr double kProductFarKd[kProductMaxOrder + 1] = {0, 0, 0, 3.1, 6.0, 9.3, 8.7, 11.8, 14.9};

/// The n x n collapsed Gauss rule (barycentric weights, weights summing to 1), n <= kProductMaxOrder.
const double (*productRule(int n))[4];

/// The product rule's order for a piece of k d at `far` (beyond kFarRatio diameters) or nearer
/// (beyond two): 0 when k d is too large for every order (split it).
inline int productOrder(double kd, bool far) {
  const double* bound = far ? kProductFarKd : kProductNearKd;
  for (int n = 3; n <= kProductMaxOrder; ++n)
    if (kd <= bound[n]) return n;
  return 0;
}

/// The rule for triangle (a, b, c) with centroid m seen from x at wavenumber k, `depth`
/// subdivisions down: 1 point (far and small in wavelengths), the 3- or 7-point rule, a product
/// rule (large in wavelengths, not near), or none (points == 0: split into four quarters, at
/// most kNearMaxDepth times). integrateTriangle and the near cache (nearRule) both choose here,
/// so the cached points are the ones it would use.
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
  if (dist > 2.0 * d) {
    const int n = productOrder(kd, dist > kFarRatio * d);
    if (n > 0) return {productRule(n), n * n};
  }
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
                       int depth, cd& int_g, cd& int_dg);

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n; symmetric by construction).
void gaussLegendre(int n, std::vector<double>& x, std::vector<double>& w);

}  // namespace strike::transfer
