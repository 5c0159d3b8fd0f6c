// SPDX-License-Identifier: MIT
// `strike bench render SCENE.json -o DIR`: render speed, phase by phase, against a baseline run
// in the same process. The machine is shared and noisy, so each repetition renders the baseline
// and then the current settings back to back, and the table reports medians and their ratio;
// process CPU time and the load average are recorded next to every wall time. The baseline is the
// 0.5 ms physics step used before, or, with --output FORMAT, a mono render at the same step: what
// that output costs over mono. Banks come from the cache (fill it with one `strike render` first).
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "args.hpp"
#include "commands.hpp"
#include "output_check.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike::cli {
namespace {

CommandSpec benchRenderSpec() {
  CommandSpec spec;
  spec.usage = "strike bench render SCENE.json -o DIR [--cache DIR] [--repeat N] [--output FORMAT] [--no-transfer]";
  spec.summary =
      "Renders the scene N times with the baseline settings (0.5 ms physics step) and N times with the\n"
      "current ones (1 ms), alternating, and writes DIR/render.csv: per run the load, simulate, modes (read\n"
      "the shapes where contacts landed, or eigen-solve), synthesize and total wall times, the process CPU time, the "
      "real-time factor (audio seconds per wall second)\n"
      "and the 1-minute load average. Prints the medians and current/baseline ratios. Reads banks from\n"
      "the cache and computes missing ones (the first run then reports their eigen-solves).\n"
      "With --output FORMAT the baseline is a mono render and the current one renders FORMAT, both at the\n"
      "current step: the ratio is what that output costs over mono.";
  spec.options = {{"-o", "DIR", "output folder; created if missing"},
                  {"--cache", "DIR", "mode bank cache folder; default $STRIKE_CACHE_DIR or ~/.cache/strike"},
                  {"--repeat", "N", "renders per configuration; default 5"},
                  {"--output", "mono|stereo|binaural|ambix1|ambix2|ambix3",
                   "render this output against a mono baseline (the KEMAR responses for binaural)"},
                  {"--no-transfer", "", "the banks `strike render --no-transfer` caches (no acoustic transfer)"}};
  spec.examples =
      "  strike bench render tests/bench/render/bench-20-plates.json -o /tmp --repeat 5\n"
      "  strike bench render tests/bench/render/bench-20-plates.json -o /tmp --output binaural\n";
  spec.min_positional = 1;
  spec.max_positional = 1;
  return spec;
}

double cpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double loadAverage() {
  double load[1] = {0.0};
  return getloadavg(load, 1) == 1 ? load[0] : -1.0;
}

struct Run {
  double load_s, simulate_s, modes_s, synthesize_s, other_s, total_s, cpu_s, realtime, loadavg;
};

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n == 0 ? 0.0 : n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

}  // namespace

int runBenchRender(const std::vector<std::string>& raw_args) {
  const CommandSpec spec = benchRenderSpec();
  if (wantsHelp(raw_args)) {
    std::fputs(helpText(spec).c_str(), stdout);
    return 0;
  }
  Result<ParsedArgs> parsed = parseArgs(spec, raw_args);
  if (!parsed) return reportError("bench", parsed.error());
  if (!parsed->has("-o")) return reportError("bench", badInput("missing -o DIR"));
  if (Status ok = prepareOutputDir("-o", parsed->text("-o")); !ok) return reportError("bench", ok.error());
  Result<long long> repeat = parsed->integer("--repeat", 5);
  if (!repeat) return reportError("bench", repeat.error());
  if (*repeat < 1 || *repeat > 1000)
    return reportError("bench", badInput("--repeat = " + parsed->text("--repeat") + " (must be 1 to 1000)"));
  Result<Scene> scene = loadScene(parsed->positional[0]);
  if (!scene) return reportError("bench", scene.error());
  const std::string csv_path = parsed->text("-o") + "/render.csv";
  std::ofstream csv(csv_path);
  if (!csv) return reportError("bench", badInput(csv_path + ": error: cannot create file"));
  csv << "run,config,substep_s,load_s,simulate_s,modes_s,synthesize_s,other_s,total_s,cpu_s,realtime_factor,loadavg_"
         "1min\n";

  struct Config {
    std::string name;
    double substep_s;
    OutputFormat output;
  };
  const double step_s = RenderSettings{}.substep_s;
  Config configs[2] = {{"baseline", 0.5e-3, OutputFormat::Mono}, {"current", step_s, OutputFormat::Mono}};
  if (parsed->has("--output")) {
    const std::optional<OutputFormat> format = parseOutputFormat(parsed->text("--output"));
    if (!format)
      return reportError("bench", badInput("--output = " + parsed->text("--output") +
                                           " (must be mono, stereo, binaural, ambix1, ambix2 or ambix3)"));
    configs[0] = {"mono", step_s, OutputFormat::Mono};
    configs[1] = {parsed->text("--output"), step_s, *format};
  }
  std::vector<Run> runs[2];
  for (long long r = 0; r < *repeat; ++r) {
    for (int c = 0; c < 2; ++c) {
      RenderSettings settings;
      settings.cache_dir = parsed->text("--cache", defaultCacheDir());
      settings.substep_s = configs[c].substep_s;
      settings.output_format = configs[c].output;
      settings.acoustic_transfer = !parsed->has("--no-transfer");  // the banks `strike render` caches
      const double loadavg = loadAverage();
      const double cpu_start = cpuSeconds();
      Result<RenderResult> result = renderScene(*scene, settings);
      const double cpu = cpuSeconds() - cpu_start;
      if (!result) return reportError("bench", result.error());
      const RenderReport& rep = result->report;
      const double audio_s = result->audio.frames() / result->audio.sample_rate_hz;
      // Time in none of the phases: sorting out what was struck, the audio buffer's peak scan.
      const double other =
          rep.total_seconds - rep.load_seconds - rep.simulate_seconds - rep.precompute_seconds - rep.synthesize_seconds;
      const Run run{rep.load_seconds,
                    rep.simulate_seconds,
                    rep.precompute_seconds,
                    rep.synthesize_seconds,
                    other,
                    rep.total_seconds,
                    cpu,
                    audio_s / rep.total_seconds,
                    loadavg};
      runs[c].push_back(run);
      csv << r << "," << configs[c].name << "," << configs[c].substep_s << "," << run.load_s << "," << run.simulate_s
          << "," << run.modes_s << "," << run.synthesize_s << "," << run.other_s << "," << run.total_s << ","
          << run.cpu_s << "," << run.realtime << "," << run.loadavg << "\n";
      std::fprintf(stderr, "  %-8s run %lld: total %.3f s, cpu %.3f s, %.1fx real time (load average %.2f)\n",
                   configs[c].name.c_str(), r, run.total_s, run.cpu_s, run.realtime, run.loadavg);
    }
  }
  csv.close();

  auto column = [&](int c, double Run::*field) {
    std::vector<double> values;
    for (const Run& run : runs[c]) values.push_back(run.*field);
    return median(values);
  };
  const std::pair<const char*, double Run::*> fields[] = {
      {"load s", &Run::load_s},   {"simulate s", &Run::simulate_s},
      {"modes s", &Run::modes_s}, {"synthesize s", &Run::synthesize_s},
      {"other s", &Run::other_s}, {"total s", &Run::total_s},
      {"cpu s", &Run::cpu_s},     {"x real time", &Run::realtime}};
  std::printf("strike bench render: %s, %lld runs each (medians), wrote %s\n", parsed->positional[0].c_str(), *repeat,
              csv_path.c_str());
  const std::string ratio = configs[1].name + "/" + configs[0].name;
  std::printf("%-14s %12s %12s %16s\n", "", configs[0].name.c_str(), configs[1].name.c_str(), ratio.c_str());
  std::printf("%-14s %12.2f %12.2f\n", "step ms", configs[0].substep_s * 1e3, configs[1].substep_s * 1e3);
  for (const auto& [name, field] : fields) {
    const double base = column(0, field), now = column(1, field);
    std::printf("%-14s %12.3f %12.3f %16.3f\n", name, base, now, base > 0 ? now / base : 0.0);
  }
  std::printf("%-14s %12.2f %12.2f\n", "load average", column(0, &Run::loadavg), column(1, &Run::loadavg));
  return 0;
}

}  // namespace strike::cli
