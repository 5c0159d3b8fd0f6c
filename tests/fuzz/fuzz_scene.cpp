// SPDX-License-Identifier: MIT
// libFuzzer target: the scene JSON parser and validator (in memory; mesh paths are not opened).
#include <string>

#include "strike/scene/scene.hpp"

// STRIKE_FUZZ_ENTRY renames the entry so that the unit tests can link every target into one
// program and replay the corpus and the kept crashers (tests/unit/catalogue/fuzz_replay_test.cpp).
#ifndef STRIKE_FUZZ_ENTRY
#define STRIKE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

extern "C" int STRIKE_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)strike::parseScene(text, "/nonexistent-fuzz-dir/scene.json");
  return 0;
}
