// SPDX-License-Identifier: MIT
// A minimal PNG encoder: 8-bit RGB, no filtering, zlib stream of stored deflate blocks. No
// compression, so no zlib dependency; spectrogram pictures are small (1024x512 is 1.5 MB).
#include <array>
#include <cstring>

#include "strike/audio/audio.hpp"

namespace strike {
namespace {

/// CRC-32 of PNG chunks (ISO/IEC 15948 Annex D): reflected polynomial 0xEDB88320.
uint32_t crc32(const uint8_t* data, size_t size, uint32_t crc = 0) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t n = 0; n < 256; ++n) {
      uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (size_t i = 0; i < size; ++i) crc = table[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

void putBigEndian32(std::string& out, uint32_t v) {
  out.push_back(static_cast<char>((v >> 24) & 0xFFu));
  out.push_back(static_cast<char>((v >> 16) & 0xFFu));
  out.push_back(static_cast<char>((v >> 8) & 0xFFu));
  out.push_back(static_cast<char>(v & 0xFFu));
}

void putChunk(std::string& out, const char type[4], const std::string& data) {
  putBigEndian32(out, static_cast<uint32_t>(data.size()));
  const size_t start = out.size();
  out.append(type, 4);
  out += data;
  const auto* bytes = reinterpret_cast<const uint8_t*>(out.data() + start);
  putBigEndian32(out, crc32(bytes, 4 + data.size()));
}

}  // namespace

std::string encodePngRgb(int width, int height, const std::vector<uint8_t>& rgb) {
  if (width <= 0 || height <= 0) return {};
  const size_t row_bytes = static_cast<size_t>(width) * 3;
  if (rgb.size() != row_bytes * static_cast<size_t>(height)) return {};

  // Raw scanlines: filter type 0 (None) then the row.
  std::string raw;
  raw.reserve((row_bytes + 1) * static_cast<size_t>(height));
  for (int y = 0; y < height; ++y) {
    raw.push_back('\0');
    raw.append(reinterpret_cast<const char*>(rgb.data()) + static_cast<size_t>(y) * row_bytes, row_bytes);
  }

  // zlib (RFC 1950): CMF 0x78 (deflate, 32 KiB window), FLG 0x01 (FCHECK: 0x7801 % 31 == 0),
  // stored blocks (RFC 1951 section 3.2.4: BFINAL/BTYPE=00 byte, LEN, NLEN little-endian),
  // then the Adler-32 of the raw data, big-endian.
  std::string zlib;
  zlib.reserve(raw.size() + raw.size() / 65535 * 5 + 16);
  zlib.push_back(static_cast<char>(0x78));
  zlib.push_back(static_cast<char>(0x01));
  size_t offset = 0;
  do {
    const size_t length = std::min<size_t>(65535, raw.size() - offset);
    const bool final_block = offset + length == raw.size();
    zlib.push_back(static_cast<char>(final_block ? 1 : 0));
    zlib.push_back(static_cast<char>(length & 0xFFu));
    zlib.push_back(static_cast<char>((length >> 8) & 0xFFu));
    zlib.push_back(static_cast<char>(~length & 0xFFu));
    zlib.push_back(static_cast<char>((~length >> 8) & 0xFFu));
    zlib.append(raw, offset, length);
    offset += length;
  } while (offset < raw.size());
  uint32_t s1 = 1, s2 = 0;  // Adler-32 (RFC 1950 section 8.2)
  for (unsigned char c : raw) {
    s1 = (s1 + c) % 65521u;
    s2 = (s2 + s1) % 65521u;
  }
  putBigEndian32(zlib, (s2 << 16) | s1);

  std::string png("\x89PNG\r\n\x1a\n", 8);
  std::string ihdr;
  putBigEndian32(ihdr, static_cast<uint32_t>(width));
  putBigEndian32(ihdr, static_cast<uint32_t>(height));
  ihdr.push_back(8);  // bit depth
  ihdr.push_back(2);  // colour type: truecolour RGB
  ihdr.push_back(0);  // compression: deflate
  ihdr.push_back(0);  // filter method 0
  ihdr.push_back(0);  // no interlace
  putChunk(png, "IHDR", ihdr);
  putChunk(png, "IDAT", zlib);
  putChunk(png, "IEND", std::string());
  return png;
}

}  // namespace strike
