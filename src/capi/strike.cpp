// SPDX-License-Identifier: MIT
// libstrike, main-thread half: the extern "C" shims of strike.h for the context, banks and
// objects. The audio-thread half (impacts, physics steps, render) is strike_audio.cpp; the
// context's layout and the step queue's records are capi_internal.hpp. Every exported body sits
// in one guard that maps exceptions to status codes, so nothing throws across the ABI.
//
// Design (see strike.h for the thread contract):
//  - One engine: the context owns the SoundEngine that `strike render` runs (strike/engine.hpp):
//    the contact scheduler, the voices and the listener model. Only the audio thread touches it.
//  - Objects: each is a Voice (its oscillators, projector and contact state), built on the main
//    thread with all the memory it will use and handed to the audio thread by an Install
//    command through an SPSC command queue. Remove is a command too; the main thread frees the
//    voice only after the audio thread has acknowledged that command (commands_done), so the
//    audio thread never frees anything.
//  - Impacts and physics steps travel through bounded lock-free MPSC queues (ring.hpp) and are
//    applied at the start of each strike_render() (strike_audio.cpp).
#include "strike/strike.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "capi_internal.hpp"
#include "strike/synth.hpp"

namespace strike::detail {
namespace {

constexpr int32_t kContextCookie = 0x53544b43;  // "STKC"
constexpr int32_t kObjectCookie = 0x53544b4f;   // "STKO"

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

// Main-thread error: kept as last_error and sent to the log callback.
strike_status fail(strike_context ctx, strike_status status, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));
strike_status fail(strike_context ctx, strike_status status, const char* fmt, ...) {
  if (!ctx) return status;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(ctx->last_error, sizeof ctx->last_error, fmt, args);
  va_end(args);
  if (ctx->config.log) ctx->config.log(ctx->config.user, STRIKE_LOG_ERROR, ctx->last_error);
  return status;
}

// The one exception boundary of each exported function.
template <typename F>
strike_status guarded(strike_context ctx, const char* where, F&& body) noexcept {
  try {
    return body();
  } catch (const std::bad_alloc&) {
    return fail(ctx, STRIKE_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
  } catch (const std::exception& e) {
    return fail(ctx, STRIKE_ERR_INTERNAL, "%s: internal error: %s", where, e.what());
  } catch (...) {
    return fail(ctx, STRIKE_ERR_INTERNAL, "%s: internal error (unknown exception)", where);
  }
}

// Frees objects whose Remove command the audio thread has consumed.
void collect(strike_context ctx) {
  const uint64_t done = ctx->commands_done.load(std::memory_order_acquire);
  size_t kept = 0;
  for (Retired& r : ctx->retired) {
    if (r.command_seq <= done) {
      r.voice->~Voice();
      ctx->release(r.voice);
    } else {
      ctx->retired[kept++] = r;
    }
  }
  ctx->retired.resize(kept);
}

bool sendCommand(strike_context ctx, const Command& c) {
  if (!ctx->commands.push(c)) return false;
  ++ctx->commands_sent;
  return true;
}

MainSlot* liveSlot(strike_context ctx, strike_object_id id) {
  if (id.index >= ctx->max_objects || id.generation == 0) return nullptr;
  MainSlot& s = ctx->main_slots[id.index];
  return (s.used && s.generation == id.generation) ? &s : nullptr;
}

strike_status loadBank(strike_context ctx, const uint8_t* bytes, size_t size, const std::string& source,
                       strike_bank* out) {
  // Version first: a newer file gets VERSION, not PARSE (its layout may legitimately differ).
  if (size >= 12 && std::memcmp(bytes, "STRKBANK", 8) == 0) {
    uint32_t version = 0;
    for (int i = 0; i < 4; ++i) version |= static_cast<uint32_t>(bytes[8 + i]) << (8 * i);
    if (version > kBankFormatVersionMax)
      return fail(ctx, STRIKE_ERR_VERSION, "%s: mode bank format version %u is newer than this library reads (%u)",
                  source.c_str(), version, kBankFormatVersionMax);
  }
  Result<ModeBank> decoded = decodeBank(bytes, size, source);
  if (!decoded) return fail(ctx, STRIKE_ERR_PARSE, "%s", decoded.error().message.c_str());
  const std::string problem = decoded->checkConsistency();
  if (!problem.empty())
    return fail(ctx, STRIKE_ERR_PARSE, "%s: inconsistent mode bank: %s", source.c_str(), problem.c_str());
  auto loaded = std::make_shared<LoadedBank>();
  loaded->bank = std::move(decoded.value());
  // The output convention: pressure / output_full_scale_pa (1.0 = 20 Pa by default, as the tools);
  // the object's gain is applied apart.
  loaded->pressure_weights = pressureWeights(loaded->bank, ctx->config.reference_distance_m,
                                             outputPerPascal(1.0, ctx->config.output_full_scale_pa));
  void* mem = ctx->allocArray<strike_bank_s>(1);
  *out = new (mem) strike_bank_s{ctx, std::move(loaded), ctx->config.free, ctx->config.user};
  ctx->last_error[0] = '\0';
  return STRIKE_OK;
}

}  // namespace
}  // namespace strike::detail

using namespace strike;          // NOLINT: this file is the C shim over these namespaces
using namespace strike::detail;  // NOLINT

// ---- exported -----------------------------------------------------------------------------

extern "C" {

STRIKE_API uint32_t STRIKE_CALL strike_get_version(void) { return STRIKE_VERSION; }

STRIKE_API const char* STRIKE_CALL strike_status_string(strike_status status) {
  switch (status) {
    case STRIKE_OK: return "ok";
    case STRIKE_ERR_INVALID_ARG: return "invalid argument";
    case STRIKE_ERR_OUT_OF_MEMORY: return "out of memory";
    case STRIKE_ERR_VERSION: return "version mismatch";
    case STRIKE_ERR_IO: return "file could not be read";
    case STRIKE_ERR_PARSE: return "not a valid mode bank";
    case STRIKE_ERR_STALE_ID: return "stale or unknown object id";
    case STRIKE_ERR_QUEUE_FULL: return "queue full (dropped)";
    case STRIKE_ERR_CAPACITY: return "capacity reached";
    case STRIKE_ERR_TOO_MANY_FRAMES: return "more frames than max_block_frames";
    case STRIKE_ERR_NOT_INITIALIZED: return "config not initialized by its _default() function";
    case STRIKE_ERR_INTERNAL: return "internal error";
    default: return "unknown status";
  }
}

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

/// strike_context_create with the output's format: from config->channels (mono or stereo), or
/// from a strike_output_desc.
strike_status createContext(const strike_context_config* config, const strike_output_desc* output,
                            strike_context* out) {
  if (!config || !out) return STRIKE_ERR_INVALID_ARG;
  if (config->internal_cookie != kContextCookie) return STRIKE_ERR_NOT_INITIALIZED;
  const uint32_t caller = config->api_version;
  // Same major, and a caller no newer than us (IPL isVersionCompatible); before 1.0 the same
  // minor too, since a minor release may change the config structs' layout (0.3 grew this one).
  const uint32_t caller_minor = (caller >> 8) & 0xffu;
  if ((caller >> 16) != STRIKE_VERSION_MAJOR || caller_minor > STRIKE_VERSION_MINOR ||
      (STRIKE_VERSION_MAJOR == 0 && caller_minor != STRIKE_VERSION_MINOR)) {
    char why[160];
    std::snprintf(
        why, sizeof why, "api_version = %u.%u.%u (this library is %d.%d.%d: %s)", caller >> 16, caller_minor,
        caller & 0xffu, STRIKE_VERSION_MAJOR, STRIKE_VERSION_MINOR, STRIKE_VERSION_PATCH,
        STRIKE_VERSION_MAJOR == 0 ? "before 1.0 the minor versions must match" : "the major versions must match");
    logRejected(*config, why);
    return STRIKE_ERR_VERSION;
  }
  const strike_context_config& c = *config;
  if (const std::string why = rejectedField(c); !why.empty()) {
    logRejected(c, why);
    return STRIKE_ERR_INVALID_ARG;
  }
  strike_context_config cfg = c;
  if (!cfg.alloc) cfg.alloc = defaultAlloc, cfg.free = defaultFree;
  OutputFormat format = cfg.channels == 2 ? OutputFormat::Stereo : OutputFormat::Mono;
  if (output) {
    if (output->struct_size < offsetof(strike_output_desc, format) + sizeof output->format) {
      logRejected(c, "output: struct_size = " + std::to_string(output->struct_size) +
                         " (set it to sizeof(strike_output_desc))");
      return STRIKE_ERR_INVALID_ARG;
    }
    switch (output->format) {
      case STRIKE_OUTPUT_MONO: format = OutputFormat::Mono; break;
      case STRIKE_OUTPUT_STEREO: format = OutputFormat::Stereo; break;
      case STRIKE_OUTPUT_AMBIX1: format = OutputFormat::Ambix1; break;
      case STRIKE_OUTPUT_AMBIX2: format = OutputFormat::Ambix2; break;
      case STRIKE_OUTPUT_AMBIX3: format = OutputFormat::Ambix3; break;
      case STRIKE_OUTPUT_BINAURAL: format = OutputFormat::Binaural; break;
      default:
        logRejected(c, "output: format = " + std::to_string(output->format) + " (must be a STRIKE_OUTPUT_* value)");
        return STRIKE_ERR_INVALID_ARG;
    }
  }
  bool air_absorption = false;
  AirConditions air;
  if (output && output->struct_size >= offsetof(strike_output_desc, air_pressure_kpa) + sizeof(double) &&
      output->air_absorption != 0) {
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
    if (why[0]) {
      logRejected(c, why);
      return STRIKE_ERR_INVALID_ARG;
    }
  }
  std::shared_ptr<const HrtfSet> hrtf;
  if (format == OutputFormat::Binaural) {
    Result<std::shared_ptr<const HrtfSet>> copied = hrtfFromOutput(*output, c.sample_rate_hz);
    if (!copied) {
      logRejected(c, copied.error().message);
      return STRIKE_ERR_INVALID_ARG;
    }
    hrtf = std::move(*copied);
  }
  cfg.channels = outputChannels(format);  // what strike_render() checks

  void* mem = cfg.alloc(cfg.user, sizeof(strike_context_s), alignof(strike_context_s));
  if (!mem) return STRIKE_ERR_OUT_OF_MEMORY;
  strike_context ctx = nullptr;
  try {
    ctx = new (mem) strike_context_s();
    ctx->config = cfg;
    ctx->max_objects = cfg.max_objects;
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
    EngineSettings& e = ctx->engine_settings;
    e.synth.sample_rate_hz = cfg.sample_rate_hz;
    e.synth.min_freq_hz = cfg.min_freq_hz;
    e.synth.max_freq_hz = cfg.max_freq_hz;
    e.synth.audibility_threshold = cfg.audibility_threshold;
    e.output = format;
    e.hrtf = hrtf;
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
    void* engine_mem = ctx->allocArray<SoundEngine>(1);
    try {
      ctx->engine = new (engine_mem) SoundEngine(e);
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

STRIKE_API strike_status STRIKE_CALL strike_bank_load_file(strike_context ctx, const char* path, strike_bank* out) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  if (!path || !out) return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_bank_load_file: path and out must not be NULL");
  return guarded(ctx, "strike_bank_load_file", [&]() -> strike_status {
    collect(ctx);
    std::ifstream in(path, std::ios::binary);
    if (!in) return fail(ctx, STRIKE_ERR_IO, "%s: error: cannot open mode bank: %s", path, std::strerror(errno));
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) return fail(ctx, STRIKE_ERR_IO, "%s: error: read failed", path);
    return loadBank(ctx, bytes.data(), bytes.size(), path, out);
  });
}

STRIKE_API strike_status STRIKE_CALL strike_bank_load_memory(strike_context ctx, const void* data, size_t size,
                                                             strike_bank* out) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  if (!data || !out) return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_bank_load_memory: data and out must not be NULL");
  return guarded(ctx, "strike_bank_load_memory", [&]() -> strike_status {
    collect(ctx);
    return loadBank(ctx, static_cast<const uint8_t*>(data), size, "<memory>", out);
  });
}

STRIKE_API void STRIKE_CALL strike_bank_destroy(strike_bank bank) {
  if (!bank) return;
  const strike_free_fn free_fn = bank->free_fn;
  void* user = bank->user;
  bank->~strike_bank_s();
  free_fn(user, bank);
}

STRIKE_API strike_status STRIKE_CALL strike_bank_get_info(strike_bank bank, strike_bank_info* out) {
  if (!bank || !out) return STRIKE_ERR_INVALID_ARG;
  const uint32_t size = out->struct_size;
  if (size < offsetof(strike_bank_info, mode_count)) return STRIKE_ERR_INVALID_ARG;
  const ModeBank& b = bank->data->bank;
  strike_bank_info info;
  std::memset(&info, 0, sizeof info);
  info.struct_size = static_cast<uint32_t>(std::min<size_t>(size, sizeof info));
  info.mode_count = static_cast<uint32_t>(b.modeCount());
  info.surface_vertex_count = static_cast<uint32_t>(b.surfaceVertexCount());
  info.surface_triangle_count = static_cast<uint32_t>(b.surface_triangles.size() / 3);
  info.mass_kg = b.mass_kg;
  info.lowest_frequency_hz = b.modeCount() ? b.frequencyHz(0) : 0.0;
  for (int k = 0; k < 3; ++k) info.bounds_min_m[k] = HUGE_VAL, info.bounds_max_m[k] = -HUGE_VAL;
  for (size_t v = 0; v < b.surfaceVertexCount(); ++v)
    for (int k = 0; k < 3; ++k) {
      info.bounds_min_m[k] = std::min(info.bounds_min_m[k], b.surface_positions[3 * v + k]);
      info.bounds_max_m[k] = std::max(info.bounds_max_m[k], b.surface_positions[3 * v + k]);
    }
  if (b.surfaceVertexCount() == 0)
    for (int k = 0; k < 3; ++k) info.bounds_min_m[k] = info.bounds_max_m[k] = 0.0;
  info.volume_m3 = b.volume_m3;
  for (int k = 0; k < 3; ++k) info.centre_of_mass_m[k] = b.centre_m[k];
  for (int k = 0; k < 9; ++k) info.inertia_kg_m2[k] = b.inertia_kg_m2[k];
  const size_t nv = b.surfaceVertexCount();
  for (size_t t = 0; t + 2 < b.surface_triangles.size(); t += 3) {
    const uint32_t i0 = b.surface_triangles[t], i1 = b.surface_triangles[t + 1], i2 = b.surface_triangles[t + 2];
    if (i0 >= nv || i1 >= nv || i2 >= nv) continue;
    const double* p0 = &b.surface_positions[3 * i0];
    const double* p1 = &b.surface_positions[3 * i1];
    const double* p2 = &b.surface_positions[3 * i2];
    const double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]},
                 e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    const double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
                 cz = e1[0] * e2[1] - e1[1] * e2[0];
    info.surface_area_m2 += 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
  }
  info.equal_volume_radius_m = b.volume_m3 > 0.0 ? std::cbrt(3.0 * b.volume_m3 / (4.0 * M_PI)) : 0.0;
  std::snprintf(info.material_name, sizeof info.material_name, "%s", b.material.name.c_str());
  info.youngs_pa = b.material.youngs_pa;
  info.poisson = b.material.poisson;
  info.density_kg_m3 = b.material.density_kg_m3;
  info.rayleigh_stiffness_s = b.material.rayleigh_stiffness;
  info.rayleigh_mass_per_s = b.material.rayleigh_mass;
  std::memcpy(out, &info, info.struct_size);  // never past the caller's struct
  return STRIKE_OK;
}

STRIKE_API strike_status STRIKE_CALL strike_bank_mode_frequency(strike_bank bank, uint32_t mode, double* out_hz) {
  if (!bank || !out_hz || mode >= bank->data->bank.modeCount()) return STRIKE_ERR_INVALID_ARG;
  *out_hz = bank->data->bank.frequencyHz(mode);
  return STRIKE_OK;
}

STRIKE_API strike_status STRIKE_CALL strike_bank_surface_vertex(strike_bank bank, uint32_t vertex,
                                                                double out_position[3], double out_normal[3]) {
  if (!bank || vertex >= bank->data->bank.surfaceVertexCount()) return STRIKE_ERR_INVALID_ARG;
  const ModeBank& b = bank->data->bank;
  for (int k = 0; k < 3; ++k) {
    if (out_position) out_position[k] = b.surface_positions[3 * vertex + k];
    if (out_normal)
      out_normal[k] = b.surface_normals.size() == b.surface_positions.size() ? b.surface_normals[3 * vertex + k] : 0.0;
  }
  return STRIKE_OK;
}

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
