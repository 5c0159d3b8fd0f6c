// SPDX-License-Identifier: MIT
#include "strike/core/interrupt_cleanup.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
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

// The interruption's message, in two buffers: a writer fills the one the handler does not read,
// then points the handler at it, so the handler never sees a half-written line.
struct InterruptMessage {
  char line[2][1024] = {};
  std::atomic<int> current{0};
};
InterruptMessage g_interrupt_message;

void strikeInterruptHandler(int signal_number) {
  for (TemporarySlot& slot : g_temporary_slots)
    if (slot.state.load(std::memory_order_acquire) == 2) ::unlink(slot.path);
  const char* line = g_interrupt_message.line[g_interrupt_message.current.load(std::memory_order_acquire)];
  const size_t length = std::strlen(line);
  if (length > 0) {
    ssize_t ignored = ::write(STDERR_FILENO, line, length);
    ignored = ::write(STDERR_FILENO, "\n", 1);
    (void)ignored;
  }
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

void setInterruptMessage(const std::string& line) {
  const int next = 1 - g_interrupt_message.current.load(std::memory_order_acquire);
  char* buffer = g_interrupt_message.line[next];
  const size_t length = std::min(line.size(), sizeof g_interrupt_message.line[0] - 1);
  std::memcpy(buffer, line.data(), length);
  buffer[length] = '\0';
  g_interrupt_message.current.store(next, std::memory_order_release);
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
