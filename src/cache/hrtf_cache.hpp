// SPDX-License-Identifier: MIT
// A binaural render's head-related responses (HrtfSet, strike/synth/hrtf.hpp) cached beside the mode
// banks, resampled to the render's rate, keyed by a hash of the SOFA file's bytes and the rate:
// reading the KEMAR set with libmysofa and resampling it to 48 kHz costs ~0.45 s of CPU every
// render, reading it back ~5 ms. The same file at the same rate gives the same responses, bit for
// bit, so a render is the same bytes with the cache cold or warm. Internal to strike_scene.
#pragma once

#include <cstdint>
#include <string>

#include "strike/synth/hrtf.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// Content key of a set: the SOFA file's bytes, the sample rate and the file format's version.
uint64_t hrtfKey(const std::string& sofa_bytes, double sample_rate_hz);

/// "<cache_dir>/<16 hex digits>.hrtf".
std::string hrtfPath(const std::string& cache_dir, uint64_t key);

/// Reads a set written for this key (not prepared: prepareHrtfSet is the caller's); an error if
/// it is missing, damaged (checksum, sizes) or for another key: the caller then reads the SOFA file.
Result<HrtfSet> readHrtf(const std::string& path, uint64_t key);

/// Writes a set atomically. Format (little-endian): "STRKHRT1", u64 key, f64 sample rate, u32
/// taps, u32 directions, 3 f64 per direction, then the left and the right responses (directions
/// x taps f32 each), then u64 FNV-1a of all before.
Status writeHrtf(const std::string& path, uint64_t key, const HrtfSet& set);

}  // namespace strike
