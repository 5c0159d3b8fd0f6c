// SPDX-License-Identifier: MIT
// One impact on one object, rendered: what `strike hit` and the Python package's strike.hit()
// share, so both give the same samples for the same inputs.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "strike/audio/audio.hpp"
#include "strike/bank/bank.hpp"
#include "strike/synth/engine.hpp"
#include "strike/core/result.hpp"
#include "strike/synth/synth.hpp"

namespace strike {

struct HitSettings {
  std::optional<size_t> vertex;                      ///< strike this surface vertex
  std::optional<std::array<double, 3>> at_m;         ///< or the surface point nearest this (mesh frame)
                                                     ///< neither: the vertex that excites most (loudestVertex)
  std::optional<std::array<double, 3>> impulse_n_s;  ///< default 0.01 N s into the surface along its normal
  double duration_s = 2.0;
  double sample_rate_hz = 48000.0;
  double distance_m = 1.0;                          ///< listener distance from the centre of mass, on the side struck
  std::optional<std::array<double, 3>> listener_m;  ///< or the listener here (mesh frame; distance_m unused)
  double gain = 1.0;                                ///< on top of kFullScalePascal
  std::optional<double> contact_time_s;             ///< force pulse length; default from Hertz theory
  std::string striker = "steel";                    ///< striker ball material (Hertz contact time)
  double striker_radius_m = kDefaultStrikerRadius_m;  ///< the defaults are the library's striker (defaultStriker)
  SimdLevel simd = SimdLevel::Auto;  ///< the synthesizer's kernel (last bits only)
};

struct HitResult {
  AudioBuffer audio;
  size_t vertex = 0;                ///< the struck vertex (nearest to at_m when given)
  std::array<double, 3> point_m{};  ///< where the impulse was applied: the surface point nearest at_m
  double off_surface_m = 0.0;       ///< with at_m: its distance from point_m
  std::array<double, 3> impulse_n_s{};
  double contact_time_s = 0.0;
  SynthStats stats;
  double peak = 0.0;
  size_t clipped_samples = 0;  ///< |sample| >= 1
};

/// The surface vertex whose in-band modes an impulse along the inward normal excites most
/// (sum over modes of (phi_i . n)^2 / lambda_i, i.e. the modal displacement energy it injects).
size_t loudestVertex(const ModeBank& bank);

/// The largest side of the bank's surface bounding box, m.
double objectSizeM(const ModeBank& bank);

/// Strikes the bank's object once at t = 0 and renders `duration_s` of what the listener hears.
/// The callers check the numeric ranges (each names its own option); this checks what needs the
/// bank: a surface, the vertex index, the striker material.
Result<HitResult> renderHit(const ModeBank& bank, const HitSettings& settings);

}  // namespace strike
