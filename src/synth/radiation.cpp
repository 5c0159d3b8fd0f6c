// SPDX-License-Identifier: MIT
// Listener model: how loud each mode is at the listener, per unit modal acceleration.
//
// Banks of format 5 and later carry an acoustic transfer (acoustic_transfer.hpp, solved with the body as an
// obstacle); their weights are its rms over directions, and the engine applies the direction
// per impact (sound_paths.cpp). What follows is the model of older banks, and of radiation_m2.
//
// Model of banks without a transfer: the radiation strength R_i of each mode
// (src/bank/radiation_strength.cpp, where the model and what it leaves out are written).
// The precomputed acoustic transfer (James, Barbic & Pai 2006; solved in src/transfer) replaces
// R_i for the modes it holds (pressureWeights below) without changing the synthesizer.
#include <algorithm>
#include <cmath>

#include "strike/core/air.hpp"
#include "strike/synth/synth.hpp"

namespace strike {

std::vector<double> radiationWeights(const ModeBank& bank, double distance_m) {
  const size_t modes = bank.modeCount();
  if (!(distance_m > 0.0) || !std::isfinite(distance_m)) return std::vector<double>(modes, 0.0);
  // A mode with an acoustic transfer: its direction average, which the engine turns toward the
  // listener per impact (sound_paths.cpp). The others (every mode of a bank without one, the
  // modes above the heard ones in format 6): the listener model's strength.
  const size_t with_transfer = std::min(bank.transfer.modeCount(), modes);
  std::vector<double> weights;
  if (with_transfer < modes)
    weights = bank.radiation_m2.size() == modes ? bank.radiation_m2 : radiationStrengths(bank);
  else
    weights.assign(modes, 0.0);
  const double gain = kAirDensity_kg_m3 / (4.0 * M_PI * distance_m);
  for (size_t i = 0; i < modes; ++i)
    weights[i] = i < with_transfer ? bank.transfer.rmsFarField(i) / distance_m : weights[i] * gain;
  return weights;
}

std::vector<double> pressureWeights(const ModeBank& bank, double reference_distance_m, double output_per_pa) {
  std::vector<double> weights = radiationWeights(bank, reference_distance_m);
  for (double& w : weights) w *= output_per_pa;
  return weights;
}

std::vector<double> radiationEfficiency(const ModeBank& bank) {
  const size_t modes = bank.modeCount();
  const size_t nv = bank.surfaceVertexCount();
  std::vector<double> efficiency(modes, 0.0);
  if (bank.shapes.size() < modes * nv * 3) return efficiency;
  const double rho_c = kAirDensity_kg_m3 * kSpeedOfSoundAir_m_s;
  for (size_t m = 0; m < std::min(bank.transfer.modeCount(), modes); ++m) {
    const double omega = std::sqrt(std::max(bank.eigenvalues[m], 0.0));
    // int |a_n|^2 dS over the surface, a_n the normal component of the shape (triangle midpoint rule
    // on the vertex average).
    double surface_a2 = 0.0;
    for (size_t t = 0; t + 2 < bank.surface_triangles.size(); t += 3) {
      const uint32_t* tri = &bank.surface_triangles[t];
      if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) continue;
      const double* a = &bank.surface_positions[3 * tri[0]];
      const double* b = &bank.surface_positions[3 * tri[1]];
      const double* c = &bank.surface_positions[3 * tri[2]];
      const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double an[3] = {0.5 * (e1[1] * e2[2] - e1[2] * e2[1]), 0.5 * (e1[2] * e2[0] - e1[0] * e2[2]),
                            0.5 * (e1[0] * e2[1] - e1[1] * e2[0])};
      const double area = std::sqrt(an[0] * an[0] + an[1] * an[1] + an[2] * an[2]);
      if (!(area > 0.0)) continue;
      double normal_a = 0.0;
      for (int v = 0; v < 3; ++v) {
        const float* phi = bank.shapeAt(m, tri[v]);
        normal_a += (phi[0] * an[0] + phi[1] * an[1] + phi[2] * an[2]) / (3.0 * area);
      }
      surface_a2 += normal_a * normal_a * area;
    }
    // Power per unit modal acceleration amplitude, 4 pi rms^2 / (2 rho c), over rho c int |v_n|^2 dS / 2
    // with v_n = a_n / omega.
    const double rms = bank.transfer.rmsFarField(m);
    const double denominator = rho_c * rho_c * surface_a2;
    if (omega > 0.0 && denominator > 0.0) efficiency[m] = 4.0 * M_PI * rms * rms * omega * omega / denominator;
  }
  return efficiency;
}

}  // namespace strike
