// SPDX-License-Identifier: MIT
// Convex decomposition of a closed triangle surface into a few convex hulls, for the collision
// shape of a concave moving body (a mug, a glass, a bowl). Internal to strike_bullet.
#pragma once

#include <cstdint>
#include <vector>

namespace strike {

struct ConvexPiecesSettings {
  /// A piece is accepted once none of its surface vertices lies deeper inside its hull than
  /// this, m: the most the piece's hull can stand proud of the surface into a hollow.
  double max_concavity_m = 1e-3;
  int max_pieces = 64;  ///< split no further (the deepest pieces are split first)
  /// Longer triangle edges are bisected first, so that a cut can fall between their ends, m
  /// (0: none).
  double max_edge_m = 0.0;
};

struct ConvexPieces {
  /// Per piece, the hull's points (x, y, z, ...), in the surface's frame.
  std::vector<std::vector<double>> hull_points;
  std::vector<double> hull_volume_m3;  ///< per piece
  double worst_concavity_m = 0.0;      ///< the deepest vertex inside its piece's hull
};

/// Splits the surface's triangles recursively by axis-aligned planes (through the middle of a
/// piece's bounding box, on the axis whose split leaves the shallower concavity) until every
/// piece is convex to within max_concavity_m, and returns the convex hull of each piece's
/// vertices. Every triangle lies in one piece's hull, so the pieces cover the surface; a wall
/// holds its inner and outer faces in one piece where it is split, so pieces are solid. The
/// same input gives the same pieces (no randomness, no unordered containers).
ConvexPieces convexPieces(const std::vector<double>& xyz, const std::vector<uint32_t>& triangles,
                          const ConvexPiecesSettings& settings);

}  // namespace strike
