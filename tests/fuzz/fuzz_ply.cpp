// SPDX-License-Identifier: MIT
// libFuzzer target: the .ply surface reader (readPly) on arbitrary bytes.
#include "fuzz_util.hpp"
#include "strike/mesh/mesh.hpp"

// STRIKE_FUZZ_ENTRY renames the entry so that the unit tests can link every target into one
// program and replay the corpus and the kept crashers (tests/unit/catalogue/fuzz_replay_test.cpp).
#ifndef STRIKE_FUZZ_ENTRY
#define STRIKE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

extern "C" int STRIKE_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  static const std::string path = strike::fuzz::scratchPath("input.ply");
  if (!strike::fuzz::writeBytes(path, data, size)) return 0;
  std::vector<strike::MeshWarning> warnings;
  strike::Result<strike::SurfaceMesh> mesh = strike::readPly(path, &warnings);
  if (mesh) (void)strike::checkClosedSurface(*mesh, path);
  return 0;
}
