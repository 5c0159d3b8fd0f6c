// SPDX-License-Identifier: MIT
// `strike render SCENE.json -o OUT.wav`: the main job.
#include <cmath>
#include <cstdio>
#include <string>

#include "args.hpp"
#include "commands.hpp"
#include "output_check.hpp"
#include "progress_reporter.hpp"
#include "strike/audio/audio.hpp"
#include "strike/cache/bank_cache.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"
#include "strike/synth/synth.hpp"
#include "via_library.hpp"

namespace strike::cli {
namespace {

CommandSpec renderSpec() {
  CommandSpec spec;
  spec.usage = "strike render SCENE.json -o OUT.wav [--rate HZ] [--duration S] [--events EVENTS.csv] [options]";
  spec.summary =
      "Renders a collision scene to sound in two phases. First the rigid bodies are simulated with Bullet\n"
      "(1 ms steps, continuous collision detection) and every contact is recorded. Then mode banks are\n"
      "loaded from the cache or computed, only for objects struck hard enough to be heard; each contact\n"
      "impulse is projected onto the struck body's modes (impacts as Hertz pulses, resting contact as a\n"
      "force over the step, so it is silent when steady) and the oscillator bank renders the listener's\n"
      "pressure: output 1.0 = 20 Pa (120 dB SPL) times --gain. The scene file format is in docs/scene-format.md,\nthe "
      "command line's contracts in docs/cli.md.";
  spec.options = {
      {"-o", "OUT.wav", "output sound file, .wav or .flac (required); written atomically"},
      {"--rate", "HZ", "sample rate; default the scene's sample_rate (48000)"},
      {"--duration", "S", "seconds to simulate and render; default the scene's duration"},
      {"--events", "EVENTS.csv", "also write every contact event (time, bodies, impulse, speed, point)"},
      {"--format", "pcm16|pcm24|float", "sample encoding; default float for .wav, pcm24 for .flac"},
      {"--gain", "G", "multiply the output (1.0 full scale = 20 Pa); default 1"},
      {"--cache", "DIR", "mode bank cache folder; default $STRIKE_CACHE_DIR or ~/.cache/strike"},
      {"--no-cache", "", "compute every bank, read and write no cache"},
      {"--cache-max-size", "SIZE",
       "after the render, remove the least recently used banks until the cache fits\n"
       "in SIZE (e.g. 500M, 2G; 0 = no cap); default 2G. See `strike cache`"},
      {"--max-tets", "N", "refuse object meshes with more tets than this (memory cap); default 2000000"},
      {"--max-memory", "SIZE",
       "memory budget of each object's solve (e.g. 4G, 500M): a solve forecast to need more is refused\n"
       "before it starts, with the forecast; default: the memory available now"},
      {"--no-transfer", "",
       "solve no acoustic transfer for the banks computed (solved by default, as by `strike modes`):\n"
       "each mode is then heard at its direction-averaged level, with no direction and a sign that\n"
       "depends on the eigen-solver. The transfer costs 0.8x-1.8x the eigen-solve per bank on the\n"
       "order-2 examples, more on plates, planks and blocks of linear tets (cached)"},
      {"--transfer", "", "solve the acoustic transfer (the default; kept so older scripts run)"},
      {"--similar", "",
       "exact similarity reuse: solve each shape once at unit size and scale it to every size and\n"
       "material (same Poisson ratio) of the scene and the cache (docs/datasets.md); changes the\n"
       "polarity of some modes against a render without it. With the transfer, one transfer per shape,\n"
       "wave speed E/rho and number of modes kept, scaled to every size and density (cached)"},
      {"--max-events", "N", "stop if the simulation records more contact events (memory cap); default 20000000"},
      {"--output", "mono|stereo|binaural|ambix1|ambix2|ambix3",
       "the channels written (docs/listener.md): mono (default), stereo (a constant-power pan),\n"
       "binaural (left and right ear through head-related responses, see --hrtf), or Ambisonics\n"
       "of order 1-3 in AmbiX (ACN order, SN3D; 4, 9 or 16 channels), each path (direct, ground\n"
       "image) from its own direction in the listener's frame"},
      {"--hrtf", "FILE.sofa",
       "the head-related responses of --output binaural: an AES69 SOFA file (SimpleFreeFieldHRIR);\n"
       "default the MIT KEMAR set of Debian's libmysofa (/usr/share/libmysofa/MIT_KEMAR_normal_pinna.sofa)"},
      {"--simd", "KERNEL", kSimdHelp},
      {"--via-library", "",
       "send the simulation through libstrike's C API, step by step, as a game would\n"
       "(strike_step, strike_render in blocks of 256): the same sound within -100 dB"},
      {"--quiet", "", "no progress or summary on stderr (warnings are still printed)"},
      {"--progress", "",
       "show progress even when stderr is not a terminal (a line every 5 s: phase, object, share done, time "
       "left); on a terminal it is shown by default"},
  };
  spec.examples =
      "  strike render examples/scenes/bar-drop.json -o bar-drop.wav\n"
      "  strike render examples/scenes/marbles-in-bowl.json -o marbles.wav --events events.csv --rate 96000\n";
  spec.min_positional = 1;
  spec.max_positional = 1;
  return spec;
}

/// Why a render came out silent, from what the report counted.
std::string silenceReason(const RenderReport& r) {
  if (r.objects_struck == 0) return "no object was struck";
  if (r.objects_sounded == 0 && r.objects_silent > 0)
    return "the struck objects have no mode in the audible band; see the warnings";
  if (r.objects_sounded == 0) return "every struck object was struck too softly to hear";
  return "every contribution was below the audibility threshold of 20 uPa";
}

void printSummary(const RenderResult& result, const std::string& output, double rate, double duration) {
  const RenderReport& r = result.report;
  std::fprintf(stderr, "strike render: wrote %s (%.3g s at %.0f Hz)\n", output.c_str(), duration, rate);
  std::fprintf(stderr,
               "  objects     %zu in the scene, %zu struck, %zu sounded, %zu silent (no mode in the audible band), "
               "%zu too soft to hear, %zu never struck\n",
               r.objects, r.objects_struck, r.objects_sounded, r.objects_silent, r.objects_inaudible,
               r.objects - r.objects_struck);
  if (r.objects_clicks_only > 0)
    std::fprintf(stderr,
                 "              %zu of those sounded only by acceleration noise (no mode in the audible band: "
                 "too small or too stiff to ring, but they click)\n",
                 r.objects_clicks_only);
  std::fprintf(stderr,
               "  banks       %zu given, %zu from the cache, %zu computed, %zu shared between identical objects, "
               "%zu scaled from a solve of the same shape\n",
               r.banks_given, r.banks_cached, r.banks_computed, r.banks_shared, r.banks_scaled);
  if (r.transfers_solved + r.transfers_cached + r.transfers_shared > 0)
    std::fprintf(stderr,
                 "  transfers   %zu solved, %zu from the cache, %zu shared (one per shape, wave speed and modes kept, "
                 "scaled to each size)\n",
                 r.transfers_solved, r.transfers_cached, r.transfers_shared);
  if (r.shape_vertices_total > 0)
    std::fprintf(stderr,
                 "  shapes      read at %zu of the bank files' %zu surface vertices (%.1f%%: where contacts landed)\n",
                 r.shape_vertices_read, r.shape_vertices_total,
                 100.0 * double(r.shape_vertices_read) / double(r.shape_vertices_total));
  // Events are contact points (one per point per 1 ms step); what reaches the oscillators counts
  // each event once per sounding body it acts on (both bodies when both sound).
  std::fprintf(stderr,
               "  events      %zu contact points recorded: %zu impacts (closing > 5 cm/s) + %zu resting or sliding\n",
               r.events, r.impact_events, r.sustained_events);
  std::fprintf(
      stderr,
      "  heard       %zu impact pulses and %zu resting/sliding impulses on sounding bodies "
      "(an event counts once per sounding body it touches), making %zu changes of load (a steady load is silent)\n",
      r.impacts, r.sustained_contacts, r.load_changes);
  if (r.continuous_contacts > 0 || r.continuous_dropped > 0) {
    std::fprintf(stderr,
                 "  rolling     %zu rolling or sliding contacts heard (a body and a partner its surface moves over)",
                 r.continuous_contacts);
    if (r.continuous_dropped > 0)
      std::fprintf(stderr, ", %zu contact points of further partners not heard (a body sounds with at most %u at once)",
                   r.continuous_dropped, static_cast<unsigned>(kForceChannels));
    if (r.continuous_last_force_s >= 0.0)
      std::fprintf(stderr, "; the last stopped at %.3f s", r.continuous_last_force_s);
    std::fprintf(stderr, "\n");
  }
  std::fprintf(stderr, "  modes       %llu in the banks, %llu out of the audible band, at most %llu ringing at once\n",
               static_cast<unsigned long long>(r.modes_total), static_cast<unsigned long long>(r.modes_out_of_band),
               static_cast<unsigned long long>(r.max_active_modes));
  // Work against every in-band mode ringing for the whole render (no sleeping, no audibility cut);
  // the time this saves is measured by `strike bench leftout`.
  const double all_mode_samples = double(r.modes_total - r.modes_out_of_band) * duration * rate;
  // The share is of the modes ringing free at the body: the copies rolling and sliding drive (a
  // mode may be driven by several contacts at once) and the ground image's own oscillators are
  // counted apart, so the share stays a share.
  const double image_free = double(r.image_mode_samples);
  const double free_mode_samples = double(r.mode_samples - r.forced_mode_samples - r.image_mode_samples);
  if (all_mode_samples > 0) {
    std::fprintf(stderr,
                 "  sleeping    %.3g mode-samples synthesized, %.1f%% of every in-band mode over the whole render",
                 free_mode_samples, 100.0 * free_mode_samples / all_mode_samples);
    if (r.forced_mode_samples > 0)
      std::fprintf(stderr, "; and %.3g driven by rolling and sliding contacts", double(r.forced_mode_samples));
    if (r.image_mode_samples > 0) std::fprintf(stderr, "; and %.3g for the ground's image", image_free);
    std::fprintf(stderr, "\n");
  }
  if (r.peak == 0.0) {
    std::fprintf(stderr, "  level       silent: every sample is 0 (%s)\n", silenceReason(r).c_str());
  } else {
    std::fprintf(stderr, "  level       peak %.4g (%.1f dBFS, %.1f dB SPL)%s\n", r.peak, 20.0 * std::log10(r.peak),
                 20.0 * std::log10(r.peak * kFullScalePascal / 20e-6),
                 r.clipped_samples ? (", CLIPPING: " + std::to_string(r.clipped_samples) +
                                      " samples at or above full scale; lower --gain")
                                         .c_str()
                                   : "");
  }
  std::fprintf(
      stderr,
      "  time        load %.2f s, simulate %.2f s, modes %.2f s, synthesize %.2f s, total %.2f s (%.1fx real time)\n",
      r.load_seconds, r.simulate_seconds, r.precompute_seconds, r.synthesize_seconds, r.total_seconds,
      r.total_seconds > 0 ? duration / r.total_seconds : 0.0);
  if (r.cache_pruned > 0)
    std::fprintf(stderr,
                 "  cache       removed %zu least recently used banks (%.1f MB) to keep the cache under its cap "
                 "(--cache-max-size)\n",
                 r.cache_pruned, double(r.cache_pruned_bytes) / 1e6);
  for (const std::string& note : r.collision_notes) std::fprintf(stderr, "  collision   %s\n", note.c_str());
  if (r.precompute_saved_seconds > 0)
    std::fprintf(stderr, "  saved       %.2f s of solves (meshing, eigen-solve and transfer) answered by the cache\n",
                 r.precompute_saved_seconds);
  if (r.transfer_saved_seconds > 0)
    std::fprintf(stderr, "  saved       %.2f s of transfer solves answered by the cache\n", r.transfer_saved_seconds);
}

}  // namespace

int runRender(const std::vector<std::string>& raw_args) {
  const CommandSpec spec = renderSpec();
  if (wantsHelp(raw_args)) {
    std::fputs(helpText(spec).c_str(), stdout);
    return 0;
  }
  Result<ParsedArgs> parsed = parseArgs(spec, raw_args);
  if (!parsed) return reportError("render", parsed.error());
  const ParsedArgs& args = *parsed;
  if (!args.has("-o")) return reportError("render", badInput("missing -o OUT.wav (where to write the sound)"));
  // Outputs first: a typo in a path must not cost a simulation and an eigen-solve.
  if (Status ok = checkOutputFile("-o", args.text("-o"), {".wav", ".flac"}); !ok)
    return reportError("render", ok.error());
  if (args.has("--events"))
    if (Status ok = checkOutputFile("--events", args.text("--events"), {}); !ok)
      return reportError("render", ok.error());
  if (Result<SampleEncoding> e = sampleEncodingFor(args, args.text("-o")); !e) return reportError("render", e.error());
  Result<Scene> scene = loadScene(args.positional[0]);
  if (!scene) return reportError("render", scene.error());

  RenderSettings settings;
  Result<double> rate = args.number("--rate", 0.0);
  Result<double> duration = args.number("--duration", 0.0);
  Result<double> gain = args.number("--gain", 1.0);
  for (const Result<double>* r : {&rate, &duration, &gain})
    if (!*r) return reportError("render", r->error());
  if (args.has("--rate") && !(*rate >= 8000 && *rate <= 384000))
    return reportError("render", badInput("--rate = " + args.text("--rate") + " (must be 8000 to 384000 Hz)"));
  if (args.has("--duration") && !(*duration > 0 && *duration <= 3600))
    return reportError("render", badInput("--duration = " + args.text("--duration") + " (must be in (0, 3600] s)"));
  if (!(*gain > 0)) return reportError("render", badInput("--gain = " + args.text("--gain") + " (must be > 0)"));
  settings.sample_rate_hz = *rate;
  settings.duration_s = *duration;
  settings.gain = *gain;
  Result<long long> max_tets = args.integer("--max-tets", kDefaultMaxTets);
  if (!max_tets) return reportError("render", max_tets.error());
  if (*max_tets < 1)
    return reportError("render", badInput("--max-tets = " + args.text("--max-tets") + " (must be >= 1)"));
  settings.max_tets = *max_tets;
  Result<double> max_memory = memoryBudgetFromArgs(args);
  if (!max_memory) return reportError("render", max_memory.error());
  settings.max_memory_bytes = *max_memory;
  Result<long long> max_events = args.integer("--max-events", static_cast<long long>(settings.max_events));
  if (!max_events) return reportError("render", max_events.error());
  if (*max_events < 1)
    return reportError("render", badInput("--max-events = " + args.text("--max-events") + " (must be >= 1)"));
  settings.max_events = static_cast<size_t>(*max_events);
  Result<SimdLevel> simd = simdLevelFor(args);
  if (!simd) return reportError("render", simd.error());
  settings.simd = *simd;
  if (args.has("--output")) {
    const std::optional<OutputFormat> format = parseOutputFormat(args.text("--output"));
    if (!format)
      return reportError("render", badInput("--output = " + args.text("--output") +
                                            " (must be mono, stereo, binaural, ambix1, ambix2 or ambix3)"));
    settings.output_format = *format;
  }
  if (args.has("--hrtf")) {
    if (settings.output_format != OutputFormat::Binaural)
      return reportError("render", badInput("--hrtf " + args.text("--hrtf") + " needs --output binaural"));
    settings.hrtf_file = args.text("--hrtf");
  }
  if (args.has("--via-library")) settings.output = libraryOutput(settings.gain);
  settings.similar_reuse = args.has("--similar");
  if (args.has("--transfer") && args.has("--no-transfer"))
    return reportError("render", badInput("give --transfer or --no-transfer, not both"));
  settings.acoustic_transfer = !args.has("--no-transfer");
  settings.cache_dir = args.has("--no-cache") ? "" : args.text("--cache", defaultCacheDir());
  if (args.has("--cache-max-size")) {
    Result<uint64_t> cap = parseByteSize(args.text("--cache-max-size"), "--cache-max-size");
    if (!cap) return reportError("render", cap.error());
    settings.cache_max_bytes = *cap;
  }

  const std::string output = args.text("-o");
  Result<SampleEncoding> encoding_result = sampleEncodingFor(args, output);
  if (!encoding_result) return reportError("render", encoding_result.error());
  const SampleEncoding encoding = *encoding_result;

  const bool quiet = args.has("--quiet");
  ProgressReporter progress("render", quiet, args.has("--progress"));
  settings.progress = progress.callback();
  // Warnings are printed as they are found, even with --quiet: they say the result is probably
  // not what was meant, and the scene's are known before the simulation starts.
  settings.on_warning = [&progress](const std::string& warning) {
    progress.finish();  // end a progress line first
    std::fprintf(stderr, "strike render: warning: %s\n", warning.c_str());
  };
  Result<RenderResult> result = renderScene(*scene, settings);
  progress.finish();
  if (!result) return reportError("render", result.error());
  Status written = writeAudio(output, result->audio, encoding);
  if (!written) return reportError("render", written.error());
  progress.written(output);
  if (args.has("--events")) {
    Status events = writeEventsCsv(args.text("--events"), *result);
    if (!events) {
      // A failed command leaves no output: the WAV is whole, but the run is not.
      std::remove(output.c_str());
      return reportError("render", events.error());
    }
  }
  if (!quiet)
    printSummary(*result, output, result->audio.sample_rate_hz, result->audio.frames() / result->audio.sample_rate_hz);
  return 0;
}

}  // namespace strike::cli
