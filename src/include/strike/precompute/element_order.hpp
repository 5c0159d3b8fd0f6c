// SPDX-License-Identifier: MIT
// The element order every front-end defaults to (`strike modes`, scenes, Python, batch): chosen
// from the shape, here and nowhere else.
#pragma once

#include <string>

#include "strike/mesh/mesh.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// A shape is thin (walls, plates, bars) when its wall thickness is under this fraction of its
/// largest extent: there bending dominates, Tet4 locks in bending and rings too high (the mug
/// assets/meshes/mug.obj, wall / extent 0.036: Tet4 108% off at 7.9k DOF where Tet10 is 0.5% off on the
/// same mesh; the README's plate: Tet4 23% off at 11.5k DOF, Tet10 0.5% at 14k).
constexpr double kThinWallFraction = 0.1;

/// The automatic order meshes a thin box or surface file for Tet10 at this many times the edge of
/// its automatic Tet4 mesh (the edge of a regular tet of the mean tet volume): a Tet10 mesh has
/// about 8 nodes per corner node, so twice the edge keeps about the Tet4 mesh's unknowns, where
/// Tet10 on the Tet4 mesh itself had ~8x (a 1 x 0.6 x 0.03 m table: 263,529 DOF, 5.6 GB).
/// Tet10 converges as h^4 in bending where Tet4 locks, so the coarser Tet10 is still the closer.
constexpr double kTet10EdgeFactor = 2.0;

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
/// else Tet4; a tet file keeps its own order. A thin box or surface file with no size asked for
/// is meshed again for Tet10 at kTet10EdgeFactor times the Tet4 mesh's edge (an explicit order 2
/// keeps the automatic Tet4 size); a thin sphere or cylinder primitive, whose size re-facets its
/// surface, and a mesh with a size asked for get Tet10 on the Tet4 mesh's own tets.
Result<LoadedMesh> loadMeshFor(const PrecomputeSettings& settings);

}  // namespace strike
