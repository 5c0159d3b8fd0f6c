// SPDX-License-Identifier: MIT
// The spatializer: how one path's sound (the direct sound, the ground's image) reaches the
// output's channels from its direction of arrival in the listener's frame. The engine renders
// each path as one signal and hands it here for per-channel gains, refreshed every render call
// and ramped over it (docs/listener.md).
//
// The listener's frame: +y forward (where the listener faces), +x to the right, +z up, as
// strike_listener_set_pose and the scene's listener.orientation define it.
//
// Formats:
//  - Mono: the level alone, one channel (the default; both paths share one signal then).
//  - Stereo: a constant-power pan by the direction's x component (left, right).
//  - Binaural: two channels (left ear, right ear); the level here, the direction by the path's
//    head-related filters (hrtf.hpp), which the engine runs after these gains.
//  - AmbiX of order N = 1..3: (N+1)^2 channels in ACN order with SN3D normalisation, the
//    real spherical harmonics without the Condon-Shortley phase [Nachbar, Zotter, Deleflie &
//    Sontacchi 2011, "AmbiX - a suggested Ambisonics format"], evaluated at the direction of
//    arrival in the Ambisonics frame (x forward, y left, z up).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace strike {

enum class OutputFormat { Mono, Stereo, Ambix1, Ambix2, Ambix3, Binaural };

/// The largest channel count of any format (third-order Ambisonics).
constexpr uint32_t kMaxOutputChannels = 16;

uint32_t outputChannels(OutputFormat format);
/// False for mono: one signal carries every path, and no direction reaches the output.
bool outputHasDirections(OutputFormat format);
/// 0 for mono and stereo, else N.
uint32_t ambisonicOrder(OutputFormat format);
/// "mono", "stereo", "ambix1", "ambix2", "ambix3", "binaural".
const char* outputFormatName(OutputFormat format);
/// The format of one of those names, or nothing.
std::optional<OutputFormat> parseOutputFormat(const std::string& name);

/// The real spherical harmonics of AmbiX (ACN order, SN3D, no Condon-Shortley phase) of orders
/// 0..order (<= 3) at the unit direction (x forward, y left, z up): (order + 1)^2 values.
void ambixHarmonics(uint32_t order, const std::array<double, 3>& unit_direction, double* out);

/// The listener's orientation (unit quaternion w, x, y, z: world from listener) that faces
/// `target` from `position` (its +y toward it) with its +z as near the world's +z as it can
/// be (its +x level). Nothing when the target is the position or straight above or below it.
std::optional<std::array<double, 4>> lookAtOrientation(const std::array<double, 3>& position,
                                                       const std::array<double, 3>& target);

/// Per-channel gains of a path arriving from `local` (the source's position relative to the
/// listener, in the listener's frame, m; its length is `distance_m`) at `level` (the listener
/// model's distance gain): outputChannels(format) values into `gains`. A source at the listener
/// (distance below 1 nm) is heard from straight ahead.
void spatialGains(OutputFormat format, const std::array<double, 3>& local, double distance_m, double level,
                  float* gains);

}  // namespace strike
