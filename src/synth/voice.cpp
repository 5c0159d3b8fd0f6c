// SPDX-License-Identifier: MIT
// A voice: one sounding body's oscillators, projector and contact state, built with all the
// memory it will ever use (libstrike builds it on the main thread and hands it to the audio
// thread). Also the rigid pose that places it.
#include <algorithm>
#include <cmath>

#include "strike/synth/engine.hpp"
#include "voice_state.hpp"

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

/// Eigenvalues and unit eigenvectors (rows) of a symmetric 3x3 matrix, by cyclic Jacobi rotations.
void symmetricEigen3(std::array<double, 9> a, std::array<double, 3>& values,
                     std::array<std::array<double, 3>, 3>& axes) {
  double v[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = a[1] * a[1] + a[2] * a[2] + a[5] * a[5];
    if (!(off > 1e-30 * (a[0] * a[0] + a[4] * a[4] + a[8] * a[8]))) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        const double apq = a[3 * p + q];
        if (apq == 0.0) continue;
        const double theta = (a[3 * q + q] - a[3 * p + p]) / (2.0 * apq);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < 3; ++k) {  // A <- A J (columns p, q)
          const double akp = a[3 * k + p], akq = a[3 * k + q];
          a[3 * k + p] = c * akp - s * akq;
          a[3 * k + q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {  // A <- J^T A (rows p, q)
          const double apk = a[3 * p + k], aqk = a[3 * q + k];
          a[3 * p + k] = c * apk - s * aqk;
          a[3 * q + k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {  // V <- V J
          const double vkp = v[3 * k + p], vkq = v[3 * k + q];
          v[3 * k + p] = c * vkp - s * vkq;
          v[3 * k + q] = s * vkp + c * vkq;
        }
      }
  }
  for (int j = 0; j < 3; ++j) {
    values[j] = a[4 * j];
    axes[j] = {v[j], v[3 + j], v[6 + j]};  // column j of V
  }
}

// The oscillators' settings: the engine's, with its allocation policy (EngineSettings::realtime).
SynthSettings synthSettings(const EngineSettings& settings) {
  SynthSettings synth = settings.synth;
  synth.allocation = settings.realtime ? Allocation::Reserved : Allocation::Grow;
  return synth;
}

// The bank's modes as the oscillators play them, with the voice's output weights.
ModalObjectDesc modalObject(const ModeBank& bank, const std::vector<double>& weights) {
  ModalObjectDesc modal;
  modal.eigenvalues = bank.eigenvalues;
  modal.rayleigh_stiffness = bank.material.rayleigh_stiffness;
  modal.rayleigh_mass = bank.material.rayleigh_mass;
  modal.radiation_weight = weights;
  return modal;
}

}  // namespace

void VoiceState::setUpRadiation(const VoiceDesc& desc, const EngineSettings& settings) {
  const ModeBank& bank = *bank_;
  const size_t modes = bank.modeCount();
  pressure_ = desc.pressure_scale > 0.0 && std::isfinite(desc.pressure_scale);
  if (!pressure_) return;
  for (PathTransfer& p : path_transfer_) p.factor.assign(modes, std::complex<double>(1.0, 0.0));
  if (settings.air_absorption) {
    // Each mode a sinusoid at its undamped frequency; dB to nepers of amplitude: ln 10 / 20.
    air_np_per_m_.assign(modes, 0.0);
    for (size_t i = 0; i < modes; ++i)
      air_np_per_m_[i] = airAttenuationDbPerM(bank.frequencyHz(i), settings.air) * (std::log(10.0) / 20.0);
    for (std::vector<std::complex<double>>& f : air_factor_) f.assign(modes, 1.0);
  }
  // The transfer of the modes this engine plays: a prefix, as the modes are ascending and the
  // band ends at synthesizedTopHz. A mode without one (above what its bank was solved for) is
  // heard at its direction-averaged level (radiationWeights), as every mode of a bank without a
  // transfer is; the transfer of modes above the band (solved for a render at a higher rate) is
  // left out, so that what is heard does not depend on it.
  const AcousticTransfer& full = bank.transfer;
  const double top_hz = synthesizedTopHz(settings.synth.max_freq_hz, settings.synth.sample_rate_hz);
  size_t heard = 0;
  while (heard < full.modeCount() && bank.frequencyHz(heard) <= top_hz) ++heard;
  AcousticTransfer prefix;
  if (heard < full.modeCount()) {
    prefix.order.assign(full.order.begin(), full.order.begin() + heard);
    prefix.offset.assign(full.offset.begin(), full.offset.begin() + heard + 1);
    prefix.coefficients.assign(full.coefficients.begin(), full.coefficients.begin() + full.offset[heard]);
  }
  const AcousticTransfer& t = heard < full.modeCount() ? prefix : full;
  if (heard > 0) {
    const size_t order = t.maxOrder();
    sh_.assign((order + 1) * (order + 1), 0.0);
    sh_table_ = sphericalHarmonicsTable(static_cast<uint32_t>(order));
    transfer_ = compactTransfer(t);
    for (std::vector<float>& w : weights_) w.assign(sh_.size(), 0.0f);
    for (std::vector<std::complex<double>>& f : far_field_) f.assign(heard, 0.0);
    inv_rms_.assign(heard, 0.0);
    for (size_t i = 0; i < heard; ++i) {
      const double rms = t.rmsFarField(i);
      inv_rms_[i] = rms > 0.0 ? 1.0 / rms : 0.0;
    }
  }
  // Acceleration noise: a free body with a mass and a volume.
  if (is_static_ || !std::isfinite(mass_kg_) || !(mass_kg_ > 0.0)) return;
  std::array<double, 9> dipole = t.translation_dipole_m3;
  const bool solved = !t.empty() && (dipole[0] > 0.0 || dipole[4] > 0.0 || dipole[8] > 0.0);
  if (!solved) {  // the sphere of the body's volume: M = 2 pi a^3 = 1.5 V
    if (!(bank.volume_m3 > 0.0) || !std::isfinite(bank.volume_m3)) return;
    dipole = {1.5 * bank.volume_m3, 0, 0, 0, 1.5 * bank.volume_m3, 0, 0, 0, 1.5 * bank.volume_m3};
  }
  symmetricEigen3(dipole, click_moment_m3_, click_axis_);
  const double rate = settings.synth.sample_rate_hz;
  // The filter's cut-off stays in the synthesized band (0.98 of its top): a body smaller than
  // about 4 mm has its click low-passed there instead of at sqrt(2) c / a above the band.
  const double top_rad_s = 0.98 * 2.0 * M_PI * synthesizedTopHz(settings.synth.max_freq_hz, rate);
  ModalObjectDesc click;
  click.radiation_weight.assign(3, desc.pressure_scale / settings.reference_distance_m);
  for (int j = 0; j < 3; ++j) {
    const double moment = click_moment_m3_[j];
    const double radius = moment > 0.0 ? std::cbrt(moment / (2.0 * M_PI)) : 0.0;
    const double omega0 = radius > 0.0 ? std::min(M_SQRT2 * kSpeedOfSoundAir_m_s / radius, top_rad_s) : 0.0;
    click.eigenvalues.push_back(omega0 * omega0);
    click.damping_c.push_back(M_SQRT2 * omega0);  // Butterworth: zeta = 1 / sqrt 2
    const std::complex<double> pole(-omega0 / M_SQRT2, omega0 / M_SQRT2);
    click_gain_[j] = omega0 > 0.0 ? omega0 * omega0 / pole : 0.0;
  }
  click_synth_ = OscillatorBank(synthSettings(settings), click);
  if (image_) image_->click_synth = OscillatorBank(synthSettings(settings), click);
  click_mono_.assign(std::max<uint32_t>(settings.max_block_frames, 1), 0.0f);
  clicks_ = true;
}

VoiceState::VoiceState(const VoiceDesc& desc, const EngineSettings& settings)
    : AccelerationClicks(synthSettings(settings)),
      bank_(desc.bank),
      synth_(synthSettings(settings), modalObject(*desc.bank, desc.weights)),
      projector_(*desc.bank, desc.locator) {
  const ModeBank& bank = *bank_;
  if (desc.use_rows) projector_.useRows(desc.rows);
  // An output with directions hears the ground's image from below: a signal of its own.
  const bool pressure = desc.pressure_scale > 0.0 && std::isfinite(desc.pressure_scale);
  // A moving body's image is heard through a delay line of its own, in mono too.
  if ((outputHasDirections(settings.output) || settings.moving_sources) && settings.ground.enabled && pressure)
    image_ = std::make_unique<ImagePath>(synthSettings(settings), modalObject(bank, desc.weights),
                                         std::max<uint32_t>(settings.max_block_frames, 1));
  if (settings.output == OutputFormat::Binaural && settings.hrtf) {
    binaural_[0].init(settings.hrtf);
    if (image_) binaural_[1].init(settings.hrtf);
  }
  const SynthStats bands = synth_.stats();
  rings_ = bands.modes_total > bands.modes_out_of_band;
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
  synth_.reserveForceInput();
  for (Source& s : sources_) s.modal.assign(modes, 0.0);
  force_.assign(static_cast<size_t>(kForceChannels) * std::max<uint32_t>(settings.max_block_frames, 1), 0.0f);
  setUpRadiation(desc, settings);
  if (settings.moving_sources) setUpMovingSource(settings);
  // Each contact may take two paths (the ground's image) and click on each.
  const size_t paths = settings.ground.enabled ? 2 : 1;
  if (settings.realtime) {
    synth_.reserveImpacts(settings.max_pending_impacts_per_voice * paths, settings.max_contact_duration_s);
    if (clicks_)
      click_synth_.reserveImpacts(settings.max_pending_impacts_per_voice * paths, settings.max_contact_duration_s);
    if (image_) {
      image_->synth.reserveImpacts(settings.max_pending_impacts_per_voice, settings.max_contact_duration_s);
      if (clicks_)
        image_->click_synth.reserveImpacts(settings.max_pending_impacts_per_voice, settings.max_contact_duration_s);
    }
  }
}

Voice::Voice(const VoiceDesc& desc, const EngineSettings& settings)
    : state_(std::make_unique<VoiceState>(desc, settings)) {}
Voice::~Voice() = default;
const ModeBank& Voice::bank() const { return *state_->bank_; }
SynthStats Voice::synthStats() const { return state_->synth_.stats(); }

}  // namespace strike
