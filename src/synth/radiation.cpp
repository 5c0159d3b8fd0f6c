// SPDX-License-Identifier: MIT
// Listener model: how loud each mode is at the listener, per unit modal acceleration.
//
// Model: a compact source (monopole + dipole), never louder than all patches in phase.
// A patch of surface of area A with outward normal n whose wall accelerates at a(t) is a point
// source of volume acceleration A n.a. For a body small against the wavelength, the far field at
// distance d is the multipole expansion of those sources about the centre of mass c
// (Kinsler et al., Fundamentals of Acoustics, 4th ed., 2000, ch. 7; Pierce, Acoustics, 1989, 4.4):
//   monopole  Q_i = sum_t A_t n_t . phi_i            (net volume acceleration per unit q'')
//   dipole    D_i = sum_t A_t (n_t . phi_i) (x_t - c) (its first moment)
//   p(t) ~= rho_air / (4 pi d) * [Q_i + i k_i rhat . D_i] q_i''(t - d / c_air),  k_i = omega_i / c_air.
// The listener's direction rhat changes as bodies tumble, so the dipole is taken at its rms over
// directions, |rhat . D|^2 -> |D|^2 / 3. The compact expansion overestimates once k L ~ 1, so the
// weight is capped by the in-phase bound sum_t A_t |n_t . phi_i| (every patch a monopole in phase):
//   R_i = min( sqrt(Q_i^2 + k_i^2 |D_i|^2 / 3),  sum_t A_t |n_t . phi_i| )   (m^2 / sqrt(kg)),
// and the weight is rho_air R_i / (4 pi d) Pa per unit modal acceleration, so the output is sound
// pressure in pascals at the listener. Checks: a breathing sphere gives Q = surface area times
// the wall acceleration; a translating compact body gives D = V u (the fluid's added-mass
// reaction, which raises a sphere's dipole by 1.5, is left out).
//
// What it leaves out:
//  - higher multipoles (a quadrupole mode of a compact body is underestimated below k L ~ 1),
//    exact radiation efficiency near and above coincidence (Fahy & Gardonio 2007, ch. 3),
//  - the phase between the monopole and dipole parts (the magnitude is used), directivity, near
//    field (d ~ body size), diffraction by the body, ground reflection, the room, air absorption.
// A precomputed acoustic transfer (James, Barbic & Pai 2006) would replace R_i without changing
// the synthesizer.
#include <cmath>

#include "strike/synth.hpp"

namespace strike {
namespace {
constexpr double kAirDensity_kg_m3 = 1.204;     // dry air at 20 C, 101.325 kPa
constexpr double kSpeedOfSoundAir_m_s = 343.0;  // dry air at 20 C
}  // namespace

std::vector<double> radiationWeights(const ModeBank& bank, double distance_m) {
  const size_t nv = bank.surfaceVertexCount();
  const size_t modes = bank.modeCount();
  std::vector<double> weights(modes, 0.0);
  if (!(distance_m > 0.0) || !std::isfinite(distance_m) || bank.shapes.size() < modes * nv * 3) return weights;
  std::vector<double> monopole(modes, 0.0), in_phase(modes, 0.0), dipole(modes * 3, 0.0);
  const double* pos = bank.surface_positions.data();
  for (size_t t = 0; t + 2 < bank.surface_triangles.size(); t += 3) {
    const uint32_t* tri = &bank.surface_triangles[t];
    if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) continue;
    const double* a = pos + 3 * tri[0];
    const double* b = pos + 3 * tri[1];
    const double* c = pos + 3 * tri[2];
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    // Area-weighted normal (|cross| = 2 area), so area_t * n_t = cross / 2.
    const double an[3] = {0.5 * (e1[1] * e2[2] - e1[2] * e2[1]), 0.5 * (e1[2] * e2[0] - e1[0] * e2[2]),
                          0.5 * (e1[0] * e2[1] - e1[1] * e2[0])};
    double arm[3];
    for (int k = 0; k < 3; ++k) arm[k] = (a[k] + b[k] + c[k]) / 3.0 - bank.centre_m[k];
    for (size_t m = 0; m < modes; ++m) {
      const float* p0 = bank.shapeAt(m, tri[0]);
      const float* p1 = bank.shapeAt(m, tri[1]);
      const float* p2 = bank.shapeAt(m, tri[2]);
      double normal_disp = 0.0;
      for (int k = 0; k < 3; ++k) normal_disp += an[k] * (static_cast<double>(p0[k]) + p1[k] + p2[k]) / 3.0;
      monopole[m] += normal_disp;
      in_phase[m] += std::fabs(normal_disp);
      for (int k = 0; k < 3; ++k) dipole[m * 3 + k] += normal_disp * arm[k];
    }
  }
  const double gain = kAirDensity_kg_m3 / (4.0 * M_PI * distance_m);
  for (size_t m = 0; m < modes; ++m) {
    const double lambda = bank.eigenvalues[m];
    const double k = lambda > 0 && std::isfinite(lambda) ? std::sqrt(lambda) / kSpeedOfSoundAir_m_s : 0.0;
    const double d2 = dipole[m * 3] * dipole[m * 3] + dipole[m * 3 + 1] * dipole[m * 3 + 1] +
                      dipole[m * 3 + 2] * dipole[m * 3 + 2];
    const double compact = std::sqrt(monopole[m] * monopole[m] + k * k * d2 / 3.0);
    weights[m] = gain * std::min(compact, in_phase[m]);
  }
  return weights;
}

}  // namespace strike
