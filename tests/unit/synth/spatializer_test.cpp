// SPDX-License-Identifier: MIT
// The spatializer (spatializer.hpp) and each path from its own direction (engine.cpp): the AmbiX
// gains against the closed forms of SN3D, a struck body decoded back to its direction, the omni
// channel against the mono render, and the ground's image arriving from below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "strike/synth/engine.hpp"
#include "strike/synth/spatializer.hpp"

namespace strike {
namespace {

constexpr double kRate = 48000.0;
constexpr double kDegree = M_PI / 180.0;

// The real SN3D spherical harmonics of orders 0-3 in ACN order, written out [Zotter & Frank
// 2019, Ambisonics, table A.1 with N3D / sqrt(2n + 1); Nachbar et al. 2011, AmbiX, table 1].
std::vector<double> closedForms(double x, double y, double z) {
  const double s3 = std::sqrt(3.0), s15 = std::sqrt(15.0), s58 = std::sqrt(5.0 / 8.0), s38 = std::sqrt(3.0 / 8.0);
  return {1.0,
          y,
          z,
          x,
          s3 * x * y,
          s3 * y * z,
          0.5 * (3.0 * z * z - 1.0),
          s3 * x * z,
          0.5 * s3 * (x * x - y * y),
          s58 * y * (3.0 * x * x - y * y),
          s15 * x * y * z,
          s38 * y * (5.0 * z * z - 1.0),
          0.5 * z * (5.0 * z * z - 3.0),
          s38 * x * (5.0 * z * z - 1.0),
          0.5 * s15 * z * (x * x - y * y),
          s58 * x * (x * x - 3.0 * y * y)};
}

TEST(Spatializer, AmbixGainsAreTheSn3dHarmonicsOfTheClosedForms) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 200; ++trial) {
    std::array<double, 3> u = {normal(rng), normal(rng), normal(rng)};
    const double length = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (double& c : u) c /= length;
    if (trial == 0) u = {0, 0, 1};  // the poles and the front
    if (trial == 1) u = {0, 0, -1};
    if (trial == 2) u = {1, 0, 0};
    const std::vector<double> expected = closedForms(u[0], u[1], u[2]);
    double y[16];
    ambixHarmonics(3, u, y);
    for (size_t c = 0; c < 16; ++c) EXPECT_NEAR(y[c], expected[c], 1e-12) << "ACN " << c << " trial " << trial;
  }
  // The listener's frame (x right, y forward, z up) to AmbiX's (x forward, y left, z up): a
  // source straight ahead is all W + X, one to the left all W + Y.
  float g[16];
  spatialGains(OutputFormat::Ambix1, {0.0, 2.0, 0.0}, 2.0, 0.5, g);
  EXPECT_FLOAT_EQ(g[0], 0.5f);
  EXPECT_FLOAT_EQ(g[3], 0.5f);
  EXPECT_NEAR(g[1], 0.0f, 1e-7);
  spatialGains(OutputFormat::Ambix1, {-3.0, 0.0, 0.0}, 3.0, 1.0, g);
  EXPECT_FLOAT_EQ(g[1], 1.0f);
  EXPECT_NEAR(g[3], 0.0f, 1e-7);
  EXPECT_EQ(outputChannels(OutputFormat::Ambix3), 16u);
  EXPECT_EQ(outputChannels(OutputFormat::Ambix2), 9u);
}

// One 1 kHz mode, no directivity (a bank of format 4: heard alike in every direction), decaying
// at rayleigh_mass / 2 per second.
std::shared_ptr<ModeBank> oneModeBank(double rayleigh_mass = 2.0) {
  auto bank = std::make_shared<ModeBank>();
  ModeBank& b = *bank;
  b.material.youngs_pa = 200e9;
  b.material.poisson = 0.3;
  b.material.density_kg_m3 = 7800;
  b.material.rayleigh_mass = rayleigh_mass;
  b.mass_kg = 0.1;
  b.eigenvalues = {std::pow(2.0 * M_PI * 1000.0, 2)};
  b.surface_positions = {0, 0, 0, 0.01, 0, 0, 0, 0.01, 0};
  b.surface_normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  b.surface_triangles = {0, 1, 2};
  b.surface_node_index = {0, 1, 2};
  b.shapes = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  b.radiation_m2 = {1e-3};
  return bank;
}

struct Listener {
  std::array<double, 3> position{};
  std::array<double, 4> orientation{1, 0, 0, 0};
};

/// Planar channels of one struck body heard by `listener` in `format`.
std::vector<std::vector<float>> strike(OutputFormat format, const std::array<double, 3>& body_at,
                                       const Listener& listener, GroundReflection ground = {}, size_t frames = 9600,
                                       double audibility_threshold = 0.0, double rayleigh_mass = 2.0,
                                       uint64_t* active_at_end = nullptr) {
  EngineSettings settings;
  settings.synth.sample_rate_hz = kRate;
  settings.synth.audibility_threshold = audibility_threshold;
  settings.max_voices = 1;
  settings.max_block_frames = 256;
  settings.ground = ground;
  settings.realtime = false;
  settings.output = format;
  SoundEngine engine(settings);
  const auto bank = oneModeBank(rayleigh_mass);
  VoiceDesc desc;
  desc.bank = bank;
  desc.weights = radiationWeights(*bank, settings.reference_distance_m);
  desc.pressure_scale = 1.0;
  const double identity[4] = {1, 0, 0, 0};
  desc.pose.set(body_at.data(), identity);
  Voice voice(desc, settings);
  engine.install(0, &voice);
  Pose pose;
  pose.set(listener.position.data(), listener.orientation.data());
  engine.setListener(pose);
  EngineImpact impact;
  impact.point = {0.003, 0.003, 0.0};
  impact.impulse = {0, 0, -0.01};
  impact.contact_duration_s = 0.0;
  impact.time_s = 0.0;
  engine.impact(impact);
  const uint32_t channels = outputChannels(format);
  std::vector<std::vector<float>> out(channels, std::vector<float>(frames));
  for (size_t at = 0; at < frames; at += 256) {
    float* blocks[kMaxOutputChannels];
    for (uint32_t c = 0; c < channels; ++c) blocks[c] = out[c].data() + at;
    engine.render(blocks, std::min<size_t>(256, frames - at));
  }
  if (active_at_end) *active_at_end = engine.stats().active_modes;
  return out;
}

/// The direction the first-order channels' energy comes from (AmbiX frame): the time average of
/// W times (X, Y, Z), the active intensity of a plane wave [Merimaa & Pulkki 2005, DirAC].
std::array<double, 3> decodedDirection(const std::vector<std::vector<float>>& ambix) {
  double v[3] = {0, 0, 0};
  for (size_t n = 0; n < ambix[0].size(); ++n) {
    const double w = ambix[0][n];
    v[0] += w * ambix[3][n];
    v[1] += w * ambix[1][n];
    v[2] += w * ambix[2][n];
  }
  const double length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return {v[0] / length, v[1] / length, v[2] / length};
}

double angleBetween(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  return std::acos(std::clamp(dot / (la * lb), -1.0, 1.0));
}

/// Where `point` lies seen from the listener, in AmbiX's frame (x forward, y left, z up).
std::array<double, 3> ambixDirectionOf(const std::array<double, 3>& point, const Listener& listener) {
  Pose pose;
  pose.set(listener.position.data(), listener.orientation.data());
  const std::array<double, 3> local = pose.toLocalPoint(point);  // x right, y forward, z up
  return {local[1], -local[0], local[2]};
}

std::array<double, 4> yaw(double degrees) {  // about +z, counter-clockwise seen from above
  return {std::cos(0.5 * degrees * kDegree), 0.0, 0.0, std::sin(0.5 * degrees * kDegree)};
}

TEST(Spatializer, OneModeHeardFromAKnownDirectionDecodesBackToIt) {
  const std::vector<std::array<double, 3>> bodies = {{0, 2, 0}, {1.5, 1, 0.4}, {-1, -1, 1}, {0.3, -2, -0.5}};
  for (double heading : {0.0, 90.0, -135.0}) {
    Listener listener;
    listener.position = {0.2, -0.1, 0.3};
    listener.orientation = yaw(heading);
    for (const auto& body : bodies) {
      const auto heard = strike(OutputFormat::Ambix3, body, listener);
      const double error = angleBetween(decodedDirection(heard), ambixDirectionOf(body, listener));
      EXPECT_LT(error, 2.0 * kDegree) << "heading " << heading << " body " << body[0] << "," << body[1];
    }
  }
  // Turning the listener by 90 degrees to its left puts a source that was ahead on its right.
  Listener turned;
  turned.orientation = yaw(90.0);
  const auto ahead = decodedDirection(strike(OutputFormat::Ambix1, {0, 2, 0}, Listener{}));
  const auto right = decodedDirection(strike(OutputFormat::Ambix1, {0, 2, 0}, turned));
  EXPECT_NEAR(ahead[0], 1.0, 1e-6);
  EXPECT_NEAR(right[1], -1.0, 1e-6);
  // ...and is what the source moving by 90 degrees to the listener's right does.
  const auto moved = decodedDirection(strike(OutputFormat::Ambix1, {2, 0, 0}, Listener{}));
  EXPECT_LT(angleBetween(right, moved), 1e-6);
}

TEST(Spatializer, OmniChannelEqualsTheMonoRender) {
  GroundReflection ground;
  ground.enabled = true;
  ground.reflection = 0.7;
  Listener listener;
  listener.position = {0, -1, 0.4};
  listener.orientation = yaw(30.0);
  const std::array<double, 3> body = {0.5, 0.8, 0.3};
  const auto mono = strike(OutputFormat::Mono, body, listener, ground)[0];
  for (OutputFormat format : {OutputFormat::Ambix1, OutputFormat::Ambix3}) {
    const auto w = strike(format, body, listener, ground)[0];
    double error = 0.0, energy = 0.0;
    for (size_t n = 0; n < mono.size(); ++n) {
      error += (double(w[n]) - mono[n]) * (double(w[n]) - mono[n]);
      energy += double(mono[n]) * mono[n];
    }
    ASSERT_GT(energy, 0.0);
    EXPECT_LT(10.0 * std::log10(error / energy + 1e-300), -100.0) << outputFormatName(format);
  }
}

// The same with the audibility threshold of a render (1e-6 full scale), through the moment the
// modes sleep under it: the image rings in synth_ too, so both paths' modes sleep when their sum
// does, as in mono, and W is still the mono render (it differed by up to the threshold when each
// path's modes slept on their own).
TEST(Spatializer, OmniChannelEqualsTheMonoRenderWhileTheModesFallAsleep) {
  GroundReflection ground;
  ground.enabled = true;
  ground.reflection = -0.8;  // the paths' modes cancel in part: their sum sleeps before either alone
  Listener listener;
  listener.position = {0, -1, 0.4};
  listener.orientation = yaw(-60.0);
  const std::array<double, 3> body = {0.5, 0.8, 0.3};
  const size_t frames = 48000;
  const double rayleigh_mass = 60.0;  // 30 / s: asleep within the second
  uint64_t mono_active = 1;
  const auto mono = strike(OutputFormat::Mono, body, listener, ground, frames, 1e-6, rayleigh_mass, &mono_active)[0];
  EXPECT_EQ(mono_active, 0u);  // the modes did sleep
  size_t last_sound = 0;
  double peak = 0.0;
  for (size_t n = 0; n < frames; ++n)
    if (mono[n] != 0.0f) last_sound = n, peak = std::max(peak, std::abs(double(mono[n])));
  EXPECT_LT(last_sound, frames - 4800) << "the mode never slept";
  EXPECT_GT(last_sound, 4800u);
  for (OutputFormat format : {OutputFormat::Stereo, OutputFormat::Ambix1, OutputFormat::Ambix3}) {
    uint64_t active = 1;
    const auto channels = strike(format, body, listener, ground, frames, 1e-6, rayleigh_mass, &active);
    EXPECT_EQ(active, 0u) << outputFormatName(format);
    if (format == OutputFormat::Stereo) continue;  // all asleep with mono: checked
    double error = 0.0, energy = 0.0, worst = 0.0;
    for (size_t n = 0; n < frames; ++n) {
      const double d = double(channels[0][n]) - mono[n];
      error += d * d;
      energy += double(mono[n]) * mono[n];
      worst = std::max(worst, std::abs(d));
    }
    std::printf("  %s: W - mono %.1f dB (energy), worst sample %.1f dB re peak\n", outputFormatName(format),
                10.0 * std::log10(error / energy + 1e-300), 20.0 * std::log10(worst / peak + 1e-300));
    EXPECT_LT(10.0 * std::log10(error / energy + 1e-300), -100.0) << outputFormatName(format);
    EXPECT_LT(worst, 1e-5 * peak) << outputFormatName(format);
  }
}

TEST(Spatializer, GroundImageArrivesFromBelowAtTheImageSourceAngle) {
  // A body 0.3 m above a rigid floor, the listener 1.2 m up and 2 m away: the image source is
  // the body mirrored below the floor, seen 1.5 / 2 below the horizon (36.9 degrees).
  GroundReflection ground;
  ground.enabled = true;
  Listener listener;
  listener.position = {0, -2, 1.2};
  const std::array<double, 3> body = {0, 0, 0.3};
  const auto free_field = strike(OutputFormat::Ambix1, body, listener);
  const auto both = strike(OutputFormat::Ambix1, body, listener, ground);
  std::vector<std::vector<float>> image(4, std::vector<float>(both[0].size()));
  for (size_t c = 0; c < 4; ++c)
    for (size_t n = 0; n < image[c].size(); ++n) image[c][n] = both[c][n] - free_field[c][n];
  const std::array<double, 3> image_source = {body[0], body[1], -body[2]};
  const auto decoded = decodedDirection(image);
  EXPECT_LT(angleBetween(decoded, ambixDirectionOf(image_source, listener)), 3.0 * kDegree);
  EXPECT_NEAR(std::asin(decoded[2]) / kDegree, -std::atan(1.5 / 2.0) / kDegree, 3.0);
  // The direct sound stays where the body is.
  EXPECT_LT(angleBetween(decodedDirection(free_field), ambixDirectionOf(body, listener)), 2.0 * kDegree);
}

TEST(Spatializer, StereoPansByTheDirectionsRightwardComponent) {
  // A body to the listener's right: the right channel is louder, by the constant-power law.
  Listener listener;
  const auto stereo = strike(OutputFormat::Stereo, {1, 1, 0}, listener);
  double left = 0.0, right = 0.0;
  for (size_t n = 0; n < stereo[0].size(); ++n) left += double(stereo[0][n]) * stereo[0][n];
  for (size_t n = 0; n < stereo[1].size(); ++n) right += double(stereo[1][n]) * stereo[1][n];
  const double theta = (1.0 / std::sqrt(2.0) + 1.0) * M_PI / 4.0;
  EXPECT_NEAR(10.0 * std::log10(right / left), 20.0 * std::log10(std::sin(theta) / std::cos(theta)), 0.01);
}

TEST(Spatializer, LookAtFacesTheTarget) {
  const auto q = lookAtOrientation({1, 1, 1}, {1, 3, 1});
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR((*q)[0], 1.0, 1e-12);  // facing +y already: identity
  const auto left = lookAtOrientation({0, 0, 0}, {-2, 0, 0.5});
  ASSERT_TRUE(left.has_value());
  Pose pose;
  const double origin[3] = {0, 0, 0};
  pose.set(origin, left->data());
  const auto local = pose.toLocalPoint({-2, 0, 0.5});
  EXPECT_NEAR(local[0], 0.0, 1e-12);
  EXPECT_GT(local[1], 0.0);
  const auto right_axis = pose.toWorld({1, 0, 0});
  EXPECT_NEAR(right_axis[2], 0.0, 1e-12);  // level
  EXPECT_FALSE(lookAtOrientation({0, 0, 0}, {0, 0, 3}).has_value());
  EXPECT_FALSE(lookAtOrientation({1, 2, 3}, {1, 2, 3}).has_value());
}

}  // namespace
}  // namespace strike
