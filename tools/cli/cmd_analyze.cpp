// SPDX-License-Identifier: MIT
// `strike analyze AUDIO.wav [--json]`: peaks, levels and decay of a sound, and its pictures.
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "output_check.hpp"
#include "strike/audio/audio.hpp"

namespace strike::cli {
namespace {

CommandSpec analyzeSpec() {
  CommandSpec spec;
  spec.usage = "strike analyze AUDIO.wav [--json] [--peaks N]";
  spec.summary =
      "Measures a sound: peak amplitude, RMS, clipping, and the strongest spectral peaks from a windowed\n"
      "FFT (FFTW) with sub-bin interpolation: frequency, level relative to the strongest peak, and the\n"
      "amplitude decay rate d of A e^(-d t) fitted per peak (T60 = 6.91 / d). A file with several\n"
      "impacts is cut at each impact (a jump of 6 dB over the last 25 ms) and each free ring analysed\n"
      "alone, so a mode struck N times is one peak with its own decay, not a comb 1/(time between\n"
      "impacts) apart; a line is reported from the impact where it is strongest.";
  spec.options = {
      {"--json", "", "print one JSON object on stdout (the contract in docs/cli.md)"},
      {"--peaks", "N", "report the N strongest peaks; default 20"},
      {"--floor", "DB", "ignore peaks more than DB below the strongest; default -60"},
      {"--spectrogram", "PNG",
       "also draw a spectrogram (log frequency, 100 dB range) to this PNG file: one panel per channel, "
       "labelled L and R for two channels, by ACN index and letter (W Y Z X ...) for Ambisonics"},
      {"--directions", "PNG",
       "also draw, for an Ambisonics file (AmbiX: ACN, SN3D; 4, 9 or 16 channels), the direction its sound "
       "arrives from over time: azimuth and elevation per 10 ms frame from the first-order intensity, "
       "coloured by level (docs/cli.md)"},
  };
  spec.examples =
      "  strike analyze hit.wav\n  strike analyze hit.wav --json --peaks 5\n"
      "  strike analyze render.wav --spectrogram render.png\n"
      "  strike analyze ambix.wav --directions directions.png\n";
  spec.min_positional = 1;
  spec.max_positional = 1;
  return spec;
}

}  // namespace

int runAnalyze(const std::vector<std::string>& raw_args) {
  const CommandSpec spec = analyzeSpec();
  if (wantsHelp(raw_args)) {
    std::fputs(helpText(spec).c_str(), stdout);
    return 0;
  }
  Result<ParsedArgs> args = parseArgs(spec, raw_args);
  if (!args) return reportError("analyze", args.error());
  AnalyzeOptions options;
  Result<long long> peaks = args->integer("--peaks", options.max_peaks);
  if (!peaks) return reportError("analyze", peaks.error());
  if (*peaks < 1 || *peaks > 10000)
    return reportError("analyze", badInput("--peaks = " + args->text("--peaks") + " (must be 1 to 10000)"));
  options.max_peaks = static_cast<int>(*peaks);
  Result<double> floor_db = args->number("--floor", options.floor_db);
  if (!floor_db) return reportError("analyze", floor_db.error());
  if (!(*floor_db < 0))
    return reportError("analyze", badInput("--floor = " + args->text("--floor") + " (must be < 0 dB)"));
  options.floor_db = *floor_db;

  if (args->has("--spectrogram"))
    if (Status ok = checkOutputFile("--spectrogram", args->text("--spectrogram"), {".png"}); !ok)
      return reportError("analyze", ok.error());
  if (args->has("--directions"))
    if (Status ok = checkOutputFile("--directions", args->text("--directions"), {".png"}); !ok)
      return reportError("analyze", ok.error());
  const std::string path = args->positional[0];
  Result<AudioBuffer> audio = readAudio(path);
  if (!audio) return reportError("analyze", audio.error());
  if (args->has("--directions") && audio->channels < 4)
    return reportError("analyze", badInput(path + ": " + std::to_string(audio->channels) +
                                           " channel(s): --directions needs Ambisonics (AmbiX: ACN order, SN3D) of "
                                           "4, 9 or 16 channels, e.g. from strike render --output ambix1"));
  const AudioAnalysis analysis = analyzeAudio(*audio, options);
  if (args->has("--spectrogram")) {
    Status drawn = writeSpectrogramPng(args->text("--spectrogram"), *audio, SpectrogramOptions{});
    if (!drawn) return reportError("analyze", drawn.error());
  }
  if (args->has("--directions")) {
    Status drawn = writeDirectionsPng(args->text("--directions"), *audio, DirectionOptions{});
    if (!drawn) return reportError("analyze", drawn.error());
  }

  if (args->has("--json")) {
    nlohmann::json j;
    j["file"] = path;
    j["sample_rate"] = analysis.sample_rate_hz;
    j["channels"] = audio->channels;
    j["duration_s"] = analysis.duration_s;
    j["peak_amplitude"] = analysis.peak_amplitude;
    j["peak_dbfs"] =
        20.0 * std::log10(std::max(analysis.peak_amplitude, 1e-30));  // -600 when silent (JSON has no -inf)
    j["silent"] = analysis.peak_amplitude == 0.0;
    j["rms"] = analysis.rms;
    j["clipped_samples"] = analysis.clipped_samples;
    j["impact_onsets_s"] = analysis.impact_onsets_s;
    j["peaks"] = nlohmann::json::array();
    for (const SpectralPeak& p : analysis.peaks) {
      nlohmann::json peak = {{"freq_hz", p.freq_hz}, {"level_db", p.level_db}};
      if (p.decay_per_s >= 0) peak["decay_per_s"] = p.decay_per_s;
      j["peaks"].push_back(peak);
    }
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("%s: %.0f Hz, %d channel(s), %.3f s\n", path.c_str(), analysis.sample_rate_hz, audio->channels,
              analysis.duration_s);
  if (analysis.peak_amplitude == 0.0) {
    std::printf("silent: every sample is 0 (no peaks)\n");
    return 0;
  }
  std::printf("peak %.4g (%.1f dBFS), RMS %.4g (%.1f dBFS)%s\n\n", analysis.peak_amplitude,
              20.0 * std::log10(std::max(analysis.peak_amplitude, 1e-30)), analysis.rms,
              20.0 * std::log10(std::max(analysis.rms, 1e-30)),
              analysis.clipped_samples > 0
                  ? (", " + std::to_string(analysis.clipped_samples) + " samples clipped").c_str()
                  : "");
  if (analysis.impact_onsets_s.size() > 1)
    std::printf("%zu impacts (first at %.3f s): peaks merged from the free ring after each\n\n",
                analysis.impact_onsets_s.size(), analysis.impact_onsets_s.front());
  std::printf("%5s %14s %10s %12s %10s\n", "peak", "frequency Hz", "level dB", "decay 1/s", "T60 s");
  for (size_t i = 0; i < analysis.peaks.size(); ++i) {
    const SpectralPeak& p = analysis.peaks[i];
    if (p.decay_per_s > 0)
      std::printf("%5zu %14.3f %10.2f %12.4g %10.4g\n", i, p.freq_hz, p.level_db, p.decay_per_s,
                  6.907755 / p.decay_per_s);
    else
      std::printf("%5zu %14.3f %10.2f %12s %10s\n", i, p.freq_hz, p.level_db, "-", "-");
  }
  return 0;
}

}  // namespace strike::cli
