// SPDX-License-Identifier: MIT
// The adaptive integration of G and dG/dn over a triangle, and Gauss-Legendre rules.
#include "quadrature.hpp"

namespace strike::transfer {

namespace {

/// The product rules of orders 0..kProductMaxOrder, built once: with u, v Gauss-Legendre nodes
/// on [0, 1], the point (1 - u, u (1 - v), u v) with weight 2 w_u w_v u (the Jacobian of the
/// collapse of the square onto the triangle, over the triangle's area 1/2).
struct ProductRules {
  double rule[kProductMaxOrder + 1][kProductMaxOrder * kProductMaxOrder][4] = {};
  ProductRules() {
    std::vector<double> x, w;
    for (int n = 1; n <= kProductMaxOrder; ++n) {
      gaussLegendre(n, x, w);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const double u = 0.5 * (1.0 + x[i]), v = 0.5 * (1.0 + x[j]);
          double* point = rule[n][i * n + j];
          point[0] = 1.0 - u;
          point[1] = u * (1.0 - v);
          point[2] = u * v;
          point[3] = 2.0 * (0.5 * w[i]) * (0.5 * w[j]) * u;
        }
    }
  }
};

}  // namespace

const double (*productRule(int n))[4] {
  static const ProductRules rules;
  return rules.rule[n];
}

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

}  // namespace strike::transfer
