// SPDX-License-Identifier: MIT
// Shared helpers of the mesh tests: data paths, volumes, error-message assertions.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <initializer_list>
#include <string>

#include "strike/mesh/mesh.hpp"

namespace strike::test {

inline std::string meshData(const std::string& name) {
  return std::string(STRIKE_SOURCE_DIR) + "/tests/data/mesh/" + name;
}

inline double tetVolume(const TetMesh& mesh, Eigen::Index t) {
  const Eigen::Vector3d p0 = mesh.nodes.row(mesh.tets(t, 0)).transpose();
  const Eigen::Vector3d a = mesh.nodes.row(mesh.tets(t, 1)).transpose() - p0;
  const Eigen::Vector3d b = mesh.nodes.row(mesh.tets(t, 2)).transpose() - p0;
  const Eigen::Vector3d c = mesh.nodes.row(mesh.tets(t, 3)).transpose() - p0;
  return a.dot(b.cross(c)) / 6.0;
}

inline double totalVolume(const TetMesh& mesh) {
  double v = 0.0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) v += tetVolume(mesh, t);
  return v;
}

inline double surfaceVolume(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  double v = 0.0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

/// Every mid-edge node of a Tet10 mesh lies at the midpoint of its edge (Gmsh order).
inline bool midEdgeNodesAtMidpoints(const TetMesh& mesh, double tol = 1e-12) {
  constexpr int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (int e = 0; e < 6; ++e) {
      const Eigen::RowVector3d mid =
          0.5 * (mesh.nodes.row(mesh.tets(t, kEdges[e][0])) + mesh.nodes.row(mesh.tets(t, kEdges[e][1])));
      if ((mesh.nodes.row(mesh.tets(t, 4 + e)) - mid).norm() > tol) return false;
    }
  }
  return true;
}

/// The error message contains every one of `parts`.
template <class R>
::testing::AssertionResult failsWith(const R& result, std::initializer_list<std::string> parts) {
  if (result.ok()) return ::testing::AssertionFailure() << "expected an error, got success";
  const std::string& message = result.error().message;
  if (result.error().kind != ErrorKind::BadInput) return ::testing::AssertionFailure() << "not BadInput: " << message;
  for (const std::string& part : parts) {
    if (message.find(part) == std::string::npos) {
      return ::testing::AssertionFailure() << "message \"" << message << "\" lacks \"" << part << "\"";
    }
  }
  return ::testing::AssertionSuccess() << message;
}

inline bool hasWarning(const std::vector<MeshWarning>& warnings, const std::string& part) {
  for (const MeshWarning& w : warnings) {
    if (w.message.find(part) != std::string::npos) return true;
  }
  return false;
}

}  // namespace strike::test
