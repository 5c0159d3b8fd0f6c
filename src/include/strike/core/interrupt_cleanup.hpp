// SPDX-License-Identifier: MIT
// Nothing half-written survives an interrupted run. Writers of outputs register the temporary file
// they are filling (writeFileAtomically, the audio writer); a program that wants it installs the
// handler (the `strike` CLI does), which on SIGINT, SIGTERM or SIGHUP unlinks every registered
// temporary with async-signal-safe calls only, then re-raises the signal with its default action
// so that the exit status still says what happened.
//
// The registry is process-global state, so it lives in strike_output (src/core), which programs
// link and libstrike does not: a game or plugin loading libstrike gets no globals and no signal
// handling from us (tests/capi checks libstrike's symbols).
#pragma once

#include <string>

namespace strike {

/// Registers `path` for removal on interruption; returns a slot number for unregisterTemporary,
/// or -1 when the path is too long or all slots are taken (then it is merely not cleaned up).
int registerTemporary(const std::string& path);

/// Forgets a slot from registerTemporary (after the rename, or after removing the file).
void unregisterTemporary(int slot_number);

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

/// The one line the handler writes to stderr when it is interrupted (a newline is added; at most
/// 1023 bytes kept), e.g. "strike render: interrupted during simulate; nothing was written" (a
/// program that draws a progress line on a terminal starts it with "\r\033[K" to clear that).
/// Empty: nothing is said. Copied into a fixed buffer, so the handler reads it without allocating.
void setInterruptMessage(const std::string& line);

/// Installs the cleanup handler for SIGINT, SIGTERM and SIGHUP (not where they are ignored, as
/// under nohup). Call once, early in main.
void installInterruptCleanup();

}  // namespace strike
