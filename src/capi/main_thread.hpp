// SPDX-License-Identifier: MIT
// libstrike's main thread, shared by the files of strike.h's main-thread half: strike.cpp (this
// file's definitions, the version and status strings), strike_context.cpp (create, destroy,
// stats, reset), strike_bank.cpp (loading banks and reading them) and strike_objects.cpp (objects
// and the listener). The configs' cookies, the error kept as last_error, the one exception
// boundary of each exported function, and the command queue to the audio thread.
#pragma once

#include <exception>
#include <new>

#include "capi_internal.hpp"
#include "strike/strike.h"

namespace strike::detail {

constexpr int32_t kContextCookie = 0x53544b43;  // "STKC"
constexpr int32_t kObjectCookie = 0x53544b4f;   // "STKO"

// Main-thread error: kept as last_error and sent to the log callback.
strike_status fail(strike_context ctx, strike_status status, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));

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
void collect(strike_context ctx);

/// Sends a command to the audio thread; false when the command queue is full.
bool sendCommand(strike_context ctx, const Command& c);

/// The main slot of a live object, or nullptr.
MainSlot* liveSlot(strike_context ctx, strike_object_id id);

}  // namespace strike::detail
