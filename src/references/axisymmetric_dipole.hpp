// SPDX-License-Identifier: MIT
// The dipole of a rigid body of revolution translating along its axis in still, incompressible
// air: M_zz = V + (1/rho) x added mass (Lamb, Hydrodynamics, 6th ed., sec. 118-121), computed
// independently of src/transfer/ by an axisymmetric boundary-element method on the body's
// generating curve, where every ring integral is a complete elliptic integral and the curve can
// be graded toward corners and rims as finely as wanted (a 3D surface mesh cannot, at a cost a
// test affords). It is the reference for a body with no closed form, a disc of finite thickness.
//
// The problem is the transfer solver's at k = 0 (docs/acoustic-transfer.md, rigid translation):
// dp/dn = -n_z on S, p -> 0 far away, and for x on S (n outward)
//   1/2 p(x) - int_S p dG/dn_y dS = - int_S G dp/dn dS,   G = 1 / (4 pi |x - y|),
// then M_zz = V + int_S n_z p dS. For an axisymmetric p, with x = (rho, 0, z), y on the ring
// (rho', theta, z'), |x - y|^2 = A - B cos theta (A = rho^2 + rho'^2 + (z - z')^2, B = 2 rho rho'),
// m = 2B / (A + B) [Gradshteyn & Ryzhik 2.575, 3.152; Kirkup 2007, ch. 3, axisymmetric forms]:
//   int_0^2pi (A - B cos)^(-1/2) = 4 K(m) / sqrt(A + B),
//   int_0^2pi (A - B cos)^(-3/2) = 4 E(m) / ((A - B) sqrt(A + B)),
//   int_0^2pi cos (A - B cos)^(-3/2) = (A I_3 - I_1) / B.
// p is constant on each straight segment of the curve, collocated at its midpoint; each segment
// integral is 8-point Gauss-Legendre on pieces split in halves until they are two of their
// lengths from the point (toward the point itself, where the ring kernel is log-singular, down to
// 2^-40 of the segment or 1e-12 of the body's size). Header-only, the C++ standard library only.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace strike::test {

/// A point of a generating curve: radius from the axis and height.
struct CurvePoint {
  double rho = 0.0, z = 0.0;
};

namespace axisymmetric_detail {

constexpr double kX8[8] = {0.019855071751231856, 0.10166676129318664, 0.2372337950418355, 0.4082826787521751,
                           0.5917173212478249,   0.7627662049581645,  0.8983332387068134, 0.9801449282487681};
constexpr double kW8[8] = {0.05061426814518813, 0.11119051722668724, 0.15685332293894363, 0.18134189168918100,
                           0.18134189168918100, 0.15685332293894363, 0.11119051722668724, 0.05061426814518813};

/// 4 pi x the ring integrals of G and dG/dn_y at source point (rho', z') with the source's normal
/// (n_rho, n_z), seen from x = (rho, z): {int G dtheta, int dG/dn_y dtheta}, each times 4 pi.
inline std::array<double, 2> ringKernels(double rho, double z, double rho_s, double z_s, double n_rho, double n_z) {
  const double dz = z - z_s, dr = rho - rho_s, A = rho * rho + rho_s * rho_s + dz * dz, B = 2.0 * rho * rho_s;
  const double a_minus_b = dr * dr + dz * dz;  // A - B without its cancellation near x
  const double m = std::min(2.0 * B / (A + B), 1.0 - 1e-15), k = std::sqrt(m), root = std::sqrt(A + B);
  const double K = std::comp_ellint_1(k), E = std::comp_ellint_2(k);
  const double i1 = 4.0 * K / root, i3 = 4.0 * E / (a_minus_b * root);
  // (x - y).n_y = n_rho (rho cos - rho') + n_z (z - z'); with cos = (A - D^2) / B the n_rho part
  // is (4 / root) ((rho^2 - rho'^2 + dz^2) E / (A - B) - K) / (2 rho').
  double dn = n_z * dz * i3;
  if (n_rho != 0.0)
    dn += n_rho * 4.0 / root * ((rho * rho - rho_s * rho_s + dz * dz) * E / a_minus_b - K) / (2.0 * rho_s);
  return {i1, dn};
}

/// 4 pi x {int_seg G rho' ds, int_seg dG/dn_y rho' ds} over the segment's part [t0, t1] (t in
/// [0, 1] along it), seen from (rho, z); `singular_t`: where the point lies on it (or < 0).
inline void segmentIntegrals(double rho, double z, const CurvePoint& a, const CurvePoint& b, double t0, double t1,
                             double singular_t, int depth, double& g, double& dg) {
  const double len = std::hypot(b.rho - a.rho, b.z - a.z), n_rho = -(b.z - a.z) / len, n_z = (b.rho - a.rho) / len;
  const double tm = 0.5 * (t0 + t1);
  const double cr = a.rho + tm * (b.rho - a.rho), cz = a.z + tm * (b.z - a.z);
  const double piece = (t1 - t0) * len, dist = std::hypot(cr - rho, cz - z);
  const bool holds_point = singular_t >= t0 && singular_t <= t1;
  // The log-singular piece at the point is dropped once it is 2^-40 of the segment or so small
  // that its Gauss points would round onto the point (its share: ~ its length times a log).
  if (holds_point && (depth >= 40 || piece < 1e-12 * (std::fabs(rho) + std::fabs(z) + len))) return;
  if (holds_point || (depth < 40 && dist < 2.0 * piece)) {
    const double split = holds_point && singular_t > t0 && singular_t < t1 ? singular_t : tm;
    if (holds_point && (singular_t == t0 || singular_t == t1)) {
      // Graded toward the singular end: halve the piece next to it.
      const double near_end = singular_t == t0 ? t0 + 0.5 * (t1 - t0) : t1 - 0.5 * (t1 - t0);
      if (singular_t == t0) {
        segmentIntegrals(rho, z, a, b, t0, near_end, singular_t, depth + 1, g, dg);
        segmentIntegrals(rho, z, a, b, near_end, t1, -1.0, depth + 1, g, dg);
      } else {
        segmentIntegrals(rho, z, a, b, t0, near_end, -1.0, depth + 1, g, dg);
        segmentIntegrals(rho, z, a, b, near_end, t1, singular_t, depth + 1, g, dg);
      }
      return;
    }
    segmentIntegrals(rho, z, a, b, t0, split, holds_point ? singular_t : -1.0, depth + 1, g, dg);
    segmentIntegrals(rho, z, a, b, split, t1, holds_point ? singular_t : -1.0, depth + 1, g, dg);
    return;
  }
  for (int i = 0; i < 8; ++i) {
    const double t = t0 + kX8[i] * (t1 - t0);
    const double sr = a.rho + t * (b.rho - a.rho), sz = a.z + t * (b.z - a.z);
    const std::array<double, 2> k = ringKernels(rho, z, sr, sz, n_rho, n_z);
    const double w = kW8[i] * (t1 - t0) * len * sr;
    g += w * k[0];
    dg += w * k[1];
  }
}

/// Solves a x = b in place (Gaussian elimination, partial pivoting).
inline std::vector<double> solveDense(std::vector<double> a, std::vector<double> b) {
  const size_t n = b.size();
  for (size_t c = 0; c < n; ++c) {
    size_t pivot = c;
    for (size_t r = c + 1; r < n; ++r)
      if (std::fabs(a[r * n + c]) > std::fabs(a[pivot * n + c])) pivot = r;
    for (size_t j = 0; j < n; ++j) std::swap(a[c * n + j], a[pivot * n + j]);
    std::swap(b[c], b[pivot]);
    for (size_t r = c + 1; r < n; ++r) {
      const double f = a[r * n + c] / a[c * n + c];
      for (size_t j = c; j < n; ++j) a[r * n + j] -= f * a[c * n + j];
      b[r] -= f * b[c];
    }
  }
  std::vector<double> x(n);
  for (size_t r = n; r-- > 0;) {
    double s = b[r];
    for (size_t j = r + 1; j < n; ++j) s -= a[r * n + j] * x[j];
    x[r] = s / a[r * n + r];
  }
  return x;
}

}  // namespace axisymmetric_detail

/// M_zz (m^3) of the body of revolution whose generating curve runs through `curve` from the axis
/// (rho = 0) at the top to the axis at the bottom, the body on its right (outward normal
/// (-dz, drho) / ds), a straight segment between successive points.
inline double axialDipole(const std::vector<CurvePoint>& curve) {
  using namespace axisymmetric_detail;
  const size_t n = curve.size() - 1;
  std::vector<double> a(n * n, 0.0), rhs(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const CurvePoint &p = curve[i], &q = curve[i + 1];
    const double rho = 0.5 * (p.rho + q.rho), z = 0.5 * (p.z + q.z);
    a[i * n + i] += 0.5;
    for (size_t j = 0; j < n; ++j) {
      const CurvePoint &u = curve[j], &v = curve[j + 1];
      const double len = std::hypot(v.rho - u.rho, v.z - u.z), n_z = (v.rho - u.rho) / len;
      double g = 0.0, dg = 0.0;
      segmentIntegrals(rho, z, u, v, 0.0, 1.0, i == j ? 0.5 : -1.0, 0, g, dg);
      a[i * n + j] -= dg / (4.0 * M_PI);
      rhs[i] -= g / (4.0 * M_PI) * (-n_z);  // - int G q, q = -n_z
    }
  }
  const std::vector<double> p = solveDense(a, rhs);
  double volume = 0.0, dipole = 0.0;
  for (size_t j = 0; j < n; ++j) {
    const CurvePoint &u = curve[j], &v = curve[j + 1];
    // int n_z dS over the frustum: 2 pi int rho n_z ds = pi (rho_v^2 - rho_u^2); its volume,
    // int pi rho^2 dz, as a frustum's.
    dipole += p[j] * M_PI * (v.rho * v.rho - u.rho * u.rho);
    volume += M_PI / 3.0 * (u.z - v.z) * (u.rho * u.rho + u.rho * v.rho + v.rho * v.rho);
  }
  return volume + dipole;
}

/// The generating curve of a cylinder of radius R and height H about the z axis, `per_face`
/// segments on each cap and `per_side` on the side, graded (power 3) toward the rim's corners,
/// where the flow's gradient is singular.
inline std::vector<CurvePoint> cylinderCurve(double R, double H, int per_face, int per_side) {
  std::vector<CurvePoint> c;
  auto graded = [](double s) { return 1.0 - std::pow(1.0 - s, 3.0); };  // 0 -> 0, 1 -> 1, fine near 1
  for (int i = 0; i <= per_face; ++i) c.push_back({R * graded(static_cast<double>(i) / per_face), 0.5 * H});
  for (int i = 1; i <= per_side; ++i) {
    const double s = static_cast<double>(i) / per_side;  // both ends graded
    const double u = s < 0.5 ? 0.5 * (1.0 - graded(1.0 - 2.0 * s)) : 0.5 + 0.5 * graded(2.0 * s - 1.0);
    c.push_back({R, 0.5 * H - H * u});
  }
  for (int i = per_face - 1; i >= 0; --i) c.push_back({R * graded(static_cast<double>(i) / per_face), -0.5 * H});
  return c;
}

/// The generating curve of the spheroid rho^2 / a^2 + z^2 / c^2 = 1, `segments` from pole to pole
/// equally spaced in the polar angle.
inline std::vector<CurvePoint> spheroidCurve(double a, double c, int segments) {
  std::vector<CurvePoint> curve;
  for (int i = 0; i <= segments; ++i) {
    const double t = M_PI * i / segments;
    curve.push_back({a * std::sin(t), c * std::cos(t)});
  }
  curve.front().rho = curve.back().rho = 0.0;
  return curve;
}

/// The exact M_zz of that spheroid translating along its axis: 2V / (2 - alpha_0) (Lamb sec. 114,
/// 373), with alpha_0 = (2 / e^2) (1 - sqrt(1 - e^2) arcsin(e) / e) for an oblate one (c < a,
/// e^2 = 1 - c^2 / a^2); 2 pi a^3 for the sphere, 8/3 a^3 in the limit of a flat disc.
inline double oblateSpheroidAxialDipole(double a, double c) {
  const double e = std::sqrt(1.0 - c * c / (a * a));
  const double alpha0 = 2.0 / (e * e) * (1.0 - (c / a) * std::asin(e) / e);
  return 2.0 * (4.0 / 3.0 * M_PI * a * a * c) / (2.0 - alpha0);
}

}  // namespace strike::test
