// SPDX-License-Identifier: MIT
// writeBank: a bank to a file, atomically. Its own target (strike_bank_writer) because atomic
// writes come with the interrupt-cleanup registry (strike_output), a process global that
// libstrike, which links strike_bank, must not carry.
#include "strike/core/atomic_file.hpp"
#include "strike/bank/bank.hpp"

namespace strike {

Status writeBank(const std::string& path, const ModeBank& bank, ShapeEncoding shapes) {
  const std::string problem = bank.checkConsistency();
  if (!problem.empty()) return internalError("refusing to write an inconsistent mode bank to " + path + ": " + problem);
  const std::vector<uint8_t> bytes = encodeBank(bank, shapes);
  return writeFileAtomically(path, bytes.data(), bytes.size());
}

}  // namespace strike
