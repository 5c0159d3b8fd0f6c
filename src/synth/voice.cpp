// SPDX-License-Identifier: MIT
// A voice: one sounding body's oscillators, projector and contact state, built with all the
// memory it will ever use (libstrike builds it on the main thread and hands it to the audio
// thread). Also the rigid pose that places it.
#include <algorithm>
#include <cmath>

#include "strike/engine.hpp"

namespace strike {

bool Pose::set(const double position[3], const double q[4]) {
  if (!position || !q) return false;
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(position[k])) return false;
  for (int k = 0; k < 4; ++k)
    if (!std::isfinite(q[k])) return false;
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 1e-12)) return false;
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  rotation = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
              2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
              2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  std::copy(position, position + 3, position_m.begin());
  return true;
}

std::array<double, 3> Pose::toWorld(const std::array<double, 3>& p) const {
  const auto& r = rotation;
  return {position_m[0] + r[0] * p[0] + r[1] * p[1] + r[2] * p[2],
          position_m[1] + r[3] * p[0] + r[4] * p[1] + r[5] * p[2],
          position_m[2] + r[6] * p[0] + r[7] * p[1] + r[8] * p[2]};
}

std::array<double, 3> Pose::toLocalDirection(const std::array<double, 3>& v) const {
  const auto& r = rotation;  // R^T v
  return {r[0] * v[0] + r[3] * v[1] + r[6] * v[2], r[1] * v[0] + r[4] * v[1] + r[7] * v[2],
          r[2] * v[0] + r[5] * v[1] + r[8] * v[2]};
}

std::array<double, 3> Pose::toLocalPoint(const std::array<double, 3>& p) const {
  return toLocalDirection({p[0] - position_m[0], p[1] - position_m[1], p[2] - position_m[2]});
}

namespace {

double surfaceExtent(const ModeBank& bank) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < bank.surfaceVertexCount(); ++v)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], bank.surface_positions[3 * v + k]);
      hi[k] = std::max(hi[k], bank.surface_positions[3 * v + k]);
    }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  return std::isfinite(extent) && extent > 0.0 ? extent : 1.0;
}

}  // namespace

Voice::Voice(const VoiceDesc& desc, const EngineSettings& settings)
    : bank_(desc.bank), synth_(settings.synth), projector_(*desc.bank) {
  const ModeBank& bank = *bank_;
  if (desc.use_rows) projector_.useRows(desc.rows);
  ModalObjectDesc modal;
  modal.eigenvalues = bank.eigenvalues;
  modal.rayleigh_stiffness = bank.material.rayleigh_stiffness;
  modal.rayleigh_mass = bank.material.rayleigh_mass;
  modal.radiation_weight = desc.weights;
  synth_.addObject(modal);
  if (settings.realtime) synth_.reserveImpacts(settings.max_pending_impacts_per_voice, settings.max_contact_duration_s);
  const size_t modes = bank.modeCount();
  modal_.assign(modes, 0.0);
  step_force_.assign(modes, 0.0);
  held_force_.assign(modes, 0.0);
  mono_.assign(std::max<uint32_t>(settings.max_block_frames, 1), 0.0f);
  levels_.assign(modes + 1, 0.0f);
  centre_m_ = bank.centre_m;
  size_m_ = surfaceExtent(bank);
  youngs_pa_ = bank.material.youngs_pa;
  poisson_ = bank.material.poisson;
  is_static_ = desc.is_static;
  mass_kg_ = desc.is_static || !(bank.mass_kg > 0.0) ? INFINITY : bank.mass_kg;
  contact_radius_m_ = desc.contact_radius_m > 0.0 ? desc.contact_radius_m : INFINITY;
  pose_ = desc.pose;
  gain_ = desc.gain;
  // Continuous contacts (contact_sources.cpp): a force channel per possible partner.
  roughness_ = desc.roughness;
  restitution_ = desc.restitution;
  synth_.reserveForceInput(0);
  for (Source& s : sources_) s.modal.assign(modes, 0.0);
  force_.assign(static_cast<size_t>(kForceChannels) * std::max<uint32_t>(settings.max_block_frames, 1), 0.0f);
}

Voice::~Voice() = default;

}  // namespace strike
