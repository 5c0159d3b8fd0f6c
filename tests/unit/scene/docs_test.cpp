// SPDX-License-Identifier: MIT
// The documentation lives in this repository: nothing points users at files
// they do not have, and every key the scene parser accepts is documented.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Docs, NothingPointsOutsideTheRepository) {
  const fs::path root = STRIKE_SOURCE_DIR;
  std::vector<fs::path> files = {root / "README.md"};
  for (const char* dir : {"docs", "src", "tools", "examples", "python"})
    for (const fs::directory_entry& e : fs::recursive_directory_iterator(root / dir))
      if (e.is_regular_file() && e.file_size() < (4u << 20)) files.push_back(e.path());
  ASSERT_GT(files.size(), 50u);
  // Split so that this file, were it ever moved under src/, would not match itself.
  const std::string outside[] = {std::string("../") + "shared", std::string("ARCHITECTURE") + ".md"};
  for (const fs::path& file : files) {
    const std::string text = slurp(file);
    for (const std::string& needle : outside)
      EXPECT_EQ(text.find(needle), std::string::npos) << file << " mentions " << needle << ", which users do not have";
  }
}

TEST(Docs, EveryKeyTheSceneParserAcceptsIsDocumented) {
  const std::string doc = slurp(fs::path(STRIKE_SOURCE_DIR) / "docs" / "scene-format.md");
  ASSERT_FALSE(doc.empty());
  size_t keys = 0;
  for (const SceneKeyTable& table : sceneKeyTables())
    for (const char* key : table.keys) {
      ++keys;
      // Documented as a table row: "| `key` |".
      EXPECT_NE(doc.find("| `" + std::string(key) + "` |"), std::string::npos)
          << "scene key \"" << key << "\" (" << table.where << ") is not in docs/scene-format.md";
    }
  EXPECT_GE(keys, 30u);
}

TEST(Docs, TheKeyTableIsTheOneTheParserChecks) {
  // A key in the table is accepted; one that is not is refused with the table in the message.
  for (const SceneKeyTable& table : sceneKeyTables()) {
    if (std::string(table.where) != "objects[]") continue;
    for (const char* key : table.keys) EXPECT_NE(std::string(key), "colour");
  }
  Result<Scene> bad = parseScene(R"({"objects": [{"mesh": "box:1,1,1", "material": "steel", "colour": 1}]})", "s.json");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("units"), std::string::npos) << bad.error().message;
  Result<Scene> ok =
      parseScene(R"({"objects": [{"mesh": "box:1,1,1", "material": "steel", "shape": "convex"}]})", "s.json");
  EXPECT_TRUE(ok) << (ok ? "" : ok.error().message);
}

// Every complete scene in README.md and docs/ (a ```json block with "objects" that is whole JSON;
// blocks with "..." are fragments) runs as written, from examples/scenes/ where its paths point:
// it parses, and its objects draw no warning about their placement, size or mesh. A short render:
// the warnings about the scene come before the simulation; the sound is the examples' and the
// golden tests' business.
TEST(Docs, EveryWholeSceneInTheDocsRunsAsWrittenWithoutWarnings) {
  const fs::path root = STRIKE_SOURCE_DIR;
  std::vector<fs::path> files = {root / "README.md"};
  for (const fs::directory_entry& e : fs::directory_iterator(root / "docs"))
    if (e.path().extension() == ".md") files.push_back(e.path());
  size_t scenes = 0;
  for (const fs::path& file : files) {
    const std::string text = slurp(file);
    for (size_t at = text.find("```json\n"); at != std::string::npos; at = text.find("```json\n", at + 1)) {
      const size_t begin = at + 8, end = text.find("```", begin);
      const std::string block = text.substr(begin, end - begin);
      if (block.find("\"objects\"") == std::string::npos || block.find("...") != std::string::npos) continue;
      ++scenes;
      Result<Scene> scene = parseScene(block, (root / "examples/scenes/from-the-docs.json").string());
      ASSERT_TRUE(scene) << file << ": " << scene.error().message;
      // Two modes a body, 10 ms: the same warnings for a fraction of the solves' cost.
      scene->max_modes = 2;
      RenderSettings settings;
      settings.duration_s = 0.01;
      Result<RenderResult> rendered = renderScene(*scene, settings);
      ASSERT_TRUE(rendered) << file << ": " << rendered.error().message;
      for (const std::string& warning : rendered->report.warnings)
        EXPECT_TRUE(warning.find("never") != std::string::npos) << file << ": " << warning;
    }
  }
  EXPECT_GE(scenes, 1u);
}

}  // namespace
}  // namespace strike
