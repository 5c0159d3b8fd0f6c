// SPDX-License-Identifier: MIT
// A driven body's path (scene key "path", docs/scene-format.md): keyframes of the pose of its
// mesh frame, and the pose at any time between them.
#pragma once

#include <array>
#include <vector>

namespace strike {

/// One keyframe: at t_s the mesh frame's origin is at position_m and the mesh frame is turned by
/// orientation_wxyz (a unit quaternion, mesh frame -> world).
struct PathKey {
  double t_s = 0.0;
  std::array<double, 3> position_m{};
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};
};

struct PathPose {
  std::array<double, 3> position_m{};
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};
};

/// The pose at time t_s on a path of keys in strictly increasing time (at least one).
/// Piecewise linear in position, so the speed between two keys is their distance over their time
/// apart, as written; the orientation turns at a constant rate between keys (slerp, the shorter
/// way). Before the first key the body is at the first key, after the last it holds the last.
PathPose pathPose(const std::vector<PathKey>& keys, double t_s);

}  // namespace strike
