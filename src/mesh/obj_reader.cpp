// SPDX-License-Identifier: MIT
// Wavefront .obj surface reader: v and f records (polygons fan-triangulated), the rest skipped.
#include <cmath>
#include <cstdint>
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

Result<SurfaceMesh> parseObj(const std::string& text, const std::string& path, std::vector<MeshWarning>* warnings) {
  detail::Tokenizer tok(text, true);
  Soup soup;
  std::vector<int> polygon;
  int64_t num_faces = 0;
  while (!tok.atEnd()) {
    const std::string_view key = tok.next();
    const int64_t line = tok.line();
    if (key == "v") {
      double xyz[3];
      for (int c = 0; c < 3; ++c) {
        const std::string_view t = tok.nextOnLine();
        if (t.empty())
          return badInput(at(path, line) + "vertex has " + std::to_string(c) + " coordinates, expected 3 (v x y z)");
        if (!detail::parseDouble(t, xyz[c])) {
          return badInput(at(path, line) + "vertex coordinate " + quoteToken(t) + " is not a number");
        }
        if (!std::isfinite(xyz[c])) return nonFinite(at(path, line), "vertex coordinate", xyz[c]);
      }
      if (static_cast<int64_t>(soup.xyz.size() / 3) >= kMaxVertices) {
        return badInput(at(path, line) + "more than " + std::to_string(kMaxVertices) + " vertices");
      }
      soup.xyz.insert(soup.xyz.end(), xyz, xyz + 3);
    } else if (key == "f") {
      ++num_faces;
      polygon.clear();
      const int64_t nv = static_cast<int64_t>(soup.xyz.size() / 3);
      for (std::string_view t = tok.nextOnLine(); !t.empty(); t = tok.nextOnLine()) {
        // v, v/vt, v//vn, v/vt/vn: only the position index matters here.
        const std::string_view index_text = t.substr(0, t.find('/'));
        int64_t index = 0;
        if (!detail::parseInt64(index_text, index) || index == 0) {
          return badInput(at(path, line) + "face " + std::to_string(num_faces) + " has vertex reference " +
                          quoteToken(t) + ", expected a non-zero integer (1-based, or negative to count back)");
        }
        const int64_t resolved = index > 0 ? index - 1 : nv + index;
        if (resolved < 0 || resolved >= nv) {
          return badInput(at(path, line) + "face " + std::to_string(num_faces) + " references vertex " +
                          std::to_string(index) + ", only " + std::to_string(nv) + " vertices are defined before it");
        }
        polygon.push_back(static_cast<int>(resolved));
      }
      if (polygon.size() < 3) {
        return badInput(at(path, line) + "face " + std::to_string(num_faces) + " has " +
                        std::to_string(polygon.size()) + " vertices, expected at least 3");
      }
      // Fan triangulation keeps the polygon's winding, so orientation is preserved.
      for (size_t k = 1; k + 1 < polygon.size(); ++k)
        soup.tri.insert(soup.tri.end(), {polygon[0], polygon[k], polygon[k + 1]});
    } else {
      // vt, vn, g, o, s, usemtl, mtllib, l, p, ...: not geometry we need.
      tok.skipLine();
    }
  }
  if (soup.tri.empty())
    return badInput(path + ": error: no faces (f records) found, expected a closed triangle surface");
  return finishSurface(std::move(soup), path, true, warnings);
}

}  // namespace

Result<SurfaceMesh> readObj(const std::string& path, std::vector<MeshWarning>* warnings) {
  Result<std::string> bytes = detail::readWholeFile(path);
  if (!bytes) return bytes.error();
  return parseObj(*bytes, path, warnings);
}

}  // namespace strike
