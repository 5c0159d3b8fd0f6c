// SPDX-License-Identifier: MIT
// Linear-elastic finite elements: Tet4 and Tet10 stiffness and consistent mass, assembled into
// sparse K and M, and mass properties of the solid. Target strike_fem (Eigen only).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "strike/core/material.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {

/// Mass properties of a solid of uniform density.
struct MassProperties {
  double mass_kg = 0.0;
  double volume_m3 = 0.0;
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();       ///< centre of mass
  Eigen::Matrix3d inertia_kg_m2 = Eigen::Matrix3d::Zero();  ///< inertia tensor about centre_m
};

/// Tet4 (tets.cols() == 4) or Tet10 (10 columns, isoparametric: curved edges are integrated
/// with quadrature; straight ones exactly). Degenerate or inverted elements contribute nothing;
/// validateAndRepair() rejects them earlier.
/// Degrees of freedom: node n, axis a (0 x, 1 y, 2 z) is dof 3 n + a. K and M are 3N by 3N,
/// symmetric, both triangles stored (CHOLMOD and Eigen may use either).
///  K  stiffness, N/m;  M  consistent mass, kg.
void assembleStiffness(const TetMesh& mesh, const Material& material, Eigen::SparseMatrix<double>& K);
void assembleMass(const TetMesh& mesh, double density_kg_m3, Eigen::SparseMatrix<double>& M);
/// Both at once, sharing one sparsity pattern (K and M then have identical structure, so
/// K - sigma M is a plain value-wise combination). Preferred for large meshes.
void assembleStiffnessAndMass(const TetMesh& mesh, const Material& material, Eigen::SparseMatrix<double>& K,
                              Eigen::SparseMatrix<double>& M);

/// Mass, volume, centre and inertia integrated exactly over the tets (Tet10 with straight edges
/// has the same geometry as its Tet4 corners).
MassProperties computeMassProperties(const TetMesh& mesh, double density_kg_m3);

}  // namespace strike
