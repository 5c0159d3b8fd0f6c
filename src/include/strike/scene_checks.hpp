// SPDX-License-Identifier: MIT
// Scenes that cannot be right, caught before (or after) the simulation and named with numbers
// (issue 15, item 10): bodies starting inside the ground or inside each other (they fly apart
// with a bang that is the solver's, not the scene's), sizes and masses no sounding object has (a
// mesh in millimetres read as metres), and dynamic bodies that nothing ever strikes.
// Warnings, not errors: each of these can be meant.
#pragma once

#include <string>
#include <vector>

#include "strike/scene.hpp"
#include "strike/sim.hpp"

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

}  // namespace strike
