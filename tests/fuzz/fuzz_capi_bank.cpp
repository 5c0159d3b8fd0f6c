// SPDX-License-Identifier: MIT
// libFuzzer target: the C API's strike_bank_load_memory, then the bank queries a host would make.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.hpp"
#include "strike/strike.h"

// STRIKE_FUZZ_ENTRY renames the entry so that the unit tests can link every target into one
// program and replay the corpus and the kept crashers (tests/unit/catalogue/fuzz_replay_test.cpp).
#ifndef STRIKE_FUZZ_ENTRY
#define STRIKE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

extern "C" int STRIKE_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  static strike_context context = [] {
    strike_context created = nullptr;
    const strike_context_config config = strike_context_config_default();
    strike_context_create(&config, &created);
    return created;
  }();
  if (!context) return 0;
  // As given, then with the checksum repaired so that mutations reach the chunk decoder.
  const std::vector<uint8_t> fixed = strike::fuzz::withValidChecksum(data, size);
  for (int pass = 0; pass < 2; ++pass) {
    strike_bank bank = nullptr;
    const void* bytes = pass == 0 ? static_cast<const void*>(data) : static_cast<const void*>(fixed.data());
    if (strike_bank_load_memory(context, bytes, size, &bank) == STRIKE_OK && bank) {
      strike_bank_info info{};
      if (strike_bank_get_info(bank, &info) == STRIKE_OK) {
        double hz = 0.0;
        (void)strike_bank_mode_frequency(bank, 0, &hz);
        if (info.surface_vertex_count > 0) {
          double position[3], normal[3];
          (void)strike_bank_surface_vertex(bank, info.surface_vertex_count - 1, position, normal);
        }
      }
      strike_bank_destroy(bank);
    }
  }
  return 0;
}
