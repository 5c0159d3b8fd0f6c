// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>
#include <tetgen.h>

#include <cstdio>
#include <string>

#include "mesh/mesh_test_util.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {
namespace {

using test::failsWith;
using test::meshData;

void expectCube(Result<TetMesh>& mesh, int order) {
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->order, order);
  EXPECT_EQ(mesh->tets.rows(), 6);
  EXPECT_EQ(mesh->tets.cols(), order == 2 ? 10 : 4);
  EXPECT_EQ(mesh->nodes.rows(), order == 2 ? 27 : 8);  // 8 corners + 19 edges of the Kuhn split
  EXPECT_NEAR(test::totalVolume(*mesh), 1.0, 1e-12);
  for (Eigen::Index t = 0; t < 6; ++t) EXPECT_GT(test::tetVolume(*mesh, t), 0.0);
  if (order == 2) {
    EXPECT_TRUE(test::midEdgeNodesAtMidpoints(*mesh));
  }
  std::vector<MeshWarning> warnings;
  ASSERT_TRUE(validateAndRepair(*mesh, "cube", &warnings).ok());
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ(mesh->surface.rows(), 12);
}

TEST(GmshReader, Tet4Version22WithSparseTagsAndOtherElements) {
  Result<TetMesh> m = readGmsh(meshData("cube_tet4_v22.msh"), nullptr);
  expectCube(m, 1);
  EXPECT_EQ(m->nodes(1, 0), 1.0);  // node rows follow the file order, whatever the tags
}
TEST(GmshReader, Tet10Version22) {
  Result<TetMesh> m = readGmsh(meshData("cube_tet10_v22.msh"), nullptr);
  expectCube(m, 2);
}
TEST(GmshReader, Tet4Version41WithNodeBlocks) {
  Result<TetMesh> m = readGmsh(meshData("cube_tet4_v41.msh"), nullptr);
  expectCube(m, 1);
}
TEST(GmshReader, Tet10Version41) {
  Result<TetMesh> m = readGmsh(meshData("cube_tet10_v41.msh"), nullptr);
  expectCube(m, 2);
}

TEST(GmshReader, BadIndexNamesLineElementNodeAndCount) {
  EXPECT_TRUE(failsWith(readGmsh(meshData("bad/bad_index.msh"), nullptr),
                        {"bad_index.msh:28:", "element 105 references node 90211", "8 nodes"}));
}
TEST(GmshReader, InfCoordinate) {
  EXPECT_TRUE(failsWith(readGmsh(meshData("bad/nan.msh"), nullptr), {"nan.msh:11:", "inf", "finite"}));
}
TEST(GmshReader, HugeNodeCountIsRefusedBeforeAllocating) {
  EXPECT_TRUE(
      failsWith(readGmsh(meshData("bad/huge_count.msh"), nullptr), {"huge_count.msh:9:", "1000000000", "bytes left"}));
}
TEST(GmshReader, Truncated) {
  EXPECT_TRUE(failsWith(readGmsh(meshData("bad/truncated.msh"), nullptr), {"truncated.msh:", "truncated"}));
}
TEST(GmshReader, SurfaceOnlyMeshHasNoTets) {
  EXPECT_TRUE(failsWith(readGmsh(meshData("bad/surface_only.msh"), nullptr), {"surface_only.msh", "no tetrahedra"}));
}

TEST(TetgenReader, Tet4OneBasedByStemNodeOrEle) {
  for (const char* name : {"cube_tet4", "cube_tet4.node", "cube_tet4.ele"}) {
    Result<TetMesh> m = readTetgen(meshData(name), nullptr);
    expectCube(m, 1);
  }
}
TEST(TetgenReader, Tet10ZeroBasedInTetgenOrder) {
  Result<TetMesh> m = readTetgen(meshData("cube_tet10"), nullptr);
  expectCube(m, 2);
}
TEST(TetgenReader, HugeCount) {
  EXPECT_TRUE(failsWith(readTetgen(meshData("bad/huge_count"), nullptr), {"huge_count.node:2:", "1000000000"}));
}
TEST(TetgenReader, BadIndexNamesLineTetNodeAndCount) {
  EXPECT_TRUE(failsWith(readTetgen(meshData("bad/bad_index.ele"), nullptr),
                        {"bad_index.ele:7:", "tet 6 references node 80", "8 nodes"}));
}
TEST(TetgenReader, MissingEleFile) {
  EXPECT_TRUE(failsWith(readTetgen(meshData("cube_tet4_v22"), nullptr), {"cube_tet4_v22.node", "not found"}));
}

// The Tet10 node order of .ele files is TetGen's own; run the real TetGen with -o2, write its
// files and check that every mid-edge node we read sits at the midpoint of the edge that our
// (Gmsh) numbering says.
TEST(TetgenReader, RealTetgenO2FilesHaveMidEdgeNodesAtMidpoints) {
  tetgenio in, out;
  in.firstnumber = 1;
  in.numberofpoints = 8;
  in.pointlist = new REAL[24];
  for (int i = 0; i < 8; ++i) {
    in.pointlist[3 * i] = i & 1;
    in.pointlist[3 * i + 1] = (i >> 1) & 1;
    in.pointlist[3 * i + 2] = (i >> 2) & 1;
  }
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  in.numberoffacets = 6;
  in.facetlist = new tetgenio::facet[6];
  for (int f = 0; f < 6; ++f) {
    tetgenio::init(&in.facetlist[f]);
    in.facetlist[f].numberofpolygons = 1;
    in.facetlist[f].polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&in.facetlist[f].polygonlist[0]);
    in.facetlist[f].polygonlist[0].numberofvertices = 4;
    in.facetlist[f].polygonlist[0].vertexlist = new int[4];
    for (int k = 0; k < 4; ++k) in.facetlist[f].polygonlist[0].vertexlist[k] = quads[f][k] + 1;
  }
  tetgenbehavior b;
  char switches[] = "pq1.4a0.02o2Q";
  ASSERT_TRUE(b.parse_commandline(switches));
  ::tetrahedralize(&b, &in, &out);
  ASSERT_EQ(out.numberofcorners, 10);
  std::string stem = ::testing::TempDir() + "tetgen_o2_cube";
  out.save_nodes(stem.data());
  out.save_elements(stem.data());

  std::vector<MeshWarning> warnings;
  Result<TetMesh> m = readTetgen(stem, &warnings);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->order, 2);
  EXPECT_EQ(m->tets.rows(), out.numberoftetrahedra);
  EXPECT_TRUE(test::midEdgeNodesAtMidpoints(*m));
  EXPECT_NEAR(test::totalVolume(*m), 1.0, 1e-12);
  ASSERT_TRUE(validateAndRepair(*m, stem, &warnings).ok());
  EXPECT_TRUE(warnings.empty()) << warnings.front().message;  // TetGen's tets are positive
  std::remove((stem + ".node").c_str());
  std::remove((stem + ".ele").c_str());
}

}  // namespace
}  // namespace strike
