// SPDX-License-Identifier: MIT
// libFuzzer target: the mode bank decoder (magic, version, chunks, checksum) on arbitrary bytes,
// and on the same bytes with a repaired checksum.
#include "fuzz_util.hpp"
#include "strike/bank/bank.hpp"

// STRIKE_FUZZ_ENTRY renames the entry so that the unit tests can link every target into one
// program and replay the corpus and the kept crashers (tests/unit/catalogue/fuzz_replay_test.cpp).
#ifndef STRIKE_FUZZ_ENTRY
#define STRIKE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

extern "C" int STRIKE_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  strike::Result<strike::ModeBank> bank = strike::decodeBank(data, size, "fuzz.modes");
  if (bank) (void)bank->checkConsistency();
  // The same bytes with the checksum repaired: exercises the chunk decoder on mutated payloads.
  const std::vector<uint8_t> fixed = strike::fuzz::withValidChecksum(data, size);
  strike::Result<strike::ModeBank> decoded = strike::decodeBank(fixed.data(), fixed.size(), "fuzz.modes");
  if (decoded) (void)decoded->checkConsistency();
  // The render's path: open, then shape rows at a few vertices (first, middle, last, out of range).
  strike::Result<strike::BankFile> file = strike::BankFile::openBytes(fixed.data(), fixed.size(), "fuzz.modes");
  if (file) {
    const uint32_t vertices = static_cast<uint32_t>(file->bank().surfaceVertexCount());
    (void)file->readShapeRows({0, vertices / 2, vertices > 0 ? vertices - 1 : 0, vertices});
    (void)file->readShapeRows({vertices / 3});
  }
  return 0;
}
