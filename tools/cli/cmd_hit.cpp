// SPDX-License-Identifier: MIT
// `strike hit BANK.modes -o OUT.wav`: one impact on one object, rendered to a sound file.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "args.hpp"
#include "commands.hpp"
#include "output_check.hpp"
#include "strike/audio/audio.hpp"
#include "strike/bank/bank.hpp"
#include "strike/scene/hit.hpp"
#include "strike/scene/render.hpp"

namespace strike::cli {
namespace {

CommandSpec hitSpec() {
  CommandSpec spec;
  spec.usage = "strike hit BANK.modes -o OUT.wav [--vertex I | --at X,Y,Z] [--impulse X,Y,Z] [options]";
  spec.summary =
      "Strikes the object of a mode bank once and renders what a listener hears. The impulse is projected\n"
      "onto the modes at the strike point (g_i = phi_i(p) . J, interpolated on the surface triangle), shaped\n"
      "as a Hertz contact pulse whose duration follows from the striker (a small sphere) and the speed, and\n"
      "every mode in the audible band is advanced exactly. Output sample 1.0 = 20 Pa at the listener\n"
      "(120 dB SPL) times --gain; clipping is reported, never silent (float output keeps values above 1).";
  spec.options = {
      {"-o", "OUT.wav", "output sound file, .wav or .flac (required); written atomically"},
      {"--vertex", "I", "strike surface vertex I (see `strike info`); default: the vertex that excites most"},
      {"--at", "X,Y,Z",
       "strike the surface point nearest to X,Y,Z (metres, mesh frame); prints that point and\n"
       "how far it is from X,Y,Z, and warns past 2% of the object's size"},
      {"--impulse", "X,Y,Z", "impulse vector, N s; default 0.01 N s into the surface along its normal"},
      {"--duration", "S", "length of the output, s; default 2"},
      {"--rate", "HZ", "sample rate; default 48000"},
      {"--format", "pcm16|pcm24|float", "sample encoding; default float for .wav, pcm24 for .flac"},
      {"--distance", "M",
       "listener distance from the object's centre of mass, on the side struck, m; default 1\n"
       "(sets level, delay and, with a bank that has an acoustic transfer, the direction heard)"},
      {"--listener", "X,Y,Z",
       "the listener at X,Y,Z (metres, mesh frame) instead of --distance: a bank with an acoustic\n"
       "transfer (strike modes --transfer) sounds different in every direction"},
      {"--gain", "G", "multiply the output (1.0 full scale = 20 Pa); default 1"},
      {"--contact-time", "S", "force pulse duration, s (0 = ideal impulse); default from Hertz theory"},
      {"--striker", "MATERIAL", "striker sphere material for the Hertz contact time; default steel"},
      {"--striker-radius", "M", "striker sphere radius, m; default 0.005"},
      {"--simd", "KERNEL", kSimdHelp},
      {"--quiet", "", "no summary on stderr (warnings are still printed)"},
  };
  spec.examples =
      "  strike hit bar.modes -o hit.wav --vertex 12 --impulse 0,0,-0.01 --duration 2\n"
      "  strike hit bowl.modes -o rim.wav --at 0.1,0,0.05 --impulse 0,0,-0.02 --rate 96000\n"
      "  strike hit bar.modes -o end.wav --listener 1,0,0   # heard from the bar's end\n";
  spec.min_positional = 1;
  spec.max_positional = 1;
  return spec;
}

}  // namespace

int runHit(const std::vector<std::string>& raw_args) {
  const CommandSpec spec = hitSpec();
  if (wantsHelp(raw_args)) {
    std::fputs(helpText(spec).c_str(), stdout);
    return 0;
  }
  Result<ParsedArgs> parsed = parseArgs(spec, raw_args);
  if (!parsed) return reportError("hit", parsed.error());
  const ParsedArgs& args = *parsed;
  if (!args.has("-o")) return reportError("hit", badInput("missing -o OUT.wav (where to write the sound)"));
  if (args.has("--vertex") && args.has("--at")) return reportError("hit", badInput("give --vertex or --at, not both"));
  if (Status ok = checkOutputFile("-o", args.text("-o"), {".wav", ".flac"}); !ok) return reportError("hit", ok.error());
  if (Result<SampleEncoding> e = sampleEncodingFor(args, args.text("-o")); !e) return reportError("hit", e.error());

  Result<ModeBank> loaded = readBank(args.positional[0]);
  if (!loaded) return reportError("hit", loaded.error());
  const ModeBank& bank = *loaded;
  if (bank.surfaceVertexCount() == 0)
    return reportError("hit", badInput(args.positional[0] + ": the bank has no surface"));

  Result<double> duration = args.number("--duration", 2.0);
  Result<double> rate = args.number("--rate", 48000.0);
  Result<SimdLevel> simd = simdLevelFor(args);
  if (!simd) return reportError("hit", simd.error());
  Result<double> distance = args.number("--distance", 1.0);
  Result<double> gain = args.number("--gain", 1.0);
  Result<double> striker_radius = args.number("--striker-radius", 0.005);
  for (const Result<double>* r : {&duration, &rate, &distance, &gain, &striker_radius})
    if (!*r) return reportError("hit", r->error());
  if (!(*duration > 0 && *duration <= 3600))
    return reportError("hit", badInput("--duration = " + args.text("--duration") + " (must be in (0, 3600] s)"));
  if (!(*rate >= 8000 && *rate <= 384000))
    return reportError("hit", badInput("--rate = " + args.text("--rate") + " (must be 8000 to 384000 Hz)"));
  if (!(*distance > 0))
    return reportError("hit", badInput("--distance = " + args.text("--distance") + " (must be > 0 m)"));
  if (!(*striker_radius > 0))
    return reportError("hit", badInput("--striker-radius = " + args.text("--striker-radius") + " (must be > 0 m)"));

  HitSettings settings;
  settings.duration_s = *duration;
  settings.sample_rate_hz = *rate;
  settings.distance_m = *distance;
  settings.gain = *gain;
  settings.striker = args.text("--striker", "steel");
  settings.striker_radius_m = *striker_radius;
  settings.simd = *simd;
  if (args.has("--listener")) {
    if (args.has("--distance")) return reportError("hit", badInput("give --distance or --listener, not both"));
    Result<std::array<double, 3>> listener = args.vector3("--listener", {});
    if (!listener) return reportError("hit", listener.error());
    settings.listener_m = *listener;
  }
  if (args.has("--at")) {
    Result<std::array<double, 3>> at = args.vector3("--at", {});
    if (!at) return reportError("hit", at.error());
    settings.at_m = *at;
  } else if (args.has("--vertex")) {
    Result<long long> chosen = args.integer("--vertex", 0);
    if (!chosen) return reportError("hit", chosen.error());
    if (*chosen < 0 || static_cast<size_t>(*chosen) >= bank.surfaceVertexCount())
      return reportError("hit",
                         badInput("--vertex = " + args.text("--vertex") + " (the bank has surface vertices 0 to " +
                                  std::to_string(bank.surfaceVertexCount() - 1) + ")"));
    settings.vertex = static_cast<size_t>(*chosen);
  }
  if (args.has("--impulse")) {
    Result<std::array<double, 3>> impulse = args.vector3("--impulse", {});
    if (!impulse) return reportError("hit", impulse.error());
    settings.impulse_n_s = *impulse;
  }
  if (args.has("--contact-time")) {
    Result<double> t = args.number("--contact-time", 0.0);
    if (!t) return reportError("hit", t.error());
    if (!(*t >= 0 && *t < 1))
      return reportError("hit", badInput("--contact-time = " + args.text("--contact-time") + " (must be in [0, 1) s)"));
    settings.contact_time_s = *t;
  }
  Result<HitResult> hit = renderHit(bank, settings);
  if (!hit) return reportError("hit", hit.error());
  const AudioBuffer& audio = hit->audio;
  const double peak = hit->peak;
  const size_t clipped = hit->clipped_samples;
  const size_t vertex = hit->vertex;
  // Adding 0.0 turns a -0.0 (a negated zero component) into 0: printed "0", not "-0".
  const std::array<double, 3> point = {hit->point_m[0] + 0.0, hit->point_m[1] + 0.0, hit->point_m[2] + 0.0};
  const std::array<double, 3> impulse = {hit->impulse_n_s[0] + 0.0, hit->impulse_n_s[1] + 0.0,
                                         hit->impulse_n_s[2] + 0.0};
  const double contact_time_s = hit->contact_time_s;
  const std::string output = args.text("-o");
  Result<SampleEncoding> encoding_result = sampleEncodingFor(args, output);
  if (!encoding_result) return reportError("hit", encoding_result.error());
  const SampleEncoding encoding = *encoding_result;
  Status written = writeAudio(output, audio, encoding);
  if (!written) return reportError("hit", written.error());

  // A point asked for far from the surface is probably a mistake (a unit, a sign, another
  // object's frame): warn past 2% of the object's size (1 mm at least), even with --quiet.
  const double size_m = objectSizeM(bank);
  const double off_surface_m = hit->off_surface_m;
  if (args.has("--at") && off_surface_m > std::max(1e-3, 0.02 * size_m))
    std::fprintf(stderr,
                 "strike hit: warning: --at %s is %.4g m from the object's surface (the object is %.4g m across); "
                 "struck the nearest surface point (%.4g, %.4g, %.4g) m instead\n",
                 args.text("--at").c_str(), off_surface_m, size_m, point[0], point[1], point[2]);
  const SynthStats& stats = hit->stats;
  if (stats.modes_total == stats.modes_out_of_band)
    std::fprintf(stderr, "strike hit: warning: silent: no mode in the audible band (%s)\n",
                 bank.modeCount() == 0
                     ? "the bank has no elastic mode below its cut-off: too small or too stiff to ring"
                     : "every mode of the bank is outside 20 Hz to min(20 kHz, 0.45 x --rate)");
  if (!args.has("--quiet")) {
    if (args.has("--at"))
      std::fprintf(stderr,
                   "strike hit: %s, surface point (%.4g, %.4g, %.4g) m (nearest vertex %zu), %.3g m from --at, "
                   "impulse (%.3g, %.3g, %.3g) N s\n",
                   args.positional[0].c_str(), point[0], point[1], point[2], vertex, off_surface_m, impulse[0],
                   impulse[1], impulse[2]);
    else
      std::fprintf(stderr, "strike hit: %s, vertex %zu at (%.4g, %.4g, %.4g) m, impulse (%.3g, %.3g, %.3g) N s\n",
                   args.positional[0].c_str(), vertex, point[0], point[1], point[2], impulse[0], impulse[1],
                   impulse[2]);
    std::fprintf(stderr, "  contact     %.3g ms (%s)\n", contact_time_s * 1e3,
                 args.has("--contact-time") ? "given" : "Hertz");
    std::fprintf(stderr, "  modes       %llu in the bank, %llu out of band, %llu started\n",
                 static_cast<unsigned long long>(stats.modes_total),
                 static_cast<unsigned long long>(stats.modes_out_of_band),
                 static_cast<unsigned long long>(stats.mode_starts));
    if (peak == 0.0)
      std::fprintf(stderr, "  level       silent: every sample is 0 (%s)\n",
                   stats.modes_total == stats.modes_out_of_band
                       ? "no mode in the audible band"
                       : "the impulse excites no mode at this point and direction");
    else
      std::fprintf(stderr, "  level       peak %.4g (%.1f dBFS, %.1f dB SPL at %.3g m)\n", peak,
                   20.0 * std::log10(peak), 20.0 * std::log10(peak * kFullScalePascal / *gain / 20e-6), *distance);
    if (bank.transfer.empty() && bank.modeCount() > 0)
      std::fprintf(
          stderr,
          "  note        the bank has no acoustic transfer (format %u, or solved with --no-transfer): each mode\n"
          "              is heard at its direction-averaged level, no direction, a sign that depends on the\n"
          "              solve (docs/listener.md); `strike modes` solves it by default\n",
          bank.format_version);
    if (clipped > 0)
      std::fprintf(stderr, "  CLIPPING    %zu samples at or above full scale%s; lower --gain\n", clipped,
                   encoding == SampleEncoding::Float32 ? " (kept in the float file)" : " (clipped in the file)");
    std::fprintf(stderr, "  wrote       %s (%.3g s at %.0f Hz, %s)\n", output.c_str(), *duration, *rate,
                 args.text("--format", "default encoding").c_str());
  }
  return 0;
}

}  // namespace strike::cli
