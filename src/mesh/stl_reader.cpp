// SPDX-License-Identifier: MIT
// STL surface reader, ASCII and binary. The binary triangle count is checked against the file
// size before anything is reserved, so a hostile header cannot make us allocate gigabytes.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "mesh_io.hpp"
#include "strike/mesh/mesh.hpp"
#include "triangle_soup.hpp"

namespace strike {

namespace {

using detail::at;
using detail::finishSurface;
using detail::kMaxVertices;
using detail::nonFinite;
using detail::quoteToken;
using detail::Soup;

float readFloatLe(const unsigned char* p) {
  const uint32_t bits = static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
                        (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

Result<SurfaceMesh> parseBinaryStl(const std::string& bytes, const std::string& path,
                                   std::vector<MeshWarning>* warnings) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  const uint64_t n = static_cast<uint64_t>(p[80]) | (static_cast<uint64_t>(p[81]) << 8) |
                     (static_cast<uint64_t>(p[82]) << 16) | (static_cast<uint64_t>(p[83]) << 24);
  Soup soup;
  soup.xyz.reserve(9 * n);
  soup.tri.reserve(3 * n);
  for (uint64_t t = 0; t < n; ++t) {
    const uint64_t offset = 84 + 50 * t + 12;  // skip the stored normal: we do not trust it
    for (int k = 0; k < 9; ++k) {
      const double c = readFloatLe(p + offset + 4 * static_cast<uint64_t>(k));
      if (!std::isfinite(c)) {
        return badInput(path + ": byte " + std::to_string(offset + 4 * static_cast<uint64_t>(k)) +
                        ": error: triangle " + std::to_string(t) + " coordinate is " + formatNumber(c, 17) +
                        ", expected a finite number");
      }
      soup.xyz.push_back(c);
    }
    const int base = static_cast<int>(3 * t);
    soup.tri.insert(soup.tri.end(), {base, base + 1, base + 2});
  }
  if (n == 0) return badInput(path + ": error: binary STL with 0 triangles, expected a closed triangle surface");
  return finishSurface(std::move(soup), path, false, warnings);
}

Result<SurfaceMesh> parseAsciiStl(const std::string& text, const std::string& path,
                                  std::vector<MeshWarning>* warnings) {
  detail::Tokenizer tok(text, false);
  Soup soup;
  auto expect = [&](std::string_view word) -> Status {
    const std::string_view t = tok.next();
    if (t != word) {
      return badInput(at(path, tok.line()) + "got " + (t.empty() ? std::string("end of file") : quoteToken(t)) +
                      ", expected \"" + std::string(word) + "\"");
    }
    return {};
  };
  int64_t facet = 0;
  while (!tok.atEnd()) {
    const std::string_view key = tok.next();
    if (key == "solid" || key == "endsolid") {
      tok.skipLine();  // the solid's name
      continue;
    }
    if (key != "facet") {
      return badInput(at(path, tok.line()) + "got " + quoteToken(key) +
                      ", expected \"facet\", \"solid\" or \"endsolid\"");
    }
    tok.skipLine();  // "normal nx ny nz": recomputed from the vertices where needed
    if (Status s = expect("outer"); !s) return s.error();
    if (Status s = expect("loop"); !s) return s.error();
    int corners = 0;
    std::string_view t = tok.next();
    while (t == "vertex") {
      const int64_t line = tok.line();
      for (int c = 0; c < 3; ++c) {
        const std::string_view v = tok.nextOnLine();
        double x = 0.0;
        if (v.empty() || !detail::parseDouble(v, x)) {
          return badInput(at(path, line) + "vertex coordinate " + (v.empty() ? std::string("missing") : quoteToken(v)) +
                          ", expected a number (vertex x y z)");
        }
        if (!std::isfinite(x)) return nonFinite(at(path, line), "vertex coordinate", x);
        soup.xyz.push_back(x);
      }
      ++corners;
      t = tok.next();
    }
    if (corners != 3) {
      return badInput(at(path, tok.line()) + "facet " + std::to_string(facet) + " has " + std::to_string(corners) +
                      " vertices, expected 3");
    }
    if (t != "endloop") {
      return badInput(at(path, tok.line()) + "got " + (t.empty() ? std::string("end of file") : quoteToken(t)) +
                      ", expected \"endloop\"");
    }
    if (Status s = expect("endfacet"); !s) return s.error();
    const int base = static_cast<int>(soup.xyz.size() / 3) - 3;
    soup.tri.insert(soup.tri.end(), {base, base + 1, base + 2});
    ++facet;
    if (facet > kMaxVertices / 3)
      return badInput(at(path, tok.line()) + "more than " + std::to_string(kMaxVertices / 3) + " facets");
  }
  if (soup.tri.empty()) return badInput(path + ": error: ASCII STL with no facets, expected a closed triangle surface");
  return finishSurface(std::move(soup), path, false, warnings);
}

}  // namespace

Result<SurfaceMesh> readStl(const std::string& path, std::vector<MeshWarning>* warnings) {
  Result<std::string> bytes = detail::readWholeFile(path);
  if (!bytes) return bytes.error();
  const std::string& b = *bytes;
  // Binary STL files often start with "solid" too (the 80-byte header is free text), so the
  // size rule 84 + 50 n decides first; "solid" alone is not proof of ASCII.
  if (b.size() >= 84) {
    const auto* p = reinterpret_cast<const unsigned char*>(b.data());
    const uint64_t n = static_cast<uint64_t>(p[80]) | (static_cast<uint64_t>(p[81]) << 8) |
                       (static_cast<uint64_t>(p[82]) << 16) | (static_cast<uint64_t>(p[83]) << 24);
    if (84 + 50 * n == b.size()) return parseBinaryStl(b, path, warnings);
  }
  // ASCII only if it also looks like text: binary STL almost always holds NUL bytes (the
  // attribute word, the zero bytes of 0.0f and 1.0f), text never does.
  const size_t first = b.find_first_not_of(" \t\r\n");
  const bool is_text = b.find('\0') == std::string::npos;
  if (first != std::string::npos && b.compare(first, 5, "solid") == 0 && is_text)
    return parseAsciiStl(b, path, warnings);
  if (b.size() < 84) {
    return badInput(path + ": error: file is " + std::to_string(b.size()) +
                    " bytes: too short for a binary STL (84-byte header) and does not start with \"solid\"");
  }
  const auto* p = reinterpret_cast<const unsigned char*>(b.data());
  const uint64_t n = static_cast<uint64_t>(p[80]) | (static_cast<uint64_t>(p[81]) << 8) |
                     (static_cast<uint64_t>(p[82]) << 16) | (static_cast<uint64_t>(p[83]) << 24);
  return badInput(path + ": byte 80: error: binary STL header says " + std::to_string(n) +
                  " triangles, so the file should be " + std::to_string(84 + 50 * n) +
                  " bytes (84 + 50 n), but it is " + std::to_string(b.size()) +
                  " bytes (truncated or not an STL file)");
}

}  // namespace strike
