// SPDX-License-Identifier: MIT
// libstrike, main thread: objects and the listener. Adding an object builds its Voice here, with
// all the memory it will use, and sends it to the audio thread by an Install command; removing it
// sends a Remove and frees the voice once the audio thread has consumed that command (collect).
// Poses, gains and the listener's pose travel as commands too.
#include "strike/strike.h"

#include <cmath>
#include <cstring>
#include <memory>
#include <new>
#include <vector>

#include "strike/synth/synth.hpp"

#include "capi_internal.hpp"
#include "main_thread.hpp"

using namespace strike;          // NOLINT: this file is the C shim over these namespaces
using namespace strike::detail;  // NOLINT

extern "C" {

STRIKE_API strike_object_config STRIKE_CALL strike_object_config_default(void) {
  strike_object_config c;
  std::memset(&c, 0, sizeof c);
  c.orientation[0] = 1.0;
  c.gain = 1.0f;
  c.radiation = STRIKE_RADIATION_PRESSURE;
  c.internal_cookie = kObjectCookie;
  c.restitution = 0.5;
  return c;
}

STRIKE_API strike_status STRIKE_CALL strike_object_add(strike_context ctx, const strike_object_config* config,
                                                       strike_object_id* out) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  if (!config || !out) return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: config and out must not be NULL");
  if (config->internal_cookie != kObjectCookie)
    return fail(ctx, STRIKE_ERR_NOT_INITIALIZED,
                "strike_object_add: config did not come from strike_object_config_default()");
  return guarded(ctx, "strike_object_add", [&]() -> strike_status {
    collect(ctx);
    const strike_object_config& c = *config;
    if (!c.bank || c.bank->context != ctx)
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: bank is NULL or from another context");
    Pose pose;
    if (!pose.set(c.position, c.orientation))
      return fail(ctx, STRIKE_ERR_INVALID_ARG,
                  "strike_object_add: position/orientation not finite, or orientation is a zero quaternion");
    if (!(c.gain >= 0.0f) || !std::isfinite(c.gain))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: gain = %g (must be finite and >= 0)",
                  static_cast<double>(c.gain));
    if (c.radiation != STRIKE_RADIATION_PRESSURE && c.radiation != STRIKE_RADIATION_UNIT)
      return fail(ctx, STRIKE_ERR_INVALID_ARG,
                  "strike_object_add: radiation = %d (must be STRIKE_RADIATION_PRESSURE or _UNIT)", c.radiation);
    if (!(c.contact_radius_m >= 0.0) || !std::isfinite(c.contact_radius_m))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: contact_radius_m = %g (must be >= 0)",
                  c.contact_radius_m);
    if (!(c.roughness_rms_m >= 0.0) || !std::isfinite(c.roughness_rms_m) || !(c.roughness_correlation_m >= 0.0) ||
        !std::isfinite(c.roughness_correlation_m) || (c.roughness_rms_m > 0.0 && !(c.roughness_correlation_m > 0.0)))
      return fail(ctx, STRIKE_ERR_INVALID_ARG,
                  "strike_object_add: roughness_rms_m = %g, roughness_correlation_m = %g (must be >= 0, and the "
                  "correlation length > 0 when the rms is)",
                  c.roughness_rms_m, c.roughness_correlation_m);
    if (!(c.restitution >= 0.0 && c.restitution <= 1.0))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: restitution = %g (must be in [0, 1])",
                  c.restitution);
    uint32_t index = ctx->max_objects;
    for (uint32_t i = 0; i < ctx->max_objects; ++i)
      if (!ctx->main_slots[i].used) {
        index = i;
        break;
      }
    if (index == ctx->max_objects)
      return fail(ctx, STRIKE_ERR_CAPACITY, "strike_object_add: max_objects = %u objects are alive", ctx->max_objects);

    const std::shared_ptr<const LoadedBank>& data = c.bank->data;
    VoiceDesc desc;
    desc.bank = std::shared_ptr<const ModeBank>(data, &data->bank);  // shares the bank's ownership
    desc.weights = c.radiation == STRIKE_RADIATION_PRESSURE ? data->pressure_weights
                                                            : std::vector<double>(data->bank.modeCount(), 1.0);
    if (c.radiation == STRIKE_RADIATION_PRESSURE)
      desc.pressure_scale = outputPerPascal(1.0, ctx->config.output_full_scale_pa);
    desc.is_static = c.is_static != 0;
    desc.contact_radius_m = c.contact_radius_m;
    desc.roughness.rms_m = c.roughness_rms_m;
    desc.roughness.correlation_m = c.roughness_correlation_m;
    desc.roughness.seed = c.roughness_seed;
    desc.restitution = c.restitution;
    desc.pose = pose;
    desc.gain = c.gain;
    void* mem = ctx->allocArray<Voice>(1);
    Voice* v = nullptr;
    try {
      v = new (mem) Voice(desc, ctx->engine_settings);
    } catch (...) {
      ctx->release(mem);
      throw;
    }
    MainSlot& slot = ctx->main_slots[index];
    const uint32_t generation = slot.generation + 1 == 0 ? 1 : slot.generation + 1;
    Command cmd{};
    cmd.type = CommandType::Install;
    cmd.index = index;
    cmd.generation = generation;
    cmd.voice = v;
    if (!sendCommand(ctx, cmd)) {
      v->~Voice();
      ctx->release(mem);
      return fail(ctx, STRIKE_ERR_QUEUE_FULL, "strike_object_add: command queue full (is the audio thread rendering?)");
    }
    slot = MainSlot{v, generation, true};
    ctx->live_generation[index].store(generation, std::memory_order_release);
    *out = strike_object_id{index, generation};
    ctx->last_error[0] = '\0';
    return STRIKE_OK;
  });
}

STRIKE_API strike_status STRIKE_CALL strike_object_remove(strike_context ctx, strike_object_id id) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  return guarded(ctx, "strike_object_remove", [&]() -> strike_status {
    collect(ctx);
    MainSlot* slot = liveSlot(ctx, id);
    if (!slot)
      return fail(ctx, STRIKE_ERR_STALE_ID, "strike_object_remove: object {%u, %u} is not alive", id.index,
                  id.generation);
    Command cmd{};
    cmd.type = CommandType::Remove;
    cmd.index = id.index;
    cmd.generation = id.generation;
    ctx->retired.reserve(ctx->retired.size() + 1);  // before the point of no return
    if (!sendCommand(ctx, cmd))
      return fail(ctx, STRIKE_ERR_QUEUE_FULL,
                  "strike_object_remove: command queue full (is the audio thread rendering?)");
    ctx->retired.push_back(Retired{slot->voice, ctx->commands_sent});
    ctx->live_generation[id.index].store(0, std::memory_order_release);
    slot->used = false;
    slot->voice = nullptr;
    ctx->last_error[0] = '\0';
    return STRIKE_OK;
  });
}

STRIKE_API int32_t STRIKE_CALL strike_object_is_valid(strike_context ctx, strike_object_id id) {
  if (!ctx || id.index >= ctx->max_objects || id.generation == 0) return 0;
  return ctx->live_generation[id.index].load(std::memory_order_acquire) == id.generation ? 1 : 0;
}

STRIKE_API strike_status STRIKE_CALL strike_object_set_pose(strike_context ctx, strike_object_id id,
                                                            const double position[3], const double orientation[4]) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  return guarded(ctx, "strike_object_set_pose", [&]() -> strike_status {
    collect(ctx);
    if (!liveSlot(ctx, id))
      return fail(ctx, STRIKE_ERR_STALE_ID, "strike_object_set_pose: object {%u, %u} is not alive", id.index,
                  id.generation);
    Command cmd{};
    cmd.type = CommandType::SetPose;
    cmd.index = id.index;
    cmd.generation = id.generation;
    if (!cmd.pose.set(position, orientation))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_set_pose: NULL, non-finite, or zero quaternion");
    if (!sendCommand(ctx, cmd)) return fail(ctx, STRIKE_ERR_QUEUE_FULL, "strike_object_set_pose: command queue full");
    return STRIKE_OK;
  });
}

STRIKE_API strike_status STRIKE_CALL strike_object_set_gain(strike_context ctx, strike_object_id id, float gain) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  return guarded(ctx, "strike_object_set_gain", [&]() -> strike_status {
    collect(ctx);
    if (!liveSlot(ctx, id))
      return fail(ctx, STRIKE_ERR_STALE_ID, "strike_object_set_gain: object {%u, %u} is not alive", id.index,
                  id.generation);
    if (!(gain >= 0.0f) || !std::isfinite(gain))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_set_gain: gain = %g (must be finite and >= 0)",
                  static_cast<double>(gain));
    Command cmd{};
    cmd.type = CommandType::SetGain;
    cmd.index = id.index;
    cmd.generation = id.generation;
    cmd.gain = gain;
    if (!sendCommand(ctx, cmd)) return fail(ctx, STRIKE_ERR_QUEUE_FULL, "strike_object_set_gain: command queue full");
    return STRIKE_OK;
  });
}

STRIKE_API strike_status STRIKE_CALL strike_listener_set_pose(strike_context ctx, const double position[3],
                                                              const double orientation[4]) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  return guarded(ctx, "strike_listener_set_pose", [&]() -> strike_status {
    collect(ctx);
    Command cmd{};
    cmd.type = CommandType::SetListener;
    if (!cmd.pose.set(position, orientation))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_listener_set_pose: NULL, non-finite, or zero quaternion");
    if (!sendCommand(ctx, cmd)) return fail(ctx, STRIKE_ERR_QUEUE_FULL, "strike_listener_set_pose: command queue full");
    return STRIKE_OK;
  });
}

}  // extern "C"
