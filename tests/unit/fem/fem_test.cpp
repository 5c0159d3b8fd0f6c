// SPDX-License-Identifier: MIT
// Tet4/Tet10 element integrals and assembly: quadrature exactness, rigid-body null space,
// symmetry, total mass, mass properties and a constant-strain patch test.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "quadrature.hpp"
#include "strike/fem/fem.hpp"

namespace strike {
namespace {

const Material kSteel{"steel", 2.0e11, 0.29, 7850.0, 0.0, 0.0};

double factorial(int k) { return k <= 1 ? 1.0 : k * factorial(k - 1); }

// int over the unit tet of xi^a eta^b zeta^c = a! b! c! / (a + b + c + 3)!
void expectRuleExact(const std::vector<fem::QuadPoint>& rule, int degree) {
  for (int a = 0; a <= degree; ++a) {
    for (int b = 0; a + b <= degree; ++b) {
      for (int c = 0; a + b + c <= degree; ++c) {
        double sum = 0.0;
        for (const auto& q : rule)
          sum += q.weight * std::pow(q.bary[1], a) * std::pow(q.bary[2], b) * std::pow(q.bary[3], c);
        const double exact = factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 3);
        EXPECT_NEAR(sum, exact, 1e-15) << "monomial " << a << " " << b << " " << c;
      }
    }
  }
}

TEST(Quadrature, RulesAreExactToTheirDegree) {
  expectRuleExact(fem::tetRuleDegree2(), 2);
  expectRuleExact(fem::tetRuleDegree5(), 5);
  for (const auto& q : fem::tetRuleDegree5()) EXPECT_GT(q.weight, 0.0);
}

TetMesh skewedBox(int order) {
  MeshOptions options;
  options.target_edge_m = 0.01;
  options.order = order;
  TetMesh mesh = makeBox(0.05, 0.02, 0.03, options).value();
  // A shear and an offset so that nothing lines up with the axes by accident.
  Eigen::Matrix3d A;
  A << 1.0, 0.2, 0.1, 0.0, 1.1, -0.15, 0.05, 0.0, 0.9;
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {
    mesh.nodes.row(i) = (A * mesh.nodes.row(i).transpose()).transpose() + Eigen::RowVector3d(0.3, -0.2, 0.1);
  }
  return mesh;
}

Eigen::MatrixXd rigidModes(const TetMesh& mesh) {
  const Eigen::Index n = mesh.nodes.rows();
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(3 * n, 6);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d x = mesh.nodes.row(i);
    for (int a = 0; a < 3; ++a) R(3 * i + a, a) = 1.0;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d u = Eigen::Vector3d::Unit(a).cross(x);  // rotation about axis a
      R.block<3, 1>(3 * i, 3 + a) = u;
    }
  }
  return R;
}

class FemOrder : public ::testing::TestWithParam<int> {};

TEST_P(FemOrder, StiffnessAnnihilatesRigidMotionsAndIsSymmetric) {
  const TetMesh mesh = skewedBox(GetParam());
  Eigen::SparseMatrix<double> K;
  assembleStiffness(mesh, kSteel, K);
  ASSERT_EQ(K.rows(), 3 * mesh.nodes.rows());
  ASSERT_TRUE(K.isCompressed());
  const Eigen::SparseMatrix<double> Kt = K.transpose();
  EXPECT_LT((K - Kt).norm(), 1e-14 * K.norm());
  const Eigen::MatrixXd R = rigidModes(mesh);
  // Relative to the size of K R's individual terms (||K|| ||r||).
  for (int k = 0; k < 6; ++k) {
    const double scale = K.norm() * R.col(k).norm();
    EXPECT_LT((K * R.col(k)).norm(), 1e-12 * scale) << "rigid mode " << k;
  }
}

TEST_P(FemOrder, MassIsSymmetricAndSumsToRhoV) {
  const TetMesh mesh = skewedBox(GetParam());
  Eigen::SparseMatrix<double> M;
  assembleMass(mesh, kSteel.density_kg_m3, M);
  const Eigen::SparseMatrix<double> Mt = M.transpose();
  EXPECT_LT((M - Mt).norm(), 1e-15 * M.norm());
  const MassProperties props = computeMassProperties(mesh, kSteel.density_kg_m3);
  EXPECT_NEAR(props.volume_m3,
              0.05 * 0.02 * 0.03 * (1.0 * 1.1 * 0.9 - 0.2 * (0.0 * 0.9 + 0.15 * 0.05) + 0.1 * (0.0 - 1.1 * 0.05)),
              1e-18);
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::VectorXd u = Eigen::VectorXd::Zero(M.rows());
    for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) u[3 * i + axis] = 1.0;
    EXPECT_NEAR(u.dot(M * u), props.mass_kg, 1e-13 * props.mass_kg);
  }
  // The consistent mass reproduces the inertia tensor: r^T M r for rotation r about the centre.
  TetMesh centred = mesh;
  centred.nodes.rowwise() -= props.centre_m.transpose();
  const Eigen::MatrixXd R = rigidModes(centred);
  const Eigen::MatrixXd J = R.rightCols(3).transpose() * (M * R.rightCols(3));
  EXPECT_LT((J - props.inertia_kg_m2).norm(), 1e-12 * props.inertia_kg_m2.norm());
}

TEST_P(FemOrder, ConstantStrainPatchTest) {
  // u = G x gives a uniform strain; the strain energy must be exact: 1/2 u^T K u = 1/2 V eps:C:eps.
  const TetMesh mesh = skewedBox(GetParam());
  Eigen::SparseMatrix<double> K;
  assembleStiffness(mesh, kSteel, K);
  Eigen::Matrix3d G;
  G << 1e-3, 2e-4, -1e-4, 0.0, -5e-4, 3e-4, 1e-4, 0.0, 2e-4;
  Eigen::VectorXd u(K.rows());
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) u.segment<3>(3 * i) = G * mesh.nodes.row(i).transpose();
  const Eigen::Matrix3d eps = 0.5 * (G + G.transpose());
  const double nu = kSteel.poisson;
  const double lambda = kSteel.youngs_pa * nu / ((1 + nu) * (1 - 2 * nu));
  const double mu = kSteel.youngs_pa / (2 * (1 + nu));
  const double volume = computeMassProperties(mesh, 1.0).volume_m3;
  const double energy =
      0.5 * volume * (lambda * eps.trace() * eps.trace() + 2 * mu * (eps.array() * eps.array()).sum());
  EXPECT_NEAR(0.5 * u.dot(K * u), energy, 1e-11 * energy);
}

TEST_P(FemOrder, CombinedAssemblyMatchesSeparate) {
  const TetMesh mesh = skewedBox(GetParam());
  Eigen::SparseMatrix<double> K, M, K2, M2;
  assembleStiffness(mesh, kSteel, K);
  assembleMass(mesh, kSteel.density_kg_m3, M);
  assembleStiffnessAndMass(mesh, kSteel, K2, M2);
  EXPECT_EQ((K - K2).norm(), 0.0);
  EXPECT_EQ((M - M2).norm(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(Tet4AndTet10, FemOrder, ::testing::Values(1, 2));

TEST(MassProperties, BoxMatchesClosedForm) {
  MeshOptions options;
  options.target_edge_m = 0.01;
  TetMesh box = makeBox(0.3, 0.02, 0.04, options).value();
  box.nodes.rowwise() += Eigen::RowVector3d(1.0, 2.0, -3.0);
  const double rho = 7850.0;
  const MassProperties p = computeMassProperties(box, rho);
  const double m = rho * 0.3 * 0.02 * 0.04;
  EXPECT_NEAR(p.mass_kg, m, 1e-13 * m);
  EXPECT_NEAR((p.centre_m - Eigen::Vector3d(1.0, 2.0, -3.0)).norm(), 0.0, 1e-14);
  EXPECT_NEAR(p.inertia_kg_m2(0, 0), m * (0.02 * 0.02 + 0.04 * 0.04) / 12, 1e-12 * m * 0.01);
  EXPECT_NEAR(p.inertia_kg_m2(1, 1), m * (0.3 * 0.3 + 0.04 * 0.04) / 12, 1e-12 * m * 0.1);
  EXPECT_NEAR(p.inertia_kg_m2(2, 2), m * (0.3 * 0.3 + 0.02 * 0.02) / 12, 1e-12 * m * 0.1);
  EXPECT_NEAR(p.inertia_kg_m2(0, 1), 0.0, 1e-12 * m * 0.1);
  EXPECT_NEAR(p.inertia_kg_m2(1, 2), 0.0, 1e-12 * m * 0.1);
  const MassProperties p10 = computeMassProperties(promoteToTet10(box), rho);
  EXPECT_NEAR(p10.mass_kg, p.mass_kg, 1e-13 * m);
}

}  // namespace
}  // namespace strike
