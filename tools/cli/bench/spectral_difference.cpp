// SPDX-License-Identifier: MIT
// How far one render's spectral peaks are from another's (bench_studies.hpp): used by the
// accuracy and leftout studies.
#include <algorithm>
#include <cmath>

#include "bench_studies.hpp"
#include "strike/audio/audio.hpp"

namespace strike::cli {

SpectralDifference spectralDifference(const AudioBuffer& reference, const AudioBuffer& test) {
  AnalyzeOptions options;
  options.fit_decay = false;
  const AudioAnalysis a = analyzeAudio(reference, options), b = analyzeAudio(test, options);
  SpectralDifference d;
  d.peaks = a.peaks.size();
  // The strongest peak sets 0 dB in each analysis; compare absolute levels (dBFS) instead.
  for (const SpectralPeak& p : a.peaks) {
    const SpectralPeak* nearest = nullptr;
    for (const SpectralPeak& q : b.peaks)
      if (!nearest || std::abs(q.freq_hz - p.freq_hz) < std::abs(nearest->freq_hz - p.freq_hz)) nearest = &q;
    if (!nearest) {
      d.unmatched_peaks++;
      continue;
    }
    // A peak that moved by more than 1 % is a different line: the reference's line went missing.
    if (std::abs(nearest->freq_hz - p.freq_hz) > 0.01 * p.freq_hz) {
      d.unmatched_peaks++;
      continue;
    }
    d.max_freq_rel = std::max(d.max_freq_rel, std::abs(nearest->freq_hz - p.freq_hz) / p.freq_hz);
    d.max_level_db = std::max(d.max_level_db, std::abs(nearest->level_dbfs - p.level_dbfs));
  }
  return d;
}

}  // namespace strike::cli
