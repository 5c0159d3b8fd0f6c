// SPDX-License-Identifier: MIT
// A driven body's pose between its keyframes (path.hpp).
#include "strike/sim/path.hpp"

#include <algorithm>
#include <cmath>

namespace strike {
namespace {

/// Spherical linear interpolation from a to b by the fraction s, the shorter way round.
std::array<double, 4> slerp(std::array<double, 4> a, std::array<double, 4> b, double s) {
  double cosine = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (cosine < 0.0) {  // q and -q are one rotation: take the nearer
    for (double& x : b) x = -x;
    cosine = -cosine;
  }
  double wa = 1.0 - s, wb = s;
  // Nearly equal: linear weights (the sine below would divide by ~0); normalized after.
  if (cosine < 1.0 - 1e-12) {
    const double angle = std::acos(std::min(cosine, 1.0));
    const double sine = std::sin(angle);
    wa = std::sin((1.0 - s) * angle) / sine;
    wb = std::sin(s * angle) / sine;
  }
  std::array<double, 4> q{};
  double norm2 = 0.0;
  for (int k = 0; k < 4; ++k) q[k] = wa * a[k] + wb * b[k], norm2 += q[k] * q[k];
  const double norm = std::sqrt(norm2);
  for (double& x : q) x /= norm;
  return q;
}

}  // namespace

PathPose pathPose(const std::vector<PathKey>& keys, double t_s) {
  PathPose pose;
  if (keys.empty()) return pose;
  if (!(t_s > keys.front().t_s)) {  // also NaN: the first key
    pose.position_m = keys.front().position_m;
    pose.orientation_wxyz = keys.front().orientation_wxyz;
    return pose;
  }
  if (t_s >= keys.back().t_s) {
    pose.position_m = keys.back().position_m;
    pose.orientation_wxyz = keys.back().orientation_wxyz;
    return pose;
  }
  // The key at or before t_s (the keys are in strictly increasing time).
  const auto after = std::upper_bound(keys.begin(), keys.end(), t_s,
                                      [](double t, const PathKey& key) { return t < key.t_s; });
  const PathKey& a = *(after - 1);
  const PathKey& b = *after;
  const double s = (t_s - a.t_s) / (b.t_s - a.t_s);
  for (int k = 0; k < 3; ++k) pose.position_m[k] = a.position_m[k] + s * (b.position_m[k] - a.position_m[k]);
  pose.orientation_wxyz = slerp(a.orientation_wxyz, b.orientation_wxyz, s);
  return pose;
}

}  // namespace strike
