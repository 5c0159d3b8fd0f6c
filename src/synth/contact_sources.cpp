// SPDX-License-Identifier: MIT
// The contact scheduler's continuous contacts: rolling, sliding and scraping (docs/contact.md,
// "Rolling, sliding and scraping"). A sustained contact whose surfaces move over each other
// feeds, per body and partner, one RoughContact generator (contact_noise.hpp): its force, in
// newtons, is one force channel of the body's oscillator bank, whose modal weights are the step's
// modal impulses over its normal impulse, g_i = sum_p phi_i(p) . J_p / sum_p N_p dt: the normal
// direction plus the friction's share, over the step's contact points weighted by their loads.
// Both bodies of a pair compute the same force from the same inputs (the two surfaces' profiles,
// the reduced mass, the same E*, R*, e), so it acts equal and opposite on them; a generator costs
// O(1) per sample, the modes it drives one complex multiply-add each (OscillatorBank).
//
// Hooks: contact() calls continuousContact() for a sustained contact that carries a load;
// endStepFor() calls continuousEndStep(); render() calls renderContactForces() before a voice's
// modes are rendered; reset() calls resetContinuous().
#include <algorithm>
#include <cmath>

#include "strike/synth/engine.hpp"
#include "voice_state.hpp"

namespace strike {
namespace {

double compliance(double youngs_pa, double poisson) {
  return youngs_pa > 0.0 ? (1.0 - poisson * poisson) / youngs_pa : 0.0;
}

double curvature(double radius_m) { return radius_m > 0.0 && std::isfinite(radius_m) ? 1.0 / radius_m : 0.0; }

}  // namespace

void SoundEngine::continuousContact(VoiceState& v, const EngineContact& c, const std::array<double, 3>& world) {
  if (!(c.normal_force_n > 0.0) || !std::isfinite(c.normal_force_n)) return;
  // A body with no mode in the band (a marble, a small block) would drive nothing: its rolling is
  // heard through its partner's modes, whose own source reads this body's roughness.
  if (!v.rings_) return;
  const ContactPartner& p = c.partner;
  const VoiceState* pv = p.voice != kNoVoice ? state(p.voice) : nullptr;
  const SurfaceRoughness& partner_roughness = pv ? pv->roughness_ : p.roughness;
  if (!(v.roughness_.rms_m > 0.0) && !(partner_roughness.rms_m > 0.0)) return;
  const uint64_t key = p.voice != kNoVoice ? p.voice : (partner_roughness.seed | (uint64_t(1) << 63));
  VoiceState::Source* source = nullptr;
  for (VoiceState::Source& s : v.sources_)
    if (s.used && s.key == key) source = &s;
  if (!source) {
    // A new pair starts only when its surfaces move: resting contacts never start a generator.
    if (std::max(trackSpeed(c), partnerTrackSpeed(c)) < RoughContact::kStillSpeed_m_s) return;
    for (VoiceState::Source& s : v.sources_)
      if (!s.used) {
        source = &s;
        break;
      }
    if (!source) {
      ++stats_.continuous_dropped;
      return;
    }
    source->used = true;
    source->key = key;
    source->partner = p;
    RoughContactDesc desc;
    desc.a = v.roughness_;
    desc.b = partner_roughness;
    const double m_self = v.is_static_ ? INFINITY : v.mass_kg_;
    const double m_other = pv ? pv->mass_kg_ : (p.mass_kg > 0.0 ? p.mass_kg : INFINITY);
    desc.mass_kg = !std::isfinite(m_self)    ? m_other
                   : !std::isfinite(m_other) ? m_self
                                             : m_self * m_other / (m_self + m_other);
    const double youngs = pv ? pv->youngs_pa_ : (p.youngs_pa > 0.0 ? p.youngs_pa : v.youngs_pa_);
    const double poisson = pv ? pv->poisson_ : (p.youngs_pa > 0.0 ? p.poisson : v.poisson_);
    const double k = compliance(v.youngs_pa_, v.poisson_) + compliance(youngs, poisson);
    desc.modulus_pa = k > 0.0 ? 1.0 / k : 0.0;
    // A static body is flat here, as in the simulation's Hertz patch (ContactEvent::patch_radius_m).
    const double curv = curvature(v.is_static_ ? INFINITY : v.contact_radius_m_) +
                        curvature(pv ? (pv->is_static_ ? INFINITY : pv->contact_radius_m_) : p.radius_m);
    desc.radius_m = curv > 0.0 ? 1.0 / curv : INFINITY;
    const double e_other = pv ? pv->restitution_ : p.restitution;
    desc.damping_ratio = contactDampingRatio(std::sqrt(std::max(0.0, v.restitution_ * e_other)));
    desc.sample_rate_hz = settings_.synth.sample_rate_hz;
    source->generator.start(desc, frames_);
    // The delay from where the pair started stays the source's for its life: a sliding body's
    // path length changes by metres per second only, and moving the delay would need resampling.
    Arrival paths[2];
    arrivals(v, world, paths);
    source->delay_s = paths[0].delay_s;
    source->stepped = false;
    ++stats_.continuous_contacts;
  }
  VoiceState::Source& s = *source;
  if (!s.stepped) {
    s.stepped = true;
    s.force_n = s.speed_n = s.partner_speed_n = s.patch_n = 0.0;
    s.spot_n = s.partner_spot_n = s.world_n = {};
    std::fill(s.modal.begin(), s.modal.end(), 0.0);
  }
  const double n = c.normal_force_n;
  s.force_n += n;
  s.speed_n += n * trackSpeed(c);
  s.partner_speed_n += n * partnerTrackSpeed(c);
  s.patch_n += n * c.patch_radius_m;
  const std::array<double, 3> own = c.world_frame ? v.pose_.toLocalPoint(c.point) : c.point;
  for (int k = 0; k < 3; ++k) {
    s.spot_n[k] += n * own[k];
    s.partner_spot_n[k] += n * c.partner_point[k];
    s.world_n[k] += n * world[k];
  }
  // v.modal_ holds this point's modal impulse (contact() projected it).
  for (size_t i = 0; i < s.modal.size(); ++i) s.modal[i] += v.modal_[i];
}

void SoundEngine::continuousEndStep(VoiceState& v, bool load_change_follows) {
  for (uint32_t ch = 0; ch < kForceChannels; ++ch) {
    VoiceState::Source& s = v.sources_[ch];
    if (!s.used || !s.stepped) continue;
    s.stepped = false;
    const double n = s.force_n;
    const double dt = step_.length_s > 0.0 ? step_.length_s : 1.0;
    // The step's force acts over the step: its state belongs to the step's middle.
    const double t = step_.end_s - 0.5 * step_.length_s + s.delay_s;
    RoughContactState state;
    state.normal_force_n = n;
    state.speed_a_m_s = s.speed_n / n;
    state.speed_b_m_s = s.partner_speed_n / n;
    state.patch_radius_m = s.patch_n / n;
    for (int k = 0; k < 3; ++k) state.spot_a[k] = s.spot_n[k] / n, state.spot_b[k] = s.partner_spot_n[k] / n;
    (void)s.generator.push(t * settings_.synth.sample_rate_hz, state);
    // Modal force per newton of normal force.
    const double per_n = 1.0 / (n * dt);
    for (double& g : s.modal) g *= per_n;
    ForceWeightsDesc w;
    w.channel = ch;
    w.time_s = t;  // with the generator's state: both carry the source's delay
    w.modal_weight = s.modal.data();
    // Directivity, looked at each physics step (not once when the source starts): a rolling
    // body turns a full revolution every 2 pi r of travel, so the direction toward the listener
    // in its frame changes within a roll. A body with a transfer of high order (a 0.4 m plate to
    // 20 kHz: order ~90, 2 MB of coefficients) costs ~0.1 ms an evaluation, so the factors are
    // kept while the direction has moved less than the bounded angle of radiationToward (a
    // resting or slowly sliding body, a static one). The direct path
    // only: the ground's image would need the force signal again behind its longer path (a delay
    // line per source), which continuous contact leaves out (docs/listener.md).
    if (v.pressure_) {
      Arrival paths[2];
      const std::array<double, 3> world = {s.world_n[0] / n, s.world_n[1] / n, s.world_n[2] / n};
      const std::complex<double>* transfer[2];
      // A load change later in this step (endStepFor) hears the same two directions (a
      // directional voice's sound leaves from its transfer's centre, whatever the point): when
      // the direct path is evaluated here, the ground's image rides along in the same pass.
      const int count = arrivals(v, world, paths);
      radiationToward(v, paths, 1, transfer, Reuse::WithinTolerance, load_change_follows ? count : 0);
      w.modal_transfer = throughAir(v, 0, transfer[0], paths[0].distance_m);
    }
    (void)v.synth_.setForceWeights(w);  // a full queue keeps the weights in force
  }
}

bool SoundEngine::renderContactForces(VoiceState& v, size_t frames) {
  bool any = false;
  for (uint32_t ch = 0; ch < kForceChannels; ++ch) {
    VoiceState::Source& s = v.sources_[ch];
    v.force_ptrs_[ch] = nullptr;
    if (!s.used) continue;
    float* out = v.force_.data() + static_cast<size_t>(ch) * settings_.max_block_frames;
    const uint64_t lost = s.generator.lostSamples();
    s.generator.generate(out, frames);
    for (size_t n = frames; n-- > 0;)
      if (out[n] != 0.0f) {
        stats_.continuous_last_force_s = std::max(stats_.continuous_last_force_s,
                                                  time() + static_cast<double>(n + 1) / settings_.synth.sample_rate_hz);
        break;
      }
    stats_.continuous_lost_samples += s.generator.lostSamples() - lost;
    stats_.continuous_samples += frames;
    v.force_ptrs_[ch] = out;
    any = true;
    if (!s.generator.active()) {
      // Ended and rung out: the channel stops, its modes ring on.
      ForceWeightsDesc w;
      w.channel = ch;
      w.time_s = time();
      w.modal_weight = nullptr;
      if (v.synth_.setForceWeights(w)) s.used = false;
    }
  }
  return any;
}

void SoundEngine::resetContinuous(VoiceState& v) {
  for (VoiceState::Source& s : v.sources_) {
    s.used = false;
    s.stepped = false;
  }
}

}  // namespace strike
