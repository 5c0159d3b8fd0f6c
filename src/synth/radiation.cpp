// SPDX-License-Identifier: MIT
// Listener model: how loud each mode is at the listener, per unit modal acceleration.
//
// Model (compact monopole sources, upper bound). A patch of surface of area A with outward normal n
// whose wall accelerates at a(t) radiates, in free field at distance d >> size, the pressure of a
// point source of volume acceleration A n.a(t):  p(t) = rho_air / (4 pi d) * A n.a(t - d/c_air)
// (Kinsler et al., Fundamentals of Acoustics, 4th ed., 2000, sec. 7.4; the Rayleigh integral for a
// compact baffled piston). Mode i moves the surface as phi_i q_i(t), so its patch accelerations
// are n.phi_i q_i''. Summing the patches' magnitudes instead of their signed values,
//
//   R_i = sum over surface triangles of  area_t * |n_t . phi_i(centroid_t)|   (m^2 / sqrt(kg)),
//   p(t) ~= rho_air / (4 pi d) * sum_i R_i q_i''(t - d / c_air),
//
// treats every patch as an in-phase monopole. This is an upper bound on the far-field amplitude
// that keeps the mode-to-mode balance physically ordered (modes moving more surface farther are
// louder; a mode that only shears the surface is silent), which is what impact sounds depend on
// most [van den Doel & Pai 1998 use the same per-mode gain idea with measured gains; O'Brien et
// al. 2002 a similar surface-velocity sum]. The weight is rho_air R_i / (4 pi d) in Pa per unit
// modal acceleration, so the synthesizer's output is sound pressure in pascals at the listener.
//
// What it leaves out:
//  - cancellation between patches moving in opposite directions (dipole and higher multipoles):
//    bending modes of compact bodies radiate much less than this, by roughly (k L)^2 in power
//    below coincidence; i.e. no radiation efficiency (Fahy & Gardonio 2007, ch. 3),
//  - directivity (the listener's direction does not matter here), near field (d ~ body size),
//    diffraction by the body itself, ground reflection and the room (reverberation),
//  - air absorption and the frequency dependence of the medium.
// A precomputed acoustic transfer (James, Barbic & Pai 2006) would replace R_i without changing
// the synthesizer.
#include <cmath>

#include "strike/synth.hpp"

namespace strike {
namespace {
constexpr double kAirDensity_kg_m3 = 1.204;  // dry air at 20 C, 101.325 kPa
}  // namespace

std::vector<double> radiationWeights(const ModeBank& bank, double distance_m) {
  const size_t nv = bank.surfaceVertexCount();
  std::vector<double> weights(bank.modeCount(), 0.0);
  if (!(distance_m > 0.0) || !std::isfinite(distance_m) || bank.shapes.size() < bank.modeCount() * nv * 3)
    return weights;
  const double gain = kAirDensity_kg_m3 / (4.0 * M_PI * distance_m);
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
    for (size_t m = 0; m < bank.modeCount(); ++m) {
      const float* p0 = bank.shapeAt(m, tri[0]);
      const float* p1 = bank.shapeAt(m, tri[1]);
      const float* p2 = bank.shapeAt(m, tri[2]);
      double normal_disp = 0.0;
      for (int k = 0; k < 3; ++k) normal_disp += an[k] * (static_cast<double>(p0[k]) + p1[k] + p2[k]) / 3.0;
      weights[m] += std::fabs(normal_disp);
    }
  }
  for (double& w : weights) w *= gain;
  return weights;
}

}  // namespace strike
