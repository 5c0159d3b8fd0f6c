// SPDX-License-Identifier: MIT
// The studies of `strike bench` (bench.cpp parses the command line and calls one of them;
// `strike bench render` is runBenchRender in commands.hpp, render.cpp).
#pragma once

#include <string>

#include "strike/audio/audio.hpp"
#include "strike/core/result.hpp"

namespace strike::cli {

/// `strike bench accuracy -o DIR [--plate]` (accuracy.cpp): FEM, synthesis and integrator
/// error against run time, written to DIR (which exists). Returns the exit code.
int benchAccuracy(const std::string& dir, bool plate);

/// `strike bench leftout SCENE -o DIR` (bench_leftout.cpp): the scene rendered with nothing left
/// out, as normal, and as normal from a warm cache; times, ratios, audio difference.
Status benchLeftOut(const std::string& scene_path, const std::string& dir);

/// (spectral_difference.cpp) How far `test`'s spectral peaks are from `reference`'s (analyzeAudio, default floor -60 dB):
/// each reference peak against the nearest test peak; a nearest peak more than 1 % away counts
/// as unmatched.
struct SpectralDifference {
  size_t peaks = 0, unmatched_peaks = 0;
  double max_freq_rel = 0.0;  ///< largest |f_test - f_ref| / f_ref over matched peaks
  double max_level_db = 0.0;  ///< largest |level_test - level_ref| (dBFS) over matched peaks
};
SpectralDifference spectralDifference(const AudioBuffer& reference, const AudioBuffer& test);

}  // namespace strike::cli
