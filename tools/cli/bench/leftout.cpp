// SPDX-License-Identifier: MIT
// `strike bench leftout SCENE.json -o DIR`: what a render leaves out, and what that saves.
// Renders one scene three times in this process:
//   everything  nothing left out (RenderSettings::leave_nothing_out): every object gets a bank
//               and an oscillator, every mode of the banks is synthesized (no 20 kHz synth cap),
//               the audibility threshold is at its -600 dB floor (nothing culled, nothing sleeps
//               before it has rung down that far), no cache;
//   normal      as `strike render` with an empty cache (eigen-solves only for what is heard);
//   cached      as `strike render` a second time (the cache answers the eigen-solves).
// Writes DIR/leftout.csv (one row per run: times per phase, modes, work), the everything and the
// normal render as DIR/leftout-everything.wav and DIR/leftout-normal.wav, and prints the ratios
// and the difference between the normal and the everything audio: largest sample difference
// (re the peak and in dB SPL, 1.0 = 20 Pa) and the spectral peaks' frequency and level changes.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "bench_studies.hpp"
#include "strike/audio/audio.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"

namespace strike::cli {
namespace {

struct LeftOutRun {
  const char* name;
  RenderReport report;
  AudioBuffer audio;
};

}  // namespace

Status benchLeftOut(const std::string& scene_path, const std::string& dir) {
  Result<Scene> scene = loadScene(scene_path);
  if (!scene) return scene.error();
  const std::string cache = dir + "/leftout-cache";
  std::error_code ignored;
  std::filesystem::remove_all(cache, ignored);  // the normal run starts from an empty cache

  std::vector<LeftOutRun> runs;
  for (const char* name : {"everything", "normal", "cached"}) {
    RenderSettings settings;
    settings.leave_nothing_out = std::string(name) == "everything";
    // No acoustic transfer: what leaving out saves is eigen-solves and synthesis, and solving a
    // transfer for every silent object would measure the BEM instead.
    settings.cache_dir = settings.leave_nothing_out ? "" : cache;
    std::fprintf(stderr, "strike bench: rendering %s (%s)\n", scene_path.c_str(), name);
    Result<RenderResult> r = renderScene(*scene, settings);
    if (!r) return r.error();
    runs.push_back({name, r->report, std::move(r->audio)});
  }
  std::filesystem::remove_all(cache, ignored);
  // Both renders, to listen to (or analyse) side by side.
  for (size_t i = 0; i < 2; ++i)
    if (Status ok = writeAudio(dir + "/leftout-" + runs[i].name + ".wav", runs[i].audio, SampleEncoding::Float32); !ok)
      return ok;

  std::ofstream csv(dir + "/leftout.csv");
  if (!csv) return badInput(dir + "/leftout.csv: error: cannot create file");
  csv << "run,objects_sounded,banks_computed,banks_cached,modes_total,modes_out_of_band,mode_samples,"
         "simulate_s,modes_s,synthesize_s,total_s\n";
  for (const LeftOutRun& run : runs) {
    const RenderReport& r = run.report;
    csv << run.name << "," << r.objects_sounded << "," << r.banks_computed << "," << r.banks_cached << ","
        << r.modes_total << "," << r.modes_out_of_band << "," << r.mode_samples << "," << r.simulate_seconds << ","
        << r.precompute_seconds << "," << r.synthesize_seconds << "," << r.total_seconds << "\n";
  }

  // Normal against everything, sample by sample (same simulation, same impacts).
  const AudioBuffer& all = runs[0].audio;
  const AudioBuffer& normal = runs[1].audio;
  double peak = 0, max_diff = 0, diff2 = 0;
  const size_t n = std::min(all.samples.size(), normal.samples.size());
  for (size_t i = 0; i < n; ++i) {
    const double d = double(normal.samples[i]) - all.samples[i];
    peak = std::max(peak, double(std::abs(all.samples[i])));
    max_diff = std::max(max_diff, std::abs(d));
    diff2 += d * d;
  }
  const double rms_diff = n ? std::sqrt(diff2 / double(n)) : 0.0;
  auto dbSpl = [](double full_scale) {
    return 20 * std::log10(std::max(full_scale * kFullScalePascal, 1e-30) / 20e-6);
  };
  const SpectralDifference spectral = spectralDifference(all, normal);
  csv << "# normal vs everything: max |difference| " << max_diff / std::max(peak, 1e-30) << " of peak ("
      << dbSpl(max_diff) << " dB SPL), rms difference " << dbSpl(rms_diff)
      << " dB SPL; spectral peaks: " << spectral.peaks << " compared, " << spectral.unmatched_peaks
      << " unmatched, frequency within " << spectral.max_freq_rel << ", level within " << spectral.max_level_db
      << " dB\n";

  const RenderReport &e = runs[0].report, &o = runs[1].report, &c = runs[2].report;
  std::fprintf(stderr,
               "strike bench leftout: %s\n"
               "  everything  %zu objects sounded, %llu modes, %.3g mode-samples; modes %.2f s, synthesize %.2f s, "
               "total %.2f s\n"
               "  normal      %zu objects sounded, %llu modes, %.3g mode-samples; modes %.2f s, synthesize %.2f s, "
               "total %.2f s\n"
               "  cached      modes %.2f s, synthesize %.2f s, total %.2f s\n"
               "  saved       everything / normal: %.2fx total (modes %.2fx, synthesis %.2fx, work %.2fx); "
               "everything / cached: %.2fx total\n"
               "  difference  max %.2g of peak (%.1f dB SPL), rms %.1f dB SPL; %zu spectral peaks, %zu unmatched, "
               "frequency within %.2g, level within %.3f dB\n"
               "strike bench: wrote %s/leftout.csv\n",
               scene_path.c_str(), e.objects_sounded, static_cast<unsigned long long>(e.modes_total),
               double(e.mode_samples), e.precompute_seconds, e.synthesize_seconds, e.total_seconds, o.objects_sounded,
               static_cast<unsigned long long>(o.modes_total), double(o.mode_samples), o.precompute_seconds,
               o.synthesize_seconds, o.total_seconds, c.precompute_seconds, c.synthesize_seconds, c.total_seconds,
               e.total_seconds / o.total_seconds, e.precompute_seconds / std::max(o.precompute_seconds, 1e-9),
               e.synthesize_seconds / std::max(o.synthesize_seconds, 1e-9),
               double(e.mode_samples) / std::max(double(o.mode_samples), 1.0), e.total_seconds / c.total_seconds,
               max_diff / std::max(peak, 1e-30), dbSpl(max_diff), dbSpl(rms_diff), spectral.peaks,
               spectral.unmatched_peaks, spectral.max_freq_rel, spectral.max_level_db, dir.c_str());
  return {};
}

}  // namespace strike::cli
