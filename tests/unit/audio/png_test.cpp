// SPDX-License-Identifier: MIT
// The PNG encoder checked by an independent decoder of its structure (signature, chunk CRCs,
// IHDR, stored deflate blocks, Adler-32), and spectrogram pictures written atomically.
#include <gtest/gtest.h>

#include <cstdint>

#include "audio/test_util.hpp"
#include "common/same_bytes.hpp"
#include "strike/audio/audio.hpp"

namespace strike {
namespace {

uint32_t be32(const std::string& s, size_t at) {
  return (uint32_t{static_cast<uint8_t>(s[at])} << 24) | (uint32_t{static_cast<uint8_t>(s[at + 1])} << 16) |
         (uint32_t{static_cast<uint8_t>(s[at + 2])} << 8) | uint32_t{static_cast<uint8_t>(s[at + 3])};
}

/// Bitwise CRC-32 (no table), independent of the encoder's table-driven one.
uint32_t referenceCrc(const std::string& bytes, size_t at, size_t size) {
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = at; i < at + size; ++i) {
    crc ^= static_cast<uint8_t>(bytes[i]);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

struct Decoded {
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgb;
  std::vector<std::string> chunk_types;
};

/// Validates every structural rule the encoder promises; returns the pixels.
Decoded decode(const std::string& png) {
  Decoded d;
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  std::string idat;
  size_t at = 8;
  while (at + 12 <= png.size()) {
    const uint32_t length = be32(png, at);
    const std::string type = png.substr(at + 4, 4);
    EXPECT_LE(at + 12 + length, png.size());
    EXPECT_EQ(be32(png, at + 8 + length), referenceCrc(png, at + 4, 4 + length)) << type;
    if (type == "IHDR") {
      EXPECT_EQ(length, 13u);
      d.width = be32(png, at + 8);
      d.height = be32(png, at + 12);
      EXPECT_EQ(png[at + 16], 8);  // bit depth
      EXPECT_EQ(png[at + 17], 2);  // RGB
    }
    if (type == "IDAT") idat += png.substr(at + 8, length);
    d.chunk_types.push_back(type);
    at += 12 + length;
  }
  EXPECT_EQ(at, png.size());
  // zlib header, then stored blocks.
  EXPECT_EQ((static_cast<uint8_t>(idat[0]) * 256 + static_cast<uint8_t>(idat[1])) % 31, 0);
  std::string raw;
  size_t p = 2;
  for (;;) {
    const auto header = static_cast<uint8_t>(idat[p]);
    EXPECT_EQ(header & 6, 0) << "not a stored block";
    const unsigned len = static_cast<uint8_t>(idat[p + 1]) | (static_cast<uint8_t>(idat[p + 2]) << 8);
    const unsigned nlen = static_cast<uint8_t>(idat[p + 3]) | (static_cast<uint8_t>(idat[p + 4]) << 8);
    EXPECT_EQ(len ^ 0xFFFFu, nlen);
    raw += idat.substr(p + 5, len);
    p += 5 + len;
    if (header & 1) break;
  }
  uint32_t a = 1, b = 0;
  for (char c : raw) {
    a = (a + static_cast<uint8_t>(c)) % 65521u;
    b = (b + a) % 65521u;
  }
  EXPECT_EQ(be32(idat, p), (b << 16) | a);
  EXPECT_EQ(p + 4, idat.size());
  const size_t row = d.width * 3 + 1;
  EXPECT_EQ(raw.size(), row * d.height);
  for (uint32_t y = 0; y < d.height && raw.size() == row * d.height; ++y) {
    EXPECT_EQ(raw[y * row], 0) << "filter type";
    d.rgb.insert(d.rgb.end(), raw.begin() + static_cast<std::ptrdiff_t>(y * row + 1),
                 raw.begin() + static_cast<std::ptrdiff_t>((y + 1) * row));
  }
  return d;
}

TEST(Png, EncodesAKnownImageExactly) {
  // 3x2: red, green, blue / black, white, grey.
  const std::vector<uint8_t> rgb = {255, 0, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 128, 128, 128};
  const std::string png = encodePngRgb(3, 2, rgb);
  const Decoded d = decode(png);
  EXPECT_EQ(d.width, 3u);
  EXPECT_EQ(d.height, 2u);
  EXPECT_EQ(d.rgb, rgb);
  EXPECT_EQ(d.chunk_types, (std::vector<std::string>{"IHDR", "IDAT", "IEND"}));
  // CRC-32 of the IEND chunk is a published constant.
  EXPECT_EQ(be32(png, png.size() - 4), 0xAE426082u);
}

TEST(Png, LargeImagesSpanSeveralStoredBlocks) {
  const int w = 300, h = 200;  // 180,200 bytes of scanlines: three stored blocks
  std::vector<uint8_t> rgb(static_cast<size_t>(w * h * 3));
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>(i * 7u);
  const Decoded d = decode(encodePngRgb(w, h, rgb));
  EXPECT_EQ(d.rgb, rgb);
}

TEST(Png, RejectsMismatchedSizes) {
  EXPECT_TRUE(encodePngRgb(2, 2, std::vector<uint8_t>(11)).empty());
  EXPECT_TRUE(encodePngRgb(0, 2, {}).empty());
}

TEST(Spectrogram, WritesAValidPngOfTheRequestedSize) {
  test::ScratchDir dir;
  const AudioBuffer audio = test::partials({{440.0, 0.5, 3.0}, {3000.0, 0.2, 20.0}}, 48000.0, 1.0, 2);
  for (bool log_axis : {true, false}) {
    SpectrogramOptions options;
    options.width_px = 640;
    options.height_px = 360;
    options.log_frequency = log_axis;
    const std::string path = dir.file(log_axis ? "log.png" : "lin.png");
    const Status s = writeSpectrogramPng(path, audio, options);
    ASSERT_TRUE(s.ok()) << s.error().message;
    const std::string png = test::readBytes(path);
    const Decoded d = decode(png);
    EXPECT_EQ(d.width, 640u);
    EXPECT_EQ(d.height, 2u * 360u) << "two channels: two panels of the requested size";
    ASSERT_EQ(d.rgb.size(), 640u * 720u * 3u);
    // The 440 Hz line at the start is the loudest: the brightest colour of the map is present.
    int bright = 0;
    for (size_t i = 0; i + 2 < d.rgb.size(); i += 3)
      if (d.rgb[i] > 240 && d.rgb[i + 1] > 200) ++bright;
    EXPECT_GT(bright, 0);
    // Deterministic bytes.
    ASSERT_TRUE(writeSpectrogramPng(dir.file("again.png"), audio, options).ok());
    EXPECT_TRUE(test::sameBytes(test::readBytes(dir.file("again.png")), png));
  }
  EXPECT_EQ(dir.list().size(), 3u) << "temporary files were left behind";
}

TEST(Spectrogram, BadOptionsAndUnwritablePathsAreErrors) {
  const AudioBuffer audio = test::partials({{440.0, 0.5, 3.0}}, 48000.0, 0.2);
  SpectrogramOptions options;
  options.width_px = 4;
  EXPECT_FALSE(writeSpectrogramPng("/tmp/never.png", audio, options).ok());
  options = SpectrogramOptions{};
  options.min_freq_hz = 0.0;
  EXPECT_FALSE(writeSpectrogramPng("/tmp/never.png", audio, options).ok());
  options = SpectrogramOptions{};
  options.width_px = 64;
  options.height_px = 64;
  const std::string path = "/nonexistent-strike-dir/x.png";
  const Status s = writeSpectrogramPng(path, audio, options);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find(path), std::string::npos);
}

}  // namespace
}  // namespace strike

namespace strike {
namespace {

/// How many pixels of rows [y0, y1) are bright (the top of the colour map: yellow-white).
int brightPixels(const Decoded& d, uint32_t y0, uint32_t y1) {
  int bright = 0;
  for (uint32_t y = y0; y < y1; ++y)
    for (uint32_t x = 0; x < d.width; ++x) {
      const size_t i = (static_cast<size_t>(y) * d.width + x) * 3;
      if (d.rgb[i] > 240 && d.rgb[i + 1] > 200) ++bright;
    }
  return bright;
}

TEST(Spectrogram, EachChannelIsAPanelOfItsOwn) {
  test::ScratchDir dir;
  // Left rings, right is silent: the top panel shows the line, the bottom one nothing, and the
  // panels' colours share one reference (the loudest cell of both).
  AudioBuffer stereo = test::partials({{1000.0, 0.5, 2.0}}, 48000.0, 0.5, 2);
  for (size_t f = 0; f < stereo.frames(); ++f) stereo.samples[2 * f + 1] = 0.0f;
  SpectrogramOptions options;
  options.width_px = 400;
  options.height_px = 200;
  ASSERT_TRUE(writeSpectrogramPng(dir.file("stereo.png"), stereo, options).ok());
  const Decoded d = decode(test::readBytes(dir.file("stereo.png")));
  ASSERT_EQ(d.width, 400u);
  ASSERT_EQ(d.height, 400u);
  EXPECT_GT(brightPixels(d, 0, 200), 0) << "the left channel's line";
  EXPECT_EQ(brightPixels(d, 200, 400), 0) << "the right channel is silent";
  EXPECT_EQ(spectrogramChannelLabel(0, 2), "L");
  EXPECT_EQ(spectrogramChannelLabel(1, 2), "R");

  // Ambisonics: (N + 1)^2 panels, each a quarter of height_px (at least 128), labelled by ACN.
  for (const int channels : {4, 9, 16}) {
    const AudioBuffer ambix = test::partials({{500.0, 0.3, 5.0}}, 48000.0, 0.2, channels);
    options = SpectrogramOptions{};
    options.width_px = 200;  // narrow: 16 channels of STFTs, one a column
    const int panel = spectrogramPanelHeight(channels, options.height_px);
    EXPECT_EQ(panel, 128);
    const std::string path = dir.file("ambix" + std::to_string(channels) + ".png");
    ASSERT_TRUE(writeSpectrogramPng(path, ambix, options).ok());
    const Decoded a = decode(test::readBytes(path));
    EXPECT_EQ(a.width, 200u);
    EXPECT_EQ(a.height, static_cast<uint32_t>(channels * panel));
    for (int c = 0; c < channels; ++c)  // every channel carries the line: every panel shows it
      EXPECT_GT(brightPixels(a, static_cast<uint32_t>(c * panel), static_cast<uint32_t>((c + 1) * panel)), 0)
          << "panel " << c;
  }
  EXPECT_EQ(spectrogramChannelLabel(0, 4), "ACN 0 W");
  EXPECT_EQ(spectrogramChannelLabel(3, 4), "ACN 3 X");
  EXPECT_EQ(spectrogramChannelLabel(8, 9), "ACN 8 U");
  EXPECT_EQ(spectrogramChannelLabel(15, 16), "ACN 15 P");
  EXPECT_EQ(spectrogramChannelLabel(2, 3), "CH 3");
  EXPECT_EQ(spectrogramPanelHeight(1, 512), 512);
  EXPECT_EQ(spectrogramPanelHeight(2, 512), 512);
  EXPECT_EQ(dir.list().size(), 4u) << "temporary files were left behind";
}

}  // namespace
}  // namespace strike
