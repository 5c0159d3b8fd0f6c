// SPDX-License-Identifier: MIT
// Short failure messages for byte-for-byte and value-for-value comparisons. EXPECT_EQ on two
// WAV files' bytes prints both files as escaped strings: a failing determinism test once wrote
// 7 MB of log. These print a few lines instead:
//   EXPECT_TRUE(test::sameBytes(a, b)) << "two renders differ";
//   EXPECT_TRUE(test::sameValues(x, y)) << "energy traces differ";
// Bytes: the sizes, the first differing offset with the bytes there, how many bytes differ, and
// for two RIFF/WAVE files (PCM 16/24/32 or float 32/64) the samples: the first differing one
// (frame, channel, both values), the largest difference and how many samples differ.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace strike::test {

namespace same_bytes_detail {

inline uint32_t le(const std::string& s, size_t at, int bytes) {
  uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= static_cast<uint32_t>(static_cast<uint8_t>(s[at + i])) << (8 * i);
  return v;
}

/// Samples of a RIFF/WAVE file, interleaved, as doubles (PCM scaled to +-1). False if the bytes
/// are not a WAV this reads (then only bytes are compared).
inline bool wavSamples(const std::string& s, std::vector<double>& out, unsigned& channels) {
  if (s.size() < 12 || s.compare(0, 4, "RIFF") != 0 || s.compare(8, 4, "WAVE") != 0) return false;
  unsigned format = 0, bits = 0;
  channels = 0;
  for (size_t at = 12; at + 8 <= s.size();) {
    const std::string id = s.substr(at, 4);
    const size_t size = le(s, at + 4, 4);
    const size_t body = at + 8;
    if (body + size > s.size()) return false;
    if (id == "fmt " && size >= 16) {
      format = le(s, body, 2);
      channels = le(s, body + 2, 2);
      bits = le(s, body + 14, 2);
      if (format == 0xFFFE && size >= 26) format = le(s, body + 24, 2);  // WAVE_FORMAT_EXTENSIBLE
    } else if (id == "data" && channels > 0 && bits % 8 == 0 && bits > 0) {
      const size_t width = bits / 8;
      out.clear();
      for (size_t k = body; k + width <= body + size; k += width) {
        if (format == 3 && bits == 32) {
          float f;
          std::memcpy(&f, s.data() + k, 4);
          out.push_back(f);
        } else if (format == 3 && bits == 64) {
          double d;
          std::memcpy(&d, s.data() + k, 8);
          out.push_back(d);
        } else if (format == 1 && bits >= 16 && bits <= 32) {
          const uint32_t raw = le(s, k, static_cast<int>(width)) << (32 - bits);  // sign bit to bit 31
          out.push_back(static_cast<double>(static_cast<int32_t>(raw)) / 2147483648.0);
        } else {
          return false;
        }
      }
      return true;
    }
    at = body + size + (size & 1);  // chunks are word-aligned
  }
  return false;
}

inline std::string hexByte(char c) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02x", static_cast<unsigned>(static_cast<uint8_t>(c)));
  return text;
}

}  // namespace same_bytes_detail

/// Equal values, element by element (operator==, as EXPECT_EQ). On a mismatch: the sizes, the
/// first differing index and both values, and (for numbers) the largest |difference|.
template <typename T>
testing::AssertionResult sameValues(const std::vector<T>& a, const std::vector<T>& b) {
  size_t first = a.size() == b.size() ? a.size() : std::min(a.size(), b.size());
  size_t differing = 0;
  double max_diff = 0;
  size_t max_at = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (a[i] == b[i]) continue;
    if (differing++ == 0) first = i;
    if constexpr (std::is_arithmetic_v<T>) {
      const double d = std::fabs(static_cast<double>(a[i]) - static_cast<double>(b[i]));
      if (!(d <= max_diff)) max_diff = d, max_at = i;  // NaN counts as the largest
    }
  }
  if (differing == 0 && a.size() == b.size()) return testing::AssertionSuccess();
  std::ostringstream m;
  m.precision(17);
  m << "sizes " << a.size() << " and " << b.size() << "; ";
  if (differing == 0) {
    m << "equal over the first " << std::min(a.size(), b.size()) << " values";
  } else {
    m << differing << " of " << std::min(a.size(), b.size()) << " values differ; first at [" << first << "]";
    if constexpr (std::is_arithmetic_v<T>) {
      m << ": " << +a[first] << " vs " << +b[first] << "; largest |difference| " << max_diff << " at [" << max_at
        << "]";
    }
  }
  return testing::AssertionFailure() << m.str();
}

/// Equal bytes (e.g. two files read whole). On a mismatch a short summary, never the bytes.
inline testing::AssertionResult sameBytes(const std::string& a, const std::string& b) {
  if (a == b) return testing::AssertionSuccess();
  using namespace same_bytes_detail;
  std::ostringstream m;
  m.precision(6);  // samples: float WAVs hold 24-bit mantissas
  m << "sizes " << a.size() << " and " << b.size() << " bytes";
  const size_t common = std::min(a.size(), b.size());
  size_t first = common, differing = 0;
  for (size_t i = 0; i < common; ++i)
    if (a[i] != b[i] && differing++ == 0) first = i;
  if (first < common) {
    m << "; first difference at byte " << first << " (" << hexByte(a[first]) << " vs " << hexByte(b[first]) << "), "
      << differing << " of " << common << " bytes differ";
  } else {
    m << "; equal over the first " << common << " bytes";
  }
  std::vector<double> sa, sb;
  unsigned ca = 0, cb = 0;
  if (wavSamples(a, sa, ca) && wavSamples(b, sb, cb)) {
    m << "\nWAV: " << sa.size() / std::max(ca, 1u) << " and " << sb.size() / std::max(cb, 1u) << " frames of " << ca
      << " and " << cb << " channels";
    const size_t n = std::min(sa.size(), sb.size());
    size_t first_sample = n, samples_differing = 0, max_at = 0;
    double max_diff = 0;
    for (size_t i = 0; i < n; ++i) {
      if (sa[i] == sb[i]) continue;
      if (samples_differing++ == 0) first_sample = i;
      const double d = std::fabs(sa[i] - sb[i]);
      if (!(d <= max_diff)) max_diff = d, max_at = i;
    }
    const unsigned ch = std::max(ca, 1u);
    if (samples_differing == 0) {
      m << "; the first " << n << " samples are equal (the header or length differs)";
    } else {
      m << "; " << samples_differing << " of " << n << " samples differ; first at frame " << first_sample / ch
        << " channel " << first_sample % ch << " (" << sa[first_sample] << " vs " << sb[first_sample]
        << "); largest |difference| " << max_diff << " (" << 20 * std::log10(std::max(max_diff, 1e-30))
        << " dBFS) at frame " << max_at / ch;
    }
  }
  return testing::AssertionFailure() << m.str();
}

}  // namespace strike::test
