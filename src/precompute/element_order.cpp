// SPDX-License-Identifier: MIT
#include "strike/precompute/element_order.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "strike/precompute/error_estimate.hpp"
#include "strike/precompute/precompute.hpp"

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

namespace {

/// The edge of a regular tet of the mesh's mean tet volume (the volume from the boundary, as above).
double meanRegularEdge(const TetMesh& mesh) {
  double volume = 0.0;
  for (Eigen::Index f = 0; f < mesh.surface.rows(); ++f) {
    const Eigen::Vector3d a = mesh.nodes.row(mesh.surface(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.nodes.row(mesh.surface(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.nodes.row(mesh.surface(f, 2)).transpose();
    volume += a.dot(b.cross(c)) / 6.0;
  }
  const double mean_tet_volume = std::fabs(volume) / static_cast<double>(std::max<Eigen::Index>(1, mesh.tets.rows()));
  return std::cbrt(6.0 * std::sqrt(2.0) * mean_tet_volume);
}

/// A box or a surface file keeps its geometry whatever the size asked for. A sphere or cylinder
/// primitive is re-faceted at the size: a coarser one would be another, rougher shape.
bool sizeKeepsTheShape(const std::string& mesh_spec) {
  return canRemesh(mesh_spec) && mesh_spec.rfind("sphere:", 0) != 0 && mesh_spec.rfind("cylinder:", 0) != 0;
}

}  // namespace

Result<LoadedMesh> loadMeshFor(const PrecomputeSettings& settings) {
  Result<LoadedMesh> loaded = loadTetMesh(settings.mesh_spec, meshOptionsFor(settings));
  if (!loaded || settings.order != kAutoOrder || !canRemesh(settings.mesh_spec)) return loaded;
  if (chooseElementOrder(loaded->mesh).order != 2) return loaded;
  if (settings.target_edge_m > 0.0 || !sizeKeepsTheShape(settings.mesh_spec)) {
    // Same tets (the cap loadTetMesh checked still holds), mid-edge nodes added.
    loaded->mesh = promoteToTet10(loaded->mesh);
    return loaded;
  }
  // Tet10 at kTet10EdgeFactor times the automatic Tet4 edge: about the unknowns of the Tet4 mesh
  // (a Tet10 mesh has ~8 nodes per corner node), so a thin table is no longer 8x the solve.
  MeshOptions options = meshOptionsFor(settings);
  options.order = 2;
  options.target_edge_m = kTet10EdgeFactor * meanRegularEdge(loaded->mesh);
  Result<LoadedMesh> coarser = loadTetMesh(settings.mesh_spec, options);
  if (!coarser) return coarser.error();
  coarser->meshing_seconds += loaded->meshing_seconds;
  // Thin walls may set TetGen's tet size rather than the target (a glass): then the mesh with
  // fewer nodes, whichever it is.
  TetMesh promoted = promoteToTet10(loaded->mesh);
  if (coarser->mesh.nodes.rows() <= promoted.nodes.rows()) return coarser;
  loaded->mesh = std::move(promoted);
  return loaded;
}

}  // namespace strike
