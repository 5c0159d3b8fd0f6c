// SPDX-License-Identifier: MIT
// Mesh checks. validateAndRepair fixes what has one right answer (orientation, unused nodes)
// and refuses what has none (NaN, degenerate tets, no tets at all): an empty or silently
// broken mesh must never flow on into an eigen-solve that then reports "0 modes".
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>  // cross()

#include "strike/core/format.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {

namespace {

// |volume| / (mean edge)^3 below this is a degenerate tet. A regular tet has 1/(6 sqrt 2) =
// 0.118; TetGen's quality meshes stay far above 1e-4 even for slivers, while four coplanar or
// coincident points give ~1e-16. The gap is wide, so the exact value is not critical.
constexpr double kDegenerateShape = 1e-10;

std::string point(const Eigen::MatrixXd& V, Eigen::Index i) {
  return "(" + formatNumber(V(i, 0), 9) + ", " + formatNumber(V(i, 1), 9) + ", " + formatNumber(V(i, 2), 9) + ")";
}

std::string prefix(const std::string& source) { return source + ": error: "; }

/// The order, the arrays' shapes, finite coordinates and node indices in range.
Status checkArrays(const TetMesh& mesh, const std::string& source) {
  const int nodes_per_tet = mesh.order == 2 ? 10 : 4;
  if (mesh.order != 1 && mesh.order != 2) {
    return internalError(prefix(source) + "element order " + std::to_string(mesh.order) + ", expected 1 or 2");
  }
  if (mesh.tets.rows() == 0) {
    return badInput(prefix(source) +
                    "the mesh has no tetrahedra (0 tets), expected a solid volume mesh; "
                    "an empty result would give zero modes");
  }
  if (mesh.tets.cols() != nodes_per_tet || mesh.nodes.cols() != 3) {
    return internalError(prefix(source) + "tets have " + std::to_string(mesh.tets.cols()) + " columns and nodes " +
                         std::to_string(mesh.nodes.cols()) + ", expected " + std::to_string(nodes_per_tet) + " and 3");
  }
  const Eigen::Index num_nodes = mesh.nodes.rows();
  const Eigen::Index num_tets = mesh.tets.rows();
  for (Eigen::Index i = 0; i < num_nodes; ++i) {
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(mesh.nodes(i, c))) {
        return badInput(prefix(source) + "node " + std::to_string(i) + " coordinate " +
                        std::string(1, static_cast<char>('x' + c)) + " is " + formatNumber(mesh.nodes(i, c), 9) +
                        ", expected a finite number");
      }
    }
  }
  for (Eigen::Index t = 0; t < num_tets; ++t) {
    for (int k = 0; k < nodes_per_tet; ++k) {
      const int v = mesh.tets(t, k);
      if (v < 0 || v >= num_nodes) {
        return badInput(prefix(source) + "tet " + std::to_string(t) + " references node " + std::to_string(v) +
                        ", mesh has " + std::to_string(num_nodes) + " nodes");
      }
    }
  }
  return {};
}

/// Refuses a degenerate tet (flat or collapsed) and turns an inverted one (negative volume)
/// the right way round, with a warning that counts them.
Status orientTets(TetMesh& mesh, const std::string& source, std::vector<MeshWarning>* warnings) {
  const int nodes_per_tet = mesh.order == 2 ? 10 : 4;
  const Eigen::Index num_tets = mesh.tets.rows();
  constexpr int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  int64_t inverted = 0;
  for (Eigen::Index t = 0; t < num_tets; ++t) {
    const Eigen::Vector3d p0 = mesh.nodes.row(mesh.tets(t, 0)).transpose();
    const Eigen::Vector3d a = mesh.nodes.row(mesh.tets(t, 1)).transpose() - p0;
    const Eigen::Vector3d b = mesh.nodes.row(mesh.tets(t, 2)).transpose() - p0;
    const Eigen::Vector3d c = mesh.nodes.row(mesh.tets(t, 3)).transpose() - p0;
    const double volume = a.dot(b.cross(c)) / 6.0;
    double mean_edge = 0.0;
    for (const auto& e : kEdges) {
      mean_edge += (mesh.nodes.row(mesh.tets(t, e[0])) - mesh.nodes.row(mesh.tets(t, e[1]))).norm() / 6.0;
    }
    if (!(std::abs(volume) > kDegenerateShape * mean_edge * mean_edge * mean_edge)) {
      std::string nodes;
      for (int k = 0; k < 4; ++k) {
        nodes += (k ? ", " : "") + std::to_string(mesh.tets(t, k)) + " " + point(mesh.nodes, mesh.tets(t, k));
      }
      return badInput(prefix(source) + "tet " + std::to_string(t) + " is degenerate: volume " +
                      formatNumber(volume, 9) + " m^3 with mean edge " + formatNumber(mean_edge, 9) +
                      " m (flat or collapsed); nodes " + nodes);
    }
    if (volume < 0) {
      // Swapping corners 1 and 2 flips the orientation; the mid-edge nodes follow their edges:
      // (0,1) <-> (0,2) is slot 4 <-> 6, (3,2) <-> (3,1) is slot 8 <-> 9, (1,2) and (3,0) stay.
      std::swap(mesh.tets(t, 1), mesh.tets(t, 2));
      if (nodes_per_tet == 10) {
        std::swap(mesh.tets(t, 4), mesh.tets(t, 6));
        std::swap(mesh.tets(t, 8), mesh.tets(t, 9));
      }
      ++inverted;
    }
  }
  if (inverted > 0 && warnings) {
    warnings->push_back({source + ": warning: " + std::to_string(inverted) + " of " + std::to_string(num_tets) +
                         " tets were inverted (negative volume) and have been reoriented"});
  }
  return {};
}

/// A face shared by three or more tets means overlapping elements: the FEM would double the
/// stiffness there. Checked here because extractSurface silently ignores such faces.
Status checkSharedFaces(const TetMesh& mesh, const std::string& source) {
  const Eigen::Index num_tets = mesh.tets.rows();
  constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::vector<std::array<int, 4>> faces;  // sorted corners + tet
  faces.reserve(static_cast<size_t>(4 * num_tets));
  for (Eigen::Index t = 0; t < num_tets; ++t) {
    for (const auto& f : kFaces) {
      std::array<int, 4> key = {mesh.tets(t, f[0]), mesh.tets(t, f[1]), mesh.tets(t, f[2]), static_cast<int>(t)};
      std::sort(key.begin(), key.begin() + 3);
      faces.push_back(key);
    }
  }
  std::sort(faces.begin(), faces.end());
  for (size_t i = 0; i + 2 < faces.size(); ++i) {
    if (std::equal(faces[i].begin(), faces[i].begin() + 3, faces[i + 2].begin())) {
      return badInput(prefix(source) + "face (" + std::to_string(faces[i][0]) + ", " + std::to_string(faces[i][1]) +
                      ", " + std::to_string(faces[i][2]) + ") is shared by tets " + std::to_string(faces[i][3]) + ", " +
                      std::to_string(faces[i + 1][3]) + " and " + std::to_string(faces[i + 2][3]) +
                      ", expected at most 2 (overlapping or duplicated tets)");
    }
  }
  return {};
}

/// Unreferenced nodes: a free node would add a zero row to K and M (a spurious zero mode).
/// They are removed, with a warning.
void removeUnusedNodes(TetMesh& mesh, const std::string& source, std::vector<MeshWarning>* warnings) {
  const int nodes_per_tet = mesh.order == 2 ? 10 : 4;
  const Eigen::Index num_nodes = mesh.nodes.rows();
  const Eigen::Index num_tets = mesh.tets.rows();
  std::vector<int> new_index(static_cast<size_t>(num_nodes), -1);
  for (Eigen::Index t = 0; t < num_tets; ++t) {
    for (int k = 0; k < nodes_per_tet; ++k) new_index[static_cast<size_t>(mesh.tets(t, k))] = 0;
  }
  int next = 0;
  for (int& v : new_index) {
    if (v == 0) v = next++;
  }
  if (next < num_nodes) {
    Eigen::MatrixXd kept(next, 3);
    for (Eigen::Index i = 0; i < num_nodes; ++i) {
      if (new_index[static_cast<size_t>(i)] >= 0) kept.row(new_index[static_cast<size_t>(i)]) = mesh.nodes.row(i);
    }
    mesh.nodes = std::move(kept);
    for (Eigen::Index t = 0; t < num_tets; ++t) {
      for (int k = 0; k < nodes_per_tet; ++k) mesh.tets(t, k) = new_index[static_cast<size_t>(mesh.tets(t, k))];
    }
    if (warnings) {
      warnings->push_back({source + ": warning: removed " + std::to_string(num_nodes - next) + " of " +
                           std::to_string(num_nodes) + " nodes that no tet uses"});
    }
  }
}

}  // namespace

Status validateAndRepair(TetMesh& mesh, const std::string& source, std::vector<MeshWarning>* warnings) {
  if (Status ok = checkArrays(mesh, source); !ok) return ok;
  if (Status ok = orientTets(mesh, source, warnings); !ok) return ok;
  if (Status ok = checkSharedFaces(mesh, source); !ok) return ok;
  removeUnusedNodes(mesh, source, warnings);
  const Eigen::Index num_tets = mesh.tets.rows();
  mesh.surface = extractSurface(mesh.tets.leftCols(4));
  if (mesh.surface.rows() == 0) {
    return internalError(prefix(source) + "the mesh has " + std::to_string(num_tets) + " tets but no boundary faces");
  }
  return {};
}

Status checkClosedSurface(const SurfaceMesh& surface, const std::string& source) {
  const Eigen::Index nv = surface.V.rows();
  const Eigen::Index nf = surface.F.rows();
  if (nf == 0) return badInput(prefix(source) + "the surface has no triangles, expected a closed surface");
  if (surface.F.cols() != 3 || surface.V.cols() != 3) {
    return internalError(prefix(source) + "surface arrays have " + std::to_string(surface.V.cols()) + " and " +
                         std::to_string(surface.F.cols()) + " columns, expected 3 and 3");
  }
  for (Eigen::Index i = 0; i < nv; ++i) {
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(surface.V(i, c))) {
        return badInput(prefix(source) + "vertex " + std::to_string(i) + " coordinate is " +
                        formatNumber(surface.V(i, c), 9) + ", expected a finite number");
      }
    }
  }
  double scale = 0.0;  // bounding-box diagonal, for a relative area test
  if (nv > 0) scale = (surface.V.colwise().maxCoeff() - surface.V.colwise().minCoeff()).norm();
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int c = 0; c < 3; ++c) {
      const int v = surface.F(f, c);
      if (v < 0 || v >= nv) {
        return badInput(prefix(source) + "triangle " + std::to_string(f) + " references vertex " + std::to_string(v) +
                        ", the surface has " + std::to_string(nv) + " vertices");
      }
    }
    const int a = surface.F(f, 0), b = surface.F(f, 1), c = surface.F(f, 2);
    const Eigen::Vector3d pa = surface.V.row(a).transpose();
    const Eigen::Vector3d ab = surface.V.row(b).transpose() - pa;
    const Eigen::Vector3d ac = surface.V.row(c).transpose() - pa;
    const double area2 = ab.cross(ac).norm();
    if (a == b || b == c || c == a || !(area2 > 1e-14 * scale * scale)) {
      return badInput(prefix(source) + "triangle " + std::to_string(f) + " (vertices " + std::to_string(a) + " " +
                      point(surface.V, a) + ", " + std::to_string(b) + " " + point(surface.V, b) + ", " +
                      std::to_string(c) + " " + point(surface.V, c) + ") is degenerate (zero area)");
    }
  }

  // Half-edges keyed by their undirected edge; a closed, consistently oriented manifold has
  // each edge exactly twice, once in each direction.
  struct HalfEdge {
    int lo, hi;
    bool forward;  // a < b as stored in the triangle
    int64_t tri;
  };
  std::vector<HalfEdge> half;
  half.reserve(static_cast<size_t>(3 * nf));
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = surface.F(f, k), b = surface.F(f, (k + 1) % 3);
      half.push_back({std::min(a, b), std::max(a, b), a < b, f});
    }
  }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    if (x.lo != y.lo) return x.lo < y.lo;
    if (x.hi != y.hi) return x.hi < y.hi;
    return x.tri < y.tri;
  });
  auto edgeText = [&](const HalfEdge& e) {
    return "edge (" + std::to_string(e.lo) + ", " + std::to_string(e.hi) + ") from " + point(surface.V, e.lo) + " to " +
           point(surface.V, e.hi);
  };
  for (size_t i = 0; i < half.size();) {
    size_t j = i + 1;
    while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
    const size_t count = j - i;
    if (count == 1) {
      return badInput(prefix(source) + "the surface is not closed: " + edgeText(half[i]) + " is used by 1 triangle (" +
                      std::to_string(half[i].tri) + "), expected exactly 2 (a hole or open boundary)");
    }
    if (count > 2) {
      return badInput(prefix(source) + "the surface is not manifold: " + edgeText(half[i]) + " is used by " +
                      std::to_string(count) + " triangles, expected exactly 2");
    }
    if (half[i].forward == half[i + 1].forward) {
      return badInput(prefix(source) + "inconsistent orientation: triangles " + std::to_string(half[i].tri) + " and " +
                      std::to_string(half[i + 1].tri) + " traverse " + edgeText(half[i]) +
                      " in the same direction, expected opposite directions (flipped triangle)");
    }
    i = j;
  }
  return {};
}

}  // namespace strike
