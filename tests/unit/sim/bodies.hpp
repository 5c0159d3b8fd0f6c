// SPDX-License-Identifier: MIT
// Bodies built by hand for the simulator tests: boxes (8 vertices, 12 triangles, exact mass
// properties), an icosahedron and geodesic spheres, and the small vector algebra they need.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "strike/sim/sim.hpp"

namespace strike::sim_bodies {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>;  // row-major

constexpr double kG = 9.81;

inline Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline Vec3 mul(const Mat3& m, const Vec3& v) {
  return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
          m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}
inline Vec3 mulT(const Mat3& m, const Vec3& v) {
  return {m[0] * v[0] + m[3] * v[1] + m[6] * v[2], m[1] * v[0] + m[4] * v[1] + m[7] * v[2],
          m[2] * v[0] + m[5] * v[1] + m[8] * v[2]};
}
inline Mat3 identity() { return {1, 0, 0, 0, 1, 0, 0, 0, 1}; }

/// Rotation matrix of angle about a (not necessarily unit) axis (Rodrigues).
inline Mat3 rotation(Vec3 axis, double angle) {
  const double n = std::sqrt(dot(axis, axis));
  for (double& a : axis) a /= n;
  const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  const double x = axis[0], y = axis[1], z = axis[2];
  return {t * x * x + c,     t * x * y - s * z, t * x * z + s * y,  //
          t * x * y + s * z, t * y * y + c,     t * y * z - s * x,  //
          t * x * z - s * y, t * y * z + s * x, t * z * z + c};
}
inline std::array<double, 4> quaternion(Vec3 axis, double angle) {
  const double n = std::sqrt(dot(axis, axis));
  const double s = std::sin(angle / 2) / n;
  return {std::cos(angle / 2), axis[0] * s, axis[1] * s, axis[2] * s};
}

/// Orient every triangle of a convex mesh outwards (normal away from `inside`).
inline void orientOutward(SimBodyDesc& body, const Vec3& inside) {
  auto vertex = [&](uint32_t i) {
    return Vec3{body.surface_positions[3 * i], body.surface_positions[3 * i + 1], body.surface_positions[3 * i + 2]};
  };
  for (size_t t = 0; t < body.surface_triangles.size(); t += 3) {
    const Vec3 a = vertex(body.surface_triangles[t]), b = vertex(body.surface_triangles[t + 1]),
               c = vertex(body.surface_triangles[t + 2]);
    if (dot(cross(sub(b, a), sub(c, a)), sub(a, inside)) < 0) {
      std::swap(body.surface_triangles[t + 1], body.surface_triangles[t + 2]);
    }
  }
}

/// A solid box of size l with its centre at `offset` and its edges along the columns of `axes`,
/// all in the mesh frame; exact mass properties for uniform density.
inline SimBodyDesc makeBox(const std::string& name, Vec3 l, double mass_kg, Vec3 offset = {0, 0, 0},
                           Mat3 axes = identity()) {
  SimBodyDesc body;
  body.name = name;
  for (int v = 0; v < 8; ++v) {
    const Vec3 local{(v & 1 ? 0.5 : -0.5) * l[0], (v & 2 ? 0.5 : -0.5) * l[1], (v & 4 ? 0.5 : -0.5) * l[2]};
    const Vec3 p = add(offset, mul(axes, local));
    body.surface_positions.insert(body.surface_positions.end(), p.begin(), p.end());
  }
  const uint32_t quads[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  for (const auto& q : quads) {
    body.surface_triangles.insert(body.surface_triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  }
  orientOutward(body, offset);
  body.mass_kg = mass_kg;
  body.centre_m = offset;
  const Vec3 d{mass_kg / 12 * (l[1] * l[1] + l[2] * l[2]), mass_kg / 12 * (l[0] * l[0] + l[2] * l[2]),
               mass_kg / 12 * (l[0] * l[0] + l[1] * l[1])};
  // I_mesh = A diag(d) A^T
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += axes[3 * r + k] * d[k] * axes[3 * c + k];
      body.inertia_kg_m2[3 * r + c] = s;
    }
  }
  return body;
}

/// Icosahedron of circumradius r centred at the mesh origin, with a solid sphere's inertia.
inline SimBodyDesc makeBall(const std::string& name, double r, double mass_kg) {
  SimBodyDesc body;
  body.name = name;
  const double phi = (1 + std::sqrt(5.0)) / 2, s = r / std::sqrt(1 + phi * phi);
  const double v[12][3] = {{-1, phi, 0},  {1, phi, 0},  {-1, -phi, 0}, {1, -phi, 0}, {0, -1, phi},  {0, 1, phi},
                           {0, -1, -phi}, {0, 1, -phi}, {phi, 0, -1},  {phi, 0, 1},  {-phi, 0, -1}, {-phi, 0, 1}};
  for (const auto& p : v) body.surface_positions.insert(body.surface_positions.end(), {s * p[0], s * p[1], s * p[2]});
  body.surface_triangles = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                            4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                            6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  orientOutward(body, {0, 0, 0});
  body.mass_kg = mass_kg;
  const double i = 0.4 * mass_kg * r * r;
  body.inertia_kg_m2 = {i, 0, 0, 0, i, 0, 0, 0, i};
  return body;
}

/// A geodesic sphere of radius r (an icosahedron subdivided `levels` times, vertices pushed onto
/// the sphere) centred at the mesh origin, with a solid sphere's mass properties. From one level
/// on its hull fills >= 90% of the sphere, so the simulator uses Bullet's exact sphere shape.
inline SimBodyDesc makeSphere(const std::string& name, double r, double mass_kg, int levels = 2) {
  SimBodyDesc body = makeBall(name, 1.0, mass_kg);
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      if (auto it = midpoints.find(key); it != midpoints.end()) return it->second;
      Vec3 m{};
      for (int k = 0; k < 3; ++k) m[k] = 0.5 * (body.surface_positions[3 * a + k] + body.surface_positions[3 * b + k]);
      const double n = std::sqrt(dot(m, m));
      const uint32_t index = uint32_t(body.surface_positions.size() / 3);
      body.surface_positions.insert(body.surface_positions.end(), {m[0] / n, m[1] / n, m[2] / n});
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<uint32_t> finer;
    for (size_t t = 0; t < body.surface_triangles.size(); t += 3) {
      const uint32_t a = body.surface_triangles[t], b = body.surface_triangles[t + 1],
                     c = body.surface_triangles[t + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      finer.insert(finer.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
    }
    body.surface_triangles = std::move(finer);
  }
  for (double& x : body.surface_positions) x *= r;
  const double i = 0.4 * mass_kg * r * r;
  body.inertia_kg_m2 = {i, 0, 0, 0, i, 0, 0, 0, i};
  return body;
}

}  // namespace strike::sim_bodies
