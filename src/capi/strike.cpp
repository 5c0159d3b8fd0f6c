// SPDX-License-Identifier: MIT
// libstrike, main-thread half: the extern "C" shims of strike.h for the context, banks and
// objects. The audio-thread half (impacts, physics steps, render) is strike_audio.cpp; the
// context's layout and the step queue's records are capi_internal.hpp. Every exported body sits
// in one guard that maps exceptions to status codes, so nothing throws across the ABI.
//
// Design (see strike.h for the thread contract):
//  - One engine: the context owns the SoundEngine that `strike render` runs (strike/synth/engine.hpp):
//    the contact scheduler, the voices and the listener model. Only the audio thread touches it.
//  - Objects: each is a Voice (its oscillators, projector and contact state), built on the main
//    thread with all the memory it will use and handed to the audio thread by an Install
//    command through an SPSC command queue. Remove is a command too; the main thread frees the
//    voice only after the audio thread has acknowledged that command (commands_done), so the
//    audio thread never frees anything.
//  - Impacts and physics steps travel through bounded lock-free MPSC queues (ring.hpp) and are
//    applied at the start of each strike_render() (strike_audio.cpp).
// The main-thread half is split by job: strike_context.cpp (the context's life), strike_bank.cpp
// (mode banks), strike_objects.cpp (objects and the listener), with their shared helpers in
// main_thread.hpp; this file holds those helpers and the version and status strings.
#include "strike/strike.h"

#include <cstdarg>
#include <cstdio>

#include "capi_internal.hpp"
#include "main_thread.hpp"

namespace strike::detail {

strike_status fail(strike_context ctx, strike_status status, const char* fmt, ...) {
  if (!ctx) return status;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(ctx->last_error, sizeof ctx->last_error, fmt, args);
  va_end(args);
  if (ctx->config.log) ctx->config.log(ctx->config.user, STRIKE_LOG_ERROR, ctx->last_error);
  return status;
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

}  // namespace strike::detail

using namespace strike;          // NOLINT: this file is the C shim over these namespaces
using namespace strike::detail;  // NOLINT

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

}  // extern "C"
