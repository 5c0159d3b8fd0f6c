// SPDX-License-Identifier: MIT
// Sizing meshes (target strike_precompute): a mesh's mean edge, and a mesh of a shape with a
// given ratio of tets to another, found by searching the target edge.
#include "mesh_sizing.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace strike::detail {
namespace {

double meshVolume(const TetMesh& mesh) {
  double volume = 0.0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const Eigen::Vector3d p0 = mesh.nodes.row(mesh.tets(t, 0)).transpose();
    const Eigen::Vector3d e1 = mesh.nodes.row(mesh.tets(t, 1)).transpose() - p0;
    const Eigen::Vector3d e2 = mesh.nodes.row(mesh.tets(t, 2)).transpose() - p0;
    const Eigen::Vector3d e3 = mesh.nodes.row(mesh.tets(t, 3)).transpose() - p0;
    volume += std::abs(e1.dot(e2.cross(e3))) / 6.0;
  }
  return volume;
}

}  // namespace

double meanEdge(const TetMesh& mesh) {
  return std::cbrt(6.0 * std::sqrt(2.0) * meshVolume(mesh) /
                   static_cast<double>(std::max<Eigen::Index>(1, mesh.tets.rows())));
}

/// A mesh of `spec` with between `lo` and `hi` times `base_tets` tets, as near `want` times as
/// the search finds. TetGen's tet count is not a smooth function of the target edge (the mug:
/// 5.5 mm gives 2.9x the automatic mesh's tets, 5 mm 8.3x, as the quality bound starts to split
/// the wall), so the edge is searched: from `start_edge` it shrinks (count too low) or grows
/// (too high) by 1.15 until the count lies in [lo, hi], then halves the step in log space between
/// the last too-low and too-high edges. At most 8 meshings; the nearest in [lo, hi] wins, or an
/// error when none lands there.
Result<SizedMesh> meshWithTetRatio(const std::string& spec, double scale, int order, int64_t max_tets, double base_tets,
                                   double start_edge, double lo, double hi, double want) {
  MeshOptions options;
  options.scale = scale;  // a file in millimetres is meshed in metres
  options.order = order;
  options.max_tets = max_tets;
  double edge = start_edge, too_small = 0.0, too_large = 0.0;  // edges whose counts were too high / too low
  Result<SizedMesh> best = badInput("no mesh of " + spec + " with " + std::to_string(lo) + " to " + std::to_string(hi) +
                                    " times " + std::to_string(static_cast<long long>(base_tets)) + " tets was found");
  double best_distance = INFINITY;
  for (int attempt = 0; attempt < 8; ++attempt) {
    options.target_edge_m = edge;
    Result<LoadedMesh> mesh = loadTetMesh(spec, options);
    if (!mesh) return mesh.error();
    const double ratio = static_cast<double>(mesh->mesh.tets.rows()) / base_tets;
    if (ratio >= lo && ratio <= hi) {
      const double distance = std::fabs(std::log(ratio / want));
      if (distance < best_distance) {
        best_distance = distance;
        best = SizedMesh{std::move(*mesh), edge};
      }
      if (distance < std::log(1.25)) break;
    }
    if (ratio < want)
      too_large = edge;  // coarser than wanted: make the edge smaller
    else
      too_small = edge;
    if (too_small > 0.0 && too_large > 0.0)
      edge = std::sqrt(too_small * too_large);
    else
      edge = ratio < want ? edge / 1.15 : edge * 1.15;
  }
  return best;
}

}  // namespace strike::detail
