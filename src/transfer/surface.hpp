// SPDX-License-Identifier: MIT
// The body's surface as the solver sees it: its triangles, the bounding-volume tree over them
// (the clusters and pieces are its nodes) and the interior points for CHIEF.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "kernels.hpp"
#include "strike/bank/bank.hpp"
#include "strike/core/result.hpp"

namespace strike::transfer {

/// Pieces of a row's sum: at most this many median triangle edges across (makeSurface).
constexpr double kPieceEdges = 4.0;

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

/// The largest distance of a corner of a triangle of nonzero area from the bank's centre
/// (Surface::radius, without the rest of makeSurface).
double surfaceRadius(const ModeBank& bank);

/// The surface of `bank` (degenerate triangles dropped), its tree and its interior points.
Result<Surface> makeSurface(const ModeBank& bank);

}  // namespace strike::transfer
