// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>

#include "mesh/mesh_test_util.hpp"
#include "strike/core/constants.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {
namespace {

using test::failsWith;

TEST(Primitives, IsPrimitiveSpec) {
  EXPECT_TRUE(isPrimitiveSpec("box:0.3,0.02,0.02"));
  EXPECT_TRUE(isPrimitiveSpec("sphere:0.05"));
  EXPECT_TRUE(isPrimitiveSpec("cylinder:0.02,0.1"));
  EXPECT_TRUE(isPrimitiveSpec("sphere:oops"));  // recognised, then rejected by loadTetMesh
  EXPECT_FALSE(isPrimitiveSpec("bowl.obj"));
  EXPECT_FALSE(isPrimitiveSpec("boxes/a.obj"));
  EXPECT_FALSE(isPrimitiveSpec(""));
}

TEST(Primitives, SphereSurfaceIsClosedOutwardAndHasTheSphereVolume) {
  for (double edge : {0.0, 0.02, 0.005}) {
    Result<SurfaceMesh> s = makeSphereSurface(0.05, edge);
    ASSERT_TRUE(s.ok()) << s.error().message;
    EXPECT_TRUE(checkClosedSurface(*s, "sphere").ok()) << checkClosedSurface(*s, "sphere").error().message;
    EXPECT_NEAR(test::surfaceVolume(s->V, s->F), 4.0 / 3.0 * kPi * std::pow(0.05, 3), 1e-12);
    EXPECT_EQ(s->V.rows() - s->F.rows() / 2, 2);  // Euler: V - E + F = 2 with E = 3F/2
    const Eigen::VectorXd r = s->V.rowwise().norm();
    EXPECT_NEAR(r.maxCoeff(), 0.05, 0.05 * 0.05);
    if (edge > 0) {
      // Edge lengths are near the target (geodesic spheres vary by ~20%).
      const double e = (s->V.row(s->F(0, 0)) - s->V.row(s->F(0, 1))).norm();
      EXPECT_LT(e, 1.3 * edge);
      EXPECT_GT(e, 0.5 * edge);
    }
  }
}

TEST(Primitives, CylinderSurfaceIsClosedOutwardAndHasTheCylinderVolume) {
  for (double edge : {0.0, 0.01, 0.003}) {
    Result<SurfaceMesh> s = makeCylinderSurface(0.03, 0.1, edge);
    ASSERT_TRUE(s.ok()) << s.error().message;
    Status closed = checkClosedSurface(*s, "cylinder");
    EXPECT_TRUE(closed.ok()) << closed.error().message;
    EXPECT_NEAR(test::surfaceVolume(s->V, s->F), kPi * 0.03 * 0.03 * 0.1, 1e-12);
    EXPECT_NEAR(s->V.col(2).maxCoeff(), 0.05, 1e-15);
    EXPECT_NEAR(s->V.col(2).minCoeff(), -0.05, 1e-15);
  }
}

TEST(Primitives, BadSizes) {
  EXPECT_TRUE(failsWith(makeSphereSurface(-1.0, 0.0), {"sphere", "R = -1", "> 0"}));
  EXPECT_TRUE(failsWith(makeSphereSurface(std::nan(""), 0.0), {"sphere", "R = nan"}));
  EXPECT_TRUE(failsWith(makeSphereSurface(1.0, 1e-9), {"sphere", "too small"}));
  EXPECT_TRUE(failsWith(makeCylinderSurface(0.1, 0.0, 0.0), {"cylinder", "H = 0"}));
}

TEST(Tetrahedralize, SphereVolumeWithinThreePercent) {
  MeshOptions options;
  Result<SurfaceMesh> s = makeSphereSurface(0.05, 0.0);
  ASSERT_TRUE(s.ok());
  int progress_calls = 0;
  options.progress = [&](std::string_view phase, double) {
    EXPECT_EQ(phase, "tetrahedralize");
    ++progress_calls;
  };
  Result<TetMesh> m = tetrahedralize(*s, options, "sphere:0.05");
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_GT(progress_calls, 0);
  const double exact = 4.0 / 3.0 * kPi * std::pow(0.05, 3);
  EXPECT_NEAR(test::totalVolume(*m), exact, 0.03 * exact);
  EXPECT_GT(m->tets.rows(), 1000);
  EXPECT_LT(m->tets.rows(), 30000);
  SurfaceMesh boundary{m->nodes, m->surface};
  EXPECT_TRUE(checkClosedSurface(boundary, "sphere boundary").ok());
  EXPECT_NEAR(test::surfaceVolume(m->nodes, m->surface), test::totalVolume(*m), 1e-12);
}

TEST(Tetrahedralize, CylinderOrder2) {
  MeshOptions options;
  options.order = 2;
  options.target_edge_m = 0.01;
  Result<SurfaceMesh> s = makeCylinderSurface(0.03, 0.1, options.target_edge_m);
  ASSERT_TRUE(s.ok());
  Result<TetMesh> m = tetrahedralize(*s, options, "cylinder:0.03,0.1");
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->order, 2);
  EXPECT_EQ(m->tets.cols(), 10);
  EXPECT_TRUE(test::midEdgeNodesAtMidpoints(*m));
  const double exact = kPi * 0.03 * 0.03 * 0.1;
  EXPECT_NEAR(test::totalVolume(*m), exact, 0.03 * exact);
}

TEST(Tetrahedralize, OpenSurfaceIsRejectedBeforeTetgen) {
  Result<SurfaceMesh> s = readObj(test::meshData("bad/open.obj"));
  ASSERT_TRUE(s.ok());
  EXPECT_TRUE(failsWith(tetrahedralize(*s, MeshOptions{}, "open.obj"), {"open.obj", "not closed"}));
}

TEST(Tetrahedralize, SelfIntersectingSurfaceBecomesAnError) {
  // Two unit cubes overlapping: closed and consistently oriented, but self-intersecting.
  Result<SurfaceMesh> cube = readObj(test::meshData("cube.obj"));
  ASSERT_TRUE(cube.ok());
  SurfaceMesh two;
  two.V.resize(16, 3);
  two.V << cube->V, (cube->V.array() + 0.5).matrix();
  two.F.resize(24, 3);
  two.F << cube->F, (cube->F.array() + 8).matrix();
  Result<TetMesh> m = tetrahedralize(two, MeshOptions{}, "two_cubes");
  EXPECT_TRUE(failsWith(m, {"two_cubes", "intersects itself", "intersecting triangles"}));
}

TEST(Tetrahedralize, BadOptions) {
  Result<SurfaceMesh> s = makeSphereSurface(0.05, 0.0);
  ASSERT_TRUE(s.ok());
  MeshOptions options;
  options.radius_edge_ratio = 0.9;
  EXPECT_TRUE(failsWith(tetrahedralize(*s, options, "s"), {"radius-edge ratio 0.9"}));
  options = MeshOptions{};
  options.target_edge_m = 1e-6;
  EXPECT_TRUE(failsWith(tetrahedralize(*s, options, "s"), {"would give more than"}));
}

}  // namespace
}  // namespace strike
