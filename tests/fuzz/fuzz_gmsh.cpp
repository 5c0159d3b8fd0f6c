// SPDX-License-Identifier: MIT
// libFuzzer target: the Gmsh .msh 2.2/4.1 reader, then geometric validation of what it accepts.
#include "fuzz_util.hpp"
#include "strike/mesh/mesh.hpp"

// STRIKE_FUZZ_ENTRY renames the entry so that the unit tests can link every target into one
// program and replay the corpus and the kept crashers (tests/unit/catalogue/fuzz_replay_test.cpp).
#ifndef STRIKE_FUZZ_ENTRY
#define STRIKE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

extern "C" int STRIKE_FUZZ_ENTRY(const uint8_t* data, size_t size) {
  static const std::string path = strike::fuzz::scratchPath("input.msh");
  if (!strike::fuzz::writeBytes(path, data, size)) return 0;
  std::vector<strike::MeshWarning> warnings;
  strike::Result<strike::TetMesh> mesh = strike::readGmsh(path, &warnings);
  if (mesh) (void)strike::validateAndRepair(*mesh, path, &warnings);
  return 0;
}
