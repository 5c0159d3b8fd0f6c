// SPDX-License-Identifier: MIT
// libFuzzer target: the TetGen .node/.ele reader. The input is the .node text, a NUL byte, then
// the .ele text (no NUL: all of it is the .node and the .ele is empty).
#include <cstring>

#include "fuzz_util.hpp"
#include "strike/mesh/mesh.hpp"

// STRIKE_FUZZ_ENTRY renames the entry so that the unit tests can link every target into one
// program and replay the corpus and the kept crashers (tests/unit/catalogue/fuzz_replay_test.cpp).
#ifndef STRIKE_FUZZ_ENTRY
#define STRIKE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

extern "C" int STRIKE_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  static const std::string node = strike::fuzz::scratchPath("input.node");
  static const std::string ele = strike::fuzz::scratchPath("input.ele");
  const void* nul = size ? std::memchr(data, 0, size) : nullptr;
  const size_t split = nul ? static_cast<size_t>(static_cast<const uint8_t*>(nul) - data) : size;
  if (!strike::fuzz::writeBytes(node, data, split)) return 0;
  if (!strike::fuzz::writeBytes(ele, data + split + (nul ? 1 : 0), size - split - (nul ? 1 : 0))) return 0;
  std::vector<strike::MeshWarning> warnings;
  strike::Result<strike::TetMesh> mesh = strike::readTetgen(ele, &warnings);
  if (mesh) (void)strike::validateAndRepair(*mesh, ele, &warnings);
  return 0;
}
