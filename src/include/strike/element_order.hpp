// SPDX-License-Identifier: MIT
// The element order every front-end defaults to (`strike modes`, scenes, Python, batch): chosen
// from the shape, here and nowhere else.
#pragma once

#include <string>

#include "strike/mesh.hpp"
#include "strike/result.hpp"

namespace strike {

/// A shape is thin (walls, plates, bars) when its wall thickness is under this fraction of its
/// largest extent: there bending dominates, Tet4 locks in bending and rings too high (the mug
/// assets/meshes/mug.obj, wall / extent 0.036: Tet4 108% off at 7.9k DOF where Tet10 is 0.5% off on the
/// same mesh; the README's plate: Tet4 23% off at 11.5k DOF, Tet10 0.5% at 14k).
constexpr double kThinWallFraction = 0.1;

/// PrecomputeSettings::order (and a scene object's "order") that asks for chooseElementOrder.
constexpr int kAutoOrder = 0;

struct OrderChoice {
  int order = 1;
  double wall_m = 0.0;    ///< wall thickness, 2 V / A (exact for a flat wall; a solid cube gives L / 3)
  double extent_m = 0.0;  ///< largest side of the bounding box
  std::string reason;     ///< one line for the summary
};

/// Tet10 for a thin shape (wall_m < kThinWallFraction extent_m), Tet4 otherwise (solids, where
/// Tet4 does not lock and costs 1/8 of the unknowns per mesh). `mesh` is any mesh of the shape.
OrderChoice chooseElementOrder(const TetMesh& mesh);

struct PrecomputeSettings;

/// The mesh a precompute with `settings` solves on, at settings.order. kAutoOrder: a mesh built
/// from a primitive or a surface file is Tet10 when chooseElementOrder calls the shape thin,
/// else Tet4 (one meshing: the Tet10 mesh is the Tet4 one promoted, as an explicit order 2
/// builds it); a tet file keeps its own order.
Result<LoadedMesh> loadMeshFor(const PrecomputeSettings& settings);

}  // namespace strike
