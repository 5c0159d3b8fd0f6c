// SPDX-License-Identifier: MIT
// libstrike: the extern "C" shims of strike.h over the oscillator bank (strike_synth) and the
// bank reader (strike_bank). Every exported body sits in one guard that maps exceptions to
// status codes, so nothing throws across the ABI.
//
// Design (see strike.h for the thread contract):
//  - Impacts: strike_impact() copies a POD strike_impact_desc into a bounded lock-free MPSC queue
//    (ring.hpp). strike_render() drains it at the start of each call and prepares every impact
//    on the audio thread into storage preallocated at strike_object_add(): projection onto the
//    modes (projectImpulseInto) and the pulse integration (OscillatorBank::addImpactNoAlloc over
//    reserved impact records). Doing it on the audio thread means a producer never touches an
//    object that the main thread may be removing; the cost is O(triangles + modes) per impact.
//  - Objects: each object owns one OscillatorBank (mono), built and reserved on the main thread
//    and handed to the audio thread by an Install command through an SPSC command queue. Remove
//    is a command too; the main thread frees the object only after the audio thread has
//    acknowledged that command (commands_done), so the audio thread never frees anything.
//  - Mixing: per object, mono output times a distance gain and a constant-power pan, ramped
//    linearly over the block when they change. Idle objects (nothing ringing or pending) are
//    skipped.
//  - Budget: when more than max_active_modes ring at the end of a call, a histogram of the
//    modes' squared levels at the listener (float bits, 1/16-octave bins of level^2) finds the
//    cut, and every mode at or below it is put to sleep: the quietest go first, and the whole
//    boundary bin (within 0.4 dB) goes, so the count lands at or just under the budget.
#include "strike/strike.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "ring.hpp"
#include "strike/bank.hpp"
#include "strike/synth.hpp"

namespace strike::detail {
namespace {

constexpr int32_t kContextCookie = 0x53544b43;  // "STKC"
constexpr int32_t kObjectCookie = 0x53544b4f;   // "STKO"
constexpr size_t kHistogramBins = 4096;         // float bits >> 19 of a non-negative float
constexpr size_t kErrorSize = 1024;

struct LoadedBank {
  ModeBank bank;
  std::vector<double> pressure_weights;  // radiationWeights at the reference distance
};

// World-from-object rigid transform.
struct Pose {
  double pos[3] = {0, 0, 0};
  double rot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
};

bool finite3(const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

bool makePose(const double* position, const double* quat, Pose& pose) {
  if (!position || !quat || !finite3(position) || !std::isfinite(quat[0]) || !finite3(quat + 1)) return false;
  const double n = std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
  if (!(n > 1e-12)) return false;
  const double w = quat[0] / n, x = quat[1] / n, y = quat[2] / n, z = quat[3] / n;
  const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                       2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  std::copy(position, position + 3, pose.pos);
  std::copy(r, r + 9, pose.rot);
  return true;
}

// R^T v: world direction into the object (or listener) frame.
void toLocal(const Pose& p, const double* v, double* out) {
  for (int i = 0; i < 3; ++i) out[i] = p.rot[0 + i] * v[0] + p.rot[3 + i] * v[1] + p.rot[6 + i] * v[2];
}

struct Voice {
  std::shared_ptr<const LoadedBank> data;
  OscillatorBank synth;
  std::vector<double> modal_impulse;  // #modes, projection scratch
  std::vector<float> mono;            // max_block_frames
  std::vector<float> levels;          // #modes, budget scratch
  double youngs = 0, poisson = 0, mass = 0, contact_radius = 0;
  // Audio-thread state.
  Pose pose;
  float gain = 1.0f;
  float cur_gain[2] = {0, 0};
  float target_gain[2] = {0, 0};
  float level_gain2 = 0;  // (gain * distance gain)^2 for the budget
  bool fresh = true;      // no ramp from zero on the first block

  explicit Voice(const SynthSettings& s) : synth(s) {}
};

enum class CommandType : uint32_t { Install, Remove, SetPose, SetGain, SetListener };

struct Command {
  CommandType type;
  uint32_t index;
  uint32_t generation;
  float gain;
  Voice* voice;
  Pose pose;
};

struct AudioSlot {
  Voice* voice;
  uint32_t generation;
};

struct MainSlot {
  Voice* voice;
  uint32_t generation;  // of the current or last occupant
  bool used;
};

struct Retired {
  Voice* voice;
  uint64_t command_seq;  // free once the audio thread has consumed this many commands
};

struct Counters {
  std::atomic<uint64_t> queued{0}, dropped_full{0}, stale{0}, capacity{0}, scheduled{0}, inaudible{0}, culled{0},
      frames{0};
  std::atomic<uint32_t> active_modes{0}, objects{0};
};

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

}  // namespace
}  // namespace strike::detail

using namespace strike;          // NOLINT: this file is the C shim over these namespaces
using namespace strike::detail;  // NOLINT

struct strike_context_s {
  strike_context_config config{};
  char last_error[kErrorSize] = {0};

  BoundedQueue<strike_impact_desc> impacts;
  BoundedQueue<strike_impact_desc>::Cell* impact_cells = nullptr;
  BoundedQueue<Command> commands;
  BoundedQueue<Command>::Cell* command_cells = nullptr;

  uint32_t max_objects = 0;
  std::atomic<uint32_t>* live_generation = nullptr;  // [any-thread] hint: 0 = not alive
  MainSlot* main_slots = nullptr;                    // main thread only
  AudioSlot* audio_slots = nullptr;                  // audio thread only
  uint32_t* histogram = nullptr;                     // audio thread only
  std::vector<Retired> retired;                      // main thread only
  uint64_t commands_sent = 0;                        // main thread only
  std::atomic<uint64_t> commands_done{0};            // written by the audio thread

  Pose listener;  // audio thread
  Counters counters;

  template <typename T>
  T* allocArray(size_t n) {
    void* p = config.alloc(config.user, n * sizeof(T), std::max<size_t>(alignof(T), 16));
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void release(void* p) {
    if (p) config.free(config.user, p);
  }
};

struct strike_bank_s {
  /// The context it was loaded in: compared (objects take banks of their own context only),
  /// never dereferenced, since a bank may outlive its context (strike.h).
  strike_context context;
  std::shared_ptr<const LoadedBank> data;
  /// The context's free function, copied: strike_bank_destroy after strike_context_destroy
  /// must not read the freed context.
  strike_free_fn free_fn;
  void* user;
};

namespace {

// Main-thread error: kept as last_error and sent to the log callback.
strike_status fail(strike_context ctx, strike_status status, const char* fmt, ...) __attribute__((format(printf, 3, 4)));
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
  if (!problem.empty()) return fail(ctx, STRIKE_ERR_PARSE, "%s: inconsistent mode bank: %s", source.c_str(), problem.c_str());
  auto loaded = std::make_shared<LoadedBank>();
  loaded->bank = std::move(decoded.value());
  loaded->pressure_weights = radiationWeights(loaded->bank, ctx->config.reference_distance_m);
  // The output convention: pressure / output_full_scale_pa (1.0 = 20 Pa by default, as the tools).
  for (double& w : loaded->pressure_weights) w /= ctx->config.output_full_scale_pa;
  void* mem = ctx->allocArray<strike_bank_s>(1);
  *out = new (mem) strike_bank_s{ctx, std::move(loaded), ctx->config.free, ctx->config.user};
  ctx->last_error[0] = '\0';
  return STRIKE_OK;
}

// ---- audio thread --------------------------------------------------------------------------

void applyCommand(strike_context ctx, const Command& c) {
  AudioSlot& slot = ctx->audio_slots[c.index < ctx->max_objects ? c.index : 0];
  switch (c.type) {
    case CommandType::Install:
      slot.voice = c.voice;
      slot.generation = c.generation;
      break;
    case CommandType::Remove:
      if (slot.generation == c.generation) slot.voice = nullptr;
      break;
    case CommandType::SetPose:
      if (slot.voice && slot.generation == c.generation) slot.voice->pose = c.pose;
      break;
    case CommandType::SetGain:
      if (slot.voice && slot.generation == c.generation) slot.voice->gain = c.gain;
      break;
    case CommandType::SetListener:
      ctx->listener = c.pose;
      break;
  }
}

void applyImpact(strike_context ctx, const strike_impact_desc& d) {
  const AudioSlot& slot = ctx->audio_slots[d.object.index < ctx->max_objects ? d.object.index : 0];
  Voice* v = (d.object.index < ctx->max_objects && slot.generation == d.object.generation) ? slot.voice : nullptr;
  if (!v) {
    ctx->counters.stale.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  const ModeBank& bank = v->data->bank;
  double point[3], impulse[3];
  if (d.frame == STRIKE_FRAME_WORLD) {
    const double rel[3] = {d.point[0] - v->pose.pos[0], d.point[1] - v->pose.pos[1], d.point[2] - v->pose.pos[2]};
    toLocal(v->pose, rel, point);
    toLocal(v->pose, d.impulse, impulse);
  } else {
    std::copy(d.point, d.point + 3, point);
    std::copy(d.impulse, d.impulse + 3, impulse);
  }
  if (d.surface_vertex >= 0) projectImpulseAtVertexInto(bank, static_cast<size_t>(d.surface_vertex), impulse, v->modal_impulse.data());
  else projectImpulseInto(bank, point, impulse, v->modal_impulse.data());

  double duration = d.contact_duration_s;
  if (duration < 0.0) {
    const double inf = HUGE_VAL;
    const double e2 = d.striker_youngs_pa > 0.0 ? d.striker_youngs_pa : v->youngs;
    const double nu2 = d.striker_youngs_pa > 0.0 ? d.striker_poisson : v->poisson;
    duration = hertzContactDuration(v->youngs, v->poisson, v->contact_radius > 0.0 ? v->contact_radius : inf,
                                    v->mass > 0.0 ? v->mass : inf, e2, nu2,
                                    d.striker_radius_m > 0.0 ? d.striker_radius_m : inf,
                                    d.striker_mass_kg > 0.0 ? d.striker_mass_kg : inf, d.normal_speed_m_s);
  }
  duration = std::min(duration, ctx->config.max_contact_duration_s);
  ImpactDesc desc;
  desc.object = 0;
  desc.time_s = v->synth.time() + static_cast<double>(d.sample_offset) / ctx->config.sample_rate_hz;
  desc.duration_s = duration;
  desc.modal_impulse = v->modal_impulse.data();
  desc.shape = d.pulse == STRIKE_PULSE_BOX ? PulseShape::Box : PulseShape::HalfSine;
  switch (v->synth.addImpactNoAlloc(desc)) {
    case ImpactResult::Scheduled: ctx->counters.scheduled.fetch_add(1, std::memory_order_relaxed); break;
    case ImpactResult::Inaudible: ctx->counters.inaudible.fetch_add(1, std::memory_order_relaxed); break;
    case ImpactResult::NoCapacity:
    case ImpactResult::BadObject: ctx->counters.capacity.fetch_add(1, std::memory_order_relaxed); break;
  }
}

void updateGains(strike_context ctx, Voice& v) {
  const Pose& l = ctx->listener;
  const double rel[3] = {v.pose.pos[0] - l.pos[0], v.pose.pos[1] - l.pos[1], v.pose.pos[2] - l.pos[2]};
  const double dist = std::sqrt(rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2]);
  const double ref = ctx->config.reference_distance_m;
  const double g = static_cast<double>(v.gain) * ref / std::max(dist, ref);
  v.level_gain2 = static_cast<float>(g * g);
  if (ctx->config.channels == 1) {
    v.target_gain[0] = static_cast<float>(g);
  } else {
    double local[3];
    toLocal(l, rel, local);
    const double pan = dist > 1e-9 ? std::clamp(local[0] / dist, -1.0, 1.0) : 0.0;
    const double theta = (pan + 1.0) * (M_PI / 4.0);  // constant power: gl^2 + gr^2 = g^2
    v.target_gain[0] = static_cast<float>(g * std::cos(theta));
    v.target_gain[1] = static_cast<float>(g * std::sin(theta));
  }
  if (v.fresh) {
    v.cur_gain[0] = v.target_gain[0], v.cur_gain[1] = v.target_gain[1];
    v.fresh = false;
  }
}

uint32_t histogramBin(float level2) {
  uint32_t bits;
  std::memcpy(&bits, &level2, sizeof bits);
  if (!(level2 > 0.0f)) return 0;
  return std::min<uint32_t>(bits >> 19, kHistogramBins - 1);  // monotonic for non-negative floats
}

void enforceBudget(strike_context ctx, uint64_t& active) {
  const uint32_t budget = ctx->config.max_active_modes;
  if (budget == 0 || active <= budget) return;
  uint32_t* hist = ctx->histogram;
  std::fill(hist, hist + kHistogramBins, 0u);
  for (uint32_t i = 0; i < ctx->max_objects; ++i) {
    Voice* v = ctx->audio_slots[i].voice;
    if (!v) continue;
    const size_t n = v->synth.activeModeLevels(v->levels.data(), v->levels.size());
    for (size_t k = 0; k < n; ++k) ++hist[histogramBin(v->levels[k] * v->level_gain2)];
  }
  // Keep the loudest bins while they fit; cull the first bin that does not, and all below it.
  uint64_t kept = 0;
  size_t cut = kHistogramBins;
  for (size_t b = kHistogramBins; b-- > 0;) {
    if (kept + hist[b] > budget) {
      cut = b;
      break;
    }
    kept += hist[b];
  }
  if (cut == kHistogramBins) return;
  // Largest float in bin `cut`; +inf (cull all) for the top bin.
  const uint32_t top_bits = static_cast<uint32_t>((cut + 1) << 19) - 1u;
  float threshold;
  std::memcpy(&threshold, &top_bits, sizeof threshold);
  if (cut == kHistogramBins - 1) threshold = HUGE_VALF;
  uint64_t culled = 0;
  active = 0;
  for (uint32_t i = 0; i < ctx->max_objects; ++i) {
    Voice* v = ctx->audio_slots[i].voice;
    if (!v) continue;
    culled += v->synth.sleepModesAtOrBelow(threshold, v->level_gain2);
    active += v->synth.activeModeCount();
  }
  ctx->counters.culled.fetch_add(culled, std::memory_order_relaxed);
}

}  // namespace

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
  c.reference_distance_m = 1.0;
  c.internal_cookie = kContextCookie;
  c.output_full_scale_pa = kFullScalePascal;
  return c;
}

STRIKE_API strike_status STRIKE_CALL strike_context_create(const strike_context_config* config, strike_context* out) {
  if (!config || !out) return STRIKE_ERR_INVALID_ARG;
  if (config->internal_cookie != kContextCookie) return STRIKE_ERR_NOT_INITIALIZED;
  const uint32_t caller = config->api_version;
  // Same major, and a caller no newer than us (IPL isVersionCompatible); before 1.0 the same
  // minor too, since a minor release may change the config structs' layout (0.2 grew this one).
  const uint32_t caller_minor = (caller >> 8) & 0xffu;
  if ((caller >> 16) != STRIKE_VERSION_MAJOR || caller_minor > STRIKE_VERSION_MINOR ||
      (STRIKE_VERSION_MAJOR == 0 && caller_minor != STRIKE_VERSION_MINOR))
    return STRIKE_ERR_VERSION;
  const strike_context_config& c = *config;
  const bool valid = c.sample_rate_hz >= 8000.0 && c.sample_rate_hz <= 768000.0 && c.max_block_frames >= 1 &&
                     c.max_block_frames <= 16384 && (c.channels == 1 || c.channels == 2) && c.max_objects >= 1 &&
                     c.max_objects <= 65536 && c.impact_queue_capacity >= 2 && c.impact_queue_capacity <= (1u << 20) &&
                     c.max_pending_impacts_per_object >= 1 && c.max_pending_impacts_per_object <= 4096 &&
                     c.max_contact_duration_s >= 0.0 && c.max_contact_duration_s <= 1.0 && c.min_freq_hz >= 0.0 &&
                     c.max_freq_hz > c.min_freq_hz && std::isfinite(c.max_freq_hz) && c.audibility_threshold >= 0.0 &&
                     std::isfinite(c.audibility_threshold) && c.reference_distance_m > 0.0 &&
                     std::isfinite(c.reference_distance_m) && c.output_full_scale_pa > 0.0 &&
                     std::isfinite(c.output_full_scale_pa) && (c.alloc == nullptr) == (c.free == nullptr);
  if (!valid) return STRIKE_ERR_INVALID_ARG;
  strike_context_config cfg = c;
  if (!cfg.alloc) cfg.alloc = defaultAlloc, cfg.free = defaultFree;

  void* mem = cfg.alloc(cfg.user, sizeof(strike_context_s), alignof(strike_context_s));
  if (!mem) return STRIKE_ERR_OUT_OF_MEMORY;
  strike_context ctx = nullptr;
  try {
    ctx = new (mem) strike_context_s();
    ctx->config = cfg;
    ctx->max_objects = cfg.max_objects;
    const uint32_t impact_cap = nextPow2(cfg.impact_queue_capacity);
    const uint32_t command_cap = nextPow2(4 * cfg.max_objects + 256);
    ctx->impact_cells = ctx->allocArray<BoundedQueue<strike_impact_desc>::Cell>(impact_cap);
    ctx->impacts.init(ctx->impact_cells, impact_cap);
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
    ctx->histogram = ctx->allocArray<uint32_t>(kHistogramBins);
    ctx->retired.reserve(cfg.max_objects);
  } catch (...) {
    strike_context_destroy(ctx);
    if (!ctx) cfg.free(cfg.user, mem);
    return STRIKE_ERR_OUT_OF_MEMORY;
  }
  *out = ctx;
  return STRIKE_OK;
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
  } catch (...) {
  }
  ctx->release(ctx->impact_cells);
  ctx->release(ctx->command_cells);
  ctx->release(ctx->live_generation);
  ctx->release(ctx->main_slots);
  ctx->release(ctx->audio_slots);
  ctx->release(ctx->histogram);
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
  const Counters& k = ctx->counters;
  strike_stats s;
  std::memset(&s, 0, sizeof s);
  s.impacts_queued = k.queued.load(std::memory_order_relaxed);
  s.impacts_dropped_queue_full = k.dropped_full.load(std::memory_order_relaxed);
  s.impacts_dropped_stale = k.stale.load(std::memory_order_relaxed);
  s.impacts_dropped_capacity = k.capacity.load(std::memory_order_relaxed);
  s.impacts_scheduled = k.scheduled.load(std::memory_order_relaxed);
  s.impacts_inaudible = k.inaudible.load(std::memory_order_relaxed);
  s.modes_culled = k.culled.load(std::memory_order_relaxed);
  s.frames_rendered = k.frames.load(std::memory_order_relaxed);
  s.active_modes = k.active_modes.load(std::memory_order_relaxed);
  s.objects = k.objects.load(std::memory_order_relaxed);
  *out = s;
  return STRIKE_OK;
}

STRIKE_API strike_status STRIKE_CALL strike_context_collect(strike_context ctx) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  return guarded(ctx, "strike_context_collect", [&]() -> strike_status {
    collect(ctx);
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
  const ModeBank& b = bank->data->bank;
  strike_bank_info info;
  std::memset(&info, 0, sizeof info);
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
  *out = info;
  return STRIKE_OK;
}

STRIKE_API strike_status STRIKE_CALL strike_bank_mode_frequency(strike_bank bank, uint32_t mode, double* out_hz) {
  if (!bank || !out_hz || mode >= bank->data->bank.modeCount()) return STRIKE_ERR_INVALID_ARG;
  *out_hz = bank->data->bank.frequencyHz(mode);
  return STRIKE_OK;
}

STRIKE_API strike_status STRIKE_CALL strike_bank_surface_vertex(strike_bank bank, uint32_t vertex, double out_position[3],
                                                                double out_normal[3]) {
  if (!bank || vertex >= bank->data->bank.surfaceVertexCount()) return STRIKE_ERR_INVALID_ARG;
  const ModeBank& b = bank->data->bank;
  for (int k = 0; k < 3; ++k) {
    if (out_position) out_position[k] = b.surface_positions[3 * vertex + k];
    if (out_normal) out_normal[k] = b.surface_normals.size() == b.surface_positions.size() ? b.surface_normals[3 * vertex + k] : 0.0;
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
  return c;
}

STRIKE_API strike_status STRIKE_CALL strike_object_add(strike_context ctx, const strike_object_config* config,
                                                       strike_object_id* out) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  if (!config || !out) return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: config and out must not be NULL");
  if (config->internal_cookie != kObjectCookie)
    return fail(ctx, STRIKE_ERR_NOT_INITIALIZED, "strike_object_add: config did not come from strike_object_config_default()");
  return guarded(ctx, "strike_object_add", [&]() -> strike_status {
    collect(ctx);
    const strike_object_config& c = *config;
    if (!c.bank || c.bank->context != ctx)
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: bank is NULL or from another context");
    Pose pose;
    if (!makePose(c.position, c.orientation, pose))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: position/orientation not finite, or orientation is a zero quaternion");
    if (!(c.gain >= 0.0f) || !std::isfinite(c.gain))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: gain = %g (must be finite and >= 0)", static_cast<double>(c.gain));
    if (c.radiation != STRIKE_RADIATION_PRESSURE && c.radiation != STRIKE_RADIATION_UNIT)
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: radiation = %d (must be STRIKE_RADIATION_PRESSURE or _UNIT)", c.radiation);
    if (!(c.contact_radius_m >= 0.0) || !std::isfinite(c.contact_radius_m))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_add: contact_radius_m = %g (must be >= 0)", c.contact_radius_m);
    uint32_t index = ctx->max_objects;
    for (uint32_t i = 0; i < ctx->max_objects; ++i)
      if (!ctx->main_slots[i].used) {
        index = i;
        break;
      }
    if (index == ctx->max_objects)
      return fail(ctx, STRIKE_ERR_CAPACITY, "strike_object_add: max_objects = %u objects are alive", ctx->max_objects);

    const std::shared_ptr<const LoadedBank>& data = c.bank->data;
    const ModeBank& bank = data->bank;
    SynthSettings s;
    s.sample_rate_hz = ctx->config.sample_rate_hz;
    s.min_freq_hz = ctx->config.min_freq_hz;
    s.max_freq_hz = ctx->config.max_freq_hz;
    s.audibility_threshold = ctx->config.audibility_threshold;
    void* mem = ctx->allocArray<Voice>(1);
    Voice* v = nullptr;
    try {
      v = new (mem) Voice(s);
      v->data = data;
      ModalObjectDesc desc;
      desc.eigenvalues = bank.eigenvalues;
      desc.rayleigh_stiffness = bank.material.rayleigh_stiffness;
      desc.rayleigh_mass = bank.material.rayleigh_mass;
      desc.radiation_weight = c.radiation == STRIKE_RADIATION_PRESSURE ? data->pressure_weights
                                                                        : std::vector<double>(bank.modeCount(), 1.0);
      v->synth.addObject(desc);
      v->synth.reserveImpacts(ctx->config.max_pending_impacts_per_object, ctx->config.max_contact_duration_s);
      v->modal_impulse.assign(bank.modeCount(), 0.0);
      v->levels.assign(bank.modeCount() + 1, 0.0f);
      v->mono.assign(ctx->config.max_block_frames, 0.0f);
      v->youngs = bank.material.youngs_pa;
      v->poisson = bank.material.poisson;
      v->mass = bank.mass_kg;
      v->contact_radius = c.contact_radius_m;
      v->pose = pose;
      v->gain = c.gain;
    } catch (...) {
      if (v) v->~Voice();
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
    if (!slot) return fail(ctx, STRIKE_ERR_STALE_ID, "strike_object_remove: object {%u, %u} is not alive", id.index, id.generation);
    Command cmd{};
    cmd.type = CommandType::Remove;
    cmd.index = id.index;
    cmd.generation = id.generation;
    ctx->retired.reserve(ctx->retired.size() + 1);  // before the point of no return
    if (!sendCommand(ctx, cmd))
      return fail(ctx, STRIKE_ERR_QUEUE_FULL, "strike_object_remove: command queue full (is the audio thread rendering?)");
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

STRIKE_API strike_status STRIKE_CALL strike_object_set_pose(strike_context ctx, strike_object_id id, const double position[3],
                                                            const double orientation[4]) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  return guarded(ctx, "strike_object_set_pose", [&]() -> strike_status {
    collect(ctx);
    if (!liveSlot(ctx, id)) return fail(ctx, STRIKE_ERR_STALE_ID, "strike_object_set_pose: object {%u, %u} is not alive", id.index, id.generation);
    Command cmd{};
    cmd.type = CommandType::SetPose;
    cmd.index = id.index;
    cmd.generation = id.generation;
    if (!makePose(position, orientation, cmd.pose))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_set_pose: NULL, non-finite, or zero quaternion");
    if (!sendCommand(ctx, cmd)) return fail(ctx, STRIKE_ERR_QUEUE_FULL, "strike_object_set_pose: command queue full");
    return STRIKE_OK;
  });
}

STRIKE_API strike_status STRIKE_CALL strike_object_set_gain(strike_context ctx, strike_object_id id, float gain) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  return guarded(ctx, "strike_object_set_gain", [&]() -> strike_status {
    collect(ctx);
    if (!liveSlot(ctx, id)) return fail(ctx, STRIKE_ERR_STALE_ID, "strike_object_set_gain: object {%u, %u} is not alive", id.index, id.generation);
    if (!(gain >= 0.0f) || !std::isfinite(gain))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_object_set_gain: gain = %g (must be finite and >= 0)", static_cast<double>(gain));
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
    if (!makePose(position, orientation, cmd.pose))
      return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_listener_set_pose: NULL, non-finite, or zero quaternion");
    if (!sendCommand(ctx, cmd)) return fail(ctx, STRIKE_ERR_QUEUE_FULL, "strike_listener_set_pose: command queue full");
    return STRIKE_OK;
  });
}

STRIKE_API strike_impact_desc STRIKE_CALL strike_impact_desc_default(void) {
  strike_impact_desc d;
  std::memset(&d, 0, sizeof d);
  d.frame = STRIKE_FRAME_OBJECT;
  d.surface_vertex = -1;
  d.normal_speed_m_s = 1.0;
  d.contact_duration_s = -1.0;
  d.striker_radius_m = 0.01;
  d.striker_poisson = 0.3;
  d.pulse = STRIKE_PULSE_HALF_SINE;
  return d;
}

STRIKE_API strike_status STRIKE_CALL strike_impact(strike_context ctx, const strike_impact_desc* impact) {
  // No allocation and nothing that throws: no guard needed, and none wanted on this path.
  if (!ctx || !impact) return STRIKE_ERR_INVALID_ARG;
  const strike_impact_desc& d = *impact;
  if (!finite3(d.point) || !finite3(d.impulse) || !std::isfinite(d.normal_speed_m_s) ||
      !std::isfinite(d.contact_duration_s) || !std::isfinite(d.striker_radius_m) || !std::isfinite(d.striker_youngs_pa) ||
      !std::isfinite(d.striker_poisson) || !std::isfinite(d.striker_mass_kg) ||
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

STRIKE_API strike_status STRIKE_CALL strike_render(strike_context ctx, float* const* out, uint32_t channels, uint32_t frames) {
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
    // 2. Impacts, at most max_impacts_per_render (and one queue's worth) so that a flood
    //    cannot stall this call; the rest stay queued, in order, for the next one.
    strike_impact_desc d;
    size_t budget = ctx->impacts.capacity();
    if (ctx->config.max_impacts_per_render > 0) budget = std::min<size_t>(budget, ctx->config.max_impacts_per_render);
    for (size_t k = budget; k > 0 && ctx->impacts.pop(d); --k) applyImpact(ctx, d);
    // 3. Render and mix.
    for (uint32_t c = 0; c < channels; ++c) std::fill(out[c], out[c] + frames, 0.0f);
    uint64_t active = 0;
    uint32_t objects = 0;
    for (uint32_t i = 0; i < ctx->max_objects; ++i) {
      Voice* v = ctx->audio_slots[i].voice;
      if (!v) continue;
      ++objects;
      updateGains(ctx, *v);
      if (frames == 0) continue;
      if (v->synth.idle()) {
        v->cur_gain[0] = v->target_gain[0], v->cur_gain[1] = v->target_gain[1];
        continue;
      }
      v->synth.render(v->mono.data(), frames);
      const float inv = 1.0f / static_cast<float>(frames);
      for (uint32_t c = 0; c < channels; ++c) {
        const float g0 = v->cur_gain[c], dg = (v->target_gain[c] - g0) * inv;
        float* o = out[c];
        const float* m = v->mono.data();
        if (dg == 0.0f) {
          for (uint32_t n = 0; n < frames; ++n) o[n] += g0 * m[n];
        } else {
          for (uint32_t n = 0; n < frames; ++n) o[n] += (g0 + dg * static_cast<float>(n + 1)) * m[n];
        }
        v->cur_gain[c] = v->target_gain[c];
      }
      active += v->synth.activeModeCount();
    }
    // 4. Budget of ringing modes.
    enforceBudget(ctx, active);
    ctx->counters.active_modes.store(static_cast<uint32_t>(std::min<uint64_t>(active, UINT32_MAX)), std::memory_order_relaxed);
    ctx->counters.objects.store(objects, std::memory_order_relaxed);
    ctx->counters.frames.fetch_add(frames, std::memory_order_relaxed);
    return STRIKE_OK;
  } catch (...) {
    return STRIKE_ERR_INTERNAL;
  }
}

}  // extern "C"
