// SPDX-License-Identifier: MIT
// Hostile input: every reader gets truncated and randomly mutated copies of the good test
// files and must return a value or a BadInput error, never crash, hang or throw. The seed is
// fixed so that a failure reproduces.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>

#include "mesh/mesh_test_util.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {
namespace {

std::string slurp(const std::string& path) {
  std::string all;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return all;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0) all.append(buffer, n);
  std::fclose(f);
  return all;
}

void spit(const std::string& path, const std::string& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
}

// Reads `path` with the reader its extension calls for.
std::string readAny(const std::string& path, const std::string& ext) {
  if (ext == ".msh") {
    Result<TetMesh> r = readGmsh(path, nullptr);
    if (r.ok()) {
      Status s = validateAndRepair(*r, path, nullptr);
      return s.ok() || s.error().kind == ErrorKind::BadInput ? std::string() : s.error().message;
    }
    return r.error().kind == ErrorKind::BadInput ? std::string() : "internal: " + r.error().message;
  }
  if (ext == ".ele") {
    Result<TetMesh> r = readTetgen(path, nullptr);
    if (r.ok()) {
      Status s = validateAndRepair(*r, path, nullptr);
      return s.ok() || s.error().kind == ErrorKind::BadInput ? std::string() : s.error().message;
    }
    return r.error().kind == ErrorKind::BadInput ? std::string() : "internal: " + r.error().message;
  }
  Result<SurfaceMesh> r = readSurfaceMesh(path);
  if (r.ok()) {
    Status s = checkClosedSurface(*r, path);
    return s.ok() || s.error().kind == ErrorKind::BadInput ? std::string() : s.error().message;
  }
  return r.error().kind == ErrorKind::BadInput ? std::string() : "internal: " + r.error().message;
}

TEST(MeshFuzz, TruncatedAndMutatedFilesNeverCrash) {
  std::mt19937 rng(12345);
  const char* names[] = {"cube.obj",          "cube_ascii.stl",     "cube_binary.stl",
                         "cube_ascii.ply",    "cube_binary_le.ply", "cube_binary_be.ply",
                         "cube_tet4_v22.msh", "cube_tet10_v41.msh", "cube_tet10.ele"};
  const std::string dir = ::testing::TempDir();
  for (const char* name : names) {
    const std::string original = slurp(test::meshData(name));
    ASSERT_FALSE(original.empty()) << name;
    const std::string ext = std::string(name).substr(std::string(name).rfind('.'));
    if (ext == ".ele") spit(dir + "fuzz.node", slurp(test::meshData("cube_tet10.node")));
    const std::string path = dir + "fuzz" + ext;
    // Digits, separators, signs and the bytes binary headers are made of.
    const std::string alphabet = "0123456789 \n-+.eE#/$xyzfvn\xff";
    for (int trial = 0; trial < 150; ++trial) {
      std::string bytes = original;
      if (trial % 3 == 0) {
        bytes.resize(std::uniform_int_distribution<size_t>(0, bytes.size())(rng));
      } else {
        const int edits = 1 + trial % 4;
        for (int e = 0; e < edits && !bytes.empty(); ++e) {
          const size_t at = std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(rng);
          bytes[at] = trial % 2 ? alphabet[rng() % alphabet.size()] : static_cast<char>(rng() & 0xff);
        }
      }
      spit(path, bytes);
      EXPECT_EQ(readAny(path, ext), "") << name << " trial " << trial;
    }
  }
}

}  // namespace
}  // namespace strike
