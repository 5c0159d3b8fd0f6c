// SPDX-License-Identifier: MIT
// `strike hit BANK.modes -o OUT.wav`: one impact on one object, rendered to a sound file.
#include <cmath>
#include <cstdio>
#include <algorithm>
#include <limits>

#include "args.hpp"
#include "commands.hpp"
#include "output_check.hpp"
#include "strike/audio.hpp"
#include "strike/bank.hpp"
#include "strike/materials.hpp"
#include "strike/render.hpp"
#include "strike/synth.hpp"

namespace strike::cli {
namespace {

constexpr double kSpeedOfSoundAir_m_s = 343.0;  // dry air at 20 C

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
      {"--at", "X,Y,Z", "strike the surface point nearest to X,Y,Z (metres, mesh frame); prints that point and\n"
                        "how far it is from X,Y,Z, and warns past 2% of the object's size"},
      {"--impulse", "X,Y,Z", "impulse vector, N s; default 0.01 N s into the surface along its normal"},
      {"--duration", "S", "length of the output, s; default 2"},
      {"--rate", "HZ", "sample rate; default 48000"},
      {"--format", "pcm16|pcm24|float", "sample encoding; default float for .wav, pcm24 for .flac"},
      {"--distance", "M", "listener distance from the object, m; default 1 (sets gain and delay)"},
      {"--gain", "G", "multiply the output (1.0 full scale = 20 Pa); default 1"},
      {"--contact-time", "S", "force pulse duration, s (0 = ideal impulse); default from Hertz theory"},
      {"--striker", "MATERIAL", "striker sphere material for the Hertz contact time; default steel"},
      {"--striker-radius", "M", "striker sphere radius, m; default 0.005"},
      {"--simd", "KERNEL", kSimdHelp},
      {"--quiet", "", "no summary on stderr (warnings are still printed)"},
  };
  spec.examples =
      "  strike hit bar.modes -o hit.wav --vertex 12 --impulse 0,0,-0.01 --duration 2\n"
      "  strike hit bowl.modes -o rim.wav --at 0.1,0,0.05 --impulse 0,0,-0.02 --rate 96000\n";
  spec.min_positional = 1;
  spec.max_positional = 1;
  return spec;
}

/// The surface vertex whose in-band modes an impulse along the inward normal excites most
/// (sum over modes of (phi_i . n)^2 / lambda_i, i.e. the modal displacement energy it injects).
size_t loudestVertex(const ModeBank& bank) {
  size_t best = 0;
  double best_score = -1.0;
  for (size_t v = 0; v < bank.surfaceVertexCount(); ++v) {
    const float* n = &bank.surface_normals[v * 3];
    double score = 0.0;
    for (size_t i = 0; i < bank.modeCount(); ++i) {
      const float* phi = bank.shapeAt(i, v);
      const double along = phi[0] * n[0] + phi[1] * n[1] + phi[2] * n[2];
      if (bank.eigenvalues[i] > 0) score += along * along / bank.eigenvalues[i];
    }
    if (score > best_score) best_score = score, best = v;
  }
  return best;
}

/// The largest side of the bank's surface bounding box, m.
double objectSizeM(const ModeBank& bank) {
  double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < bank.surfaceVertexCount(); ++v)
    for (int a = 0; a < 3; ++a) {
      low[a] = std::min(low[a], double(bank.surface_positions[v * 3 + a]));
      high[a] = std::max(high[a], double(bank.surface_positions[v * 3 + a]));
    }
  return std::max({high[0] - low[0], high[1] - low[1], high[2] - low[2], 0.0});
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
  if (bank.surfaceVertexCount() == 0) return reportError("hit", badInput(args.positional[0] + ": the bank has no surface"));

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
  if (!(*distance > 0)) return reportError("hit", badInput("--distance = " + args.text("--distance") + " (must be > 0 m)"));
  if (!(*striker_radius > 0))
    return reportError("hit", badInput("--striker-radius = " + args.text("--striker-radius") + " (must be > 0 m)"));

  // Where: a vertex, or the nearest surface point to --at.
  size_t vertex = 0;
  double point[3];
  double requested[3] = {0, 0, 0};
  double off_surface_m = 0.0;  // --at: distance from the requested point to the surface point struck
  if (args.has("--at")) {
    Result<std::array<double, 3>> at = args.vector3("--at", {});
    if (!at) return reportError("hit", at.error());
    for (int a = 0; a < 3; ++a) requested[a] = point[a] = (*at)[a];
    // The point struck is the nearest point on the surface (what projectImpulse uses): report
    // it, not the point asked for, and how far apart they are.
    const SurfaceLocator locator(bank);
    uint32_t corners[3] = {0, 0, 0};
    double weights[3] = {1, 0, 0};
    locator.nearest(requested, corners, weights);
    double best_weight = -1.0;
    point[0] = point[1] = point[2] = 0.0;
    for (int k = 0; k < 3; ++k) {
      if (weights[k] > best_weight) best_weight = weights[k], vertex = corners[k];  // the impulse's default normal
      for (int a = 0; a < 3; ++a) point[a] += weights[k] * bank.surface_positions[corners[k] * 3 + a];
    }
    off_surface_m = std::sqrt(std::pow(point[0] - requested[0], 2) + std::pow(point[1] - requested[1], 2) +
                              std::pow(point[2] - requested[2], 2));
  } else {
    Result<long long> chosen = args.integer("--vertex", static_cast<long long>(loudestVertex(bank)));
    if (!chosen) return reportError("hit", chosen.error());
    if (*chosen < 0 || static_cast<size_t>(*chosen) >= bank.surfaceVertexCount())
      return reportError("hit", badInput("--vertex = " + args.text("--vertex") + " (the bank has surface vertices 0 to " +
                                         std::to_string(bank.surfaceVertexCount() - 1) + ")"));
    vertex = static_cast<size_t>(*chosen);
    for (int a = 0; a < 3; ++a) point[a] = bank.surface_positions[vertex * 3 + a];
  }
  const float* normal = &bank.surface_normals[vertex * 3];
  Result<std::array<double, 3>> impulse_arg =
      args.vector3("--impulse", {-0.01 * normal[0], -0.01 * normal[1], -0.01 * normal[2]});
  if (!impulse_arg) return reportError("hit", impulse_arg.error());
  const double impulse[3] = {(*impulse_arg)[0], (*impulse_arg)[1], (*impulse_arg)[2]};
  const std::vector<double> modal_impulse =
      args.has("--at") ? projectImpulse(bank, requested, impulse) : projectImpulseAtVertex(bank, vertex, impulse);

  // How long the contact lasts: Hertz theory for a sphere striking a locally flat surface, at the
  // speed that gives this impulse in an elastic rebound (J = 2 m* v).
  double contact_time_s = 0.0;
  if (args.has("--contact-time")) {
    Result<double> t = args.number("--contact-time", 0.0);
    if (!t) return reportError("hit", t.error());
    if (!(*t >= 0 && *t < 1)) return reportError("hit", badInput("--contact-time = " + args.text("--contact-time") + " (must be in [0, 1) s)"));
    contact_time_s = *t;
  } else {
    Result<Material> striker = builtinMaterials().find(args.text("--striker", "steel"));
    if (!striker) return reportError("hit", striker.error());
    const double striker_mass = striker->density_kg_m3 * 4.0 / 3.0 * M_PI * std::pow(*striker_radius, 3);
    const double reduced_mass = striker_mass * bank.mass_kg / (striker_mass + bank.mass_kg);
    const double j_normal = std::fabs(impulse[0] * normal[0] + impulse[1] * normal[1] + impulse[2] * normal[2]);
    const double speed = j_normal / (2.0 * reduced_mass);
    if (speed > 0)
      contact_time_s = hertzContactDuration(striker->youngs_pa, striker->poisson, *striker_radius, striker_mass,
                                            bank.material.youngs_pa, bank.material.poisson,
                                            std::numeric_limits<double>::infinity(), bank.mass_kg, speed);
  }

  SynthSettings settings;
  settings.sample_rate_hz = *rate;
  settings.simd = *simd;
  OscillatorBank synth(settings);
  ModalObjectDesc object;
  object.eigenvalues = bank.eigenvalues;
  object.rayleigh_stiffness = bank.material.rayleigh_stiffness;
  object.rayleigh_mass = bank.material.rayleigh_mass;
  object.radiation_weight = radiationWeights(bank, *distance);
  for (double& w : object.radiation_weight) w *= *gain / kFullScalePascal;
  object.delay_s = *distance / kSpeedOfSoundAir_m_s;
  const uint32_t id = synth.addObject(object);
  ImpactDesc impact;
  impact.object = id;
  impact.time_s = 0.0;
  impact.duration_s = contact_time_s;
  impact.modal_impulse = modal_impulse.data();
  synth.addImpact(impact);

  AudioBuffer audio;
  audio.sample_rate_hz = *rate;
  audio.channels = 1;
  audio.samples.resize(static_cast<size_t>(std::llround(*duration * *rate)));
  synth.render(audio.samples.data(), audio.samples.size());

  double peak = 0.0;
  size_t clipped = 0;
  for (float s : audio.samples) {
    peak = std::max(peak, static_cast<double>(std::fabs(s)));
    if (std::fabs(s) >= 1.0f) ++clipped;
  }
  const std::string output = args.text("-o");
  Result<SampleEncoding> encoding_result = sampleEncodingFor(args, output);
  if (!encoding_result) return reportError("hit", encoding_result.error());
  const SampleEncoding encoding = *encoding_result;
  Status written = writeAudio(output, audio, encoding);
  if (!written) return reportError("hit", written.error());

  // A point asked for far from the surface is probably a mistake (a unit, a sign, another
  // object's frame): warn past 2% of the object's size (1 mm at least), even with --quiet.
  const double size_m = objectSizeM(bank);
  if (args.has("--at") && off_surface_m > std::max(1e-3, 0.02 * size_m))
    std::fprintf(stderr,
                 "strike hit: warning: --at %s is %.4g m from the object's surface (the object is %.4g m across); "
                 "struck the nearest surface point (%.4g, %.4g, %.4g) m instead\n",
                 args.text("--at").c_str(), off_surface_m, size_m, point[0], point[1], point[2]);
  const SynthStats stats = synth.stats();
  if (stats.modes_total == stats.modes_out_of_band)
    std::fprintf(stderr, "strike hit: warning: silent: no mode in the audible band (%s)\n",
                 bank.modeCount() == 0 ? "the bank has no elastic mode below its cut-off: too small or too stiff to ring"
                                       : "every mode of the bank is outside 20 Hz to min(20 kHz, 0.45 x --rate)");
  if (!args.has("--quiet")) {
    if (args.has("--at"))
      std::fprintf(stderr, "strike hit: %s, surface point (%.4g, %.4g, %.4g) m (nearest vertex %zu), %.3g m from --at, "
                   "impulse (%.3g, %.3g, %.3g) N s\n",
                   args.positional[0].c_str(), point[0], point[1], point[2], vertex, off_surface_m, impulse[0], impulse[1],
                   impulse[2]);
    else
      std::fprintf(stderr, "strike hit: %s, vertex %zu at (%.4g, %.4g, %.4g) m, impulse (%.3g, %.3g, %.3g) N s\n",
                   args.positional[0].c_str(), vertex, point[0], point[1], point[2], impulse[0], impulse[1], impulse[2]);
    std::fprintf(stderr, "  contact     %.3g ms (%s)\n", contact_time_s * 1e3,
                 args.has("--contact-time") ? "given" : "Hertz");
    std::fprintf(stderr, "  modes       %llu in the bank, %llu out of band, %llu started\n",
                 static_cast<unsigned long long>(stats.modes_total),
                 static_cast<unsigned long long>(stats.modes_out_of_band),
                 static_cast<unsigned long long>(stats.mode_starts));
    if (peak == 0.0)
      std::fprintf(stderr, "  level       silent: every sample is 0 (%s)\n",
                   stats.modes_total == stats.modes_out_of_band ? "no mode in the audible band"
                                                                : "the impulse excites no mode at this point and direction");
    else
      std::fprintf(stderr, "  level       peak %.4g (%.1f dBFS, %.1f dB SPL at %.3g m)\n", peak, 20.0 * std::log10(peak),
                   20.0 * std::log10(peak * kFullScalePascal / *gain / 20e-6), *distance);
    if (clipped > 0)
      std::fprintf(stderr, "  CLIPPING    %zu samples at or above full scale%s; lower --gain\n", clipped,
                   encoding == SampleEncoding::Float32 ? " (kept in the float file)" : " (clipped in the file)");
    std::fprintf(stderr, "  wrote       %s (%.3g s at %.0f Hz, %s)\n", output.c_str(), *duration, *rate, args.text("--format", "default encoding").c_str());
  }
  return 0;
}

}  // namespace strike::cli
