// SPDX-License-Identifier: MIT
// Directions of arrival from an Ambisonics file (the numbers `strike analyze --directions`
// draws): a sinusoid encoded from a known direction comes back from that direction.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "audio/test_util.hpp"
#include "common/same_bytes.hpp"
#include "strike/audio/audio.hpp"
#include "strike/synth/spatializer.hpp"

namespace strike {
namespace {

constexpr double kDeg = test::kPi / 180.0;

struct Source {
  double azimuth_deg, elevation_deg;
};

std::array<double, 3> unitDirection(const Source& s) {
  return {std::cos(s.azimuth_deg * kDeg) * std::cos(s.elevation_deg * kDeg),
          std::sin(s.azimuth_deg * kDeg) * std::cos(s.elevation_deg * kDeg), std::sin(s.elevation_deg * kDeg)};
}

/// A 1 kHz sinusoid from `first` for the first half and from `second` for the second half,
/// encoded in AmbiX of `order` by the renderer's own harmonics (ACN, SN3D) and rounded to float
/// as a file stores it.
AudioBuffer encodedSinusoid(uint32_t order, const Source& first, const Source& second, double duration_s) {
  AudioBuffer audio;
  audio.sample_rate_hz = 48000.0;
  audio.channels = static_cast<int>((order + 1) * (order + 1));
  const auto frames = static_cast<size_t>(std::llround(duration_s * audio.sample_rate_hz));
  audio.samples.resize(frames * static_cast<size_t>(audio.channels));
  std::array<double, 16> gains_first{}, gains_second{};
  ambixHarmonics(order, unitDirection(first), gains_first.data());
  ambixHarmonics(order, unitDirection(second), gains_second.data());
  for (size_t n = 0; n < frames; ++n) {
    const double s = 0.25 * std::sin(2.0 * test::kPi * 1000.0 * static_cast<double>(n) / audio.sample_rate_hz);
    const std::array<double, 16>& g = n < frames / 2 ? gains_first : gains_second;
    for (int c = 0; c < audio.channels; ++c)
      audio.samples[n * static_cast<size_t>(audio.channels) + static_cast<size_t>(c)] =
          static_cast<float>(s * g[static_cast<size_t>(c)]);
  }
  return audio;
}

/// The smallest difference of two angles in degrees, across the +-180 seam.
double angleApart(double a_deg, double b_deg) {
  const double d = std::fmod(std::fabs(a_deg - b_deg), 360.0);
  return std::min(d, 360.0 - d);
}

TEST(Directions, ASinusoidFromAKnownDirectionArrivesFromItWithin2Degrees) {
  // The closed form first: SN3D's first order is W = s, Y = s sin(a) cos(e), Z = s sin(e),
  // X = s cos(a) cos(e) (Nachbar et al. 2011); the renderer's harmonics must say the same.
  const Source probe{35.0, 20.0};
  std::array<double, 4> h{};
  ambixHarmonics(1, unitDirection(probe), h.data());
  EXPECT_NEAR(h[0], 1.0, 1e-12);
  EXPECT_NEAR(h[1], std::sin(35.0 * kDeg) * std::cos(20.0 * kDeg), 1e-12);
  EXPECT_NEAR(h[2], std::sin(20.0 * kDeg), 1e-12);
  EXPECT_NEAR(h[3], std::cos(35.0 * kDeg) * std::cos(20.0 * kDeg), 1e-12);

  // Directions on every side, above and below; first order and third (whose higher channels
  // the method ignores). Each frame of each half (not the one that straddles the switch).
  const Source cases[][2] = {
      {{35.0, 20.0}, {-120.0, -40.0}}, {{170.0, 5.0}, {-90.0, 70.0}}, {{0.0, -80.0}, {90.0, 0.0}}};
  for (const uint32_t order : {1u, 3u})
    for (const auto& pair : cases) {
      const AudioBuffer audio = encodedSinusoid(order, pair[0], pair[1], 0.4);
      const Result<std::vector<DirectionFrame>> frames = directionsOfArrival(audio, 0.01);
      ASSERT_TRUE(frames.ok()) << frames.error().message;
      ASSERT_EQ(frames->size(), 40u);
      for (const DirectionFrame& f : *frames) {
        if (std::fabs(f.time_s - 0.2) < 0.01) continue;
        const Source& want = f.time_s < 0.2 ? pair[0] : pair[1];
        ASSERT_TRUE(f.has_direction) << "t " << f.time_s;
        EXPECT_LT(std::fabs(f.elevation_deg - want.elevation_deg), 2.0) << "order " << order << ", t " << f.time_s;
        // Azimuth is loose near the poles: there, what matters is the angle on the sphere.
        EXPECT_LT(angleApart(f.azimuth_deg, want.azimuth_deg) * std::cos(want.elevation_deg * kDeg), 2.0)
            << "order " << order << ", t " << f.time_s;
        EXPECT_LT(f.diffuseness, 0.01) << "one plane wave";
        EXPECT_NEAR(f.level_dbfs, 20.0 * std::log10(0.25 / std::sqrt(2.0)), 0.1) << "the omni channel's rms";
      }
    }
}

TEST(Directions, OppositeSourcesAtOnceAreDiffuseAndSilenceHasNoDirection) {
  // The same signal from the front and from behind: the intensities cancel, nothing arrives
  // from anywhere, and the diffuseness is 1. Silence has no direction and no level.
  AudioBuffer front = encodedSinusoid(1, {0.0, 0.0}, {0.0, 0.0}, 0.1);
  const AudioBuffer back = encodedSinusoid(1, {180.0, 0.0}, {180.0, 0.0}, 0.1);
  for (size_t i = 0; i < front.samples.size(); ++i) front.samples[i] += back.samples[i];
  Result<std::vector<DirectionFrame>> frames = directionsOfArrival(front, 0.01);
  ASSERT_TRUE(frames.ok());
  for (const DirectionFrame& f : *frames) {
    EXPECT_FALSE(f.has_direction);
    EXPECT_NEAR(f.diffuseness, 1.0, 1e-9);
  }
  AudioBuffer silence = front;
  for (float& s : silence.samples) s = 0.0f;
  frames = directionsOfArrival(silence, 0.01);
  ASSERT_TRUE(frames.ok());
  for (const DirectionFrame& f : *frames) {
    EXPECT_FALSE(f.has_direction);
    EXPECT_TRUE(std::isinf(f.level_dbfs));
  }
}

TEST(Directions, NeedsAmbisonicsAndDrawsTwoPanels) {
  const AudioBuffer stereo = test::partials({{440.0, 0.5, 3.0}}, 48000.0, 0.1, 2);
  const Result<std::vector<DirectionFrame>> refused = directionsOfArrival(stereo, 0.01);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("2"), std::string::npos) << refused.error().message;
  EXPECT_FALSE(directionsOfArrival(encodedSinusoid(1, {0, 0}, {0, 0}, 0.1), 0.0).ok());

  test::ScratchDir dir;
  EXPECT_FALSE(writeDirectionsPng(dir.file("stereo.png"), stereo, DirectionOptions{}).ok());
  DirectionOptions options;
  options.width_px = 500;
  options.height_px = 300;
  const std::string path = dir.file("doa.png");
  ASSERT_TRUE(writeDirectionsPng(path, encodedSinusoid(2, {60.0, 10.0}, {-30.0, -10.0}, 0.3), options).ok());
  const std::string png = test::readBytes(path);
  ASSERT_GT(png.size(), 24u);
  auto be32 = [&](size_t at) {
    return (uint32_t{static_cast<uint8_t>(png[at])} << 24) | (uint32_t{static_cast<uint8_t>(png[at + 1])} << 16) |
           (uint32_t{static_cast<uint8_t>(png[at + 2])} << 8) | uint32_t{static_cast<uint8_t>(png[at + 3])};
  };
  EXPECT_EQ(be32(16), 500u);  // IHDR's width and height
  EXPECT_EQ(be32(20), 300u);
  ASSERT_TRUE(
      writeDirectionsPng(dir.file("again.png"), encodedSinusoid(2, {60.0, 10.0}, {-30.0, -10.0}, 0.3), options).ok());
  EXPECT_TRUE(test::sameBytes(test::readBytes(dir.file("again.png")), png)) << "the same bytes for the same sound";
  EXPECT_EQ(dir.list().size(), 2u) << "nothing left behind by the refusal";
}

}  // namespace
}  // namespace strike
