// SPDX-License-Identifier: MIT
// The contact scheduler: what a physics engine's contacts sound like. Each contact is resolved
// once and played by the first contact model that takes it (contact_model.hpp; the built-in
// ones in contact_models.cpp). Per body and step:
//  - an impact (approach faster than the impact rule) is a Hertz half-sine pulse of the
//    contact time of the two bodies [Johnson 1985, Contact Mechanics, eq. 11.24];
//  - sustained contact is a force: the step's impulses over the step. Its modal force is held
//    until the body's load changes (its net force and moment, by kSteadyLoadTolerance), and
//    each change is a force step ramped over one physics step, so a steady load is silent
//    whatever the physics engine does with its contact points, and the step forces are linearly
//    interpolated rather than a staircase that rings at the step rate;
//  - a body with no sustained contact in a step lets go of its load (a ramp to zero), unless it
//    is asleep (the physics engine stopped reporting it, but it still rests) or it is static and
//    every body it carried is asleep;
//  - contact damping (extra modal decay) is on from a body's first sustained contact until
//    kContactGap_s after its last, and stays on while it sleeps on its support.
// Every pulse and step is heard propagationDelay_s(distance) after it happens, along each path
// to the listener, as sound_paths.cpp describes.
#include <algorithm>
#include <cmath>

#include "strike/synth/contact_model.hpp"
#include "strike/synth/engine.hpp"
#include "voice_state.hpp"

namespace strike {
namespace {

double norm6(const std::array<double, 6>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s);
}

}  // namespace

double ballMass(double density_kg_m3, double radius_m) {
  return density_kg_m3 * 4.0 / 3.0 * M_PI * std::pow(radius_m, 3);
}

ContactPartner defaultStriker() {
  ContactPartner striker;
  striker.youngs_pa = kDefaultStrikerYoungs_pa;
  striker.poisson = kDefaultStrikerPoisson;
  striker.radius_m = kDefaultStrikerRadius_m;
  striker.mass_kg = ballMass(kDefaultStrikerDensity_kg_m3, kDefaultStrikerRadius_m);
  return striker;
}

double tapSpeed(double j_normal_n_s, double striker_kg, double object_kg) {
  const double reduced_mass = striker_kg > 0.0 ? striker_kg * object_kg / (striker_kg + object_kg) : object_kg;
  return reduced_mass > 0.0 ? j_normal_n_s / (2.0 * reduced_mass) : 0.0;
}

double trackSpeed(const EngineContact& c) {
  const std::array<double, 3>& r = c.rolling_velocity_m_s;
  return std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
}

double partnerTrackSpeed(const EngineContact& c) {
  const std::array<double, 3>& r = c.rolling_velocity_m_s;
  const std::array<double, 3>& s = c.slip_velocity_m_s;
  const double x = r[0] + s[0], y = r[1] + s[1], z = r[2] + s[2];
  return std::sqrt(x * x + y * y + z * z);
}

double SoundEngine::contactDuration(uint32_t slot, const ContactPartner& partner, double normal_speed_m_s) const {
  const VoiceState* v = state(slot);
  return v ? hertzDuration(*v, partner, normal_speed_m_s) : 0.0;
}

double SoundEngine::hertzDuration(const VoiceState& v, const ContactPartner& p, double speed) const {
  // A partner that is a voice and gives no material of its own: its bank's material, its contact
  // radius and mass (what libstrike's contact call does for two objects).
  if (p.youngs_pa <= 0.0 && p.voice != kNoVoice) {
    if (const VoiceState* q = state(p.voice)) {
      const double tau = hertzContactDuration(v.youngs_pa_, v.poisson_, v.contact_radius_m_, v.mass_kg_, q->youngs_pa_,
                                              q->poisson_, q->contact_radius_m_, q->mass_kg_, speed);
      return std::min(tau, settings_.max_contact_duration_s);
    }
  }
  const double youngs2 = p.youngs_pa > 0.0 ? p.youngs_pa : v.youngs_pa_;
  const double poisson2 = p.youngs_pa > 0.0 ? p.poisson : v.poisson_;
  const double radius2 = p.radius_m > 0.0 ? p.radius_m : INFINITY;
  const double mass2 = p.mass_kg > 0.0 ? p.mass_kg : INFINITY;
  const double tau = hertzContactDuration(v.youngs_pa_, v.poisson_, v.contact_radius_m_, v.mass_kg_, youngs2, poisson2,
                                          radius2, mass2, speed);
  return std::min(tau, settings_.max_contact_duration_s);
}

void SoundEngine::beginStep(double step_end_s, double step_s) {
  if (step_.open) endStep();
  step_.open = true;
  step_.end_s = step_end_s >= 0.0 && std::isfinite(step_end_s) ? step_end_s : time();
  step_.length_s = step_s > 0.0 && std::isfinite(step_s) ? step_s : 0.0;
}

void SoundEngine::contact(const EngineContact& c) {
  const bool own_step = !step_.open;
  if (own_step) beginStep(c.time_s, 0.0);
  VoiceState* v = state(c.voice);
  if (!v) {
    ++stats_.stale;
    if (own_step) endStep();
    return;
  }
  ResolvedContact rc;
  rc.reported = &c;
  rc.point = c.world_frame ? v->pose_.toLocalPoint(c.point) : c.point;
  rc.impulse = c.world_frame ? v->pose_.toLocalDirection(c.impulse) : c.impulse;
  rc.world_point = c.world_frame ? c.point : v->pose_.toWorld(c.point);
  rc.time_s = c.time_s >= 0.0 ? c.time_s : time();
  rc.impact = settings_.isImpact(c.normal_speed_m_s);
  VoiceInput input(*this, *v);
  for (const std::unique_ptr<ContactModel>& model : models_) {
    if (!model->takes(rc)) continue;
    model->play(rc, input);
    break;
  }
  if (own_step) endStep();
}

void SoundEngine::sustainedContact(VoiceState& v, const ResolvedContact& rc, const double* modal) {
  const EngineContact& c = *rc.reported;
  const std::array<double, 3>& point = rc.point;
  const std::array<double, 3>& impulse = rc.impulse;
  // A force over the step (its impulse / step length), summed over the step's points.
  ++stats_.sustained_contacts;
  const double per_s = step_.length_s > 0.0 ? 1.0 / step_.length_s : 1.0;
  for (size_t i = 0; i < v.step_force_.size(); ++i) v.step_force_[i] += modal[i] * per_s;
  const std::array<double, 3> arm = {point[0] - v.centre_m_[0], point[1] - v.centre_m_[1], point[2] - v.centre_m_[2]};
  const std::array<double, 3> moment = {arm[1] * impulse[2] - arm[2] * impulse[1],
                                        arm[2] * impulse[0] - arm[0] * impulse[2],
                                        arm[0] * impulse[1] - arm[1] * impulse[0]};
  for (int k = 0; k < 3; ++k) {
    v.step_load_[k] += impulse[k] * per_s;
    v.step_load_[3 + k] += moment[k] * per_s / v.size_m_;
  }
  if (!v.in_step_) v.partner_count_ = 0, v.partners_overflow_ = false;  // this step's partners from here
  v.in_step_ = true;
  if (c.partner.voice != kNoVoice) {
    bool known = false;
    for (uint32_t k = 0; k < v.partner_count_; ++k) known = known || v.partners_[k] == c.partner.voice;
    if (!known && v.partner_count_ < v.partners_.size())
      v.partners_[v.partner_count_++] = c.partner.voice;
    else if (!known)
      v.partners_overflow_ = true;
  } else {
    v.partners_overflow_ = true;  // the ground or an unnamed body: it never sleeps
  }
  if (settings_.contact_damping_per_s > 0.0 && !v.span_open_) {
    setExtraDamping(v, rc.time_s, rc.world_point, settings_.contact_damping_per_s);
    v.span_open_ = true;
  }
  v.last_sustained_s_ = rc.time_s;
  continuousContact(v, c, rc.world_point);  // rolling, sliding, scraping (contact_sources.cpp)
}

void SoundEngine::endStep() {
  if (!step_.open) return;
  for (uint32_t slot = 0; slot < slots_.size(); ++slot)
    if (slots_[slot]) endStepFor(*slots_[slot]->state_);
  step_.open = false;
}

void SoundEngine::endStepFor(VoiceState& v) {
  // A step's force acts over the step: centred on the step, its change ramps over one step.
  const double step_start_s = step_.end_s - step_.length_s;
  const double change_at_s = step_start_s - 0.5 * step_.length_s;
  const std::array<double, 3> centre = v.pose_.toWorld(v.centre_m_);
  // Whether the step ends in a load change: the body was pressed this step and its load moved
  // (steady: no), or a held load is let go (keep: no).
  bool steady = false, keep = false;
  if (v.in_step_) {
    std::array<double, 6> change{};
    for (int k = 0; k < 6; ++k) change[k] = v.step_load_[k] - v.held_load_[k];
    steady = v.holding_ && norm6(change) <= kSteadyLoadTolerance * norm6(v.held_load_);
  } else if (v.holding_) {
    if (v.asleep_) {
      keep = true;
    } else if (v.is_static_ && v.partner_count_ > 0 && !v.partners_overflow_) {
      keep = true;
      for (uint32_t k = 0; k < v.partner_count_; ++k) {
        const VoiceState* p = state(v.partners_[k]);
        keep = keep && p && p->asleep_;
      }
    }
  }
  const bool load_change = v.in_step_ ? !steady : v.holding_ && !keep;
  continuousEndStep(v, load_change);  // contact_sources.cpp
  if (v.in_step_) {
    if (!steady) {
      for (size_t i = 0; i < v.modal_.size(); ++i) v.modal_[i] = v.step_force_[i] - v.held_force_[i];
      scheduleForceStep(v, v.modal_.data(), change_at_s, step_.length_s, centre);
      v.held_force_ = v.step_force_;  // same size: no allocation
      v.held_load_ = v.step_load_;
      v.holding_ = true;
    }
    std::fill(v.step_force_.begin(), v.step_force_.end(), 0.0);
    v.step_load_ = {};
    v.in_step_ = false;
    return;
  }
  if (v.holding_) {
    if (keep) {
      ++stats_.load_holds;
    } else {
      for (size_t i = 0; i < v.modal_.size(); ++i) v.modal_[i] = -v.held_force_[i];
      scheduleForceStep(v, v.modal_.data(), change_at_s, step_.length_s, centre);
      std::fill(v.held_force_.begin(), v.held_force_.end(), 0.0);
      v.held_load_ = {};
      v.holding_ = false;
    }
  }
  if (v.span_open_ && !keep && step_start_s - v.last_sustained_s_ > kContactGap_s) {
    setExtraDamping(v, v.last_sustained_s_ + kContactGap_s, centre, 0.0);
    v.span_open_ = false;
  }
}

void SoundEngine::impact(const EngineImpact& d) {
  VoiceState* v = state(d.voice);
  if (!v) {
    ++stats_.stale;
    return;
  }
  const std::array<double, 3> point = d.world_frame ? v->pose_.toLocalPoint(d.point) : d.point;
  const std::array<double, 3> impulse = d.world_frame ? v->pose_.toLocalDirection(d.impulse) : d.impulse;
  const ModeBank& bank = *v->bank_;
  std::array<double, 3> world = d.world_frame ? d.point : v->pose_.toWorld(d.point);
  if (d.surface_vertex >= 0 && static_cast<size_t>(d.surface_vertex) < bank.surfaceVertexCount()) {
    const size_t vertex = static_cast<size_t>(d.surface_vertex);
    projectImpulseAtVertexInto(bank, vertex, impulse.data(), v->modal_.data());
    world = v->pose_.toWorld({bank.surface_positions[3 * vertex], bank.surface_positions[3 * vertex + 1],
                              bank.surface_positions[3 * vertex + 2]});
  } else {
    v->projector_.projectOnce(point.data(), impulse.data(), v->modal_.data());
  }
  double speed = d.normal_speed_m_s;
  if (d.contact_duration_s < 0.0 && !(speed > 0.0)) {
    // The striker's speed from the impulse (tapSpeed), along the normal of the vertex nearest
    // the point (the largest of its triangle's weights), as `strike hit` reckons it.
    size_t vertex = static_cast<size_t>(std::max(d.surface_vertex, 0));
    if (d.surface_vertex < 0 || vertex >= bank.surfaceVertexCount()) {
      uint32_t corners[3] = {0, 0, 0};
      double weights[3] = {1, 0, 0};
      v->projector_.locator().nearest(point.data(), corners, weights);
      vertex = corners[std::max_element(weights, weights + 3) - weights];
    }
    const float* n = &bank.surface_normals[3 * vertex];
    speed =
        tapSpeed(std::fabs(impulse[0] * n[0] + impulse[1] * n[1] + impulse[2] * n[2]), d.partner.mass_kg, v->mass_kg_);
  }
  const double duration = d.contact_duration_s < 0.0 ? hertzDuration(*v, d.partner, speed)
                                                     : std::min(d.contact_duration_s, settings_.max_contact_duration_s);
  scheduleImpact(*v, v->modal_.data(), d.time_s >= 0.0 ? d.time_s : time(), duration, d.shape, world, impulse);
}

void SoundEngine::reset() {
  for (Voice* installed : slots_) {
    VoiceState* v = installed ? installed->state_.get() : nullptr;
    if (!v) continue;
    v->synth_.reset();
    v->click_synth_.reset();
    if (v->image_) v->image_->synth.reset(), v->image_->click_synth.reset();
    v->resetLoad();
    resetContinuous(*v);
    for (BinauralPath& path : v->binaural_) path.clear();
    v->moving_ = false;
    v->key_count_ = 0;
    v->fresh_ = true;
  }
  step_ = Step{};
  frames_ = 0;
}

}  // namespace strike
