// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include "mesh/mesh_test_util.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {
namespace {

using test::failsWith;
using test::meshData;

void expectUnitCube(const Result<SurfaceMesh>& mesh) {
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  EXPECT_EQ(mesh->V.rows(), 8);
  EXPECT_EQ(mesh->F.rows(), 12);
  EXPECT_NEAR(test::surfaceVolume(mesh->V, mesh->F), 1.0, 1e-12);  // positive: outward
  EXPECT_NEAR(mesh->V.minCoeff(), 0.0, 0.0);
  EXPECT_NEAR(mesh->V.maxCoeff(), 1.0, 0.0);
  EXPECT_TRUE(checkClosedSurface(*mesh, "cube").ok());
}

TEST(SurfaceReaders, ObjCubeWithQuadsSlashFormsAndNegativeIndices) { expectUnitCube(readObj(meshData("cube.obj"))); }

TEST(SurfaceReaders, StlAsciiCubeIsWelded) {
  std::vector<MeshWarning> warnings;
  expectUnitCube(readStl(meshData("cube_ascii.stl"), &warnings));
  EXPECT_TRUE(warnings.empty());  // welding is what STL needs; no warning for it
}

TEST(SurfaceReaders, StlBinaryWithSolidHeaderIsDetectedBySize) { expectUnitCube(readStl(meshData("cube_binary.stl"))); }

TEST(SurfaceReaders, PlyAsciiSkipsUnknownPropertiesListsAndElements) {
  expectUnitCube(readPly(meshData("cube_ascii.ply")));
}
TEST(SurfaceReaders, PlyBinaryLittleEndian) { expectUnitCube(readPly(meshData("cube_binary_le.ply"))); }
TEST(SurfaceReaders, PlyBinaryBigEndian) { expectUnitCube(readPly(meshData("cube_binary_be.ply"))); }

TEST(SurfaceReaders, DispatchOnExtension) {
  expectUnitCube(readSurfaceMesh(meshData("cube.obj")));
  expectUnitCube(readSurfaceMesh(meshData("cube_binary.stl")));
  expectUnitCube(readSurfaceMesh(meshData("cube_ascii.ply")));
  EXPECT_TRUE(failsWith(readSurfaceMesh(meshData("cube_tet4_v22.msh")), {"cube_tet4_v22.msh", "\".msh\"", ".obj"}));
}

TEST(SurfaceReaders, ObjBadIndexNamesLineIndexAndCount) {
  EXPECT_TRUE(
      failsWith(readObj(meshData("bad/bad_index.obj")), {"bad_index.obj:23:", "references vertex 9", "8 vertices"}));
}

TEST(SurfaceReaders, ObjNanCoordinate) {
  EXPECT_TRUE(failsWith(readObj(meshData("bad/nan.obj")), {"nan.obj:11:", "nan", "finite"}));
}

TEST(SurfaceReaders, OpenAndFlippedSurfacesAreRejectedByCheckClosedSurface) {
  Result<SurfaceMesh> open = readObj(meshData("bad/open.obj"));
  ASSERT_TRUE(open.ok());
  EXPECT_TRUE(
      failsWith(checkClosedSurface(*open, "open.obj"), {"open.obj", "not closed", "edge (", "used by 1 triangle"}));
  Result<SurfaceMesh> flipped = readObj(meshData("bad/flipped.obj"));
  ASSERT_TRUE(flipped.ok());
  EXPECT_TRUE(failsWith(checkClosedSurface(*flipped, "flipped.obj"), {"flipped.obj", "orientation", "same direction"}));
}

TEST(SurfaceReaders, StlTruncatedBinaryNamesExpectedSize) {
  EXPECT_TRUE(failsWith(readStl(meshData("bad/truncated.stl")),
                        {"truncated.stl: byte 80", "12 triangles", "684 bytes", "351 bytes"}));
}

TEST(SurfaceReaders, StlHugeTriangleCount) {
  EXPECT_TRUE(failsWith(readStl(meshData("bad/huge_count.stl")), {"huge_count.stl", "1000000000 triangles"}));
}

TEST(SurfaceReaders, StlTruncatedAscii) {
  EXPECT_TRUE(failsWith(readStl(meshData("bad/truncated_ascii.stl")), {"truncated_ascii.stl:", "expected"}));
}

TEST(SurfaceReaders, PlyTruncatedBinaryNamesByteOffset) {
  EXPECT_TRUE(failsWith(readPly(meshData("bad/truncated.ply")), {"truncated.ply: byte ", "truncated file"}));
}

TEST(SurfaceReaders, PlyHugeCountIsRefusedBeforeAllocating) {
  EXPECT_TRUE(failsWith(readPly(meshData("bad/huge_count.ply")), {"huge_count.ply:4:", "1000000000"}));
}

TEST(SurfaceReaders, PlyBadIndexNamesLineFaceAndCount) {
  EXPECT_TRUE(
      failsWith(readPly(meshData("bad/bad_index.ply")), {"bad_index.ply:31:", "face 5", "vertex 70", "8 vertices"}));
}

TEST(SurfaceReaders, MissingFileAndDirectory) {
  EXPECT_TRUE(failsWith(readObj(meshData("no_such.obj")), {"no_such.obj", "not found"}));
  EXPECT_TRUE(failsWith(readStl(meshData("bad")), {"bad", "directory"}));
}

TEST(SurfaceReaders, GarbageNeverCrashes) {
  // Every prefix of every good file must either parse or fail cleanly (no crash, no hang).
  for (const char* name : {"cube.obj", "cube_ascii.stl", "cube_binary.stl", "cube_ascii.ply", "cube_binary_le.ply",
                           "cube_binary_be.ply"}) {
    Result<std::string> bytes = std::string();
    std::FILE* f = std::fopen(meshData(name).c_str(), "rb");
    ASSERT_NE(f, nullptr);
    std::string all;
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0) all.append(buffer, n);
    std::fclose(f);
    const std::string ext = std::string(name).substr(std::string(name).rfind('.'));
    const std::string tmp = ::testing::TempDir() + "prefix" + ext;
    for (size_t cut = 0; cut < all.size(); cut += 19) {
      std::FILE* out = std::fopen(tmp.c_str(), "wb");
      std::fwrite(all.data(), 1, cut, out);
      std::fclose(out);
      Result<SurfaceMesh> r = readSurfaceMesh(tmp);
      if (!r.ok()) {
        EXPECT_EQ(r.error().kind, ErrorKind::BadInput) << r.error().message;
      }
    }
  }
}

}  // namespace
}  // namespace strike
