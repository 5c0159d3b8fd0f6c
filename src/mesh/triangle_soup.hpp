// SPDX-License-Identifier: MIT
// What the surface readers (obj_reader.cpp, stl_reader.cpp, ply_reader.cpp) share: the raw
// triangle soup a reader fills, and the welding that turns it into a SurfaceMesh
// (triangle_soup.cpp). Private to src/mesh.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "strike/core/format.hpp"  // formatNumber(v, 17): the readers' numbers in messages, exact
#include "strike/mesh/mesh.hpp"
#include "strike/core/result.hpp"

namespace strike::detail {

/// Most vertices a surface file may hold (and a quarter of int's range: 3 coordinates per
/// vertex and 3 indices per triangle stay indexable by int).
inline constexpr int64_t kMaxVertices = std::numeric_limits<int>::max() / 4;

// Raw triangle soup as read from a file, before welding.
struct Soup {
  std::vector<double> xyz;  // 3 per vertex
  std::vector<int> tri;     // 3 per triangle
};

// Merges vertices with exactly equal coordinates (STL stores every triangle's corners
// separately; some OBJ/PLY exporters split vertices at normal or colour seams, which would
// open the surface), drops triangles that collapse, and drops unreferenced vertices, which
// TetGen would otherwise treat as Steiner points. Output vertices keep first-appearance order
// so that the result is deterministic.
SurfaceMesh finishSurface(Soup soup, const std::string& path, bool warn_on_weld, std::vector<MeshWarning>* warnings);

/// "WHERE WHAT is VALUE, expected a finite number" (BadInput).
Error nonFinite(const std::string& where, const char* what, double value);

}  // namespace strike::detail
