// SPDX-License-Identifier: MIT
// `strike batch MANIFEST.jsonl -o DIR ...`: runs the Python package's batch renderer
// (python/strike/batch.py, on Dask) with the Python this build found, by exec: the same process,
// so its exit code and signals are the batch's.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"

namespace strike::cli {

namespace {

// The options are python/strike/batch.py's (its parser checks them); this help says what they do.
CommandSpec batchSpec() {
  CommandSpec spec;
  spec.usage = "strike batch MANIFEST.jsonl -o DIR [--workers N | --scheduler ADDRESS | --shard K/N] [options]";
  spec.summary =
      "Renders a manifest of scenes into a folder, on this machine or a Dask cluster, and writes beside every\n"
      "sound (ID.wav, as `strike render`) what made it (ID.json: the scene as rendered, its parameters, seed,\n"
      "versions and levels). MANIFEST.jsonl holds one JSON object a line: {\"scene\": FILE or object}, a\n"
      "template with parameters, or a randomized dataset's seed and index or count; optionally \"id\" (the\n"
      "output's name), \"rate\", \"duration\", \"gain\". A bad line stops the batch before anything renders,\n"
      "naming MANIFEST:LINE, the key and the value. Runs the Python package (python3 -m strike.batch); the\n"
      "manifest format, randomized scenes and clusters are in docs/datasets.md.";
  spec.options = {
      {"-o", "DIR", "output folder (required; made if missing)"},
      {"--workers", "N", "a local Dask cluster of N worker processes; default: the cores"},
      {"--scheduler", "ADDRESS", "use a running Dask cluster, e.g. tcp://head:8786"},
      {"--shard", "K/N", "render lines K, K+N, K+2N, ... here, with no Dask (Slurm arrays)"},
      {"--cache", "DIR", "bank cache folder shared by the workers; default $STRIKE_CACHE_DIR or ~/.cache/strike"},
      {"--similar", "", "one eigen-solve per shape at unit size, scaled to every size and material (docs/datasets.md)"},
      {"--quiet", "", "no progress bar"},
  };
  spec.examples =
      "  strike batch scenes.jsonl -o out/ --workers 2\n"
      "  strike batch scenes.jsonl -o out/ --scheduler tcp://head:8786\n"
      "  strike batch scenes.jsonl -o out/ --shard 3/100\n";
  return spec;
}

}  // namespace

int runBatch(const std::vector<std::string>& args) {
  if (wantsHelp(args)) {
    std::fputs(helpText(batchSpec()).c_str(), stdout);
    return 0;
  }
#ifndef STRIKE_PYTHON_EXECUTABLE
  (void)args;
  std::fputs(
      "strike batch: error: this strike was built without the Python package (STRIKE_BUILD_PYTHON=OFF); "
      "see docs/install.md\n",
      stderr);
  return 1;
#else
  // The package beside this executable: the build tree (BUILD/tools/strike, BUILD/python/strike)
  // or an install (PREFIX/bin/strike, PREFIX/STRIKE_PYTHON_INSTALL_DIR/strike). Else Python's own path.
  namespace fs = std::filesystem;
  std::error_code ignored;
  const fs::path self = fs::read_symlink("/proc/self/exe", ignored);
  std::string python_path;
  for (const fs::path& dir :
       {self.parent_path().parent_path() / "python", self.parent_path().parent_path() / STRIKE_PYTHON_INSTALL_DIR}) {
    if (fs::is_regular_file(dir / "strike" / "__init__.py", ignored)) {
      python_path = dir.string();
      break;
    }
  }
  if (!python_path.empty()) {
    const char* old = std::getenv("PYTHONPATH");
    if (old && *old) python_path += ":" + std::string(old);
    ::setenv("PYTHONPATH", python_path.c_str(), 1);
  }
  std::vector<std::string> command = {STRIKE_PYTHON_EXECUTABLE, "-m", "strike.batch"};
  command.insert(command.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : command) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(argv[0], argv.data());
  std::fprintf(stderr, "strike batch: error: cannot run %s: %s (install python3; see docs/install.md)\n",
               STRIKE_PYTHON_EXECUTABLE, std::strerror(errno));
  return 1;
#endif
}

}  // namespace strike::cli
