// SPDX-License-Identifier: MIT
#include "quadrature.hpp"

#include <cmath>

namespace strike::fem {

namespace {

// All permutations of (a, b, b, b).
void addOrbit31(std::vector<QuadPoint>& rule, double a, double weight) {
  const double b = (1.0 - a) / 3.0;
  for (int k = 0; k < 4; ++k) {
    QuadPoint q{{b, b, b, b}, weight};
    q.bary[k] = a;
    rule.push_back(q);
  }
}

// All permutations of (a, a, b, b), b = 1/2 - a.
void addOrbit22(std::vector<QuadPoint>& rule, double a, double weight) {
  const double b = 0.5 - a;
  constexpr int kPairs[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (const auto& p : kPairs) {
    QuadPoint q{{b, b, b, b}, weight};
    q.bary[p[0]] = a;
    q.bary[p[1]] = a;
    rule.push_back(q);
  }
}

}  // namespace

const std::vector<QuadPoint>& tetRuleDegree2() {
  static const std::vector<QuadPoint> rule = [] {
    std::vector<QuadPoint> r;
    addOrbit31(r, (5.0 + 3.0 * std::sqrt(5.0)) / 20.0, 1.0 / 24.0);
    return r;
  }();
  return rule;
}

const std::vector<QuadPoint>& tetRuleDegree5() {
  static const std::vector<QuadPoint> rule = [] {
    std::vector<QuadPoint> r;
    // Orbit points given as the small coordinate b of (1 - 3b, b, b, b).
    const double b1 = 0.0927352503108912264023345;
    const double b2 = 0.3108859192633006097973457;
    addOrbit31(r, 1.0 - 3.0 * b1, 0.0122488405193936582572851);
    addOrbit31(r, 1.0 - 3.0 * b2, 0.0187813209530026417998642);
    addOrbit22(r, 0.0455037041256496494918805, 0.0070910034628469110730292);
    return r;
  }();
  return rule;
}

}  // namespace strike::fem
