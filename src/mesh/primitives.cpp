// SPDX-License-Identifier: MIT
// Sphere and cylinder surfaces (for tetrahedralize()) and primitive spec recognition.
// Both surfaces are scaled so that the enclosed polyhedron has exactly the analytic volume
// (4/3 pi r^3, pi r^2 h): an inscribed polyhedron is always too small, and the mass of a body
// is the one number a listener notices first (it sets every modal amplitude).
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>  // cross()

#include "strike/core/constants.hpp"
#include "strike/core/format.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {

namespace {

constexpr int kMaxSubdivision = 200;  // 20 * 200^2 = 800k triangles: beyond any sane FEM mesh
constexpr int kMaxSegments = 20000;

Status checkLength(const char* what, const char* name, double value, bool allow_zero) {
  if (!std::isfinite(value) || value < 0.0 || (!allow_zero && value == 0.0)) {
    return badInput(std::string(what) + ": " + name + " = " + formatNumber(value, 9) +
                    " (must be a finite length in metres " + (allow_zero ? ">= 0" : "> 0") + ")");
  }
  return {};
}

double signedVolume(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  double volume = 0.0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    volume += a.dot(b.cross(c)) / 6.0;
  }
  return volume;
}

}  // namespace

bool isPrimitiveSpec(const std::string& spec) {
  return spec.rfind("box:", 0) == 0 || spec.rfind("sphere:", 0) == 0 || spec.rfind("cylinder:", 0) == 0;
}

Result<SurfaceMesh> makeSphereSurface(double radius, double target_edge_m) {
  if (Status s = checkLength("sphere", "R", radius, false); !s) return s.error();
  if (Status s = checkLength("sphere", "target edge", target_edge_m, true); !s) return s.error();

  // Geodesic sphere: each icosahedron face split into k^2 triangles (class I, frequency k),
  // then projected. Any k is allowed, so the edge length can follow the target closely.
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  const double ico[12][3] = {{-1, phi, 0},  {1, phi, 0},  {-1, -phi, 0}, {1, -phi, 0}, {0, -1, phi},  {0, 1, phi},
                             {0, -1, -phi}, {0, 1, -phi}, {phi, 0, -1},  {phi, 0, 1},  {-phi, 0, -1}, {-phi, 0, 1}};
  const int faces[20][3] = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                            {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                            {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  const double ico_edge = 2.0 / std::sqrt(phi * phi + 1.0);  // on the unit sphere: 1.0515
  int k = 7;                                                 // default: 980 triangles, edge ~ r / 6.7
  if (target_edge_m > 0.0) {
    const double want = std::ceil(ico_edge * radius / target_edge_m);
    if (!(want <= kMaxSubdivision)) {
      return badInput("sphere: target edge " + formatNumber(target_edge_m, 9) + " m is too small for radius " +
                      formatNumber(radius, 9) + " m (more than " +
                      std::to_string(20 * kMaxSubdivision * kMaxSubdivision) + " triangles)");
    }
    k = std::max(2, static_cast<int>(want));
  }

  std::vector<Eigen::Vector3d> verts;
  for (const auto& p : ico) verts.push_back(Eigen::Vector3d(p[0], p[1], p[2]).normalized());
  // Points on an edge are generated once, from the lower corner index, so neighbouring faces
  // share them bit-for-bit.
  std::vector<std::vector<int>> edge_points(12 * 12);
  auto edgePoint = [&](int a, int b, int i) {  // i-th point from a towards b, 0 < i < k
    const int lo = std::min(a, b), hi = std::max(a, b);
    std::vector<int>& list = edge_points[static_cast<size_t>(lo * 12 + hi)];
    if (list.empty()) {
      for (int j = 1; j < k; ++j) {
        const double s = static_cast<double>(j) / k;
        verts.push_back(((1.0 - s) * verts[static_cast<size_t>(lo)] + s * verts[static_cast<size_t>(hi)]).normalized());
        list.push_back(static_cast<int>(verts.size()) - 1);
      }
    }
    return a == lo ? list[static_cast<size_t>(i - 1)] : list[static_cast<size_t>(k - i - 1)];
  };
  std::vector<std::array<int, 3>> tris;
  std::vector<int> grid;
  for (const auto& f : faces) {
    // grid(i, j): point i steps from corner 0 towards corner 1 and j towards corner 2, i + j <= k.
    grid.assign(static_cast<size_t>((k + 1) * (k + 1)), -1);
    auto g = [&](int i, int j) -> int& { return grid[static_cast<size_t>(i * (k + 1) + j)]; };
    for (int i = 0; i <= k; ++i) {
      for (int j = 0; i + j <= k; ++j) {
        int id;
        if (i == 0 && j == 0)
          id = f[0];
        else if (i == k)
          id = f[1];
        else if (j == k)
          id = f[2];
        else if (j == 0)
          id = edgePoint(f[0], f[1], i);
        else if (i == 0)
          id = edgePoint(f[0], f[2], j);
        else if (i + j == k)
          id = edgePoint(f[1], f[2], j);
        else {
          const Eigen::Vector3d& p0 = verts[static_cast<size_t>(f[0])];
          const Eigen::Vector3d& p1 = verts[static_cast<size_t>(f[1])];
          const Eigen::Vector3d& p2 = verts[static_cast<size_t>(f[2])];
          const double u = static_cast<double>(i) / k, w = static_cast<double>(j) / k;
          verts.push_back(((1.0 - u - w) * p0 + u * p1 + w * p2).normalized());
          id = static_cast<int>(verts.size()) - 1;
        }
        g(i, j) = id;
      }
    }
    for (int i = 0; i < k; ++i) {
      for (int j = 0; i + j < k; ++j) {
        tris.push_back({g(i, j), g(i + 1, j), g(i, j + 1)});
        if (i + j + 1 < k) tris.push_back({g(i + 1, j), g(i + 1, j + 1), g(i, j + 1)});
      }
    }
  }
  SurfaceMesh mesh;
  mesh.V.resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) mesh.V.row(static_cast<Eigen::Index>(i)) = verts[i].transpose();
  mesh.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t t = 0; t < tris.size(); ++t)
    mesh.F.row(static_cast<Eigen::Index>(t)) << tris[t][0], tris[t][1], tris[t][2];
  // The icosahedron faces above are counter-clockwise from outside; check rather than trust.
  double volume = signedVolume(mesh.V, mesh.F);
  if (volume < 0) {
    mesh.F.col(1).swap(mesh.F.col(2));
    volume = -volume;
  }
  mesh.V *= radius * std::cbrt((4.0 / 3.0 * kPi) / volume);
  return mesh;
}

Result<SurfaceMesh> makeCylinderSurface(double radius, double height, double target_edge_m) {
  if (Status s = checkLength("cylinder", "R", radius, false); !s) return s.error();
  if (Status s = checkLength("cylinder", "H", height, false); !s) return s.error();
  if (Status s = checkLength("cylinder", "target edge", target_edge_m, true); !s) return s.error();

  // Axis along z, centred at the origin. n segments around; rows along the side; concentric
  // rings on the caps, each with about as many segments as its circumference needs.
  // Default: the edge a TetGen default mesh would use for this volume (see tetgen_mesher.cpp),
  // with 24..64 segments around so the circle stays round.
  double length_edge = std::cbrt(6.0 * std::sqrt(2.0) * kPi * radius * radius * height / 600.0);
  int n = std::clamp(static_cast<int>(std::ceil(2.0 * kPi * radius / length_edge)), 24, 64);
  if (target_edge_m > 0.0) {
    const double want = std::ceil(2.0 * kPi * radius / target_edge_m);
    if (!(want <= kMaxSegments)) {
      return badInput("cylinder: target edge " + formatNumber(target_edge_m, 9) + " m is too small for radius " +
                      formatNumber(radius, 9) + " m");
    }
    n = std::max(8, static_cast<int>(want));
  }
  if (target_edge_m > 0.0) length_edge = 2.0 * kPi * radius / n;
  const double edge = std::max(2.0 * kPi * radius / n, length_edge);
  const double rows_want = std::round(height / edge);
  const double rings_want = std::round(radius / (2.0 * kPi * radius / n));
  if (!(rows_want <= kMaxSegments) || !(rings_want <= kMaxSegments)) {
    return badInput("cylinder: R = " + formatNumber(radius, 9) + ", H = " + formatNumber(height, 9) + " with edge " +
                    formatNumber(edge, 9) + " m gives too many triangles");
  }
  const int rows = std::max(1, static_cast<int>(rows_want));
  const int rings = std::max(1, static_cast<int>(rings_want));
  // Polygon of n sides with area pi r^2: R = r sqrt(2 pi / (n sin(2 pi / n))).
  const double big_r = radius * std::sqrt(2.0 * kPi / (n * std::sin(2.0 * kPi / n)));

  std::vector<Eigen::Vector3d> verts;
  std::vector<std::array<int, 3>> tris;
  auto ring = [&](int segments, double r, double z, double phase) {
    std::vector<int> ids;
    for (int i = 0; i < segments; ++i) {
      const double a = 2.0 * kPi * (i + phase) / segments;
      verts.emplace_back(r * std::cos(a), r * std::sin(a), z);
      ids.push_back(static_cast<int>(verts.size()) - 1);
    }
    return ids;
  };
  // Side: rows + 1 rings of n vertices. Triangles (i, j) (i+1, j) (i+1, j+1) are
  // counter-clockwise seen from outside, because theta-hat x z-hat = r-hat.
  std::vector<std::vector<int>> side;
  for (int j = 0; j <= rows; ++j) side.push_back(ring(n, big_r, -0.5 * height + height * j / rows, 0.0));
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < n; ++i) {
      const int i1 = (i + 1) % n;
      tris.push_back({side[j][i], side[j][i1], side[j + 1][i1]});
      tris.push_back({side[j][i], side[j + 1][i1], side[j + 1][i]});
    }
  }
  // Caps: zip each pair of neighbouring rings by angle (advance the ring whose next vertex
  // comes first), which triangulates an annulus between rings of different sizes.
  auto cap = [&](const std::vector<int>& outer, double z, bool top) {
    std::vector<int> prev = outer;
    for (int c = rings - 1; c >= 1; --c) {
      const int segments = std::max(6, static_cast<int>(std::lround(static_cast<double>(n) * c / rings)));
      std::vector<int> inner = ring(segments, big_r * c / rings, z, 0.5 * ((rings - c) % 2));
      const size_t no = prev.size(), ni = inner.size();
      size_t io = 0, ii = 0;
      auto angle = [&](const std::vector<int>& r, size_t idx) {
        const size_t m = r.size();
        const double base = 2.0 * kPi * static_cast<double>(idx / m);
        const Eigen::Vector3d& p = verts[static_cast<size_t>(r[idx % m])];
        double a = std::atan2(p.y(), p.x());
        if (a < 0) a += 2.0 * kPi;
        // The first vertex of each ring is at angle >= 0 and < one step, so unwrap by turns.
        return a + base;
      };
      while (io < no || ii < ni) {
        const bool advance_outer = ii >= ni || (io < no && angle(prev, io + 1) <= angle(inner, ii + 1));
        const int o0 = prev[io % no], i0 = inner[ii % ni];
        if (advance_outer) {
          const int o1 = prev[(io + 1) % no];
          // Counter-clockwise seen from +z is (o0, o1, i0); the bottom cap is seen from -z.
          if (top)
            tris.push_back({o0, o1, i0});
          else
            tris.push_back({o0, i0, o1});
          ++io;
        } else {
          const int i1 = inner[(ii + 1) % ni];
          if (top)
            tris.push_back({o0, i1, i0});
          else
            tris.push_back({o0, i0, i1});
          ++ii;
        }
      }
      prev = std::move(inner);
    }
    verts.emplace_back(0.0, 0.0, z);
    const int centre = static_cast<int>(verts.size()) - 1;
    for (size_t i = 0; i < prev.size(); ++i) {
      const int a = prev[i], b = prev[(i + 1) % prev.size()];
      if (top)
        tris.push_back({a, b, centre});
      else
        tris.push_back({a, centre, b});
    }
  };
  cap(side.back(), 0.5 * height, true);
  cap(side.front(), -0.5 * height, false);

  SurfaceMesh mesh;
  mesh.V.resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) mesh.V.row(static_cast<Eigen::Index>(i)) = verts[i].transpose();
  mesh.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t t = 0; t < tris.size(); ++t)
    mesh.F.row(static_cast<Eigen::Index>(t)) << tris[t][0], tris[t][1], tris[t][2];
  return mesh;
}

}  // namespace strike
