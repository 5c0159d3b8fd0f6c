// SPDX-License-Identifier: MIT
#include "strike/interrupt_cleanup.hpp"

#include <signal.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstring>

namespace strike {

namespace {

struct TemporarySlot {
  /// 0 free, 1 being filled or emptied, 2 holds a path the handler may unlink.
  std::atomic<int> state{0};
  char path[4096] = {};
};

std::array<TemporarySlot, 64> g_temporary_slots;  // outputs in progress, per process

void strikeInterruptHandler(int signal_number) {
  for (TemporarySlot& slot : g_temporary_slots)
    if (slot.state.load(std::memory_order_acquire) == 2) ::unlink(slot.path);
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

}  // namespace

int registerTemporary(const std::string& path) {
  if (path.size() >= sizeof(TemporarySlot::path)) return -1;
  for (size_t i = 0; i < g_temporary_slots.size(); ++i) {
    TemporarySlot& slot = g_temporary_slots[i];
    int expected = 0;
    if (!slot.state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) continue;
    std::memcpy(slot.path, path.c_str(), path.size() + 1);
    slot.state.store(2, std::memory_order_release);
    return static_cast<int>(i);
  }
  return -1;
}

void unregisterTemporary(int slot_number) {
  if (slot_number < 0 || static_cast<size_t>(slot_number) >= g_temporary_slots.size()) return;
  TemporarySlot& slot = g_temporary_slots[static_cast<size_t>(slot_number)];
  slot.state.store(1, std::memory_order_release);
  slot.path[0] = '\0';
  slot.state.store(0, std::memory_order_release);
}

void installInterruptCleanup() {
  for (int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction current {};
    if (::sigaction(signal_number, nullptr, &current) == 0 && current.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = strikeInterruptHandler;
    sigemptyset(&action.sa_mask);
    action.sa_flags = 0;
    ::sigaction(signal_number, &action, nullptr);
  }
}

}  // namespace strike
