// SPDX-License-Identifier: MIT
// `strike bench STUDY`: parses the command line and runs one study: accuracy (accuracy.cpp),
// leftout (leftout.cpp) or render (render.cpp, which parses its own options).
#include <cstdio>
#include <string>
#include <vector>

#include "args.hpp"
#include "bench_studies.hpp"
#include "commands.hpp"
#include "output_check.hpp"

namespace strike::cli {
namespace {

CommandSpec benchSpec() {
  CommandSpec spec;
  spec.usage =
      "strike bench accuracy -o DIR | strike bench leftout SCENE.json -o DIR | strike bench render SCENE.json -o DIR";
  spec.summary =
      "Runs the accuracy study and writes DIR/accuracy-fem.csv (+ .svg plot), accuracy-synth.csv and\n"
      "accuracy-euler.csv: FEM frequency error against precompute time (Tet4, Tet10, 4 sizes, free-free\n"
      "bar vs Timoshenko, sphere vs Lamb), synthesis error against time (float vs double state, culling thresholds),\n"
      "and symplectic Euler against the exact update at the audio step. Takes ~35 s (2 cores).\n"
      "`leftout` renders SCENE three times (nothing left out; as normal from an empty cache; from the warm\n"
      "cache), writes DIR/leftout.csv and prints the time ratios and the audio difference.\n"
      "`render` times a render phase by phase against a baseline run (see `strike bench render --help`).";
  spec.options = {{"-o", "DIR", "output folder; created if missing"},
                  {"--plate", "",
                   "accuracy: also the free thick plate (Tet4/Tet10 at 4 sizes against a fine Tet10\n"
                   "reference; ~45 s more, 1.9 GB peak)"}};
  spec.examples = "  strike bench accuracy -o study/\n  strike bench leftout examples/scenes/bar-drop.json -o study/\n";
  spec.min_positional = 1;
  spec.max_positional = 2;
  return spec;
}

}  // namespace

int runBench(const std::vector<std::string>& raw_args) {
  if (!raw_args.empty() && raw_args[0] == "render") return runBenchRender({raw_args.begin() + 1, raw_args.end()});
  const CommandSpec spec = benchSpec();
  if (wantsHelp(raw_args)) {
    std::fputs(helpText(spec).c_str(), stdout);
    return 0;
  }
  Result<ParsedArgs> parsed = parseArgs(spec, raw_args);
  if (!parsed) return reportError("bench", parsed.error());
  if (!parsed->has("-o")) return reportError("bench", badInput("missing -o DIR"));
  const std::string dir = parsed->text("-o");
  const std::string& study = parsed->positional[0];
  if (study != "leftout" && (study != "accuracy" || parsed->positional.size() != 1))
    return reportError(
        "bench", badInput("unknown study '" + study + "' (known: accuracy, leftout SCENE.json, render SCENE.json)"));
  // The folder is made (or refused) before the study runs, not after it.
  if (Status ok = prepareOutputDir("-o", dir); !ok) return reportError("bench", ok.error());
  if (study == "leftout") {
    if (parsed->positional.size() != 2) return reportError("bench", badInput("bench leftout needs SCENE.json"));
    Status ok = benchLeftOut(parsed->positional[1], dir);
    return ok ? 0 : reportError("bench", ok.error());
  }
  if (study != "accuracy" || parsed->positional.size() != 1)
    return reportError(
        "bench", badInput("unknown study '" + study + "' (known: accuracy, leftout SCENE.json, render SCENE.json)"));
  return benchAccuracy(dir, parsed->has("--plate"));
}

}  // namespace strike::cli
