// SPDX-License-Identifier: MIT
// writeAudio / readAudio: round trips against the quantization step, atomicity, errors,
// clipping and byte-for-byte determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "audio/test_util.hpp"
#include "common/same_bytes.hpp"
#include "strike/audio/audio.hpp"

namespace strike {
namespace {

using test::ScratchDir;

/// Deterministic pseudo-random samples in [-0.999, 0.999] plus the exact extremes of the
/// PCM range, so both rounding and the full-scale ends are exercised.
AudioBuffer noise(double rate_hz, int channels, size_t frames) {
  AudioBuffer audio;
  audio.sample_rate_hz = rate_hz;
  audio.channels = channels;
  audio.samples.resize(frames * static_cast<size_t>(channels));
  uint32_t state = 12345u;
  for (float& s : audio.samples) {
    state = state * 1664525u + 1013904223u;  // Numerical Recipes LCG
    s = static_cast<float>((static_cast<double>(state) / 4294967296.0 * 2.0 - 1.0) * 0.999);
  }
  audio.samples[0] = -1.0f;
  audio.samples[1] = static_cast<float>(32767.0 / 32768.0);
  return audio;
}

struct Format {
  const char* ext;
  SampleEncoding encoding;
  double step;  ///< quantization step (LSB); 0 for float
};

TEST(AudioFile, RoundTripEveryFormatRateAndChannelCount) {
  ScratchDir dir;
  const Format formats[] = {{"wav", SampleEncoding::Pcm16, 1.0 / 32768.0},
                            {"wav", SampleEncoding::Pcm24, 1.0 / 8388608.0},
                            {"wav", SampleEncoding::Float32, 0.0},
                            {"flac", SampleEncoding::Pcm16, 1.0 / 32768.0},
                            {"flac", SampleEncoding::Pcm24, 1.0 / 8388608.0}};
  for (const Format& format : formats)
    for (double rate : {8000.0, 44100.0, 48000.0, 96000.0, 192000.0})
      for (int channels : {1, 2, 6}) {
        SCOPED_TRACE(std::string(format.ext) + " " + std::to_string(static_cast<int>(format.encoding)) + " " +
                     std::to_string(rate) + " Hz " + std::to_string(channels) + " ch");
        const AudioBuffer in = noise(rate, channels, 1500);
        const std::string path = dir.file("round_trip." + std::string(format.ext));
        const Status written = writeAudio(path, in, format.encoding);
        ASSERT_TRUE(written.ok()) << written.error().message;
        const Result<AudioBuffer> out = readAudio(path);
        ASSERT_TRUE(out.ok()) << out.error().message;
        EXPECT_EQ(out->sample_rate_hz, rate);
        EXPECT_EQ(out->channels, channels);
        ASSERT_EQ(out->samples.size(), in.samples.size());
        double worst = 0.0;
        for (size_t i = 0; i < in.samples.size(); ++i)
          worst = std::max(worst, std::fabs(static_cast<double>(out->samples[i]) - in.samples[i]));
        // Rounding to the nearest step: at most half a step (plus float rounding of the read).
        EXPECT_LE(worst, 0.5 * format.step + 1e-7);
      }
}

TEST(AudioFile, ExtensionIsCaseInsensitive) {
  ScratchDir dir;
  const AudioBuffer in = noise(48000.0, 1, 100);
  ASSERT_TRUE(writeAudio(dir.file("upper.WAV"), in, SampleEncoding::Pcm16).ok());
  ASSERT_TRUE(writeAudio(dir.file("upper.Flac"), in, SampleEncoding::Pcm24).ok());
  EXPECT_TRUE(readAudio(dir.file("upper.WAV")).ok());
  EXPECT_TRUE(readAudio(dir.file("upper.Flac")).ok());
}

TEST(AudioFile, UnsupportedExtensionNamesPathAndChoices) {
  ScratchDir dir;
  const std::string path = dir.file("out.mp3");
  const Status s = writeAudio(path, noise(48000.0, 1, 10), SampleEncoding::Pcm16);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().kind, ErrorKind::BadInput);
  EXPECT_NE(s.error().message.find(path), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find(".wav"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find(".flac"), std::string::npos) << s.error().message;
  EXPECT_TRUE(dir.list().empty());
}

TEST(AudioFile, FloatFlacIsBadInput) {
  ScratchDir dir;
  const Status s = writeAudio(dir.file("out.flac"), noise(48000.0, 1, 10), SampleEncoding::Float32);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().kind, ErrorKind::BadInput);
  EXPECT_TRUE(dir.list().empty());
}

TEST(AudioFile, InvalidBuffersAreBadInput) {
  ScratchDir dir;
  AudioBuffer odd = noise(48000.0, 2, 10);
  odd.samples.pop_back();
  EXPECT_FALSE(writeAudio(dir.file("a.wav"), odd, SampleEncoding::Pcm16).ok());
  AudioBuffer fractional = noise(44100.5, 1, 10);
  EXPECT_FALSE(writeAudio(dir.file("b.wav"), fractional, SampleEncoding::Pcm16).ok());
  AudioBuffer no_channels = noise(48000.0, 1, 10);
  no_channels.channels = 0;
  EXPECT_FALSE(writeAudio(dir.file("c.wav"), no_channels, SampleEncoding::Pcm16).ok());
  EXPECT_TRUE(dir.list().empty());
}

TEST(AudioFile, AtomicWriteLeavesOnlyTheDestination) {
  ScratchDir dir;
  const std::string path = dir.file("out.wav");
  ASSERT_TRUE(writeAudio(path, noise(48000.0, 2, 5000), SampleEncoding::Pcm24).ok());
  // Overwrite an existing file: still exactly one file, with the new content.
  ASSERT_TRUE(writeAudio(path, noise(44100.0, 1, 100), SampleEncoding::Pcm16).ok());
  const std::vector<std::string> names = dir.list();
  ASSERT_EQ(names.size(), 1u);
  EXPECT_EQ(names[0], "out.wav");
  const Result<AudioBuffer> back = readAudio(path);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->sample_rate_hz, 44100.0);
}

TEST(AudioFile, UnwritableDirectoryIsAnErrorNamingThePath) {
  const std::string path = "/nonexistent-strike-dir/sub/out.wav";
  const Status s = writeAudio(path, noise(48000.0, 1, 10), SampleEncoding::Pcm16);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find(path), std::string::npos) << s.error().message;
}

TEST(AudioFile, ReadOnlyDirectoryIsAnErrorAndLeavesNoTemporary) {
  if (geteuid() == 0) GTEST_SKIP() << "root ignores directory permissions";
  ScratchDir dir;
  ASSERT_EQ(chmod(dir.path().c_str(), 0555), 0);
  const Status s = writeAudio(dir.file("out.flac"), noise(48000.0, 1, 10), SampleEncoding::Pcm16);
  chmod(dir.path().c_str(), 0755);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find(dir.file("out.flac")), std::string::npos) << s.error().message;
  EXPECT_TRUE(dir.list().empty());
}

TEST(AudioFile, DestinationIsADirectoryFailsCleanly) {
  ScratchDir dir;
  const std::string path = dir.file("sub.wav");
  ASSERT_EQ(mkdir(path.c_str(), 0755), 0);
  const Status s = writeAudio(path, noise(48000.0, 1, 10), SampleEncoding::Pcm16);
  EXPECT_FALSE(s.ok());
  rmdir(path.c_str());
  EXPECT_TRUE(dir.list().empty()) << "a temporary file was left behind";
}

TEST(AudioFile, PcmClipsInsteadOfWrapping) {
  ScratchDir dir;
  AudioBuffer in;
  in.sample_rate_hz = 48000.0;
  in.samples = {1.5f, -1.5f, 1.0f, -1.0f, 100.0f, -100.0f, 0.25f, std::nanf("")};
  for (const char* name : {"clip.wav", "clip.flac"})
    for (SampleEncoding encoding : {SampleEncoding::Pcm16, SampleEncoding::Pcm24}) {
      const double step = encoding == SampleEncoding::Pcm16 ? 1.0 / 32768.0 : 1.0 / 8388608.0;
      ASSERT_TRUE(writeAudio(dir.file(name), in, encoding).ok());
      const Result<AudioBuffer> out = readAudio(dir.file(name));
      ASSERT_TRUE(out.ok());
      const std::vector<double> expected = {1.0 - step, -1.0, 1.0 - step, -1.0, 1.0 - step, -1.0, 0.25, 0.0};
      ASSERT_EQ(out->samples.size(), expected.size());
      for (size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(out->samples[i], expected[i], 1e-9) << name << " " << i;
    }
  // Float keeps values beyond full scale.
  ASSERT_TRUE(writeAudio(dir.file("float.wav"), in, SampleEncoding::Float32).ok());
  const Result<AudioBuffer> f = readAudio(dir.file("float.wav"));
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->samples[0], 1.5f);
  EXPECT_EQ(f->samples[5], -100.0f);
}

TEST(AudioFile, SameInputGivesIdenticalBytes) {
  ScratchDir dir;
  const AudioBuffer in = noise(48000.0, 2, 20000);
  for (const Format& format : {Format{"wav", SampleEncoding::Float32, 0}, Format{"wav", SampleEncoding::Pcm24, 0},
                               Format{"flac", SampleEncoding::Pcm16, 0}, Format{"flac", SampleEncoding::Pcm24, 0}}) {
    const std::string a = dir.file(std::string("a.") + format.ext);
    const std::string b = dir.file(std::string("b.") + format.ext);
    ASSERT_TRUE(writeAudio(a, in, format.encoding).ok());
    ASSERT_TRUE(writeAudio(b, in, format.encoding).ok());
    const std::string bytes_a = test::readBytes(a);
    EXPECT_FALSE(bytes_a.empty());
    EXPECT_TRUE(test::sameBytes(bytes_a, test::readBytes(b))) << format.ext;
    if (format.encoding == SampleEncoding::Float32) {
      EXPECT_EQ(bytes_a.find("PEAK"), std::string::npos);
    }
  }
}

TEST(AudioFile, ReadErrorsNameThePath) {
  ScratchDir dir;
  const std::string missing = dir.file("missing.wav");
  Result<AudioBuffer> r = readAudio(missing);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find(missing), std::string::npos);

  const std::string garbage = dir.file("garbage.wav");
  {
    std::FILE* f = std::fopen(garbage.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("this is not a RIFF file at all, just some text", f);
    std::fclose(f);
  }
  r = readAudio(garbage);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().kind, ErrorKind::BadInput);
  EXPECT_NE(r.error().message.find(garbage), std::string::npos) << r.error().message;

  r = readAudio(dir.path());
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("directory"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace strike
