// SPDX-License-Identifier: MIT
// Scenes that cannot be right, caught before (or after) the simulation and named with numbers:
// bodies starting inside the ground or inside each other (they fly apart
// with a bang that is the solver's, not the scene's), sizes and masses no sounding object has (a
// mesh in millimetres read as metres), and dynamic bodies that nothing ever strikes.
// Warnings, not errors: each of these can be meant.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "strike/scene/scene.hpp"
#include "strike/sim/sim.hpp"

namespace strike {

/// Limits of what the checks accept silently.
struct PlacementLimits {
  double overlap_tolerance_m = 5e-4;    ///< penetration deeper than this is reported (meshes are faceted)
  double max_extent_m = 10.0;           ///< larger than this: implausible for a sounding object
  double min_extent_m = 1e-3;           ///< smaller than this: likely a mesh in metres read as mm
  double max_dynamic_mass_kg = 1000.0;  ///< a heavier moving body is implausible in a sound scene
  size_t max_vertices_tested = 2048;    ///< per body and pair (an even sample), bounds the cost
};

/// Warnings about the bodies' starting placement and size: one line each, naming the objects and
/// the numbers. `bodies[i]` is scene.objects[i] as the simulator gets it (pose, surface, mass).
std::vector<std::string> checkStartingPlacement(const Scene& scene, const std::vector<SimBodyDesc>& bodies,
                                                const PlacementLimits& limits = {});

/// The warning for a dynamic body that nothing struck during `duration_s`: where it started,
/// how far above the ground and how long a free fall from there takes.
std::string neverStruckWarning(const Scene& scene, const SimBodyDesc& body, double duration_s);

/// Depth of point p inside the closed surface (positive inside, 0 outside), from the winding
/// number (the solid angles of the triangles, Van Oosterom and Strackee 1983) and the distance
/// to the nearest triangle. Positions are #V*3, triangles #F*3 CCW from outside.
double depthInside(const double p[3], const std::vector<double>& positions, const std::vector<uint32_t>& triangles);

/// Whether points lie inside a closed surface, as depthInside decides it, in O(1) triangles per
/// point instead of O(#F) arc tangents: a vertical ray from the point crosses the surface, and
/// the signed count of crossings (+1 through a face whose outward normal points up, -1 down) is
/// the winding number of a closed, consistently oriented surface (each directed edge once, its
/// reverse once), found through an xy grid of the triangles. That integer is what depthInside's
/// sum of solid angles rounds to for every point farther than rounding from the surface (a point
/// nearer than that is at depth ~0 either way). Undecided when the surface is not closed and
/// consistently oriented (its winding number need not be an integer), when the ray passes within
/// rounding of an edge or vertex of a triangle, or when the point lies within rounding of a face.
/// The positions and triangles must outlive it.
class InsideTest {
 public:
  InsideTest(const std::vector<double>& positions, const std::vector<uint32_t>& triangles);
  /// 1 inside, 0 outside, -1 undecided (ask depthInside).
  int classify(const double p[3]) const;
  bool closed() const { return closed_; }

 private:
  static constexpr int kCells = 64;  ///< per side of the xy grid
  int cellOf(double x, int k) const;
  const std::vector<double>& positions_;
  const std::vector<uint32_t>& triangles_;
  bool closed_ = false;
  double scale_m_ = 0.0;  ///< largest |coordinate|: the rounding scale
  double low_[3] = {0, 0, 0}, high_[3] = {0, 0, 0};
  double cell_m_[2] = {1, 1};
  std::vector<uint32_t> cell_start_, cell_tris_;  ///< CSR: triangles of xy cell c
};

}  // namespace strike
