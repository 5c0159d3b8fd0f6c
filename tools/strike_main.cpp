// SPDX-License-Identifier: MIT
// `strike`: the command line. Start here to follow a command down to the library.
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "cli/args.hpp"
#include "cli/commands.hpp"
#include "strike/core/interrupt_cleanup.hpp"
#include "strike/modal/modal.hpp"

namespace {

const char kUsage[] =
    "strike: rigid-body impact sound synthesis (version " STRIKE_VERSION_STRING
    ")\n"
    "\n"
    "usage: strike COMMAND [ARGS] [--help]\n"
    "\n"
    "commands:\n"
    "  render SCENE.json -o OUT.wav   simulate a collision scene (Bullet) and render its sound\n"
    "  modes MESH -o BANK.modes       precompute an object's vibration modes (FEM + ARPACK)\n"
    "  info BANK.modes [--json]       show a mode bank: frequencies, decay, T60, mass\n"
    "  hit BANK.modes -o OUT.wav      strike an object once and render the sound\n"
    "  analyze AUDIO.wav [--json]     spectral peaks, levels and decay rates of a sound\n"
    "  cache list|size|prune          the mode bank cache: list, measure, remove old or least used banks\n"
    "  batch MANIFEST.jsonl -o DIR    render a manifest of scenes on Dask (--workers N, --scheduler, --shard K/N)\n"
    "  bench accuracy -o DIR          accuracy study: FEM and synthesis error against run time (CSV, SVG)\n"
    "  bench leftout SCENE.json -o DIR what leaving out saves: time and audio against rendering everything\n"
    "  bench render SCENE.json -o DIR render speed per phase against a baseline run (CSV)\n"
    "\n"
    "Run `strike COMMAND --help` for a command's options and examples. SI units everywhere.\n"
    "The command line is documented in docs/cli.md, the scene file in docs/scene-format.md.\n"
    "Exit codes: 0 success, 1 bad input (the message names the file, field and value), 2 internal error.\n";

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 1 : 0;
  }
  if (std::strcmp(argv[1], "--version") == 0) {
    std::printf("strike %s\n", STRIKE_VERSION_STRING);
    return 0;
  }
  // OpenBLAS's workers, started when it loaded, stop spinning now, not ~0.1 s of CPU per core later.
  strike::useOneBlasThread();
  // An interrupted run leaves no temporary output behind (outputs appear only by rename).
  strike::installInterruptCleanup();
  const std::string command = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  try {
    if (command == "render") return strike::cli::runRender(args);
    if (command == "modes") return strike::cli::runModes(args);
    if (command == "bench") return strike::cli::runBench(args);
    if (command == "info") return strike::cli::runInfo(args);
    if (command == "hit") return strike::cli::runHit(args);
    if (command == "analyze") return strike::cli::runAnalyze(args);
    if (command == "cache") return strike::cli::runCache(args);
    if (command == "batch") return strike::cli::runBatch(args);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "strike %s: error: out of memory\n", command.c_str());
    return 2;
  } catch (const std::exception& e) {
    // The core does not throw; reaching this is a bug in strike or a library it calls.
    std::fprintf(stderr, "strike %s: internal error: %s\n", command.c_str(), e.what());
    return 2;
  }
  const std::string near =
      strike::cli::closestName(command, {"render", "modes", "info", "hit", "analyze", "cache", "batch", "bench"});
  std::fprintf(stderr, "strike: error: unknown command '%s'%s\n\n%s", command.c_str(),
               near.empty() ? "" : ("; did you mean " + near + "?").c_str(), kUsage);
  return 1;
}
