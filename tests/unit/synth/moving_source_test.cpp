// SPDX-License-Identifier: MIT
// Moving sources (moving_source.cpp): a ringing body that flies past is heard at its Doppler
// frequency f c / (c - v_r) and at the level 1 / r of where it was when the sound left it; a
// body that comes to rest sounds as one that never moved, to the bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "strike/synth/engine.hpp"

namespace strike {
namespace {

constexpr double kRate = 48000.0;
constexpr double kModeHz = 1000.0;
constexpr double kRayleighMass = 1.0;  // the mode's amplitude decays at 0.5 / s

/// One ringing 1 kHz mode with no far field of its own (heard alike in every direction), on a
/// small triangle at the origin (for the projector), mass 1 kg, no acceleration noise.
std::shared_ptr<ModeBank> ringingBank() {
  auto bank = std::make_shared<ModeBank>();
  ModeBank& b = *bank;
  b.material.youngs_pa = 2e11;
  b.material.poisson = 0.3;
  b.material.rayleigh_mass = kRayleighMass;
  b.mass_kg = 1.0;
  b.volume_m3 = 0.0;
  b.eigenvalues = {std::pow(2.0 * M_PI * kModeHz, 2)};
  b.surface_positions = {0, 0, 0, 0.01, 0, 0, 0, 0.01, 0};
  b.surface_normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  b.surface_triangles = {0, 1, 2};
  b.surface_node_index = {0, 1, 2};
  b.shapes = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  b.radiation_m2 = {1e-3};
  return bank;
}

/// The mode's ringing frequency: omega_d = sqrt(lambda - (c / 2)^2).
double ringingHz() {
  const double lambda = std::pow(2.0 * M_PI * kModeHz, 2);
  return std::sqrt(lambda - 0.25 * kRayleighMass * kRayleighMass) / (2.0 * M_PI);
}

// The fly-by: the body moves along x at kSpeed, kMiss metres from the listener at the origin,
// passing closest at kClosest_s.
constexpr double kSpeed = 20.0, kMiss = 5.0, kClosest_s = 2.0;
std::array<double, 3> flyBy(double t) { return {kSpeed * (t - kClosest_s), kMiss, 0.0}; }

/// The emission time of what is heard at t: t - t_e = r(t_e) / c.
double emissionTime(double t) {
  double t_e = t;
  for (int i = 0; i < 60; ++i) t_e = t - distance(flyBy(t_e), {0, 0, 0}) / kSpeedOfSoundAir_m_s;
  return t_e;
}

struct Path {
  std::array<double, 3> start{}, end{};
  double move_from_s = 0.0, move_to_s = 0.0;  ///< straight and uniform in between
  std::array<double, 3> at(double t) const {
    if (move_to_s <= move_from_s) return flyBy(t);
    const double w = std::clamp((t - move_from_s) / (move_to_s - move_from_s), 0.0, 1.0);
    return {start[0] + w * (end[0] - start[0]), start[1] + w * (end[1] - start[1]), start[2] + w * (end[2] - start[2])};
  }
};

/// Strikes the body at strike_s and renders `seconds`, setting its pose every `block` frames
/// (the pose at the engine's clock, as libstrike's host does).
std::vector<float> render(const Path& path, double strike_s, double seconds, bool moving_sources,
                          OutputFormat output = OutputFormat::Mono, bool ground = false, size_t block = 48) {
  EngineSettings settings;
  settings.synth.sample_rate_hz = kRate;
  settings.synth.audibility_threshold = 0.0;
  settings.max_voices = 1;
  settings.max_block_frames = 256;
  settings.realtime = false;
  settings.output = output;
  settings.moving_sources = moving_sources;
  settings.ground.enabled = ground;
  settings.ground.height_m = -1.5;
  SoundEngine engine(settings);
  const auto bank = ringingBank();
  VoiceDesc desc;
  desc.bank = bank;
  desc.weights = radiationWeights(*bank, settings.reference_distance_m);
  desc.pressure_scale = 1.0;
  const double identity[4] = {1, 0, 0, 0};
  desc.pose.set(path.at(0.0).data(), identity);
  Voice voice(desc, settings);
  engine.install(0, &voice);
  const uint32_t channels = engine.settings().channels;
  const size_t frames = static_cast<size_t>(seconds * kRate);
  std::vector<float> planar(static_cast<size_t>(channels) * frames);
  bool struck = false;
  for (size_t at = 0; at < frames; at += block) {
    Pose pose;
    pose.set(path.at(engine.time()).data(), identity);
    engine.setPose(0, pose);
    if (!struck && engine.time() + 1e-9 >= strike_s) {
      EngineImpact impact;
      impact.point = {0.003, 0.003, 0.0};
      impact.impulse = {0, 0, -0.01};
      impact.contact_duration_s = 0.0;
      impact.time_s = engine.time();
      engine.impact(impact);
      struck = true;
    }
    float* out[kMaxOutputChannels];
    for (uint32_t c = 0; c < channels; ++c) out[c] = planar.data() + c * frames + at;
    engine.render(out, std::min(block, frames - at));
  }
  return planar;
}

/// The mean frequency over [from_s, to_s) from its upward zero crossings (linearly interpolated).
double frequencyIn(const std::vector<float>& x, double from_s, double to_s) {
  const size_t a = static_cast<size_t>(from_s * kRate), b = static_cast<size_t>(to_s * kRate);
  double first = -1.0, last = -1.0;
  int crossings = 0;
  for (size_t n = a; n + 1 < b; ++n) {
    if (x[n] < 0.0f && x[n + 1] >= 0.0f) {
      const double t = (double(n) + double(x[n]) / (double(x[n]) - double(x[n + 1]))) / kRate;
      if (first < 0.0) first = t;
      last = t;
      ++crossings;
    }
  }
  return (crossings - 1) / (last - first);
}

/// The rms over the whole periods in [from_s, to_s): from its first upward zero crossing to its last.
double rmsIn(const std::vector<float>& x, double from_s, double to_s) {
  const size_t a = static_cast<size_t>(from_s * kRate), b = static_cast<size_t>(to_s * kRate);
  size_t first = 0, last = 0;
  for (size_t n = a; n + 1 < b; ++n)
    if (x[n] < 0.0f && x[n + 1] >= 0.0f) {
      if (first == 0) first = n + 1;
      last = n + 1;
    }
  double sum = 0.0;
  for (size_t n = first; n < last; ++n) sum += double(x[n]) * x[n];
  return std::sqrt(sum / double(last - first));
}

TEST(MovingSource, AFlyByIsHeardAtItsDopplerFrequencyAndLevel) {
  // Struck 0.02 s in, 40 m before the closest point; heard approaching (~0.7 s, v_r ~ +19.6 m/s)
  // and receding (~3.3 s, v_r ~ -19.6 m/s): f c / (c - v_r) is 6% above and 5% below f.
  const Path fly_by;
  const std::vector<float> heard = render(fly_by, 0.02, 4.0, true);
  const double f = ringingHz();
  const double window_s = 0.1;
  for (double from : {0.6, 0.9, 3.1, 3.3}) {
    const double t_e = emissionTime(from + 0.5 * window_s);
    const std::array<double, 3> p = flyBy(t_e);
    const double r = distance(p, {0, 0, 0});
    const double v_r = -kSpeed * p[0] / r;  // toward the listener
    const double expected = f * kSpeedOfSoundAir_m_s / (kSpeedOfSoundAir_m_s - v_r);
    const double measured = frequencyIn(heard, from, from + window_s);
    EXPECT_NEAR(measured / expected - 1.0, 0.0, 1e-3) << "at " << from << " s: v_r " << v_r << " m/s";
  }
  // The level: 1 / r(t_e) times the mode's decay at t_e, against the first window.
  const double decay_per_s = 0.5 * kRayleighMass;
  auto expectedLevel = [&](double t) {
    const double t_e = emissionTime(t);
    return std::exp(-decay_per_s * t_e) / distance(flyBy(t_e), {0, 0, 0});
  };
  const double short_window_s = 0.02;
  const double reference = rmsIn(heard, 0.6, 0.6 + short_window_s) / expectedLevel(0.6 + 0.5 * short_window_s);
  for (double from : {1.2, 1.8, 2.0, 2.1, 2.4, 3.3}) {
    const double level = rmsIn(heard, from, from + short_window_s) / expectedLevel(from + 0.5 * short_window_s);
    EXPECT_NEAR(level / reference, 1.0, 0.003) << "at " << from << " s";
  }
  // Fixed delays (each pulse's delay set when it happens): no Doppler shift at all.
  const std::vector<float> fixed = render(fly_by, 0.02, 4.0, false);
  EXPECT_NEAR(frequencyIn(fixed, 0.6, 0.7) / f - 1.0, 0.0, 1e-4);
  EXPECT_GT(frequencyIn(heard, 0.6, 0.7) / f - 1.0, 0.05);
}

TEST(MovingSource, ItsDirectionFollowsItInStereo) {
  // Passing from left (x < 0) to right, the listener facing +y: the right channel's share grows.
  const Path fly_by;
  const std::vector<float> heard = render(fly_by, 0.02, 4.0, true, OutputFormat::Stereo);
  const size_t frames = heard.size() / 2;
  const std::vector<float> left(heard.begin(), heard.begin() + static_cast<std::ptrdiff_t>(frames));
  const std::vector<float> right(heard.begin() + static_cast<std::ptrdiff_t>(frames), heard.end());
  double before = 0.0;
  for (double from : {0.6, 1.2, 1.8, 2.2, 2.8, 3.4}) {
    // The pan of the position at the emission time: sin of the azimuth from the listener's front.
    const std::array<double, 3> p = flyBy(emissionTime(from + 0.01));
    const double pan = p[0] / distance(p, {0, 0, 0});
    const double theta = (pan + 1.0) * M_PI / 4.0;
    const double share = rmsIn(right, from, from + 0.02) / rmsIn(left, from, from + 0.02);
    EXPECT_NEAR(share / std::tan(theta), 1.0, 0.01) << "at " << from << " s";
    EXPECT_GT(share, before);
    before = share;
  }
}

TEST(MovingSource, ABodyAtRestSoundsAsWithFixedDelaysToTheBit) {
  // Never moving: the same bytes with and without moving sources, mono or ambix, with a ground.
  Path still;
  still.start = still.end = {1.0, 2.0, 0.0};
  still.move_from_s = 0.0;
  still.move_to_s = 1.0;
  for (OutputFormat format : {OutputFormat::Mono, OutputFormat::Ambix1})
    EXPECT_EQ(render(still, 0.1, 0.5, true, format, true), render(still, 0.1, 0.5, false, format, true))
        << outputFormatName(format);
  // Moved while silent, then at rest and heard to the end: struck there, it sounds as a body
  // that was always there (the delay lines are left for scheduled delays again).
  Path arriving = still;
  arriving.start = {-3.0, 2.0, 0.5};
  arriving.move_to_s = 0.2;
  for (OutputFormat format : {OutputFormat::Mono, OutputFormat::Ambix1}) {
    const std::vector<float> moved = render(arriving, 0.5, 0.8, true, format, true);
    const std::vector<float> stayed = render(still, 0.5, 0.8, true, format, true);
    ASSERT_EQ(moved.size(), stayed.size());
    double peak = 0.0;
    for (float x : stayed) peak = std::max(peak, std::fabs(double(x)));
    EXPECT_GT(peak, 0.0);
    EXPECT_EQ(moved, stayed) << outputFormatName(format);
  }
}

TEST(MovingSource, TheGroundsImageMovesWithItsOwnDelay) {
  // With a ground 1.5 m below, the image path is longer: approaching, its Doppler factor is
  // c / (c - v_r') with v_r' along the image path. The sum of both is not one sinusoid, so
  // look at the image alone: the render with the ground less the one without.
  const Path fly_by;
  const std::vector<float> both = render(fly_by, 0.02, 1.2, true, OutputFormat::Mono, true);
  const std::vector<float> direct = render(fly_by, 0.02, 1.2, true, OutputFormat::Mono, false);
  std::vector<float> image(both.size());
  for (size_t n = 0; n < image.size(); ++n) image[n] = both[n] - direct[n];
  const std::array<double, 3> listener_image = {0, 0, -3.0};
  const double window_s = 0.1, from = 0.8;
  const double t = from + 0.5 * window_s;
  double t_e = t;
  for (int i = 0; i < 60; ++i) t_e = t - distance(flyBy(t_e), listener_image) / kSpeedOfSoundAir_m_s;
  const std::array<double, 3> p = flyBy(t_e);
  const double r = distance(p, listener_image);
  const double v_r = -kSpeed * p[0] / r;
  const double expected = ringingHz() * kSpeedOfSoundAir_m_s / (kSpeedOfSoundAir_m_s - v_r);
  EXPECT_NEAR(frequencyIn(image, from, from + window_s) / expected - 1.0, 0.0, 1e-3);
  // Its level: 1 / r along its path, against the direct sound's 1 / r along the direct path.
  double t_d = t;
  for (int i = 0; i < 60; ++i) t_d = t - distance(flyBy(t_d), {0, 0, 0}) / kSpeedOfSoundAir_m_s;
  const double expected_ratio = std::exp(-0.5 * kRayleighMass * (t_e - t_d)) * distance(flyBy(t_d), {0, 0, 0}) / r;
  EXPECT_NEAR(rmsIn(image, from, from + window_s) / rmsIn(direct, from, from + window_s) / expected_ratio, 1.0, 0.01);
}

}  // namespace
}  // namespace strike
