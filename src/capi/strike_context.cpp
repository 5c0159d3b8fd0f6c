// SPDX-License-Identifier: MIT
// libstrike, main thread: the context's life. Its config's defaults and checks (each refusal names
// the field and its value), creating it with the output's format (mono or stereo from
// config->channels, or a strike_output_desc: Ambisonics, binaural with the host's responses, air
// absorption), destroying it, its last error and statistics, collecting removed objects and
// resetting its clock.
#include "strike/strike.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <string>

#include "capi_internal.hpp"
#include "main_thread.hpp"

namespace strike::detail {
namespace {

void* defaultAlloc(void*, size_t size, size_t alignment) {
  alignment = std::max<size_t>(alignment, alignof(std::max_align_t));
  return std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
}
void defaultFree(void*, void* p) { std::free(p); }

uint32_t nextPow2(uint32_t v) {
  uint32_t p = 2;
  while (p < v) p <<= 1;
  return p;
}

/// Why a config is refused, naming the field and its value; empty when it is valid.
std::string rejectedField(const strike_context_config& c) {
  char why[256];
  auto say = [&](const char* fmt, auto value) {
    std::snprintf(why, sizeof why, fmt, value);
    return std::string(why);
  };
  if (!(c.sample_rate_hz >= 8000.0 && c.sample_rate_hz <= 768000.0))
    return say("sample_rate_hz = %g (must be 8000 .. 768000)", c.sample_rate_hz);
  if (c.max_block_frames < 1 || c.max_block_frames > 16384)
    return say("max_block_frames = %u (must be 1 .. 16384)", c.max_block_frames);
  if (c.channels != 1 && c.channels != 2) return say("channels = %u (must be 1 or 2)", c.channels);
  if (c.max_objects < 1 || c.max_objects > 65536) return say("max_objects = %u (must be 1 .. 65536)", c.max_objects);
  if (c.impact_queue_capacity < 2 || c.impact_queue_capacity > (1u << 20))
    return say("impact_queue_capacity = %u (must be 2 .. 1048576)", c.impact_queue_capacity);
  if (c.contact_queue_capacity < 16 || c.contact_queue_capacity > (1u << 20))
    return say("contact_queue_capacity = %u (must be 16 .. 1048576)", c.contact_queue_capacity);
  if (c.max_pending_impacts_per_object < 1 || c.max_pending_impacts_per_object > 4096)
    return say("max_pending_impacts_per_object = %u (must be 1 .. 4096)", c.max_pending_impacts_per_object);
  if (!(c.max_contact_duration_s >= 0.0 && c.max_contact_duration_s <= 1.0))
    return say("max_contact_duration_s = %g (must be 0 .. 1)", c.max_contact_duration_s);
  if (!(c.min_freq_hz >= 0.0) || !std::isfinite(c.min_freq_hz))
    return say("min_freq_hz = %g (must be >= 0)", c.min_freq_hz);
  if (!(c.max_freq_hz > c.min_freq_hz) || !std::isfinite(c.max_freq_hz))
    return say("max_freq_hz = %g (must be finite and above min_freq_hz)", c.max_freq_hz);
  if (!(c.audibility_threshold >= 0.0) || !std::isfinite(c.audibility_threshold))
    return say("audibility_threshold = %g (must be finite and >= 0)", c.audibility_threshold);
  if (!(c.reference_distance_m > 0.0) || !std::isfinite(c.reference_distance_m))
    return say("reference_distance_m = %g (must be finite and > 0)", c.reference_distance_m);
  if (c.ground_reflects != 0 && c.ground_reflects != 1)
    return say("ground_reflects = %d (must be 0 or 1)", c.ground_reflects);
  {
    const double* n = c.ground_normal;
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(length > 1e-9) || !std::isfinite(length)) {
      std::snprintf(why, sizeof why, "ground_normal = (%g, %g, %g) (must be finite and not zero)", n[0], n[1], n[2]);
      return std::string(why);
    }
  }
  if (!std::isfinite(c.ground_height_m)) return say("ground_height_m = %g (must be finite)", c.ground_height_m);
  if (!(c.ground_reflection >= -1.0 && c.ground_reflection <= 1.0))
    return say("ground_reflection = %g (must be -1 .. 1)", c.ground_reflection);
  if (!(c.min_distance_m > 0.0) || !std::isfinite(c.min_distance_m))
    return say("min_distance_m = %g (must be finite and > 0)", c.min_distance_m);
  if (!(c.output_full_scale_pa > 0.0) || !std::isfinite(c.output_full_scale_pa))
    return say("output_full_scale_pa = %g (must be finite and > 0)", c.output_full_scale_pa);
  if (!(c.contact_damping_per_s >= 0.0) || !std::isfinite(c.contact_damping_per_s))
    return say("contact_damping_per_s = %g (must be finite and >= 0)", c.contact_damping_per_s);
  if ((c.alloc == nullptr) != (c.free == nullptr))
    return say("%s", c.alloc ? "alloc is set but free is NULL (set both or neither)"
                             : "free is set but alloc is NULL (set both or neither)");
  return {};
}

void logRejected(const strike_context_config& c, const std::string& why) {
  if (!c.log) return;
  const std::string message = "strike_context_create: " + why;
  c.log(c.user, STRIKE_LOG_ERROR, message.c_str());
}

}  // namespace
}  // namespace strike::detail

using namespace strike;          // NOLINT: this file is the C shim over these namespaces
using namespace strike::detail;  // NOLINT

extern "C" {

STRIKE_API strike_context_config STRIKE_CALL strike_context_config_default(void) {
  strike_context_config c;
  std::memset(&c, 0, sizeof c);
  c.api_version = STRIKE_VERSION;
  c.sample_rate_hz = 48000.0;
  c.max_block_frames = 1024;
  c.channels = 2;
  c.max_objects = 64;
  c.max_active_modes = 100000;
  c.impact_queue_capacity = 1024;
  c.max_pending_impacts_per_object = 32;
  c.max_impacts_per_render = 64;
  c.max_contact_duration_s = 0.005;
  c.min_freq_hz = 20.0;
  c.max_freq_hz = 20000.0;
  c.audibility_threshold = 1e-6;
  c.reference_distance_m = kReferenceDistance_m;
  c.internal_cookie = kContextCookie;
  c.output_full_scale_pa = kFullScalePascal;
  c.min_distance_m = kMinListenerDistance_m;
  c.contact_damping_per_s = 0.0;
  c.contact_queue_capacity = 8192;
  c.ground_reflects = 0;
  c.ground_normal[0] = 0.0, c.ground_normal[1] = 0.0, c.ground_normal[2] = 1.0;
  c.ground_height_m = 0.0;
  c.ground_reflection = 1.0;
  return c;
}

namespace {

/// A binaural output's responses, copied from the caller's arrays, or why they cannot be.
Result<std::shared_ptr<const HrtfSet>> hrtfFromOutput(const strike_output_desc& output, double sample_rate_hz) {
  if (output.struct_size < offsetof(strike_output_desc, hrtf_right) + sizeof output.hrtf_right)
    return badInput("output: struct_size = " + std::to_string(output.struct_size) +
                    " does not cover the hrtf_* fields STRIKE_OUTPUT_BINAURAL needs (set it to "
                    "sizeof(strike_output_desc))");
  if (output.hrtf_count < 4 || output.hrtf_count > (1u << 20))
    return badInput("output: hrtf_count = " + std::to_string(output.hrtf_count) + " (must be 4 .. 1048576)");
  if (output.hrtf_length < 1 || output.hrtf_length > 16384)
    return badInput("output: hrtf_length = " + std::to_string(output.hrtf_length) + " (must be 1 .. 16384)");
  if (!output.hrtf_directions || !output.hrtf_left || !output.hrtf_right)
    return badInput("output: hrtf_directions, hrtf_left and hrtf_right must not be NULL");
  auto set = std::make_shared<HrtfSet>();
  set->sample_rate_hz = sample_rate_hz;
  set->taps = output.hrtf_length;
  const size_t count = output.hrtf_count, values = count * output.hrtf_length;
  set->directions.resize(count);
  for (size_t i = 0; i < count; ++i)
    for (size_t k = 0; k < 3; ++k) set->directions[i][k] = output.hrtf_directions[3 * i + k];
  set->left.assign(output.hrtf_left, output.hrtf_left + values);
  set->right.assign(output.hrtf_right, output.hrtf_right + values);
  if (const std::string why = prepareHrtfSet(*set); !why.empty()) return badInput("output: hrtf: " + why);
  return std::shared_ptr<const HrtfSet>(std::move(set));
}

/// Why the caller's api_version is refused; empty when this library serves it. Same major, and a
/// caller no newer than us (IPL isVersionCompatible); before 1.0 the same minor too, since a minor
/// release may change the config structs' layout (0.3 grew this one).
std::string versionRefusal(uint32_t caller) {
  const uint32_t caller_minor = (caller >> 8) & 0xffu;
  if ((caller >> 16) != STRIKE_VERSION_MAJOR || caller_minor > STRIKE_VERSION_MINOR ||
      (STRIKE_VERSION_MAJOR == 0 && caller_minor != STRIKE_VERSION_MINOR)) {
    char why[160];
    std::snprintf(
        why, sizeof why, "api_version = %u.%u.%u (this library is %d.%d.%d: %s)", caller >> 16, caller_minor,
        caller & 0xffu, STRIKE_VERSION_MAJOR, STRIKE_VERSION_MINOR, STRIKE_VERSION_PATCH,
        STRIKE_VERSION_MAJOR == 0 ? "before 1.0 the minor versions must match" : "the major versions must match");
    return why;
  }
  return {};
}

/// The output's format into `format`: from config->channels (mono or stereo) unless a
/// strike_output_desc names one. Why it is refused, or empty.
std::string outputFormat(const strike_context_config& c, const strike_output_desc* output, OutputFormat& format) {
  format = c.channels == 2 ? OutputFormat::Stereo : OutputFormat::Mono;
  if (!output) return {};
  if (output->struct_size < offsetof(strike_output_desc, format) + sizeof output->format)
    return "output: struct_size = " + std::to_string(output->struct_size) + " (set it to sizeof(strike_output_desc))";
  switch (output->format) {
    case STRIKE_OUTPUT_MONO: format = OutputFormat::Mono; break;
    case STRIKE_OUTPUT_STEREO: format = OutputFormat::Stereo; break;
    case STRIKE_OUTPUT_AMBIX1: format = OutputFormat::Ambix1; break;
    case STRIKE_OUTPUT_AMBIX2: format = OutputFormat::Ambix2; break;
    case STRIKE_OUTPUT_AMBIX3: format = OutputFormat::Ambix3; break;
    case STRIKE_OUTPUT_BINAURAL: format = OutputFormat::Binaural; break;
    default: return "output: format = " + std::to_string(output->format) + " (must be a STRIKE_OUTPUT_* value)";
  }
  return {};
}

/// Air absorption as the output descriptor asks for it (read only when its struct_size covers
/// the air's fields) into `air_absorption` and `air`. Why it is refused, or empty.
std::string airFromOutput(const strike_output_desc* output, bool& air_absorption, AirConditions& air) {
  air_absorption = false;
  if (!output || output->struct_size < offsetof(strike_output_desc, air_pressure_kpa) + sizeof(double) ||
      output->air_absorption == 0)
    return {};
  air_absorption = true;
  air.temperature_c = output->air_temperature_c;
  air.relative_humidity_percent = output->air_relative_humidity_percent;
  air.pressure_kpa = output->air_pressure_kpa;
  char why[160] = "";
  if (output->air_absorption != 1)
    std::snprintf(why, sizeof why, "output: air_absorption = %d (must be 0 or 1)", output->air_absorption);
  else if (!(air.temperature_c >= -50.0 && air.temperature_c <= 60.0))
    std::snprintf(why, sizeof why, "output: air_temperature_c = %g (must be -50 .. 60)", air.temperature_c);
  else if (!(air.relative_humidity_percent >= 0.0 && air.relative_humidity_percent <= 100.0))
    std::snprintf(why, sizeof why, "output: air_relative_humidity_percent = %g (must be 0 .. 100)",
                  air.relative_humidity_percent);
  else if (!(air.pressure_kpa >= 50.0 && air.pressure_kpa <= 200.0))
    std::snprintf(why, sizeof why, "output: air_pressure_kpa = %g (must be 50 .. 200)", air.pressure_kpa);
  return why;
}

/// The new context's queues and object slots, all taken now so the audio thread never allocates
/// (throws std::bad_alloc).
void allocateQueuesAndSlots(strike_context ctx) {
  const strike_context_config& cfg = ctx->config;
  const uint32_t impact_cap = nextPow2(cfg.impact_queue_capacity);
  const uint32_t step_cap = nextPow2(cfg.contact_queue_capacity);
  const uint32_t command_cap = nextPow2(4 * cfg.max_objects + 256);
  ctx->impact_cells = ctx->allocArray<BoundedQueue<strike_impact_desc>::Cell>(impact_cap);
  ctx->impacts.init(ctx->impact_cells, impact_cap);
  ctx->step_cells = ctx->allocArray<BoundedQueue<StepRecord>::Cell>(step_cap);
  ctx->steps.init(ctx->step_cells, step_cap);
  ctx->command_cells = ctx->allocArray<BoundedQueue<Command>::Cell>(command_cap);
  ctx->commands.init(ctx->command_cells, command_cap);
  ctx->live_generation = ctx->allocArray<std::atomic<uint32_t>>(cfg.max_objects);
  ctx->main_slots = ctx->allocArray<MainSlot>(cfg.max_objects);
  ctx->audio_slots = ctx->allocArray<AudioSlot>(cfg.max_objects);
  for (uint32_t i = 0; i < cfg.max_objects; ++i) {
    new (&ctx->live_generation[i]) std::atomic<uint32_t>(0);
    ctx->main_slots[i] = MainSlot{nullptr, 0, false};
    ctx->audio_slots[i] = AudioSlot{nullptr, 0};
  }
  ctx->retired.reserve(cfg.max_objects);
}

/// The sound engine's settings from a checked config and output (realtime: libstrike's audio
/// thread never allocates).
EngineSettings engineSettings(const strike_context_config& cfg, OutputFormat format,
                              std::shared_ptr<const HrtfSet> hrtf, bool air_absorption, const AirConditions& air) {
  EngineSettings e;
  e.synth.sample_rate_hz = cfg.sample_rate_hz;
  e.synth.min_freq_hz = cfg.min_freq_hz;
  e.synth.max_freq_hz = cfg.max_freq_hz;
  e.synth.audibility_threshold = cfg.audibility_threshold;
  e.output = format;
  e.hrtf = std::move(hrtf);
  e.air_absorption = air_absorption;
  e.air = air;
  e.channels = cfg.channels;
  e.max_voices = cfg.max_objects;
  e.max_block_frames = cfg.max_block_frames;
  e.max_active_modes = cfg.max_active_modes;
  e.reference_distance_m = cfg.reference_distance_m;
  e.min_distance_m = cfg.min_distance_m;
  e.max_contact_duration_s = cfg.max_contact_duration_s;
  e.contact_damping_per_s = cfg.contact_damping_per_s;
  e.realtime = true;
  e.ground.enabled = cfg.ground_reflects != 0;
  const double* n = cfg.ground_normal;
  const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  e.ground.normal = {n[0] / length, n[1] / length, n[2] / length};
  e.ground.height_m = cfg.ground_height_m;
  e.ground.reflection = cfg.ground_reflection;
  e.max_pending_impacts_per_voice = cfg.max_pending_impacts_per_object;
  return e;
}

/// strike_context_create with the output's format: from config->channels (mono or stereo), or
/// from a strike_output_desc. Each refusal is logged with the field and its value.
strike_status createContext(const strike_context_config* config, const strike_output_desc* output,
                            strike_context* out) {
  if (!config || !out) return STRIKE_ERR_INVALID_ARG;
  if (config->internal_cookie != kContextCookie) return STRIKE_ERR_NOT_INITIALIZED;
  const strike_context_config& c = *config;
  if (const std::string why = versionRefusal(c.api_version); !why.empty()) {
    logRejected(c, why);
    return STRIKE_ERR_VERSION;
  }
  OutputFormat format = OutputFormat::Mono;
  bool air_absorption = false;
  AirConditions air;
  std::string why = rejectedField(c);
  if (why.empty()) why = outputFormat(c, output, format);
  if (why.empty()) why = airFromOutput(output, air_absorption, air);
  std::shared_ptr<const HrtfSet> hrtf;
  if (why.empty() && format == OutputFormat::Binaural) {
    Result<std::shared_ptr<const HrtfSet>> copied = hrtfFromOutput(*output, c.sample_rate_hz);
    if (copied)
      hrtf = std::move(*copied);
    else
      why = copied.error().message;
  }
  if (!why.empty()) {
    logRejected(c, why);
    return STRIKE_ERR_INVALID_ARG;
  }
  strike_context_config cfg = c;
  if (!cfg.alloc) cfg.alloc = defaultAlloc, cfg.free = defaultFree;
  cfg.channels = outputChannels(format);  // what strike_render() checks

  void* mem = cfg.alloc(cfg.user, sizeof(strike_context_s), alignof(strike_context_s));
  if (!mem) return STRIKE_ERR_OUT_OF_MEMORY;
  strike_context ctx = nullptr;
  try {
    ctx = new (mem) strike_context_s();
    ctx->config = cfg;
    ctx->max_objects = cfg.max_objects;
    allocateQueuesAndSlots(ctx);
    ctx->engine_settings = engineSettings(cfg, format, std::move(hrtf), air_absorption, air);
    void* engine_mem = ctx->allocArray<SoundEngine>(1);
    try {
      ctx->engine = new (engine_mem) SoundEngine(ctx->engine_settings);
    } catch (...) {
      ctx->release(engine_mem);
      throw;
    }
  } catch (...) {
    strike_context_destroy(ctx);
    if (!ctx) cfg.free(cfg.user, mem);
    return STRIKE_ERR_OUT_OF_MEMORY;
  }
  *out = ctx;
  return STRIKE_OK;
}

}  // namespace

STRIKE_API strike_status STRIKE_CALL strike_context_create(const strike_context_config* config, strike_context* out) {
  return createContext(config, nullptr, out);
}

STRIKE_API strike_output_desc STRIKE_CALL strike_output_desc_default(void) {
  strike_output_desc d;
  std::memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.format = STRIKE_OUTPUT_MONO;
  d.air_absorption = 0;
  d.air_temperature_c = 20.0;
  d.air_relative_humidity_percent = 50.0;
  d.air_pressure_kpa = 101.325;
  return d;
}

STRIKE_API strike_status STRIKE_CALL strike_context_create_with_output(const strike_context_config* config,
                                                                       const strike_output_desc* output,
                                                                       strike_context* out) {
  if (!output) return STRIKE_ERR_INVALID_ARG;
  return createContext(config, output, out);
}

STRIKE_API void STRIKE_CALL strike_context_destroy(strike_context ctx) {
  if (!ctx) return;
  try {
    // The audio thread is stopped (contract), so every voice is ours to free: live ones via the
    // main slots, removed ones via the retired list.
    if (ctx->main_slots)
      for (uint32_t i = 0; i < ctx->max_objects; ++i)
        if (ctx->main_slots[i].used && ctx->main_slots[i].voice) {
          ctx->main_slots[i].voice->~Voice();
          ctx->release(ctx->main_slots[i].voice);
        }
    for (Retired& r : ctx->retired) {
      r.voice->~Voice();
      ctx->release(r.voice);
    }
    if (ctx->engine) {
      ctx->engine->~SoundEngine();
      ctx->release(ctx->engine);
    }
  } catch (...) {
  }
  ctx->release(ctx->impact_cells);
  ctx->release(ctx->step_cells);
  ctx->release(ctx->command_cells);
  ctx->release(ctx->live_generation);
  ctx->release(ctx->main_slots);
  ctx->release(ctx->audio_slots);
  const strike_free_fn free_fn = ctx->config.free;
  void* user = ctx->config.user;
  ctx->~strike_context_s();
  free_fn(user, ctx);
}

STRIKE_API const char* STRIKE_CALL strike_context_last_error(strike_context ctx) {
  return ctx ? ctx->last_error : "strike_context_last_error: NULL context";
}

STRIKE_API strike_status STRIKE_CALL strike_context_get_stats(strike_context ctx, strike_stats* out) {
  if (!ctx || !out) return STRIKE_ERR_INVALID_ARG;
  const uint32_t size = out->struct_size;
  if (size < offsetof(strike_stats, impacts_queued)) return STRIKE_ERR_INVALID_ARG;
  const Counters& k = ctx->counters;
  auto get = [](const std::atomic<uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  strike_stats s;
  std::memset(&s, 0, sizeof s);
  s.struct_size = static_cast<uint32_t>(std::min<size_t>(size, sizeof s));
  s.impacts_queued = get(k.queued);
  s.impacts_dropped_queue_full = get(k.dropped_full);
  s.impacts_dropped_stale = get(k.stale);
  s.impacts_dropped_capacity = get(k.capacity);
  s.impacts_scheduled = get(k.scheduled);
  s.impacts_inaudible = get(k.inaudible);
  s.modes_culled = get(k.culled);
  s.frames_rendered = get(k.frames);
  s.active_modes = k.active_modes.load(std::memory_order_relaxed);
  s.objects = k.objects.load(std::memory_order_relaxed);
  s.steps = get(k.steps);
  s.contacts_queued = get(k.contacts_queued);
  s.contacts_dropped_queue_full = get(k.contacts_dropped_full);
  s.contacts_dropped_stale = get(k.contacts_stale);
  s.sustained_contacts = get(k.sustained);
  s.load_changes = get(k.load_changes);
  s.load_holds = get(k.load_holds);
  s.clock_frames = get(k.clock_frames);
  s.continuous_contacts = get(k.continuous);
  s.continuous_dropped = get(k.continuous_dropped);
  std::memcpy(out, &s, s.struct_size);  // never past the caller's struct
  return STRIKE_OK;
}

STRIKE_API strike_status STRIKE_CALL strike_context_collect(strike_context ctx) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  return guarded(ctx, "strike_context_collect", [&]() -> strike_status {
    collect(ctx);
    return STRIKE_OK;
  });
}

STRIKE_API strike_status STRIKE_CALL strike_context_reset(strike_context ctx) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  return guarded(ctx, "strike_context_reset", [&]() -> strike_status {
    collect(ctx);
    Command cmd{};
    cmd.type = CommandType::Reset;
    cmd.impacts_mark = ctx->impacts.pushedCount();
    cmd.steps_mark = ctx->steps.pushedCount();
    if (!sendCommand(ctx, cmd)) return fail(ctx, STRIKE_ERR_QUEUE_FULL, "strike_context_reset: command queue full");
    ctx->last_error[0] = '\0';
    return STRIKE_OK;
  });
}

}  // extern "C"
