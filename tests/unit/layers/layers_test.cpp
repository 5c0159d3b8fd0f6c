// SPDX-License-Identifier: MIT
// The layers of docs/architecture.md ("Headers by module"): every file of a module, its sources in
// src/<module>/ and its public headers in src/include/strike/<module>/, includes only the modules
// below it. The runtime (libstrike: core, bank, synth, capi) must build with nothing but a
// compiler, so it may not reach the mesh, the FEM, the eigen-solver, the transfer solver, the
// simulation, scenes, sound files or the cache.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// What each module may include besides itself. The far-field record and its evaluation
// (strike/transfer/acoustic_transfer.hpp) are built into the runtime's strike_bank, so the
// runtime may include that one header of strike/transfer.
struct Layer {
  std::set<std::string> modules;
  std::set<std::string> headers;
};

const std::map<std::string, Layer>& layers() {
  static const std::map<std::string, Layer> kLayers = {
      {"core", {{}, {}}},
      {"mesh", {{"core"}, {}}},
      {"fem", {{"core", "mesh"}, {}}},
      {"modal", {{"core", "mesh", "fem"}, {}}},
      {"bank", {{"core"}, {"strike/transfer/acoustic_transfer.hpp"}}},
      {"synth", {{"core", "bank"}, {"strike/transfer/acoustic_transfer.hpp"}}},
      {"capi", {{"core", "bank", "synth"}, {"strike/transfer/acoustic_transfer.hpp", "strike/strike.h"}}},
      {"transfer", {{"core", "mesh", "bank"}, {}}},
      {"precompute", {{"core", "mesh", "fem", "modal", "bank", "transfer"}, {}}},
      {"sim", {{"core", "mesh", "synth"}, {}}},
  };
  return kLayers;
}

std::vector<std::string> strikeIncludes(const fs::path& file) {
  static const std::regex kInclude(R"(^\s*#\s*include\s*["<](strike/[^">]+)[">])");
  std::vector<std::string> found;
  std::ifstream in(file);
  std::string line;
  std::smatch match;
  while (std::getline(in, line))
    if (std::regex_search(line, match, kInclude)) found.push_back(match[1]);
  return found;
}

// "strike/synth/engine.hpp" -> "synth"; "strike/strike.h" -> "".
std::string moduleOf(const std::string& include) {
  const size_t first = include.find('/');
  const size_t second = include.find('/', first + 1);
  return second == std::string::npos ? std::string() : include.substr(first + 1, second - first - 1);
}

std::vector<fs::path> filesOf(const std::string& module) {
  const fs::path root = STRIKE_SOURCE_DIR;
  std::vector<fs::path> files;
  for (const fs::path& dir : {root / "src" / module, root / "src" / "include" / "strike" / module}) {
    if (!fs::is_directory(dir)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      const std::string ext = entry.path().extension().string();
      if (ext == ".cpp" || ext == ".hpp" || ext == ".h" || ext == ".inc") files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(Layers, EveryModuleIncludesOnlyTheModulesBelowIt) {
  size_t checked = 0;
  for (const auto& [module, layer] : layers()) {
    const std::vector<fs::path> files = filesOf(module);
    EXPECT_FALSE(files.empty()) << "no files for module " << module;
    for (const fs::path& file : files) {
      for (const std::string& include : strikeIncludes(file)) {
        ++checked;
        const std::string of = moduleOf(include);
        const bool allowed = of == module || layer.modules.count(of) > 0 || layer.headers.count(include) > 0;
        EXPECT_TRUE(allowed) << file.string() << " (module " << module << ") includes " << include;
      }
    }
  }
  EXPECT_GT(checked, 100u);  // the scan saw the tree, not an empty directory
}

TEST(Layers, PublicHeadersSitInTheirModulesFolder) {
  const fs::path root = fs::path(STRIKE_SOURCE_DIR) / "src" / "include" / "strike";
  for (const auto& entry : fs::directory_iterator(root)) {
    if (entry.is_directory()) {
      EXPECT_TRUE(fs::is_directory(fs::path(STRIKE_SOURCE_DIR) / "src" / entry.path().filename()))
          << entry.path().string() << " names no module folder in src/";
    } else {
      EXPECT_EQ(entry.path().filename(), "strike.h") << entry.path().string() << " sits outside a module folder";
    }
  }
}

}  // namespace
