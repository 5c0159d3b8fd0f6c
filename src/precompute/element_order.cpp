// SPDX-License-Identifier: MIT
#include "strike/element_order.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "strike/error_estimate.hpp"
#include "strike/precompute.hpp"

namespace strike {

OrderChoice chooseElementOrder(const TetMesh& mesh) {
  // Volume and area from the boundary triangles (divergence theorem), so the mesh order and the
  // interior do not matter.
  double volume = 0.0, area = 0.0;
  for (Eigen::Index f = 0; f < mesh.surface.rows(); ++f) {
    const Eigen::Vector3d a = mesh.nodes.row(mesh.surface(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.nodes.row(mesh.surface(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.nodes.row(mesh.surface(f, 2)).transpose();
    volume += a.dot(b.cross(c)) / 6.0;
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  OrderChoice choice;
  const Eigen::Vector3d extent = mesh.nodes.colwise().maxCoeff() - mesh.nodes.colwise().minCoeff();
  choice.extent_m = extent.maxCoeff();
  // A wall of thickness t and one-side area S has V = S t and A = 2 S (plus its edges): t = 2 V / A.
  choice.wall_m = area > 0.0 ? 2.0 * std::fabs(volume) / area : 0.0;
  const bool thin = choice.wall_m < kThinWallFraction * choice.extent_m;
  choice.order = thin ? 2 : 1;
  char text[200];
  std::snprintf(text, sizeof text, "wall %.3g mm (2 V / A) is %s %.0f%% of the %.3g mm extent: %s", 1e3 * choice.wall_m,
                thin ? "under" : "at least", 100.0 * kThinWallFraction, 1e3 * choice.extent_m,
                thin ? "thin, Tet4 would lock in bending" : "a solid, Tet4 does not lock");
  choice.reason = text;
  return choice;
}

Result<LoadedMesh> loadMeshFor(const PrecomputeSettings& settings) {
  Result<LoadedMesh> loaded = loadTetMesh(settings.mesh_spec, meshOptionsFor(settings));
  if (!loaded || settings.order != kAutoOrder || !canRemesh(settings.mesh_spec)) return loaded;
  // Same tets (the cap loadTetMesh checked still holds), mid-edge nodes added.
  if (chooseElementOrder(loaded->mesh).order == 2) loaded->mesh = promoteToTet10(loaded->mesh);
  return loaded;
}

}  // namespace strike
