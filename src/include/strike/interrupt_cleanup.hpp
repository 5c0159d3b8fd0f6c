// SPDX-License-Identifier: MIT
// Nothing half-written survives an interrupted run. Writers of outputs register the temporary file
// they are filling (writeFileAtomically, the audio writer); a program that wants it installs the
// handler (the `strike` CLI does), which on SIGINT, SIGTERM or SIGHUP unlinks every registered
// temporary with async-signal-safe calls only, then re-raises the signal with its default action
// so that the exit status still says what happened.
//
// Header-only on purpose: the registry is one C++17 inline variable shared by every library that
// includes this, so strike_sndfile and strike_bank need no common link dependency.
#pragma once

#include <signal.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstring>
#include <string>

namespace strike {

namespace detail {

struct TemporarySlot {
  /// 0 free, 1 being filled or emptied, 2 holds a path the handler may unlink.
  std::atomic<int> state{0};
  char path[4096] = {};
};

inline std::array<TemporarySlot, 64> g_temporary_slots;  // outputs in progress, per process

inline void strikeInterruptHandler(int signal_number) {
  for (TemporarySlot& slot : g_temporary_slots)
    if (slot.state.load(std::memory_order_acquire) == 2) ::unlink(slot.path);
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

}  // namespace detail

/// Registers `path` for removal on interruption; returns a slot number for unregisterTemporary,
/// or -1 when the path is too long or all slots are taken (then it is merely not cleaned up).
inline int registerTemporary(const std::string& path) {
  if (path.size() >= sizeof(detail::TemporarySlot::path)) return -1;
  for (size_t i = 0; i < detail::g_temporary_slots.size(); ++i) {
    detail::TemporarySlot& slot = detail::g_temporary_slots[i];
    int expected = 0;
    if (!slot.state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) continue;
    std::memcpy(slot.path, path.c_str(), path.size() + 1);
    slot.state.store(2, std::memory_order_release);
    return static_cast<int>(i);
  }
  return -1;
}

/// Forgets a slot from registerTemporary (after the rename, or after removing the file).
inline void unregisterTemporary(int slot_number) {
  if (slot_number < 0 || static_cast<size_t>(slot_number) >= detail::g_temporary_slots.size()) return;
  detail::TemporarySlot& slot = detail::g_temporary_slots[static_cast<size_t>(slot_number)];
  slot.state.store(1, std::memory_order_release);
  slot.path[0] = '\0';
  slot.state.store(0, std::memory_order_release);
}

/// RAII form: registers on construction, unregisters on destruction.
class TemporaryRegistration {
 public:
  explicit TemporaryRegistration(const std::string& path) : slot_(registerTemporary(path)) {}
  ~TemporaryRegistration() { unregisterTemporary(slot_); }
  TemporaryRegistration(const TemporaryRegistration&) = delete;
  TemporaryRegistration& operator=(const TemporaryRegistration&) = delete;

 private:
  int slot_;
};

/// Installs the cleanup handler for SIGINT, SIGTERM and SIGHUP (not where they are ignored, as
/// under nohup). Call once, early in main.
inline void installInterruptCleanup() {
  for (int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction current {};
    if (::sigaction(signal_number, nullptr, &current) == 0 && current.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = detail::strikeInterruptHandler;
    sigemptyset(&action.sa_mask);
    action.sa_flags = 0;
    ::sigaction(signal_number, &action, nullptr);
  }
}

}  // namespace strike
