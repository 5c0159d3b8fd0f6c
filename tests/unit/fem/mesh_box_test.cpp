// SPDX-License-Identifier: MIT
// The box primitive, surface extraction and Tet10 promotion.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <utility>

#include "strike/mesh/mesh.hpp"

namespace strike {
namespace {

double tetVolume(const TetMesh& m, Eigen::Index t) {
  Eigen::Matrix3d J;
  for (int c = 0; c < 3; ++c) J.col(c) = (m.nodes.row(m.tets(t, c + 1)) - m.nodes.row(m.tets(t, 0))).transpose();
  return J.determinant() / 6.0;
}

TEST(Box, CellCountsOrientationAndExtent) {
  MeshOptions options;
  options.target_edge_m = 0.01;
  auto box = makeBox(0.3, 0.02, 0.04, options);
  ASSERT_TRUE(box.ok()) << box.error().message;
  EXPECT_EQ(box->order, 1);
  EXPECT_EQ(box->tets.rows(), 6 * 30 * 2 * 4);
  EXPECT_EQ(box->nodes.rows(), 31 * 3 * 5);
  double volume = 0.0;
  for (Eigen::Index t = 0; t < box->tets.rows(); ++t) {
    const double v = tetVolume(*box, t);
    ASSERT_GT(v, 0.0) << "tet " << t;
    volume += v;
  }
  EXPECT_NEAR(volume, 0.3 * 0.02 * 0.04, 1e-15);
  EXPECT_DOUBLE_EQ(box->nodes.col(0).minCoeff(), -0.15);
  EXPECT_DOUBLE_EQ(box->nodes.col(2).maxCoeff(), 0.02);
}

TEST(Box, DefaultResolutionHasFourCellsAcrossTheBar) {
  auto box = makeBox(0.3, 0.02, 0.02, MeshOptions{});
  ASSERT_TRUE(box.ok());
  EXPECT_EQ(box->tets.rows(), 6 * 60 * 4 * 4);
}

TEST(Box, RejectsBadSizesNamingTheValue) {
  auto negative = makeBox(0.3, -0.02, 0.02, MeshOptions{});
  ASSERT_FALSE(negative.ok());
  EXPECT_EQ(negative.error().kind, ErrorKind::BadInput);
  EXPECT_NE(negative.error().message.find("-0.02"), std::string::npos) << negative.error().message;
  EXPECT_NE(negative.error().message.find("LY"), std::string::npos);
  auto nan = makeBox(std::nan(""), 0.02, 0.02, MeshOptions{});
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.error().message.find("nan"), std::string::npos) << nan.error().message;
  EXPECT_FALSE(makeBox(0.0, 1.0, 1.0, MeshOptions{}).ok());
  MeshOptions bad_order;
  bad_order.order = 3;
  EXPECT_FALSE(makeBox(1.0, 1.0, 1.0, bad_order).ok());
}

TEST(Surface, ClosedOutwardAndAreaOfBox) {
  MeshOptions options;
  options.target_edge_m = 0.05;
  auto box = makeBox(0.3, 0.1, 0.2, options);
  ASSERT_TRUE(box.ok());
  const Eigen::MatrixXi& F = box->surface;
  EXPECT_EQ(F.rows(), 2 * 2 * (6 * 2 + 2 * 4 + 6 * 4));
  // Closed and consistently oriented: every directed edge appears once, its reverse once.
  std::map<std::pair<int, int>, int> directed;
  double area = 0.0;
  double divergence_volume = 0.0;  // (1/3) sum x . n dA = V for outward normals
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int e = 0; e < 3; ++e) ++directed[{F(f, e), F(f, (e + 1) % 3)}];
    const Eigen::Vector3d a = box->nodes.row(F(f, 0)), b = box->nodes.row(F(f, 1)), c = box->nodes.row(F(f, 2));
    const Eigen::Vector3d n2 = (b - a).cross(c - a);
    area += 0.5 * n2.norm();
    divergence_volume += a.dot(n2) / 6.0;
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
  }
  EXPECT_NEAR(area, 2 * (0.3 * 0.1 + 0.1 * 0.2 + 0.3 * 0.2), 1e-12);
  EXPECT_NEAR(divergence_volume, 0.3 * 0.1 * 0.2, 1e-12);
}

TEST(Surface, SingleTet) {
  Eigen::MatrixXi tet(1, 4);
  tet << 0, 1, 2, 3;
  const Eigen::MatrixXi F = extractSurface(tet);
  ASSERT_EQ(F.rows(), 4);
  Eigen::MatrixXi expected(4, 3);
  expected << 1, 2, 3, 0, 3, 2, 0, 1, 3, 0, 2, 1;
  EXPECT_EQ(F, expected);
}

TEST(Tet10, MidEdgeNodesAreSharedAndInGmshOrder) {
  MeshOptions options;
  options.target_edge_m = 0.5;
  auto box4 = makeBox(1.0, 1.0, 1.0, options);  // 2x2x2 cells
  ASSERT_TRUE(box4.ok());
  const TetMesh tet10 = promoteToTet10(*box4);
  EXPECT_EQ(tet10.order, 2);
  ASSERT_EQ(tet10.tets.cols(), 10);
  // Kuhn-split grid of n^3 cells: edges = 3 n (n+1)^2 axis + 3 n^2 (n+1) face diagonals + n^3 body diagonals.
  const int n = 2;
  const int edges = 3 * n * (n + 1) * (n + 1) + 3 * n * n * (n + 1) + n * n * n;
  EXPECT_EQ(tet10.nodes.rows(), 27 + edges);
  const int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  for (Eigen::Index t = 0; t < tet10.tets.rows(); ++t) {
    for (int e = 0; e < 6; ++e) {
      const Eigen::RowVector3d mid =
          0.5 * (tet10.nodes.row(tet10.tets(t, kEdges[e][0])) + tet10.nodes.row(tet10.tets(t, kEdges[e][1])));
      EXPECT_LT((tet10.nodes.row(tet10.tets(t, 4 + e)) - mid).norm(), 1e-15);
    }
  }
  EXPECT_EQ(tet10.surface, box4->surface);
  MeshOptions order2 = options;
  order2.order = 2;
  auto direct = makeBox(1.0, 1.0, 1.0, order2);
  ASSERT_TRUE(direct.ok());
  EXPECT_EQ(direct->tets, tet10.tets);
}

}  // namespace
}  // namespace strike
