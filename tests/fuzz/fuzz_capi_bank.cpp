// SPDX-License-Identifier: MIT
// libFuzzer target: the C API's strike_bank_load_memory, then the bank queries a host would make.
#include <cstddef>
#include <cstdint>

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
  strike_bank bank = nullptr;
  if (strike_bank_load_memory(context, data, size, &bank) == STRIKE_OK && bank) {
    strike_bank_info info{};
    if (strike_bank_get_info(bank, &info) == STRIKE_OK) {
      double hz = 0.0;
      (void)strike_bank_mode_frequency(bank, 0, &hz);
    }
    strike_bank_destroy(bank);
  }
  return 0;
}
