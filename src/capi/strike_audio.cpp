// SPDX-License-Identifier: MIT
// libstrike, audio-thread half: impacts and physics steps in (from any thread, through lock-free
// queues), audio out. strike_render() applies the main thread's commands, then the queued
// physics steps and impacts, in order, to the sound engine (strike/synth/engine.hpp), then renders.
// Nothing here allocates, locks or throws once the context exists.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "capi_internal.hpp"
#include "strike/strike.h"

namespace strike::detail {
namespace {

bool finite3(const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// strike_contact's layouts: 0.3's ends before the continuous-contact fields; 0.4's after them.
constexpr size_t kContactSize03 = offsetof(strike_contact, normal_force_n);
constexpr size_t kContactSize04 = offsetof(strike_contact, partner_restitution) + sizeof(double);

/// The engine slot of a live object on the audio thread, or kNoVoice.
uint32_t audioSlot(strike_context ctx, strike_object_id id) {
  if (id.index >= ctx->max_objects || id.generation == 0) return kNoVoice;
  const AudioSlot& slot = ctx->audio_slots[id.index];
  return slot.voice && slot.generation == id.generation ? id.index : kNoVoice;
}

void applyCommand(strike_context ctx, const Command& c) {
  SoundEngine& engine = *ctx->engine;
  AudioSlot& slot = ctx->audio_slots[c.index < ctx->max_objects ? c.index : 0];
  switch (c.type) {
    case CommandType::Install:
      slot.voice = c.voice;
      slot.generation = c.generation;
      engine.install(c.index, c.voice);
      break;
    case CommandType::Remove:
      if (slot.generation == c.generation) slot.voice = nullptr, (void)engine.uninstall(c.index);
      break;
    case CommandType::SetPose:
      if (slot.voice && slot.generation == c.generation) engine.setPose(c.index, c.pose);
      break;
    case CommandType::SetGain:
      if (slot.voice && slot.generation == c.generation) engine.setGain(c.index, c.gain);
      break;
    case CommandType::SetListener: engine.setListener(c.pose); break;
    case CommandType::Reset: {
      engine.reset();
      // Only what was queued before strike_context_reset(): steps and impacts reported after it
      // returned belong to the restarted clock.
      strike_impact_desc impact;
      while (ctx->impacts.poppedCount() < c.impacts_mark && ctx->impacts.pop(impact)) {
      }
      StepRecord record;
      while (ctx->steps.poppedCount() < c.steps_mark && ctx->steps.pop(record)) {
      }
      break;
    }
  }
}

void applyImpact(strike_context ctx, const strike_impact_desc& d) {
  const uint32_t slot = audioSlot(ctx, d.object);
  if (slot == kNoVoice) {
    ctx->counters.stale.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  EngineImpact impact;
  impact.voice = slot;
  impact.world_frame = d.frame == STRIKE_FRAME_WORLD;
  impact.surface_vertex = d.surface_vertex;
  std::copy(d.point, d.point + 3, impact.point.begin());
  std::copy(d.impulse, d.impulse + 3, impact.impulse.begin());
  impact.normal_speed_m_s = d.normal_speed_m_s;
  impact.contact_duration_s = d.contact_duration_s;
  impact.partner.youngs_pa = d.striker_youngs_pa;
  impact.partner.poisson = d.striker_poisson;
  impact.partner.radius_m = d.striker_radius_m;
  impact.partner.mass_kg = d.striker_mass_kg;
  impact.time_s = ctx->engine->time() + static_cast<double>(d.sample_offset) / ctx->config.sample_rate_hz;
  impact.shape = d.pulse == STRIKE_PULSE_BOX ? PulseShape::Box : PulseShape::HalfSine;
  ctx->engine->impact(impact);
}

void applyStepRecord(strike_context ctx, const StepRecord& r) {
  SoundEngine& engine = *ctx->engine;
  if (const StepBegin* begin = std::get_if<StepBegin>(&r)) {
    engine.beginStep(begin->end_time_s, begin->duration_s);
  } else if (const StepBodyState* state = std::get_if<StepBodyState>(&r)) {
    const uint32_t slot = audioSlot(ctx, state->object);
    Pose pose;
    if (slot != kNoVoice && pose.set(state->position, state->orientation)) engine.setPose(slot, pose, state->asleep);
  } else if (const StepContact* queued = std::get_if<StepContact>(&r)) {
    const uint32_t slot = audioSlot(ctx, queued->object);
    if (slot == kNoVoice) {
      ctx->counters.contacts_stale.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    EngineContact c = queued->contact;
    c.voice = slot;
    c.partner.voice = audioSlot(ctx, queued->partner);
    engine.contact(c);
  } else {
    engine.endStep();
    ctx->counters.steps.fetch_add(1, std::memory_order_relaxed);
  }
}

/// strike_contact as the sound engine's contact record (the same quantities, field for field);
/// `continuous`: the element is 0.4's or larger and has the rolling and sliding fields.
EngineContact engineContact(const strike_contact& c, bool continuous, double step_start_s) {
  EngineContact e;
  e.world_frame = c.frame == STRIKE_FRAME_WORLD;
  std::copy(c.point, c.point + 3, e.point.begin());
  std::copy(c.impulse, c.impulse + 3, e.impulse.begin());
  e.normal_speed_m_s = c.normal_speed_m_s;
  e.time_s = c.time_s >= 0.0 ? c.time_s : step_start_s;
  e.partner.youngs_pa = c.partner_youngs_pa;
  e.partner.poisson = c.partner_poisson;
  e.partner.radius_m = c.partner_radius_m;
  e.partner.mass_kg = c.partner_mass_kg;
  if (!continuous) return e;  // a 0.3 element: no continuous contact, the defaults
  e.normal_force_n = c.normal_force_n;
  std::copy(c.slip_velocity_m_s, c.slip_velocity_m_s + 3, e.slip_velocity_m_s.begin());
  std::copy(c.rolling_velocity_m_s, c.rolling_velocity_m_s + 3, e.rolling_velocity_m_s.begin());
  std::copy(c.partner_point, c.partner_point + 3, e.partner_point.begin());
  e.patch_radius_m = c.patch_radius_m;
  e.partner.roughness.rms_m = c.partner_roughness_rms_m;
  e.partner.roughness.correlation_m = c.partner_roughness_correlation_m;
  e.partner.roughness.seed = c.partner_roughness_seed;
  e.partner.restitution = c.partner_restitution;
  return e;
}

// The engine's counters into the context's atomics (read by strike_context_get_stats).
void publishStats(strike_context ctx) {
  const EngineStats s = ctx->engine->stats();
  Counters& k = ctx->counters;
  k.scheduled.store(s.impacts, std::memory_order_relaxed);
  k.inaudible.store(s.impacts_inaudible, std::memory_order_relaxed);
  k.capacity.store(s.impacts_dropped, std::memory_order_relaxed);
  k.culled.store(s.modes_culled, std::memory_order_relaxed);
  k.sustained.store(s.sustained_contacts, std::memory_order_relaxed);
  k.load_changes.store(s.load_changes, std::memory_order_relaxed);
  k.load_holds.store(s.load_holds, std::memory_order_relaxed);
  k.continuous.store(s.continuous_contacts, std::memory_order_relaxed);
  k.continuous_dropped.store(s.continuous_dropped, std::memory_order_relaxed);
  k.active_modes.store(static_cast<uint32_t>(std::min<uint64_t>(s.active_modes, UINT32_MAX)),
                       std::memory_order_relaxed);
  k.clock_frames.store(static_cast<uint64_t>(std::llround(ctx->engine->time() * ctx->config.sample_rate_hz)),
                       std::memory_order_relaxed);
}

}  // namespace
}  // namespace strike::detail

using namespace strike;          // NOLINT: this file is the C shim over these namespaces
using namespace strike::detail;  // NOLINT

extern "C" {

STRIKE_API strike_impact_desc STRIKE_CALL strike_impact_desc_default(void) {
  strike_impact_desc d;
  std::memset(&d, 0, sizeof d);
  d.frame = STRIKE_FRAME_OBJECT;
  d.surface_vertex = -1;
  // The library's striker (defaultStriker: a steel ball 5 mm in radius), its speed from the
  // impulse: the tap `strike hit` and Python's strike.hit() strike by default.
  const ContactPartner striker = defaultStriker();
  d.normal_speed_m_s = 0.0;
  d.contact_duration_s = -1.0;
  d.striker_radius_m = striker.radius_m;
  d.striker_youngs_pa = striker.youngs_pa;
  d.striker_poisson = striker.poisson;
  d.striker_mass_kg = striker.mass_kg;
  d.pulse = STRIKE_PULSE_HALF_SINE;
  return d;
}

STRIKE_API strike_status STRIKE_CALL strike_impact(strike_context ctx, const strike_impact_desc* impact) {
  // No allocation and nothing that throws: no guard needed, and none wanted on this path.
  if (!ctx || !impact) return STRIKE_ERR_INVALID_ARG;
  const strike_impact_desc& d = *impact;
  if (!finite3(d.point) || !finite3(d.impulse) || !std::isfinite(d.normal_speed_m_s) ||
      !std::isfinite(d.contact_duration_s) || !std::isfinite(d.striker_radius_m) ||
      !std::isfinite(d.striker_youngs_pa) || !std::isfinite(d.striker_poisson) || !std::isfinite(d.striker_mass_kg) ||
      (d.frame != STRIKE_FRAME_OBJECT && d.frame != STRIKE_FRAME_WORLD) ||
      (d.pulse != STRIKE_PULSE_HALF_SINE && d.pulse != STRIKE_PULSE_BOX) || d.surface_vertex < -1)
    return STRIKE_ERR_INVALID_ARG;
  if (!strike_object_is_valid(ctx, d.object)) return STRIKE_ERR_STALE_ID;
  if (!ctx->impacts.push(d)) {
    ctx->counters.dropped_full.fetch_add(1, std::memory_order_relaxed);
    return STRIKE_ERR_QUEUE_FULL;
  }
  ctx->counters.queued.fetch_add(1, std::memory_order_relaxed);
  return STRIKE_OK;
}

STRIKE_API strike_contact STRIKE_CALL strike_contact_default(void) {
  strike_contact c;
  std::memset(&c, 0, sizeof c);
  c.frame = STRIKE_FRAME_OBJECT;
  c.time_s = -1.0;
  c.partner_poisson = 0.3;
  c.partner_restitution = 0.5;
  return c;
}

STRIKE_API strike_step_desc STRIKE_CALL strike_step_desc_default(void) {
  strike_step_desc d;
  std::memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.duration_s = 1.0 / 60.0;
  d.state_size = sizeof(strike_body_state);
  d.contact_size = sizeof(strike_contact);
  return d;
}

STRIKE_API strike_status STRIKE_CALL strike_step(strike_context ctx, const strike_step_desc* step) {
  // No allocation and nothing that throws: no guard needed, and none wanted on this path.
  if (!ctx || !step) return STRIKE_ERR_INVALID_ARG;
  const strike_step_desc& d = *step;
  // 0.3 is the first layout: a newer caller's larger elements are read by their stride. A
  // contact is 0.3's (without the continuous-contact fields) or 0.4's or larger.
  const bool continuous = d.contact_size >= kContactSize04;
  if (d.struct_size < sizeof(strike_step_desc) || d.state_size < sizeof(strike_body_state) ||
      (d.contact_size != kContactSize03 && !continuous) || (d.state_count > 0 && !d.states) ||
      (d.contact_count > 0 && !d.contacts) || !std::isfinite(d.end_time_s) || !(d.duration_s > 0.0) ||
      !std::isfinite(d.duration_s))
    return STRIKE_ERR_INVALID_ARG;
  auto stateAt = [&](uint32_t i) {
    return reinterpret_cast<const strike_body_state*>(reinterpret_cast<const char*>(d.states) +
                                                      size_t(i) * d.state_size);
  };
  auto contactAt = [&](uint32_t i) {
    return reinterpret_cast<const strike_contact*>(reinterpret_cast<const char*>(d.contacts) +
                                                   size_t(i) * d.contact_size);
  };
  for (uint32_t i = 0; i < d.state_count; ++i) {
    const strike_body_state& s = *stateAt(i);
    if (!finite3(s.position) || !finite3(s.orientation + 1) || !std::isfinite(s.orientation[0]))
      return STRIKE_ERR_INVALID_ARG;
  }
  for (uint32_t i = 0; i < d.contact_count; ++i) {
    const strike_contact& c = *contactAt(i);
    if (!finite3(c.point) || !finite3(c.impulse) || !std::isfinite(c.normal_speed_m_s) || !std::isfinite(c.time_s) ||
        (c.frame != STRIKE_FRAME_OBJECT && c.frame != STRIKE_FRAME_WORLD) || !std::isfinite(c.partner_youngs_pa) ||
        !std::isfinite(c.partner_poisson) || !std::isfinite(c.partner_radius_m) || !std::isfinite(c.partner_mass_kg))
      return STRIKE_ERR_INVALID_ARG;
    if (continuous &&
        (!(c.normal_force_n >= 0.0) || !std::isfinite(c.normal_force_n) || !finite3(c.slip_velocity_m_s) ||
         !finite3(c.rolling_velocity_m_s) || !finite3(c.partner_point) || !(c.patch_radius_m >= 0.0) ||
         !std::isfinite(c.patch_radius_m) || !(c.partner_roughness_rms_m >= 0.0) ||
         !std::isfinite(c.partner_roughness_rms_m) || !(c.partner_roughness_correlation_m >= 0.0) ||
         !std::isfinite(c.partner_roughness_correlation_m) || !std::isfinite(c.partner_restitution)))
      return STRIKE_ERR_INVALID_ARG;
  }
  const uint64_t items = uint64_t(d.state_count) + d.contact_count;
  if (!ctx->steps.push(StepBegin{d.end_time_s, d.duration_s})) {
    ctx->counters.contacts_dropped_full.fetch_add(items, std::memory_order_relaxed);
    return STRIKE_ERR_QUEUE_FULL;
  }
  uint64_t pushed = 0;
  bool full = false;
  for (uint32_t i = 0; i < d.state_count && !full; ++i, ++pushed) {
    const strike_body_state& s = *stateAt(i);
    StepBodyState state{s.object, {}, {}, s.asleep != 0};
    std::copy(s.position, s.position + 3, state.position);
    std::copy(s.orientation, s.orientation + 4, state.orientation);
    full = !ctx->steps.push(state);
  }
  for (uint32_t i = 0; i < d.contact_count && !full; ++i, ++pushed) {
    const strike_contact& c = *contactAt(i);
    full =
        !ctx->steps.push(StepContact{c.object, c.partner, engineContact(c, continuous, d.end_time_s - d.duration_s)});
    if (!full) ctx->counters.contacts_queued.fetch_add(1, std::memory_order_relaxed);
  }
  if (full) --pushed;
  if (full || !ctx->steps.push(StepEnd{})) {
    // What did not fit is dropped; the step still closes at the next Begin.
    ctx->counters.contacts_dropped_full.fetch_add(items - pushed, std::memory_order_relaxed);
    return STRIKE_ERR_QUEUE_FULL;
  }
  return STRIKE_OK;
}

STRIKE_API strike_status STRIKE_CALL strike_render(strike_context ctx, float* const* out, uint32_t channels,
                                                   uint32_t frames) {
  if (!ctx || !out) return STRIKE_ERR_INVALID_ARG;
  if (channels != ctx->config.channels) return STRIKE_ERR_INVALID_ARG;
  for (uint32_t c = 0; c < channels; ++c)
    if (!out[c]) return STRIKE_ERR_INVALID_ARG;
  if (frames > ctx->config.max_block_frames) return STRIKE_ERR_TOO_MANY_FRAMES;
  // Nothing below allocates or throws (reserved storage, noexcept math); the try is the ABI
  // boundary all the same.
  try {
    // 1. Commands from the main thread, then acknowledge them (frees removed objects later).
    uint64_t consumed = 0;
    Command cmd;
    while (ctx->commands.pop(cmd)) applyCommand(ctx, cmd), ++consumed;
    if (consumed) ctx->commands_done.fetch_add(consumed, std::memory_order_release);
    // 2. Physics steps, in order: at most one queue's worth, so a producer cannot stall this call.
    StepRecord record;
    for (size_t k = ctx->steps.capacity(); k > 0 && ctx->steps.pop(record); --k) applyStepRecord(ctx, record);
    // 3. Impacts, at most max_impacts_per_render (and one queue's worth) so that a flood
    //    cannot stall this call; the rest stay queued, in order, for the next one.
    strike_impact_desc d;
    size_t budget = ctx->impacts.capacity();
    if (ctx->config.max_impacts_per_render > 0) budget = std::min<size_t>(budget, ctx->config.max_impacts_per_render);
    for (size_t k = budget; k > 0 && ctx->impacts.pop(d); --k) applyImpact(ctx, d);
    // 4. Render and mix (levels, pans, budget: the engine).
    ctx->engine->render(out, frames);
    uint32_t objects = 0;
    for (uint32_t i = 0; i < ctx->max_objects; ++i) objects += ctx->audio_slots[i].voice ? 1 : 0;
    ctx->counters.objects.store(objects, std::memory_order_relaxed);
    ctx->counters.frames.fetch_add(frames, std::memory_order_relaxed);
    publishStats(ctx);
    return STRIKE_OK;
  } catch (...) {
    return STRIKE_ERR_INTERNAL;
  }
}

}  // extern "C"
