// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "mesh/mesh_test_util.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {
namespace {

using test::failsWith;
using test::hasWarning;
using test::meshData;

TetMesh singleTet() {
  TetMesh m;
  m.nodes.resize(4, 3);
  m.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  m.tets.resize(1, 4);
  m.tets << 0, 1, 2, 3;
  return m;
}

TEST(ValidateAndRepair, InvertedTetsAreReorientedWithAWarning) {
  Result<TetMesh> m = readGmsh(meshData("bad/inverted.msh"), nullptr);
  ASSERT_TRUE(m.ok()) << m.error().message;
  std::vector<MeshWarning> warnings;
  ASSERT_TRUE(validateAndRepair(*m, "inverted.msh", &warnings).ok());
  EXPECT_TRUE(hasWarning(warnings, "2 of 6 tets were inverted")) << (warnings.empty() ? "" : warnings[0].message);
  for (Eigen::Index t = 0; t < m->tets.rows(); ++t) EXPECT_GT(test::tetVolume(*m, t), 0.0);
  EXPECT_NEAR(test::totalVolume(*m), 1.0, 1e-12);
  EXPECT_EQ(m->surface.rows(), 12);
}

TEST(ValidateAndRepair, InvertedTet10KeepsMidEdgeNodesOnTheirEdges) {
  Result<TetMesh> m = readGmsh(meshData("bad/inverted_tet10.msh"), nullptr);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_TRUE(test::midEdgeNodesAtMidpoints(*m));
  std::vector<MeshWarning> warnings;
  ASSERT_TRUE(validateAndRepair(*m, "inverted_tet10.msh", &warnings).ok());
  EXPECT_TRUE(hasWarning(warnings, "1 of 6 tets were inverted"));
  EXPECT_TRUE(test::midEdgeNodesAtMidpoints(*m));
  EXPECT_NEAR(test::totalVolume(*m), 1.0, 1e-12);
}

TEST(ValidateAndRepair, DegenerateTetNamesIndexNodesAndVolume) {
  Result<TetMesh> m = readGmsh(meshData("bad/degenerate.msh"), nullptr);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_TRUE(failsWith(validateAndRepair(*m, "degenerate.msh", nullptr),
                        {"degenerate.msh", "tet 0 is degenerate", "volume 0", "nodes 0 (0, 0, 0), 1 (1, 0, 0)"}));
}

TEST(ValidateAndRepair, UnreferencedNodeIsRemovedWithAWarning) {
  Result<TetMesh> m = readGmsh(meshData("bad/unreferenced.msh"), nullptr);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->nodes.rows(), 9);
  std::vector<MeshWarning> warnings;
  ASSERT_TRUE(validateAndRepair(*m, "unreferenced.msh", &warnings).ok());
  EXPECT_TRUE(hasWarning(warnings, "removed 1 of 9 nodes"));
  EXPECT_EQ(m->nodes.rows(), 8);
  EXPECT_LE(m->nodes.maxCoeff(), 1.0);  // the stray node at (5, 5, 5) is gone
  EXPECT_NEAR(test::totalVolume(*m), 1.0, 1e-12);
}

TEST(ValidateAndRepair, EmptyMeshIsAnErrorNotASilentEmptyResult) {
  TetMesh m;
  m.nodes.resize(4, 3);
  m.nodes.setZero();
  m.tets.resize(0, 4);
  EXPECT_TRUE(failsWith(validateAndRepair(m, "empty.msh", nullptr), {"empty.msh", "no tetrahedra", "0 tets"}));
}

TEST(ValidateAndRepair, NonFiniteNodeAndOutOfRangeIndex) {
  TetMesh m = singleTet();
  m.nodes(2, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(failsWith(validateAndRepair(m, "x", nullptr), {"node 2 coordinate y", "nan"}));
  m = singleTet();
  m.tets(0, 3) = 7;
  EXPECT_TRUE(failsWith(validateAndRepair(m, "x", nullptr), {"tet 0 references node 7", "4 nodes"}));
}

TEST(ValidateAndRepair, OverlappingTetsAreRejected) {
  TetMesh m = singleTet();
  m.tets.resize(3, 4);
  m.tets << 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3;
  EXPECT_TRUE(failsWith(validateAndRepair(m, "x", nullptr), {"shared by tets 0, 1 and 2"}));
}

TEST(CheckClosedSurface, SingleTriangleIsOpen) {
  SurfaceMesh s;
  s.V.resize(3, 3);
  s.V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  s.F.resize(1, 3);
  s.F << 0, 1, 2;
  EXPECT_TRUE(
      failsWith(checkClosedSurface(s, "tri"), {"tri", "not closed", "edge (0, 1) from (0, 0, 0) to (1, 0, 0)"}));
}

TEST(CheckClosedSurface, DegenerateTriangle) {
  SurfaceMesh s;
  s.V.resize(3, 3);
  s.V << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  s.F.resize(2, 3);
  s.F << 0, 1, 2, 0, 2, 1;
  EXPECT_TRUE(failsWith(checkClosedSurface(s, "flat"), {"flat", "triangle 0", "degenerate"}));
}

TEST(CheckClosedSurface, NonManifoldEdge) {
  // Three triangles on one edge (a "book" of pages): not a solid boundary.
  SurfaceMesh s;
  s.V.resize(5, 3);
  s.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1;
  s.F.resize(3, 3);
  s.F << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  EXPECT_TRUE(failsWith(checkClosedSurface(s, "book"), {"book", "not manifold", "used by 3 triangles"}));
}

}  // namespace
}  // namespace strike
