// SPDX-License-Identifier: MIT
#include "strike/scene/scene_checks.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <utility>

namespace strike {
namespace {

using Vec = std::array<double, 3>;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double length(const Vec& a) { return std::sqrt(dot(a, a)); }

/// Rotates v by the unit quaternion q = (w, x, y, z).
Vec rotate(const std::array<double, 4>& q, const Vec& v) {
  const Vec u{q[1], q[2], q[3]};
  const Vec t = cross(u, v);
  const Vec t2{2 * t[0], 2 * t[1], 2 * t[2]};
  const Vec c = cross(u, t2);
  return {v[0] + q[0] * t2[0] + c[0], v[1] + q[0] * t2[1] + c[1], v[2] + q[0] * t2[2] + c[2]};
}

/// Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
double distanceSquaredToTriangle(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
  const Vec ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  auto dist2 = [&](const Vec& q) {
    const Vec d = sub(p, q);
    return dot(d, d);
  };
  if (d1 <= 0 && d2 <= 0) return dist2(a);
  const Vec bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dist2(b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return dist2({a[0] + v * ab[0], a[1] + v * ab[1], a[2] + v * ab[2]});
  }
  const Vec cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dist2(c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return dist2({a[0] + w * ac[0], a[1] + w * ac[1], a[2] + w * ac[2]});
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return dist2({b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2])});
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return dist2({a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w});
}

/// A body's surface in world coordinates, its bounding box, and its box in its own mesh frame.
struct WorldSurface {
  std::vector<double> positions;
  std::vector<double> probes;  ///< the vertices and the triangles' centroids: where overlap is tested
  Vec low{}, high{};
  Vec local_low{}, local_high{};  ///< the mesh-frame box: tight for a tilted plank, unlike the world one
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};
  Vec position{};
};

/// The body's boxes in the world and in its own frame; its points stay empty until a pair needs
/// them (addWorldPoints): most pairs' boxes never meet, and twenty plates of 14,000 vertices
/// would otherwise be turned into the world for nothing.
WorldSurface worldBoxes(const SimBodyDesc& body) {
  WorldSurface w;
  const double inf = std::numeric_limits<double>::infinity();
  w.low = w.local_low = {inf, inf, inf};
  w.high = w.local_high = {-inf, -inf, -inf};
  w.orientation_wxyz = body.orientation_wxyz;
  w.position = body.position_m;
  for (size_t v = 0; v + 2 < body.surface_positions.size(); v += 3) {
    const Vec local{body.surface_positions[v], body.surface_positions[v + 1], body.surface_positions[v + 2]};
    const Vec r = rotate(body.orientation_wxyz, local);
    for (int a = 0; a < 3; ++a) {
      w.local_low[a] = std::min(w.local_low[a], local[a]);
      w.local_high[a] = std::max(w.local_high[a], local[a]);
      const double x = r[a] + body.position_m[a];
      w.low[a] = std::min(w.low[a], x);
      w.high[a] = std::max(w.high[a], x);
    }
  }
  return w;
}

/// Its vertices in the world (the same numbers as worldBoxes' bounds), and the probes where
/// overlap is tested: the vertices and the triangles' centroids.
void addWorldPoints(const SimBodyDesc& body, WorldSurface& w) {
  if (!w.positions.empty()) return;
  w.positions.reserve(body.surface_positions.size());
  for (size_t v = 0; v + 2 < body.surface_positions.size(); v += 3) {
    const Vec local{body.surface_positions[v], body.surface_positions[v + 1], body.surface_positions[v + 2]};
    const Vec r = rotate(body.orientation_wxyz, local);
    for (int a = 0; a < 3; ++a) w.positions.push_back(r[a] + body.position_m[a]);
  }
  // Centroids too: two boxes can overlap with every corner of each on the other's faces.
  w.probes.reserve(w.positions.size() + body.surface_triangles.size());
  w.probes = w.positions;
  for (size_t t = 0; t + 2 < body.surface_triangles.size(); t += 3)
    for (int a = 0; a < 3; ++a) {
      double sum = 0.0;
      for (int k = 0; k < 3; ++k) sum += w.positions[body.surface_triangles[t + k] * size_t(3) + a];
      w.probes.push_back(sum / 3.0);
    }
}

std::string format(const char* fmt, double a = 0, double b = 0, double c = 0, double d = 0) {
  char text[256];
  std::snprintf(text, sizeof text, fmt, a, b, c, d);
  return text;
}

/// The three corners of the triangle whose indices start at triangles[t].
std::array<Vec, 3> cornersOf(const std::vector<double>& positions, const std::vector<uint32_t>& triangles, size_t t) {
  std::array<Vec, 3> corner;
  for (int k = 0; k < 3; ++k) {
    const size_t v = triangles[t + k] * size_t(3);
    corner[k] = {positions[v], positions[v + 1], positions[v + 2]};
  }
  return corner;
}

/// Squared distance from p to the nearest of the triangles.
double nearestSquared(const Vec& point, const std::vector<double>& positions, const std::vector<uint32_t>& triangles) {
  double nearest2 = std::numeric_limits<double>::infinity();
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const std::array<Vec, 3> corner = cornersOf(positions, triangles, t);
    nearest2 = std::min(nearest2, distanceSquaredToTriangle(point, corner[0], corner[1], corner[2]));
  }
  return nearest2;
}

/// Deepest penetration of `a`'s probe points (those inside b's box) into b's closed surface.
/// `inside_b` decides most probes (a pair of 5000-triangle bodies whose boxes met cost a render
/// ~50 ms of depthInside's arc tangents); the rest go to depthInside. The same depths.
double deepestVertexInside(const WorldSurface& a, const WorldSurface& b, const SimBodyDesc& b_desc, size_t max_tested,
                           const InsideTest& inside_b) {
  // The candidates: probes inside b's box in b's own frame. A tilted plank's world box holds
  // every block resting on it, and each probe tested costs a pass over b's triangles.
  const std::array<double, 4> inverse{b.orientation_wxyz[0], -b.orientation_wxyz[1], -b.orientation_wxyz[2],
                                      -b.orientation_wxyz[3]};
  std::vector<size_t> candidates;
  for (size_t v = 0; v + 2 < a.probes.size(); v += 3) {
    const Vec local = rotate(inverse, sub({a.probes[v], a.probes[v + 1], a.probes[v + 2]}, b.position));
    bool in_box = true;
    for (int k = 0; k < 3; ++k) in_box = in_box && local[k] >= b.local_low[k] && local[k] <= b.local_high[k];
    if (in_box) candidates.push_back(v);
  }
  // Each probe costs a pass over b's triangles: keep a pair under ~2e7 triangle visits (~0.3 s).
  const size_t triangles = std::max<size_t>(1, b_desc.surface_triangles.size() / 3);
  max_tested = std::clamp<size_t>(size_t(2e7) / triangles, 64, max_tested);
  const size_t stride = std::max<size_t>(1, (candidates.size() + max_tested - 1) / max_tested);
  double deepest = 0.0;
  for (size_t i = 0; i < candidates.size(); i += stride) {
    const double* p = &a.probes[candidates[i]];
    const int inside = inside_b.classify(p);
    // The same depth as depthInside's: the distance to the nearest triangle when inside.
    const double depth = inside < 0 ? depthInside(p, b.positions, b_desc.surface_triangles)
                         : inside > 0
                             ? std::sqrt(nearestSquared({p[0], p[1], p[2]}, b.positions, b_desc.surface_triangles))
                             : 0.0;
    deepest = std::max(deepest, depth);
  }
  return deepest;
}

}  // namespace

InsideTest::InsideTest(const std::vector<double>& positions, const std::vector<uint32_t>& triangles)
    : positions_(positions), triangles_(triangles) {
  const size_t nt = triangles.size() / 3;
  const size_t nv = positions.size() / 3;
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  edges.reserve(3 * nt);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) edges.emplace_back(triangles[3 * t + k], triangles[3 * t + (k + 1) % 3]);
  std::sort(edges.begin(), edges.end());
  closed_ = nt > 0;
  for (size_t e = 0; e < edges.size() && closed_; ++e) {
    const auto [u, v] = edges[e];
    // Every directed edge once, and its reverse once: a closed, consistently oriented surface.
    closed_ = u != v && u < nv && v < nv && (e + 1 == edges.size() || edges[e + 1] != edges[e]) &&
              std::binary_search(edges.begin(), edges.end(), std::make_pair(v, u));
  }
  if (!closed_) return;
  for (int k = 0; k < 3; ++k) low_[k] = INFINITY, high_[k] = -INFINITY;
  for (size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k)
      low_[k] = std::min(low_[k], positions[3 * v + k]), high_[k] = std::max(high_[k], positions[3 * v + k]);
  for (int k = 0; k < 3; ++k) scale_m_ = std::max({scale_m_, std::abs(low_[k]), std::abs(high_[k])});
  if (!std::isfinite(scale_m_)) {
    closed_ = false;  // NaN or infinite coordinates: depthInside answers
    return;
  }
  for (int k = 0; k < 2; ++k) cell_m_[k] = std::max((high_[k] - low_[k]) / kCells, 1e-300);
  // Each triangle in every cell its xy box (widened by the margin) meets: the cell of a point
  // then lists every triangle a vertical ray through it can touch.
  const double margin = 1e-9 * scale_m_;
  std::vector<std::vector<uint32_t>> cells(size_t(kCells) * kCells);
  for (size_t t = 0; t < nt; ++t) {
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 2; ++k) {
        lo[k] = std::min(lo[k], positions[3 * size_t(triangles[3 * t + c]) + k]);
        hi[k] = std::max(hi[k], positions[3 * size_t(triangles[3 * t + c]) + k]);
      }
    int from[2], to[2];
    for (int k = 0; k < 2; ++k) from[k] = cellOf(lo[k] - margin, k), to[k] = cellOf(hi[k] + margin, k);
    for (int x = from[0]; x <= to[0]; ++x)
      for (int y = from[1]; y <= to[1]; ++y) cells[size_t(x) * kCells + size_t(y)].push_back(uint32_t(t));
  }
  cell_start_.assign(cells.size() + 1, 0);
  for (size_t c = 0; c < cells.size(); ++c) cell_start_[c + 1] = cell_start_[c] + uint32_t(cells[c].size());
  cell_tris_.reserve(cell_start_.back());
  for (const auto& list : cells) cell_tris_.insert(cell_tris_.end(), list.begin(), list.end());
}

int InsideTest::cellOf(double x, int k) const {
  const double cell = (x - low_[k]) / cell_m_[k];
  return cell <= 0.0 ? 0 : cell >= kCells - 1 ? kCells - 1 : int(cell);
}

int InsideTest::classify(const double p[3]) const {
  if (!closed_) return -1;
  for (int k = 0; k < 3; ++k)
    if (p[k] < low_[k] || p[k] > high_[k]) return 0;    // outside the box: outside (winding 0)
  const double tol_area = 1e-10 * scale_m_ * scale_m_;  // ~1e6 x the rounding of a 2D cross product
  const double tol_m = 1e-9 * scale_m_;
  const size_t c = size_t(cellOf(p[0], 0)) * kCells + size_t(cellOf(p[1], 1));
  int winding = 0;
  for (uint32_t i = cell_start_[c]; i < cell_start_[c + 1]; ++i) {
    const uint32_t* tri = &triangles_[3 * size_t(cell_tris_[i])];
    const double* a = &positions_[3 * size_t(tri[0])];
    const double* b = &positions_[3 * size_t(tri[1])];
    const double* d = &positions_[3 * size_t(tri[2])];
    const double ax = a[0] - p[0], ay = a[1] - p[1], bx = b[0] - p[0], by = b[1] - p[1];
    const double dx = d[0] - p[0], dy = d[1] - p[1];
    // Twice the signed areas of (p, a, b), (p, b, d), (p, d, a) in xy.
    const double e_ab = ax * by - ay * bx, e_bd = bx * dy - by * dx, e_da = dx * ay - dy * ax;
    const bool some_positive = e_ab > tol_area || e_bd > tol_area || e_da > tol_area;
    const bool some_negative = e_ab < -tol_area || e_bd < -tol_area || e_da < -tol_area;
    if (some_positive && some_negative) continue;  // the ray misses this triangle
    const bool all_clear = std::abs(e_ab) > tol_area && std::abs(e_bd) > tol_area && std::abs(e_da) > tol_area;
    if (!all_clear) return -1;  // through (or within rounding of) an edge or vertex, or NaN
    const double area = e_ab + e_bd + e_da;
    const double z = (e_bd * a[2] + e_da * b[2] + e_ab * d[2]) / area;  // the face above or below p
    if (std::abs(z - p[2]) <= tol_m) return -1;                         // p on the face
    if (z > p[2]) winding += area > 0.0 ? 1 : -1;
  }
  return winding > 0 ? 1 : 0;
}

double depthInside(const double p[3], const std::vector<double>& positions, const std::vector<uint32_t>& triangles) {
  const Vec point{p[0], p[1], p[2]};
  double solid_angle = 0.0;
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const std::array<Vec, 3> corner = cornersOf(positions, triangles, t);
    // Solid angle of the triangle seen from p: tan(Omega/2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|).
    const Vec a = sub(corner[0], point), b = sub(corner[1], point), c = sub(corner[2], point);
    const double la = length(a), lb = length(b), lc = length(c);
    const double numerator = dot(a, cross(b, c));
    const double denominator = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    solid_angle += 2.0 * std::atan2(numerator, denominator);
  }
  const double winding = solid_angle / (4.0 * M_PI);  // 1 inside a closed CCW surface, 0 outside
  // Inside: the depth is the distance to the nearest triangle (a second pass, skipped outside).
  return winding > 0.5 ? std::sqrt(nearestSquared(point, positions, triangles)) : 0.0;
}

std::vector<std::string> checkStartingPlacement(const Scene& scene, const std::vector<SimBodyDesc>& bodies,
                                                const PlacementLimits& limits) {
  std::vector<std::string> warnings;
  std::vector<WorldSurface> world;
  for (const SimBodyDesc& body : bodies) world.push_back(worldBoxes(body));
  std::vector<std::unique_ptr<InsideTest>> inside_tests(bodies.size());  // built when a pair needs one
  auto insideTest = [&](size_t i) -> const InsideTest& {
    addWorldPoints(bodies[i], world[i]);
    if (!inside_tests[i])
      inside_tests[i] = std::make_unique<InsideTest>(world[i].positions, bodies[i].surface_triangles);
    return *inside_tests[i];
  };
  auto hasPoints = [&](size_t i) { return bodies[i].surface_positions.size() >= 3; };
  for (size_t i = 0; i < bodies.size() && i < scene.objects.size(); ++i) {
    const SimBodyDesc& body = bodies[i];
    const SceneObject& object = scene.objects[i];
    const WorldSurface& w = world[i];
    if (!hasPoints(i)) continue;
    const std::string who = "objects \"" + body.name + "\": ";
    // Size and mass: a mesh file in millimetres read as metres is 1000x too long, 1e9x too heavy.
    const Vec extent = sub(w.high, w.low);
    const double largest = std::max({extent[0], extent[1], extent[2]});
    const bool mesh_file = !object.mesh.empty() && object.bank.empty() && object.mesh.find(':') == std::string::npos;
    const bool too_heavy = !body.is_static && body.mass_kg > limits.max_dynamic_mass_kg;
    if (largest > limits.max_extent_m || too_heavy) {
      std::string hint = mesh_file && object.units == "m"
                             ? "; if the mesh file is in millimetres, add \"units\": \"mm\" to the object"
                             : "; check the mesh's units and the material's density";
      warnings.push_back(who + format("%.3g x %.3g x %.3g m, ", extent[0], extent[1], extent[2]) +
                         format("%.3g kg (%.3g tonnes): implausibly ", body.mass_kg, body.mass_kg / 1000.0) +
                         (largest > limits.max_extent_m ? "large" : "heavy") + " for a sounding object" + hint);
    } else if (largest < limits.min_extent_m) {
      warnings.push_back(
          who +
          format("%.3g x %.3g x %.3g mm: implausibly small for a sounding object", extent[0] * 1e3, extent[1] * 1e3,
                 extent[2] * 1e3) +
          (mesh_file ? "; check its \"units\" (a mesh file is read in metres unless \"units\" says otherwise)" : ""));
    }
    // Inside the ground: Bullet pushes it out at once, and the push sounds like a blow.
    if (scene.has_ground && !body.is_static) {
      const double depth = scene.ground_height_m - w.low[2];
      if (depth > limits.overlap_tolerance_m)
        warnings.push_back(
            who +
            format("starts %.3g mm inside the ground (its lowest point is at z = %.4g m, the ground at z = %.4g m); "
                   "the simulation pushes it out at once (a jump, heard as a knock only if it then strikes something "
                   "hard enough): place it above the ground",
                   depth * 1e3, w.low[2], scene.ground_height_m));
    }
  }
  // Inside each other: boxes first, then vertices inside the other's closed surface.
  for (size_t i = 0; i < bodies.size(); ++i) {
    for (size_t j = i + 1; j < bodies.size(); ++j) {
      if (bodies[i].is_static && bodies[j].is_static) continue;  // never simulated against each other
      const WorldSurface &a = world[i], &b = world[j];
      if (!hasPoints(i) || !hasPoints(j)) continue;
      bool boxes_meet = true;
      for (int k = 0; k < 3; ++k)
        boxes_meet = boxes_meet && a.low[k] < b.high[k] - limits.overlap_tolerance_m &&
                     b.low[k] < a.high[k] - limits.overlap_tolerance_m;
      if (!boxes_meet) continue;
      const InsideTest &inside_j = insideTest(j), &inside_i = insideTest(i);  // both bodies' points now
      const double depth = std::max(deepestVertexInside(a, b, bodies[j], limits.max_vertices_tested, inside_j),
                                    deepestVertexInside(b, a, bodies[i], limits.max_vertices_tested, inside_i));
      if (depth > limits.overlap_tolerance_m)
        warnings.push_back(
            "objects \"" + bodies[i].name + "\" and \"" + bodies[j].name +
            format("\" start inside each other (a surface point %.3g mm deep); ", depth * 1e3) +
            "the simulation pushes them apart at once (a jump that may be heard as a knock): move them apart");
    }
  }
  return warnings;
}

std::string neverStruckWarning(const Scene& scene, const SimBodyDesc& body, double duration_s) {
  const WorldSurface w = worldBoxes(body);
  std::string text = "objects \"" + body.name + "\": never struck (it starts at " +
                     format("(%.4g, %.4g, %.4g) m", body.position_m[0], body.position_m[1], body.position_m[2]);
  const double g = -scene.gravity_m_s2[2];
  if (!body.path.empty()) {  // a driven body goes where its path takes it, not where it falls
    const PathKey& last = body.path.back();
    return text + format("; its path ends at (%.4g, %.4g, %.4g) m at %.4g s without touching anything)",
                         last.position_m[0], last.position_m[1], last.position_m[2], last.t_s);
  }
  if (scene.has_ground && body.surface_positions.size() >= 3) {
    const double height = w.low[2] - scene.ground_height_m;
    text += format(", its lowest point %.4g m above the ground", height);
    const double v = body.velocity_m_s[2];
    if (g > 0 && height > 0) {
      // Time to fall `height` from vertical speed v: height = -v t + g t^2 / 2.
      const double t = (v + std::sqrt(v * v + 2.0 * g * height)) / g;
      text += format("; falling from there takes %.3g s, the render lasts %.3g s", t, duration_s);
    }
  } else if (!scene.has_ground) {
    text += "; the scene has no ground";
  }
  return text + ")";
}

}  // namespace strike
