// SPDX-License-Identifier: MIT
// Convex decomposition by recursive plane splitting, in the spirit of V-HACD [Mamou & Ghorbel
// 2009, "A simple and efficient approach for 3D mesh approximate convex decomposition", ICIP;
// Mamou, V-HACD 2.0 (2016)]: concavity is a surface point's depth inside its piece's hull, and a
// piece is cut by the axis-aligned plane that leaves the smallest concavity. Simpler than V-HACD
// (it cuts the surface, not a voxelization, and only through the middle of a piece's box), which
// is enough for the turned and moulded shapes of tableware and keeps it exact on the surface.
#include "convex_pieces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <LinearMath/btConvexHullComputer.h>

namespace strike {
namespace {

/// A piece's convex hull as points and outward face planes n . x = offset (unit n).
struct Hull {
  std::vector<double> points;
  std::vector<btVector3> normals;
  std::vector<double> offsets;
  double volume_m3 = 0.0;
};

Hull hullOf(const std::vector<double>& xyz, const std::vector<uint32_t>& vertices) {
  std::vector<double> coords;
  coords.reserve(3 * vertices.size());
  for (uint32_t v : vertices) coords.insert(coords.end(), &xyz[3 * size_t(v)], &xyz[3 * size_t(v)] + 3);
  btConvexHullComputer computer;
  Hull hull;
  if (computer.compute(coords.data(), int(3 * sizeof(double)), int(vertices.size()), 0.0, 0.0) < 0) return hull;
  for (int v = 0; v < computer.vertices.size(); ++v)
    for (int k = 0; k < 3; ++k) hull.points.push_back(computer.vertices[v][k]);
  double six_volume = 0.0;
  for (int f = 0; f < computer.faces.size(); ++f) {
    // Newell's normal of the planar n-gon (counter-clockwise from outside): robust for any n.
    const btConvexHullComputer::Edge* first = &computer.edges[computer.faces[f]];
    const btConvexHullComputer::Edge* e = first;
    btVector3 normal(0, 0, 0);
    const btVector3& a = computer.vertices[first->getSourceVertex()];
    do {
      const btVector3& p = computer.vertices[e->getSourceVertex()];
      const btVector3& q = computer.vertices[e->getTargetVertex()];
      normal += p.cross(q);
      six_volume += a.dot(p.cross(q));
      e = e->getNextEdgeOfFace();
    } while (e != first);
    const double length = normal.length();
    if (!(length > 0.0)) continue;
    normal /= length;
    hull.normals.push_back(normal);
    hull.offsets.push_back(normal.dot(a));
  }
  hull.volume_m3 = std::abs(six_volume) / 6.0;
  return hull;
}

struct Piece {
  std::vector<uint32_t> triangles;  ///< triangle indices
  std::vector<uint32_t> vertices;   ///< their vertices, sorted
  Hull hull;
  double concavity_m = 0.0;
  uint32_t deepest_vertex = 0;  ///< the vertex deepest inside the hull
  double depth_sum_m = 0.0;     ///< all its vertices' depths: what a cut is chosen to reduce
  bool splittable = true;
};

/// What makePiece and splitPiece read: the (refined) surface and its vertex normals.
struct Surface {
  std::vector<double> xyz;
  std::vector<uint32_t> triangles;
  std::vector<btVector3> normals;  ///< per vertex, unit, outward (area-weighted)
};

Piece makePiece(const Surface& surface, std::vector<uint32_t> tris) {
  const std::vector<double>& xyz = surface.xyz;
  const std::vector<uint32_t>& triangles = surface.triangles;
  Piece piece;
  piece.triangles = std::move(tris);
  for (uint32_t t : piece.triangles)
    for (int k = 0; k < 3; ++k) piece.vertices.push_back(triangles[3 * size_t(t) + size_t(k)]);
  std::sort(piece.vertices.begin(), piece.vertices.end());
  piece.vertices.erase(std::unique(piece.vertices.begin(), piece.vertices.end()), piece.vertices.end());
  piece.hull = hullOf(xyz, piece.vertices);
  for (uint32_t v : piece.vertices) {
    const btVector3 p(xyz[3 * size_t(v)], xyz[3 * size_t(v) + 1], xyz[3 * size_t(v) + 2]);
    // Concavity as in V-HACD: how far the hull lies from the vertex along its outward normal
    // (the nearest hull face would say only a wall's thickness for the inside of a bowl).
    const btVector3& outward = surface.normals[v];
    double depth = std::numeric_limits<double>::infinity();
    for (size_t f = 0; f < piece.hull.normals.size(); ++f) {
      const double cosine = piece.hull.normals[f].dot(outward);
      if (cosine > 1e-9) depth = std::min(depth, (piece.hull.offsets[f] - piece.hull.normals[f].dot(p)) / cosine);
    }
    if (std::isfinite(depth)) piece.depth_sum_m += depth;
    if (std::isfinite(depth) && depth > piece.concavity_m) {
      piece.concavity_m = depth;
      piece.deepest_vertex = v;
    }
  }
  return piece;
}

/// The best cut of a piece into two solid pieces, or false when no axis gives one.
bool splitPiece(const Surface& surface, const Piece& piece, Piece& left, Piece& right) {
  const std::vector<double>& xyz = surface.xyz;
  const std::vector<uint32_t>& triangles = surface.triangles;
  bool found = false;
  double best_depth = 0.0, best_volume = 0.0;
  for (int cut = 0; cut < 9; ++cut) {
    // Per axis: through the middle of the piece's box, and just either side of its deepest
    // vertex, which a cut must separate from the far side of the hollow it faces (a glass's
    // floor, whose triangles all lie in the plane of that vertex, from its walls).
    const int axis = cut % 3;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (uint32_t v : piece.vertices) {
      lo = std::min(lo, xyz[3 * size_t(v) + size_t(axis)]);
      hi = std::max(hi, xyz[3 * size_t(v) + size_t(axis)]);
    }
    const double deepest = xyz[3 * size_t(piece.deepest_vertex) + size_t(axis)];
    const double nudge = 1e-6 * (hi - lo);
    const double middle = cut < 3 ? 0.5 * (lo + hi) : cut < 6 ? deepest + nudge : deepest - nudge;
    std::vector<uint32_t> below, above;
    for (uint32_t t : piece.triangles) {
      double centroid = 0.0;
      for (int k = 0; k < 3; ++k) centroid += xyz[3 * size_t(triangles[3 * size_t(t) + size_t(k)]) + size_t(axis)];
      (centroid < 3.0 * middle ? below : above).push_back(t);
    }
    if (below.empty() || above.empty()) continue;
    Piece a = makePiece(surface, std::move(below));
    Piece b = makePiece(surface, std::move(above));
    // A piece holding one face of a wall without the other is flat: no volume to collide with.
    const double min_volume = 1e-6 * piece.hull.volume_m3;
    if (!(a.hull.volume_m3 > min_volume) || !(b.hull.volume_m3 > min_volume)) continue;
    // The cut that leaves the least depth in all: the deepest vertex alone would not tell a cut
    // that halves a tube from one that shortens it (both leave vertices facing across it).
    const double depth = a.depth_sum_m + b.depth_sum_m;
    const double volume = a.hull.volume_m3 + b.hull.volume_m3;
    if (!found || depth < best_depth || (depth == best_depth && volume < best_volume)) {
      found = true;
      best_depth = depth;
      best_volume = volume;
      left = std::move(a);
      right = std::move(b);
    }
  }
  return found;
}

/// Bisects triangles on their longest edge until no edge is longer than max_edge_m, appending
/// the midpoints: a plane cut assigns whole triangles, so a wall made of a few long triangles
/// (a tray's) could not be cut at all. The pieces need no conforming mesh (only vertices and
/// which triangle goes where), so neighbours do not share midpoints.
void refine(std::vector<double>& xyz, std::vector<uint32_t>& triangles, double max_edge_m) {
  const double max2 = max_edge_m * max_edge_m;
  std::vector<uint32_t> done;
  std::vector<uint32_t> todo = triangles;
  while (!todo.empty()) {
    const uint32_t c = todo.back();
    todo.pop_back();
    const uint32_t b = todo.back();
    todo.pop_back();
    const uint32_t a = todo.back();
    todo.pop_back();
    const uint32_t v[3] = {a, b, c};
    int longest = -1;
    double longest2 = max2;
    for (int e = 0; e < 3; ++e) {
      double d2 = 0.0;
      for (int k = 0; k < 3; ++k) {
        const double d = xyz[3 * size_t(v[e]) + size_t(k)] - xyz[3 * size_t(v[(e + 1) % 3]) + size_t(k)];
        d2 += d * d;
      }
      if (d2 > longest2) {
        longest2 = d2;
        longest = e;
      }
    }
    if (longest < 0) {
      done.insert(done.end(), {a, b, c});
      continue;
    }
    const uint32_t p = v[longest], q = v[(longest + 1) % 3], r = v[(longest + 2) % 3];
    const uint32_t m = uint32_t(xyz.size() / 3);
    for (int k = 0; k < 3; ++k) xyz.push_back(0.5 * (xyz[3 * size_t(p) + size_t(k)] + xyz[3 * size_t(q) + size_t(k)]));
    todo.insert(todo.end(), {p, m, r, m, q, r});
  }
  triangles = std::move(done);
}

}  // namespace

ConvexPieces convexPieces(const std::vector<double>& surface_xyz, const std::vector<uint32_t>& surface_triangles,
                          const ConvexPiecesSettings& settings) {
  Surface surface{surface_xyz, surface_triangles, {}};
  if (settings.max_edge_m > 0.0) refine(surface.xyz, surface.triangles, settings.max_edge_m);
  surface.normals.assign(surface.xyz.size() / 3, btVector3(0, 0, 0));
  for (size_t t = 0; t + 2 < surface.triangles.size(); t += 3) {
    btVector3 corner[3];
    for (int k = 0; k < 3; ++k) {
      const double* p = &surface.xyz[3 * size_t(surface.triangles[t + size_t(k)])];
      corner[k] = btVector3(p[0], p[1], p[2]);
    }
    const btVector3 twice_area_normal = (corner[1] - corner[0]).cross(corner[2] - corner[0]);
    for (int k = 0; k < 3; ++k) surface.normals[surface.triangles[t + size_t(k)]] += twice_area_normal;
  }
  for (btVector3& n : surface.normals)
    if (n.length2() > 0.0) n.normalize();
  std::vector<uint32_t> all(surface.triangles.size() / 3);
  for (size_t t = 0; t < all.size(); ++t) all[t] = uint32_t(t);
  std::vector<Piece> pieces;
  pieces.push_back(makePiece(surface, std::move(all)));
  while (int(pieces.size()) < settings.max_pieces) {
    // The deepest piece first (the first of equals), so a budget cut leaves the worst ones split.
    size_t worst = pieces.size();
    for (size_t p = 0; p < pieces.size(); ++p) {
      if (!pieces[p].splittable || !(pieces[p].concavity_m > settings.max_concavity_m)) continue;
      if (worst == pieces.size() || pieces[p].concavity_m > pieces[worst].concavity_m) worst = p;
    }
    if (worst == pieces.size()) break;
    Piece left, right;
    if (!splitPiece(surface, pieces[worst], left, right)) {
      pieces[worst].splittable = false;
      continue;
    }
    pieces[worst] = std::move(left);
    pieces.push_back(std::move(right));
  }
  ConvexPieces result;
  for (Piece& piece : pieces) {
    if (piece.hull.points.empty()) continue;
    result.worst_concavity_m = std::max(result.worst_concavity_m, piece.concavity_m);
    result.hull_points.push_back(std::move(piece.hull.points));
    result.hull_volume_m3.push_back(piece.hull.volume_m3);
  }
  return result;
}

}  // namespace strike
