// SPDX-License-Identifier: MIT
// What one impact sends to the listener: the paths (direct, and the ground's image), the
// direction each leaves the body in, the per-mode far field along it, and the click of the
// body's rigid acceleration. The engine's contact scheduler calls scheduleImpact and
// scheduleForceStep; everything here runs on the audio thread without allocating.
//
// Directivity. A bank with an acoustic transfer (acoustic_transfer.hpp) knows each mode's far
// field F_i(d) in the body frame. The voice's weights are the direction average rms_d |F_i| / r
// (radiationWeights), so an impact's factor for mode i is conj(F_i(d)) / rms_d |F_i| along the
// direction d toward the listener at the moment of the impact (bodies tumble): its level and phase
// that way. The conjugate turns the acoustic e^{-i omega t} convention into the oscillators'
// e^{+i omega t}. Older banks have no direction: factor 1.
//
// Ground. The listener's mirror image in the ground plane hears the same body along its own
// direction, delayed by its longer path and weighted by the reflection coefficient and the
// ratio of the distances: the image source of a flat reflector [Allen & Berkley 1979]. Only
// when both the body and the listener are above the ground.
//
// Acceleration noise [Chadwick, Zheng & James 2012, "Precomputed acceleration noise for improved
// rigid-body sound"]. During a Hertz contact of ~0.1 ms a small hard body accelerates by
// thousands of g, and the air it pushes radiates a click even when every vibration mode is
// ultrasonic. For rigid translation with acceleration a(t) the far field of a compact body is a
// dipole, p = rho / (4 pi c r) d . M da/dt, where M = volume + added mass / rho (m^3; a sphere of
// radius a: M = 2 pi a^3). The exact rigid sphere adds a second-order low-pass: its transfer
// is the compact one times 2 / (2 - 2 i ka - (ka)^2) [from h_1(kr) / h_1'(ka); Morse & Ingard
// 1968, sec. 7.2], a Butterworth filter at omega0 = sqrt(2) c / a. Each principal axis j of M is
// one such filter (the sphere of that axis's M, a_j = (M_j / 2 pi)^(1/3)), run as an oscillator
// whose input is the axis's acceleration and whose output lambda q' is d/dt of the low-passed
// acceleration: exact for a sphere, an equivalent-sphere estimate for other shapes. Rotation is
// left out: a compact body's rotation has no dipole, and its quadrupole is a factor ka weaker.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "strike/synth/engine.hpp"
#include "voice_state.hpp"

namespace strike {

int SoundEngine::arrivals(const VoiceState& v, const std::array<double, 3>& world_point, Arrival out[2]) const {
  const bool directional = !v.far_field_[0].empty();
  // The transfer's phases are about its centre: its sound leaves from there. Otherwise from the
  // contact, toward the centre of mass's direction.
  const std::array<double, 3> centre_of_mass = v.pose_.toWorld(v.centre_m_);
  const std::array<double, 3> origin = directional ? v.pose_.toWorld(v.bank_->transfer.centre_m) : centre_of_mass;
  const std::array<double, 3> from = directional ? origin : world_point;
  auto direction = [&](const std::array<double, 3>& to) {
    return v.pose_.toLocalDirection({to[0] - origin[0], to[1] - origin[1], to[2] - origin[2]});
  };
  const std::array<double, 3>& listener = listener_.position_m;
  // A moving body's pulses leave when they happen: its delay lines add each path's delay as it
  // changes (moving_source.cpp).
  out[0].distance_m = distance(from, listener);
  out[0].delay_s = v.moving_ ? 0.0 : propagationDelay_s(out[0].distance_m);
  out[0].gain = 1.0;
  out[0].direction = direction(listener);
  const GroundReflection& g = settings_.ground;
  if (!g.enabled || !v.pressure_) return 1;  // a voice whose output is not pressure has no image
  const std::array<double, 3>& n = g.normal;
  const double listener_height = n[0] * listener[0] + n[1] * listener[1] + n[2] * listener[2] - g.height_m;
  const double body_height =
      n[0] * centre_of_mass[0] + n[1] * centre_of_mass[1] + n[2] * centre_of_mass[2] - g.height_m;
  if (!(listener_height > 0.0) || !(body_height > 0.0)) return 1;
  const std::array<double, 3> image = {listener[0] - 2.0 * listener_height * n[0],
                                       listener[1] - 2.0 * listener_height * n[1],
                                       listener[2] - 2.0 * listener_height * n[2]};
  const double min_d = settings_.min_distance_m;
  out[1].distance_m = distance(from, image);
  out[1].delay_s = v.moving_ ? 0.0 : propagationDelay_s(out[1].distance_m);
  // At rest the image's level is the direct sound's times the ratio of the distances; moving,
  // each path's delay line has its own distance gain.
  out[1].gain = v.moving_ ? g.reflection
                          : g.reflection * std::max(distance(centre_of_mass, listener), min_d) /
                                std::max(distance(centre_of_mass, image), min_d);
  out[1].direction = direction(image);
  return 2;
}

namespace {

// sin of the angle between two directions (any lengths): |a x b| / (|a| |b|), or 1 when they
// point apart (a negative dot product) or either is zero.
double sinAngleBetween(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double cross[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  const double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const double lengths =
      std::sqrt((a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) * (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]));
  if (!(dot > 0.0) || !(lengths > 0.0)) return 1.0;
  return std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]) / lengths;
}

}  // namespace

void SoundEngine::radiationToward(VoiceState& v, const Arrival paths[], int count,
                                  const std::complex<double>* factors[2], Reuse reuse, int also_to) {
  const bool directional = !v.far_field_[0].empty();
  int evaluate[2];  // the paths whose factors are evaluated now
  int evaluations = 0;
  for (int k = 0; k < 2; ++k) factors[k] = nullptr;
  const int last = std::min(std::max(count, also_to), 2);
  for (int k = 0; k < last && v.pressure_; ++k) {
    const Arrival& a = paths[k];
    const bool wanted = k < count;
    if (!wanted && (evaluations == 0 || !directional)) break;  // no pass to ride along with
    if (!directional && a.gain == 1.0) continue;
    VoiceState::PathTransfer& p = v.path_transfer_[static_cast<size_t>(k)];
    if (wanted) factors[k] = p.factor.data();
    if (p.valid && std::memcmp(&p.gain, &a.gain, sizeof a.gain) == 0) {
      // The same bits (not ==, which equates -0 and +0): a reuse gives exactly what an evaluation would.
      if (std::memcmp(p.direction.data(), a.direction.data(), sizeof a.direction) == 0) continue;
      // A continuous source may keep factors evaluated at a direction theta away while N theta <=
      // kContinuousTransferTolerance, N the highest order of the body's transfer. Along any great
      // circle F_i is a trigonometric polynomial of degree <= N, so by Bernstein's inequality
      // |F_i(d') - F_i(d)| <= N theta max|F_i|: the kept factor is within that fraction of the mode's
      // loudest direction. The per-step evaluation it saves was already a hold of one step.
      if (reuse == Reuse::WithinTolerance && wanted && directional) {
        const double order = std::max(1.0, static_cast<double>(v.sh_table_.order));
        if (order * sinAngleBetween(p.direction, a.direction) <= kContinuousTransferTolerance) continue;
      }
    }
    p.direction = a.direction;
    p.gain = a.gain;
    p.valid = true;
    if (!directional) {
      std::fill(p.factor.begin(), p.factor.end(), std::complex<double>(a.gain, 0.0));
      continue;
    }
    realSphericalHarmonics(v.sh_table_, a.direction.data(), v.sh_.data());
    farFieldWeights(v.sh_.data(), v.sh_.size(), v.weights_[static_cast<size_t>(evaluations)].data());
    evaluate[evaluations++] = k;
  }
  if (evaluations == 0) return;
  const float* weights[2] = {v.weights_[0].data(), v.weights_[1].data()};
  std::complex<double>* far_field[2] = {v.far_field_[0].data(), v.far_field_[1].data()};
  evaluateFarFields(v.transfer_, static_cast<size_t>(evaluations), weights, far_field);
  for (int e = 0; e < evaluations; ++e) {
    VoiceState::PathTransfer& p = v.path_transfer_[static_cast<size_t>(evaluate[e])];
    const std::complex<double>* f = far_field[e];
    // The modes with a transfer, then the others as a voice without one hears them (its gain).
    const size_t heard = v.inv_rms_.size();
    for (size_t i = 0; i < heard; ++i) p.factor[i] = std::conj(f[i]) * (v.inv_rms_[i] * p.gain);
    for (size_t i = heard; i < p.factor.size(); ++i) p.factor[i] = std::complex<double>(p.gain, 0.0);
  }
}

void SoundEngine::scheduleImpact(VoiceState& v, const double* modal, double time_s, double duration_s, PulseShape shape,
                                 const std::array<double, 3>& world_point, const std::array<double, 3>& impulse_local) {
  Arrival paths[2];
  const int count = arrivals(v, world_point, paths);
  const std::complex<double>* transfer[2];
  radiationToward(v, paths, count, transfer);
  for (int k = 0; k < count; ++k) transfer[k] = throughAir(v, k, transfer[k], paths[k].distance_m);
  for (int k = 0; k < count; ++k) {
    ImpactDesc impact;
    impact.time_s = time_s + paths[k].delay_s;
    impact.duration_s = duration_s;
    impact.shape = shape;
    impact.modal_impulse = modal;
    impact.modal_transfer = transfer[k];
    OscillatorBank& synth = pathSynth(v, k);
    const ImpactResult r = synth.addImpact(impact);
    // synth_ carries both paths (voice_state.hpp).
    if (k > 0 && imageApart(v)) (void)v.synth_.addImpact(impact);
    if (k == 0) {  // one impact, however many paths it takes
      switch (r) {
        case ImpactResult::Scheduled: ++stats_.impacts; break;
        case ImpactResult::Inaudible: ++stats_.impacts_inaudible; break;
        case ImpactResult::NoCapacity: ++stats_.impacts_dropped; break;
      }
    }
    if (v.clicks_ && shape == PulseShape::HalfSine) scheduleClick(v, k, paths[k], time_s, duration_s, impulse_local);
  }
}

void SoundEngine::scheduleForceStep(VoiceState& v, const double* modal_change, double time_s, double ramp_s,
                                    const std::array<double, 3>& world_point) {
  Arrival paths[2];
  const int count = arrivals(v, world_point, paths);
  const std::complex<double>* transfer[2];
  radiationToward(v, paths, count, transfer);
  for (int k = 0; k < count; ++k) transfer[k] = throughAir(v, k, transfer[k], paths[k].distance_m);
  for (int k = 0; k < count; ++k) {
    ForceStepDesc step;
    step.time_s = time_s + paths[k].delay_s;
    step.ramp_s = ramp_s;
    step.modal_force_change = modal_change;
    step.modal_transfer = transfer[k];
    OscillatorBank& synth = pathSynth(v, k);
    const ImpactResult r = synth.addForceStep(step);
    if (k > 0 && imageApart(v)) (void)v.synth_.addForceStep(step);
    if (k > 0) continue;
    if (r == ImpactResult::NoCapacity)
      ++stats_.impacts_dropped;
    else
      ++stats_.load_changes;
  }
}

// Per axis j: input a_j(t) = (e_j . J / m) f(t) (the pulse's acceleration), output
// K_j lambda_j q_j' with K_j = rho M_j (d . e_j) / (4 pi c). The oscillators' output is
// Re(factor b g y) with b = -i p^2 R / omega_d and q' = g Im(p y) / omega_d, so
// factor = K_j lambda_j / p_j gives it (R = the voice's pressure scale / reference distance).
void SoundEngine::scheduleClick(VoiceState& v, int path, const Arrival& a, double time_s, double duration_s,
                                const std::array<double, 3>& impulse_local) {
  const double inv_mass = 1.0 / v.mass_kg_;
  const double k_air = kAirDensity_kg_m3 / (4.0 * M_PI * kSpeedOfSoundAir_m_s);
  for (int j = 0; j < 3; ++j) {
    const std::array<double, 3>& e = v.click_axis_[j];
    v.click_force_[j] = (e[0] * impulse_local[0] + e[1] * impulse_local[1] + e[2] * impulse_local[2]) * inv_mass;
    const double toward = e[0] * a.direction[0] + e[1] * a.direction[1] + e[2] * a.direction[2];
    v.click_transfer_[j] = v.click_gain_[j] * (k_air * v.click_moment_m3_[j] * toward * a.gain);
  }
  ImpactDesc click;
  click.time_s = time_s + a.delay_s;
  click.duration_s = duration_s;
  click.shape = PulseShape::HalfSine;
  click.modal_impulse = v.click_force_.data();
  click.modal_transfer = v.click_transfer_.data();
  OscillatorBank& clicks = pathClicks(v, path);
  (void)clicks.addImpact(click);
  if (path > 0 && imageApart(v)) (void)v.click_synth_.addImpact(click);
}

const std::complex<double>* SoundEngine::throughAir(VoiceState& v, int path, const std::complex<double>* factors,
                                                    double distance_m) {
  if (v.air_np_per_m_.empty()) return factors;
  std::vector<std::complex<double>>& out = v.air_factor_[static_cast<size_t>(path)];
  for (size_t i = 0; i < out.size(); ++i) {
    const double gain = std::exp(-v.air_np_per_m_[i] * distance_m);
    out[i] = factors ? factors[i] * gain : std::complex<double>(gain, 0.0);
  }
  return out.data();
}

void SoundEngine::setExtraDamping(VoiceState& v, double time_s, const std::array<double, 3>& world_point,
                                  double per_s) {
  const double at_s = time_s + (v.moving_ ? 0.0 : delayTo(world_point));
  (void)v.synth_.setExtraDamping(at_s, per_s);
  if (!v.image_) return;  // the image rings in synth_ too
  // The image's modes change with the direct sound's, as they do when both ring in synth_: the
  // omni channel of an output with directions is then the mono render.
  (void)v.image_->synth.setExtraDamping(at_s, per_s);
}

}  // namespace strike
