// SPDX-License-Identifier: MIT
// The comparison helpers of tests/unit/common/same_bytes.hpp: a mismatch between two WAV files
// is told in a few hundred characters (where, by how much), not as the files' bytes: EXPECT_EQ
// on two 3 s stereo renders once wrote megabytes of escaped bytes to the log.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "audio/test_util.hpp"
#include "common/same_bytes.hpp"
#include "strike/audio/audio.hpp"

namespace strike {
namespace {

AudioBuffer ramp(size_t frames) {
  AudioBuffer a;
  a.sample_rate_hz = 48000;
  a.channels = 2;
  for (size_t i = 0; i < frames * 2; ++i) a.samples.push_back(static_cast<float>(i % 1000) * 1e-4f);
  return a;
}

TEST(SameBytes, AWavMismatchIsSummarisedNotDumped) {
  test::ScratchDir dir;
  for (SampleEncoding encoding : {SampleEncoding::Float32, SampleEncoding::Pcm16, SampleEncoding::Pcm24}) {
    AudioBuffer a = ramp(144000), b = a;  // 3 s of stereo: 1.1 MB as float
    b.samples[2 * 70000 + 1] += 0.25f;    // frame 70000, right channel
    b.samples[2 * 90000] += 0.125f;
    ASSERT_TRUE(writeAudio(dir.file("a.wav"), a, encoding).ok());
    ASSERT_TRUE(writeAudio(dir.file("b.wav"), b, encoding).ok());
    const std::string bytes_a = test::readBytes(dir.file("a.wav")), bytes_b = test::readBytes(dir.file("b.wav"));
    EXPECT_TRUE(test::sameBytes(bytes_a, bytes_a));
    const testing::AssertionResult r = test::sameBytes(bytes_a, bytes_b);
    ASSERT_FALSE(r);
    const std::string message = r.message();
    std::printf("%s\n", message.c_str());
    EXPECT_LT(message.size(), 400u) << "the summary must stay short";
    EXPECT_NE(message.find("2 of 288000 samples differ; first at frame 70000 channel 1"), std::string::npos) << message;
    EXPECT_NE(message.find("largest |difference| 0.25 (-12.0412 dBFS)"), std::string::npos) << message;
    EXPECT_NE(message.find("at frame 70000"), std::string::npos) << message;
  }
}

TEST(SameBytes, SizesAndFirstDifferingByteOfOtherFiles) {
  const std::string a(100000, 'x');
  std::string b = a + "tail";
  b[4242] = 'y';
  const testing::AssertionResult r = test::sameBytes(a, b);
  ASSERT_FALSE(r);
  const std::string message = r.message();
  EXPECT_LT(message.size(), 200u);
  EXPECT_NE(message.find("sizes 100000 and 100004 bytes; first difference at byte 4242 (0x78 vs 0x79), 1 of 100000"),
            std::string::npos)
      << message;
  EXPECT_FALSE(test::sameBytes(a, a.substr(0, 10)));  // a prefix is not equal
}

TEST(SameValues, FirstDifferenceAndLargest) {
  std::vector<double> x(50000, 1.0), y = x;
  y[123] = 1.5;
  y[40000] = -2.0;
  const testing::AssertionResult r = test::sameValues(x, y);
  ASSERT_FALSE(r);
  const std::string message = r.message();
  EXPECT_LT(message.size(), 200u);
  EXPECT_NE(message.find("2 of 50000 values differ; first at [123]: 1 vs 1.5; largest |difference| 3 at [40000]"),
            std::string::npos)
      << message;
  EXPECT_TRUE(test::sameValues(x, x));
  EXPECT_FALSE(test::sameValues(x, std::vector<double>(x.begin(), x.end() - 1)));
}

}  // namespace
}  // namespace strike
