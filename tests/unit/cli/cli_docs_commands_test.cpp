// SPDX-License-Identifier: MIT
// Every command of the docs runs: each line of a ```sh block and each ```python block of
// README.md and docs/*.md is run, in the order the page gives them, in a folder of its own per
// page (the repository's examples/, assets/ and tests/ beside it, as in a clone), with the `strike`
// of this build first on PATH and one bank cache for the whole test. A command that fails here
// fails for a reader too. The whole scenes of the docs are rendered by
// Docs.EveryWholeSceneInTheDocsRunsAsWrittenWithoutWarnings, the options of every command line are
// checked against --help by FirstHourDocs.EveryCommandLineInTheDocsUsesOptionsTheCommandHas.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "run_cli.hpp"

namespace strike {
namespace {

namespace fs = std::filesystem;
using test::slurp;

struct DocCommand {
  std::string page;  // README.md, docs/guide.md, ...
  int line = 0;
  std::string text;  // as written, without its trailing comment
  bool python = false;
};

/// The commands a reader cannot run as written on a build machine, and why. Each must still be in
/// the docs (an entry no page has any more fails), and any other command runs.
const std::map<std::string, std::string>& notRun() {
  static const std::map<std::string, std::string> reasons = {
      {"bash tools/quickstart.sh", "installs Debian packages as root and builds build/release (minutes)"},
      {"bash tools/test.sh", "is the whole test suite, this test among it"},
      {"cmake --preset release && cmake --build --preset release && cmake --install build/release --prefix PREFIX",
       "a full release build (minutes); ctest -R tools.install installs a build and builds a program against it"},
      {"cmake -S . -B build/runtime -DSTRIKE_RUNTIME_ONLY=ON && cmake --build build/runtime && ctest --test-dir "
       "build/runtime",
       "a second build; tools/test.sh runs it as its stage \"runtime-only build + tests\""},
      {"cmake --install build/runtime --prefix PREFIX", "needs the build of the line before"},
      {"/usr/bin/python3 -m venv --system-site-packages ~/strike-venv",
       "writes to the home folder; python/tests/test_install.py makes this venv in a temporary folder"},
      {"~/strike-venv/bin/pip install --no-build-isolation ./python",
       "builds the module (minutes); python/tests/test_install.py runs this pip install into a temporary venv"},
      {"~/strike-venv/bin/python -c \"import strike; print(strike.__version__)\"",
       "needs the venv of the lines before; python/tests/test_install.py imports strike from it"},
      {"strike batch scenes.jsonl -o out/ --scheduler tcp://head:8786",
       "needs a running Dask cluster on a host 'head'"},
      {"strike batch scenes.jsonl -o /shared/out --scheduler tcp://head:8786 --cache /shared/cache",
       "needs a running Dask cluster on a host 'head' and a cluster's shared folder"},
      {"strike batch scenes.jsonl -o /shared/out --shard 3/100",
       "writes to a cluster's shared folder /shared; the same command into out/ runs (docs/datasets.md)"},
      {"strike bench accuracy -o study/",
       "the accuracy study, ~35 s on 2 cores; CliAccuracy.BenchAccuracyWritesItsTables runs it"},
      {"strike bench render tests/bench/render/bench-20-plates.json -o study/",
       "20 plates' solves, 5 renders per configuration (minutes); NewcomerOutputs.BenchCreatesItsOutputFolder "
       "runs the benchmark on a small scene"},
  };
  return reasons;
}

/// Files the reader brings (a page names them as the reader's own), made from the repository's.
const std::map<std::string, std::string>& readersFiles() {
  static const std::map<std::string, std::string> files = {
      {"part.msh", "tests/data/mesh/cube_tet10_v22.msh"},  // "your Gmsh file": a Tet10 cube
  };
  return files;
}

/// A manifest for the pages' `strike batch scenes.jsonl` lines: a glass marble dropped on the
/// floor, whose modes are all ultrasonic, so its bank solves in a moment and has no transfer.
const char* kManifest =
    R"({"id": "marble", "scene": {"duration": 0.2, "objects": [{"name": "marble", "mesh": "sphere:0.008", "material": "glass", "position": [0, 0, 0.02]}]}})"
    "\n";

/// What the test runs for a page's command. The acoustic transfer is left out of every solve
/// (`--no-transfer`, `transfer=False`): it costs 0.8-20x the eigen-solve, the rest of each command
/// is what a reader's typing can get wrong, and the transfer's own tests are in tests/unit/transfer.
/// The bowl's solve skips its error estimate, which solves a finer mesh at ~3x the solve's cost
/// (CliAccuracy tests the estimate). One render is shortened: marbles-in-bowl, 4 s of a scene that
/// simulates at ~0.3x real time.
std::string whatRuns(const DocCommand& c) {
  std::string run = c.text;
  if (c.python) {
    for (const std::string call : {"strike.modes(", "strike.render("}) {
      const size_t at = run.find(call);
      if (at == std::string::npos) continue;
      size_t depth = 0, close = at + call.size() - 1;
      for (; close < run.size(); ++close)
        if (run[close] == '(')
          ++depth;
        else if (run[close] == ')' && --depth == 0)
          break;
      run.insert(close, ", transfer=False");
    }
    return run;
  }
  const bool solves = (run.rfind("strike modes ", 0) == 0 && run.find("--list-materials") == std::string::npos) ||
                      run.rfind("strike render ", 0) == 0;
  if (solves && run.find("--no-transfer") == std::string::npos) run += " --no-transfer";
  if (run.rfind("strike modes assets/meshes/bowl.obj", 0) == 0) run += " --no-error-estimate";
  if (run.find("examples/scenes/marbles-in-bowl.json") != std::string::npos) run += " --duration 0.3";
  return run;
}

/// The ```sh lines (a trailing `# comment` dropped) and ```python blocks of a page.
std::vector<DocCommand> commandsOf(const fs::path& root, const std::string& page) {
  std::vector<DocCommand> commands;
  std::istringstream lines(slurp((root / page).string()));
  std::string line, fence, python_block;
  int number = 0, python_line = 0;
  while (std::getline(lines, line)) {
    ++number;
    if (line.rfind("```", 0) == 0) {
      if (fence.empty()) {
        fence = line.substr(3).empty() ? "plain" : line.substr(3);
        python_line = number + 1;
      } else {
        if (fence == "python") commands.push_back({page, python_line, python_block, true});
        fence.clear();
        python_block.clear();
      }
      continue;
    }
    if (fence == "python") {
      python_block += line + "\n";
    } else if (fence == "sh" || fence == "bash") {
      const size_t comment = line.find(" #");
      std::string text = line.substr(0, comment);
      text.erase(text.find_last_not_of(' ') + 1);
      text.erase(0, text.find_first_not_of(' '));
      if (!text.empty() && text[0] != '#') commands.push_back({page, number, text, false});
    } else if (fence == "plain") {
      // A command in a block with no language is not run: it must be in a ```sh block.
      std::istringstream words(line);
      std::string strike, command;
      words >> strike >> command;
      static const std::set<std::string> commands_of_strike = {"render",  "modes", "info",  "hit",
                                                               "analyze", "cache", "batch", "bench"};
      EXPECT_FALSE(strike == "strike" && commands_of_strike.count(command))
          << page << ":" << number << ": `" << line << "` is in a ``` block, not ```sh: it is not run";
    }
  }
  return commands;
}

struct Ran {
  int exit_code = -1;
  std::string output;
  double seconds = 0.0;
};

Ran runIn(const fs::path& folder, const std::string& shell_text) {
  const fs::path log = folder / ".command.log";
  const std::string command = "cd '" + folder.string() + "' && { " + shell_text + "\n} >'" + log.string() + "' 2>&1";
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  Ran ran;
  ran.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ran.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  ran.output = slurp(log.string());
  return ran;
}

/// Sets an environment variable for the test's commands and puts the old value back after it, so
/// the other tests of this program see the environment they were started with.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old, had_ = true;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (had_)
      ::setenv(name_, old_.c_str(), 1);
    else
      ::unsetenv(name_);
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

std::string tail(const std::string& text, size_t chars) {
  return text.size() <= chars ? text : "..." + text.substr(text.size() - chars);
}

TEST(DocsCommands, EveryCommandInTheReadmeAndDocsRuns) {
  const fs::path root = STRIKE_SOURCE_DIR;
  std::vector<std::string> pages = {"README.md"};
  for (const fs::directory_entry& e : fs::directory_iterator(root / "docs"))
    if (e.path().extension() == ".md") pages.push_back("docs/" + e.path().filename().string());
  std::sort(pages.begin() + 1, pages.end());

  const fs::path work = fs::path(testing::TempDir()) / ("docs-commands-" + std::to_string(getpid()));
  fs::remove_all(work);
  fs::create_directories(work);
  // The environment of a reader who built and installed Strike: `strike` on PATH, one bank cache,
  // the Python package importable, libstrike installed where pkg-config finds it.
  const std::string cli_dir = fs::path(STRIKE_CLI).parent_path().string();
  const char* path = std::getenv("PATH");
  const ScopedEnv on_path("PATH", cli_dir + ":" + (path ? path : "/usr/bin:/bin"));
  const ScopedEnv cache("STRIKE_CACHE_DIR", (work / "cache").string());
#ifdef STRIKE_PYTHON_PATH
  const ScopedEnv python_path("PYTHONPATH", STRIKE_PYTHON_PATH);
#endif
#ifdef STRIKE_LIBSTRIKE_DIR
  // The layout `cmake --install` gives (docs/install.md), its files linked from the build tree.
  const fs::path prefix = work / "prefix";
  fs::create_directories(prefix / "lib" / "pkgconfig");
  fs::create_directories(prefix / "include" / "strike");
  fs::copy_file(STRIKE_LIBSTRIKE_PC, prefix / "lib" / "pkgconfig" / "strike.pc");
  fs::create_symlink(root / "src" / "include" / "strike" / "strike.h", prefix / "include" / "strike" / "strike.h");
  for (const fs::directory_entry& e : fs::directory_iterator(STRIKE_LIBSTRIKE_DIR))
    if (e.path().filename().string().rfind("libstrike.so", 0) == 0)
      fs::create_symlink(e.path(), prefix / "lib" / e.path().filename());
  const ScopedEnv pkg_config_path("PKG_CONFIG_PATH", (prefix / "lib" / "pkgconfig").string());
#endif

  std::set<std::string> seen;
  size_t ran_count = 0;
  double total_s = 0.0;
  for (const std::string& page : pages) {
    const std::vector<DocCommand> commands = commandsOf(root, page);
    if (commands.empty()) continue;
    const fs::path folder = work / fs::path(page).filename().replace_extension("");
    fs::create_directories(folder);
    for (const char* tree : {"examples", "assets", "tests", "python"}) fs::create_symlink(root / tree, folder / tree);
    for (const auto& [name, from] : readersFiles()) fs::copy_file(root / from, folder / name);
    std::ofstream(folder / "scenes.jsonl") << kManifest;
    for (const DocCommand& c : commands) {
      seen.insert(c.text);
      const std::string where = c.page + ":" + std::to_string(c.line);
      if (auto reason = notRun().find(c.text); reason != notRun().end()) {
        std::printf("not run  %s  %s\n         (%s)\n", where.c_str(), c.text.c_str(), reason->second.c_str());
        continue;
      }
      std::string shell = whatRuns(c);
      if (c.python) {
#ifndef STRIKE_PYTHON_EXECUTABLE
        std::printf("not run  %s  a python block: this build has no Python package\n", where.c_str());
        continue;
#else
        std::ofstream(folder / ".snippet.py") << shell;
        shell = std::string("'") + STRIKE_PYTHON_EXECUTABLE + "' .snippet.py";
#endif
      }
#ifndef STRIKE_PYTHON_EXECUTABLE
      if (c.text.rfind("strike batch ", 0) == 0) {
        std::printf("not run  %s  %s (this build has no Python package)\n", where.c_str(), c.text.c_str());
        continue;
      }
#endif
#ifndef STRIKE_LIBSTRIKE_DIR
      if (c.text.find("pkg-config") != std::string::npos) {
        std::printf("not run  %s  %s (this build installs no libstrike)\n", where.c_str(), c.text.c_str());
        continue;
      }
#endif
      const Ran ran = runIn(folder, shell);
      ++ran_count;
      total_s += ran.seconds;
      std::printf("ran      %s  %s%s  (%.1f s)\n", where.c_str(), c.python ? "python block" : c.text.c_str(),
                  whatRuns(c) != c.text && !c.python ? ("\n         as " + whatRuns(c)).c_str() : "", ran.seconds);
      EXPECT_EQ(ran.exit_code, 0) << where << ": `" << shell << "` failed; it printed:\n" << tail(ran.output, 3000);
    }
  }
  for (const auto& [command, reason] : notRun())
    EXPECT_TRUE(seen.count(command)) << "the list of commands not run names one no page has any more: " << command;
  std::printf("%zu commands ran in %.1f s\n", ran_count, total_s);
  EXPECT_GE(ran_count, 20u);
  if (!HasFailure()) fs::remove_all(work);  // kept when something failed, to look at
}

}  // namespace
}  // namespace strike
