// SPDX-License-Identifier: MIT
// Replays every fuzz target's seed corpus and every kept crasher (tests/fuzz/corpus/<target>/,
// tests/fuzz/regressions/<target>/) through the same entry points the fuzzers use, in the normal
// build: a finding that was fixed stays fixed. Under STRIKE_SANITIZE this is a sanitizer run too.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" {
int fuzzObj(const uint8_t*, size_t);
int fuzzStl(const uint8_t*, size_t);
int fuzzPly(const uint8_t*, size_t);
int fuzzGmsh(const uint8_t*, size_t);
int fuzzTetgen(const uint8_t*, size_t);
int fuzzScene(const uint8_t*, size_t);
int fuzzBank(const uint8_t*, size_t);
int fuzzCapiBank(const uint8_t*, size_t);
}

namespace strike {
namespace {

namespace fs = std::filesystem;

struct Target {
  const char* name;
  int (*entry)(const uint8_t*, size_t);
};

TEST(FuzzReplay, CorpusAndKeptCrashersRunClean) {
  const Target targets[] = {{"obj", fuzzObj},   {"stl", fuzzStl},           {"ply", fuzzPly},
                            {"gmsh", fuzzGmsh}, {"tetgen", fuzzTetgen},     {"scene", fuzzScene},
                            {"bank", fuzzBank}, {"capi_bank", fuzzCapiBank}};
  const fs::path root = fs::path(STRIKE_SOURCE_DIR) / "tests" / "fuzz";
  for (const Target& t : targets) {
    size_t corpus = 0, regressions = 0;
    for (const char* kind : {"corpus", "regressions"}) {
      const fs::path dir = root / kind / t.name;
      if (!fs::is_directory(dir)) continue;
      for (const auto& entry : fs::directory_iterator(dir)) {
        if (!entry.is_regular_file()) continue;
        std::ifstream in(entry.path(), std::ios::binary);
        const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        SCOPED_TRACE(entry.path().string());
        EXPECT_EQ(t.entry(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()), 0);
        ++(std::string(kind) == "corpus" ? corpus : regressions);
      }
    }
    std::printf("[ fuzz replay ] %-10s %3zu corpus inputs, %3zu kept crashers: clean\n", t.name, corpus, regressions);
    EXPECT_GT(corpus, 0u) << t.name;
  }
}

}  // namespace
}  // namespace strike
