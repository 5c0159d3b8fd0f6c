// SPDX-License-Identifier: MIT
// The listener model's radiation strength R_i of each mode: what a bank without an acoustic
// transfer (and the modes above its heard ones) is heard at, stored in the bank as radiation_m2.
//
// Model: the surface as free monopoles, heard at the rms over directions.
// A patch of surface of area A with outward normal n whose wall accelerates at a(t) is a point
// source of volume acceleration A n.a; in free field its pressure at distance d >> size is
// rho_air / (4 pi d) * A n.a(t - d / c_air) (Kinsler et al., Fundamentals of Acoustics, 4th ed.,
// 2000, sec. 7.4). Summing the patches of mode i with their far-field phases e^{i k r.x}
// (k = omega_i / c_air, r the listener's direction) and averaging |.|^2 over all directions
// (the body tumbles, so no direction is special; the average of e^{i k r.(x - y)} over the sphere
// is sinc(k |x - y|) = sin(k r) / (k r)) gives
//   R_i^2 = sum_a sum_b  s_a s_b sinc(k_i |x_a - x_b|),   s_a = A_a n_a . phi_i(x_a),
//   p(t) ~= rho_air / (4 pi d) * sum_i R_i q_i''(t - d / c_air).
// For a compact body this is exactly the multipole expansion: a volume change radiates as a
// monopole (R = sum s_a), a body whose surface moves without changing its volume as a dipole
// (R = k |D| / sqrt 3, D = sum s_a x_a), a bending bar whose length is not compact as a chain of
// dipoles; for a large body (k L >> 1) it tends to the incoherent sum sqrt(sum s_a^2). So the
// mode-to-mode balance follows the physics of radiation efficiency rather than a fixed guess
// [compare van den Doel & Pai 1998, who use measured per-mode gains]. The weight is
// rho_air R_i / (4 pi d) Pa per unit modal acceleration, so the output is pressure in pascals.
//
// Cost: patches are merged into cells with k * cell <= 1/4, so low modes of large objects are
// cheap, and the average over directions is taken on the 162 vertices of a twice-subdivided
// icosahedron instead of the O(cells^2) double sum: the set is invariant under the icosahedral
// group, hence a spherical 5-design, exact for the monopole, dipole and quadrupole parts of
// |p|^2, and within about 0.5 dB for large bodies whose pattern has many lobes. A cell keeps its
// own dipole moment d_c (about its centre) as a self term k^2 |d_c|^2 / 3, so a body whose
// monopoles cancel inside one cell still radiates as a dipole.
//
// What it leaves out:
//  - the body as an obstacle: patches radiate as if the body were acoustically transparent (no
//    scattering, no baffle), so the fluid's added-mass reaction (x1.5 for a translating sphere)
//    and shadowing are missing,
//  - the phase and direction of the sound (magnitude only, rms over directions) and the near
//    field (d ~ body size). The ground's image and air absorption are the paths' (sound_paths.cpp,
//    air_absorption.cpp) and the room is left out, with either model.
#include "strike/bank/radiation_strength.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "strike/core/air.hpp"

namespace strike {

namespace {

/// One radiating patch: area-weighted normal and centroid.
struct Patch {
  double an[3];
  double centre[3];
  uint32_t tri[3];
};

/// The 162 unit vectors of a twice-subdivided icosahedron (see the cost note above).
std::vector<std::array<double, 3>> icosphereDirections() {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                           {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                           {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                           {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  auto unit = [](std::array<double, 3> p) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / n, p[1] / n, p[2] / n};
  };
  for (auto& p : v) p = unit(p);
  for (int level = 0; level < 2; ++level) {
    std::map<std::pair<int, int>, int> midpoint;
    auto middle = [&](int a, int b) {
      const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back(unit({v[a][0] + v[b][0], v[a][1] + v[b][1], v[a][2] + v[b][2]}));
      return midpoint[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> finer;
    for (const auto& f : faces) {
      const int ab = middle(f[0], f[1]), bc = middle(f[1], f[2]), ca = middle(f[2], f[0]);
      finer.insert(finer.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    faces = std::move(finer);
  }
  return v;  // 12 + 30 + 120 = 162 directions
}

/// The cell of a patch `offset` metres from the box corner. Clamped, so that a hostile bank
/// (finite but absurd positions, 1e249 m: found by fuzz_capi_bank) cannot overflow the integer;
/// 2^40 cells span any physical body at any audible wavelength.
int64_t cellIndex(double offset_m, double cell_m) {
  const double index = std::floor(offset_m / cell_m);
  return index >= 0.0 ? static_cast<int64_t>(std::min(index, 1099511627776.0)) : 0;  // NaN -> 0
}

}  // namespace

std::vector<double> radiationStrengths(const ModeBank& bank) {
  const size_t nv = bank.surfaceVertexCount();
  const size_t modes = bank.modeCount();
  std::vector<double> weights(modes, 0.0);
  if (bank.shapes.size() < modes * nv * 3) return weights;
  std::vector<Patch> patches;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  const double* pos = bank.surface_positions.data();
  for (size_t t = 0; t + 2 < bank.surface_triangles.size(); t += 3) {
    const uint32_t* tri = &bank.surface_triangles[t];
    if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) continue;
    const double* a = pos + 3 * tri[0];
    const double* b = pos + 3 * tri[1];
    const double* c = pos + 3 * tri[2];
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    Patch p;
    // Area-weighted normal (|cross| = 2 area), so area_t * n_t = cross / 2.
    p.an[0] = 0.5 * (e1[1] * e2[2] - e1[2] * e2[1]);
    p.an[1] = 0.5 * (e1[2] * e2[0] - e1[0] * e2[2]);
    p.an[2] = 0.5 * (e1[0] * e2[1] - e1[1] * e2[0]);
    for (int k = 0; k < 3; ++k) {
      p.centre[k] = (a[k] + b[k] + c[k]) / 3.0;
      lo[k] = std::min(lo[k], p.centre[k]);
      hi[k] = std::max(hi[k], p.centre[k]);
      p.tri[k] = tri[k];
    }
    patches.push_back(p);
  }
  if (patches.empty()) return weights;
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-9});

  const std::vector<std::array<double, 3>> directions = icosphereDirections();
  std::map<std::array<int64_t, 3>, size_t> cell_of;
  std::vector<double> cell_strength, cell_centre, cell_weight, cell_moment;
  for (size_t m = 0; m < modes; ++m) {
    const double lambda = bank.eigenvalues[m];
    const double k = lambda > 0 && std::isfinite(lambda) ? std::sqrt(lambda) / kSpeedOfSoundAir_m_s : 0.0;
    // Merge patches into cells with k * cell <= 1/4.
    const double cell = k > 0 ? std::min(0.25 / k, 2.0 * extent) : 2.0 * extent;
    cell_of.clear();
    cell_strength.clear();
    cell_centre.clear();
    cell_weight.clear();
    cell_moment.clear();
    for (const Patch& p : patches) {
      const float* p0 = bank.shapeAt(m, p.tri[0]);
      const float* p1 = bank.shapeAt(m, p.tri[1]);
      const float* p2 = bank.shapeAt(m, p.tri[2]);
      double s = 0.0;
      for (int c = 0; c < 3; ++c) s += p.an[c] * (static_cast<double>(p0[c]) + p1[c] + p2[c]) / 3.0;
      const std::array<int64_t, 3> key = {cellIndex(p.centre[0] - lo[0], cell), cellIndex(p.centre[1] - lo[1], cell),
                                          cellIndex(p.centre[2] - lo[2], cell)};
      auto [it, inserted] = cell_of.emplace(key, cell_strength.size());
      if (inserted) {
        cell_strength.push_back(0.0);
        cell_weight.push_back(0.0);
        cell_centre.insert(cell_centre.end(), {0.0, 0.0, 0.0});
        cell_moment.insert(cell_moment.end(), {0.0, 0.0, 0.0});
      }
      // The cell's centre is the area-weighted mean of its patches (fixed per mode, sign-free).
      const double area = std::sqrt(p.an[0] * p.an[0] + p.an[1] * p.an[1] + p.an[2] * p.an[2]);
      cell_strength[it->second] += s;
      cell_weight[it->second] += area;
      for (int c = 0; c < 3; ++c) {
        cell_centre[it->second * 3 + c] += area * p.centre[c];
        cell_moment[it->second * 3 + c] += s * p.centre[c];
      }
    }
    const size_t cells = cell_strength.size();
    double r2 = 0.0;
    for (size_t a = 0; a < cells; ++a) {
      for (int c = 0; c < 3; ++c) cell_centre[a * 3 + c] /= std::max(cell_weight[a], 1e-300);
      double dipole2 = 0.0;  // |d_a|^2, the cell's dipole about its own centre
      for (int c = 0; c < 3; ++c) {
        const double d = cell_moment[a * 3 + c] - cell_strength[a] * cell_centre[a * 3 + c];
        dipole2 += d * d;
      }
      r2 += k * k * dipole2 / 3.0;
    }
    double power = 0.0;
    for (const std::array<double, 3>& dir : directions) {
      double re = 0.0, im = 0.0;
      for (size_t a = 0; a < cells; ++a) {
        const double phase =
            k * (dir[0] * cell_centre[a * 3] + dir[1] * cell_centre[a * 3 + 1] + dir[2] * cell_centre[a * 3 + 2]);
        re += cell_strength[a] * std::cos(phase);
        im += cell_strength[a] * std::sin(phase);
      }
      power += re * re + im * im;
    }
    r2 += power / static_cast<double>(directions.size());
    weights[m] = std::sqrt(std::max(r2, 0.0));  // the quadratic form is PSD; clamp rounding
  }
  return weights;
}

}  // namespace strike
