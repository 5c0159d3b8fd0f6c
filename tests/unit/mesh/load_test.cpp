// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>

#include "mesh/mesh_test_util.hpp"
#include "strike/core/constants.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {
namespace {

using test::failsWith;
using test::hasWarning;
using test::meshData;

uint64_t fnv(const std::string& s) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

TEST(LoadTetMesh, BoxPrimitive) {
  Result<LoadedMesh> m = loadTetMesh("box:0.3,0.02,0.02", MeshOptions{});
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_NEAR(test::totalVolume(m->mesh), 0.3 * 0.02 * 0.02, 1e-15);
  EXPECT_EQ(m->source_hash, fnv("box:0.3,0.02,0.02"));
  EXPECT_GE(m->meshing_seconds, 0.0);
}

TEST(LoadTetMesh, SphereAndCylinderPrimitives) {
  Result<LoadedMesh> s = loadTetMesh("sphere:0.05", MeshOptions{});
  ASSERT_TRUE(s.ok()) << s.error().message;
  const double sphere = 4.0 / 3.0 * kPi * std::pow(0.05, 3);
  EXPECT_NEAR(test::totalVolume(s->mesh), sphere, 0.03 * sphere);
  EXPECT_GT(s->mesh.surface.rows(), 0);
  EXPECT_GT(s->meshing_seconds, 0.0);
  Result<LoadedMesh> c = loadTetMesh("cylinder:0.02,0.1", MeshOptions{});
  ASSERT_TRUE(c.ok()) << c.error().message;
  const double cylinder = kPi * 0.02 * 0.02 * 0.1;
  EXPECT_NEAR(test::totalVolume(c->mesh), cylinder, 0.03 * cylinder);
}

TEST(LoadTetMesh, BadPrimitiveSpecsNameSpecValueAndForm) {
  const MeshOptions o;
  EXPECT_TRUE(failsWith(loadTetMesh("box:0.1,0.02", o), {"box:0.1,0.02", "got 2", "expected 3", "box:LX,LY,LZ"}));
  EXPECT_TRUE(failsWith(loadTetMesh("box:0.1,abc,0.02", o), {"LY = \"abc\"", "not a number", "box:LX,LY,LZ"}));
  EXPECT_TRUE(failsWith(loadTetMesh("box:0.1,,0.02", o), {"LY = \"\"", "box:LX,LY,LZ"}));
  EXPECT_TRUE(failsWith(loadTetMesh("sphere:-1", o), {"sphere:-1", "R = -1", "> 0", "sphere:R"}));
  EXPECT_TRUE(failsWith(loadTetMesh("sphere:nan", o), {"R = nan", "sphere:R"}));
  EXPECT_TRUE(failsWith(loadTetMesh("sphere:1e999", o), {"R = inf"}));
  EXPECT_TRUE(failsWith(loadTetMesh("sphere: 0.1", o), {"R = \" 0.1\"", "not a number"}));
  EXPECT_TRUE(failsWith(loadTetMesh("cylinder:0.1,0", o), {"H = 0", "cylinder:R,H"}));
  EXPECT_TRUE(failsWith(loadTetMesh("cylinder:0.1", o), {"got 1", "expected 2", "cylinder:R,H"}));
  EXPECT_TRUE(failsWith(loadTetMesh("sphere:0.1x", o), {"R = \"0.1x\""}));
}

TEST(LoadTetMesh, SurfaceFilesGoThroughTetgen) {
  for (const char* name : {"cube.obj", "cube_binary.stl", "cube_ascii.stl", "cube_ascii.ply", "cube_binary_be.ply"}) {
    Result<LoadedMesh> m = loadTetMesh(meshData(name), MeshOptions{});
    ASSERT_TRUE(m.ok()) << name << ": " << m.error().message;
    EXPECT_NEAR(test::totalVolume(m->mesh), 1.0, 1e-9) << name;
    EXPECT_GT(m->mesh.tets.rows(), 100) << name;
  }
}

TEST(LoadTetMesh, SourceHashIsTheFileHash) {
  Result<LoadedMesh> a = loadTetMesh(meshData("cube_ascii.stl"), MeshOptions{});
  Result<LoadedMesh> b = loadTetMesh(meshData("cube_binary.stl"), MeshOptions{});
  Result<LoadedMesh> c = loadTetMesh(meshData("cube_binary.stl"), MeshOptions{});
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  EXPECT_NE(a->source_hash, b->source_hash);
  EXPECT_EQ(b->source_hash, c->source_hash);
}

TEST(LoadTetMesh, Tet4FileWithOrder2IsPromoted) {
  MeshOptions o;
  o.order = 2;
  Result<LoadedMesh> m = loadTetMesh(meshData("cube_tet4_v41.msh"), o);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.order, 2);
  EXPECT_EQ(m->mesh.tets.cols(), 10);
  EXPECT_TRUE(test::midEdgeNodesAtMidpoints(m->mesh));
}

TEST(LoadTetMesh, Tet10FileWithOrder1KeepsOrder2WithAWarning) {
  Result<LoadedMesh> m = loadTetMesh(meshData("cube_tet10_v22.msh"), MeshOptions{});
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.order, 2);
  EXPECT_TRUE(hasWarning(m->warnings, "keeping order 2"));
}

TEST(LoadTetMesh, TetgenStemAndRepairWarnings) {
  Result<LoadedMesh> m = loadTetMesh(meshData("cube_tet4"), MeshOptions{});
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->mesh.tets.rows(), 6);
  Result<LoadedMesh> inv = loadTetMesh(meshData("bad/inverted.msh"), MeshOptions{});
  ASSERT_TRUE(inv.ok()) << inv.error().message;
  EXPECT_TRUE(hasWarning(inv->warnings, "inverted"));
  EXPECT_TRUE(
      failsWith(loadTetMesh(meshData("bad/degenerate.msh"), MeshOptions{}), {"degenerate.msh", "tet 0 is degenerate"}));
}

TEST(LoadTetMesh, MissingDirectoryUnknownExtension) {
  EXPECT_TRUE(failsWith(loadTetMesh(meshData("nope.obj"), MeshOptions{}), {"nope.obj", "not found"}));
  EXPECT_TRUE(failsWith(loadTetMesh(meshData("bad"), MeshOptions{}), {"/bad", "directory"}));
  EXPECT_TRUE(failsWith(loadTetMesh(meshData("../../../README.md"), MeshOptions{}),
                        {"README.md", "unknown mesh file extension", ".md"}));
  MeshOptions o;
  o.order = 3;
  EXPECT_TRUE(failsWith(loadTetMesh("box:1,1,1", o), {"order 3"}));
}

TEST(LoadTetMesh, BowlAssetTetrahedralizesIntoAValidMesh) {
  const std::string bowl = std::string(STRIKE_SOURCE_DIR) + "/assets/meshes/bowl.obj";
  Result<SurfaceMesh> surface = readObj(bowl);
  ASSERT_TRUE(surface.ok()) << surface.error().message;
  EXPECT_GE(surface->F.rows(), 300);
  EXPECT_LE(surface->F.rows(), 2000);
  ASSERT_TRUE(checkClosedSurface(*surface, bowl).ok()) << checkClosedSurface(*surface, bowl).error().message;
  const double volume = test::surfaceVolume(surface->V, surface->F);
  EXPECT_GT(volume, 0.0);  // outward
  const Eigen::RowVector3d size = surface->V.colwise().maxCoeff() - surface->V.colwise().minCoeff();
  EXPECT_NEAR(size(0), 0.12, 0.005);

  Result<LoadedMesh> m = loadTetMesh(bowl, MeshOptions{});
  ASSERT_TRUE(m.ok()) << m.error().message;
  // TetGen may nudge nearly coplanar input (the .obj has 6 decimals) by its -T tolerance.
  EXPECT_NEAR(test::totalVolume(m->mesh), volume, 1e-5 * volume);
  for (Eigen::Index t = 0; t < m->mesh.tets.rows(); ++t) ASSERT_GT(test::tetVolume(m->mesh, t), 0.0);
  EXPECT_GT(m->mesh.tets.rows(), 500);
  EXPECT_LT(m->mesh.tets.rows(), 50000);
  SurfaceMesh boundary{m->mesh.nodes, m->mesh.surface};
  EXPECT_TRUE(checkClosedSurface(boundary, "bowl boundary").ok());
}

}  // namespace
}  // namespace strike
