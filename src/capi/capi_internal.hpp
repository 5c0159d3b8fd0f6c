// SPDX-License-Identifier: MIT
// libstrike's context: the sound engine (strike/synth/engine.hpp) that `strike render` also runs, owned
// by the audio thread, and the lock-free queues that carry the main thread's commands and any
// thread's impacts and physics steps to it. Shared by the main thread's files
// (strike.cpp, strike_context.cpp, strike_bank.cpp, strike_objects.cpp) and strike_audio.cpp
// (impacts, steps, render).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <variant>
#include <vector>

#include "ring.hpp"
#include "strike/bank/bank.hpp"
#include "strike/synth/engine.hpp"
#include "strike/strike.h"

namespace strike::detail {

constexpr size_t kErrorSize = 1024;

struct LoadedBank {
  ModeBank bank;
  std::vector<double> pressure_weights;  ///< radiationWeights at the reference distance, / full scale
};

enum class CommandType : uint32_t { Install, Remove, SetPose, SetGain, SetListener, Reset };

struct Command {
  CommandType type;
  uint32_t index;
  uint32_t generation;
  float gain;
  Voice* voice;
  Pose pose;
  /// Reset: the impact and step queues' push counts when it was sent; it drops what came before
  /// these marks and keeps what came after (reported after strike_context_reset() returned).
  size_t impacts_mark;
  size_t steps_mark;
};

/// The records of a physics step in the step queue, typed: its start, a body's state, one
/// contact (the sound engine's own record, filled from strike_contact when it is queued; only the
/// object ids wait for the audio thread to name their voices), its end.
struct StepBegin {
  double end_time_s;
  double duration_s;
};
struct StepBodyState {
  strike_object_id object;
  double position[3];
  double orientation[4];
  bool asleep;
};
struct StepContact {
  strike_object_id object;
  strike_object_id partner;  ///< {0, 0}: not an object (contact.partner is the partner then)
  EngineContact contact;     ///< voice and partner.voice set on the audio thread
};
struct StepEnd {};
using StepRecord = std::variant<StepBegin, StepBodyState, StepContact, StepEnd>;

struct AudioSlot {
  Voice* voice;
  uint32_t generation;
};

struct MainSlot {
  Voice* voice;
  uint32_t generation;  ///< of the current or last occupant
  bool used;
};

struct Retired {
  Voice* voice;
  uint64_t command_seq;  ///< free once the audio thread has consumed this many commands
};

struct Counters {
  std::atomic<uint64_t> queued{0}, dropped_full{0}, stale{0}, capacity{0}, scheduled{0}, inaudible{0}, culled{0},
      frames{0}, steps{0}, contacts_queued{0}, contacts_dropped_full{0}, contacts_stale{0}, sustained{0},
      load_changes{0}, load_holds{0}, clock_frames{0}, continuous{0}, continuous_dropped{0};
  std::atomic<uint32_t> active_modes{0}, objects{0};
};

}  // namespace strike::detail

struct strike_context_s {
  strike_context_config config{};
  char last_error[strike::detail::kErrorSize] = {0};

  strike::detail::BoundedQueue<strike_impact_desc> impacts;
  strike::detail::BoundedQueue<strike_impact_desc>::Cell* impact_cells = nullptr;
  strike::detail::BoundedQueue<strike::detail::StepRecord> steps;
  strike::detail::BoundedQueue<strike::detail::StepRecord>::Cell* step_cells = nullptr;
  strike::detail::BoundedQueue<strike::detail::Command> commands;
  strike::detail::BoundedQueue<strike::detail::Command>::Cell* command_cells = nullptr;

  uint32_t max_objects = 0;
  std::atomic<uint32_t>* live_generation = nullptr;  ///< [any-thread] hint: 0 = not alive
  strike::detail::MainSlot* main_slots = nullptr;    ///< main thread only
  strike::detail::AudioSlot* audio_slots = nullptr;  ///< audio thread only
  std::vector<strike::detail::Retired> retired;      ///< main thread only
  uint64_t commands_sent = 0;                        ///< main thread only
  std::atomic<uint64_t> commands_done{0};            ///< written by the audio thread

  strike::EngineSettings engine_settings;
  strike::SoundEngine* engine = nullptr;  ///< audio thread (built and freed on the main thread)
  uint64_t engine_stale_seen = 0;         ///< audio thread: engine stats already counted
  strike::detail::Counters counters;

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
  std::shared_ptr<const strike::detail::LoadedBank> data;
  /// The context's free function, copied: strike_bank_destroy after strike_context_destroy
  /// must not read the freed context.
  strike_free_fn free_fn;
  void* user;
};
