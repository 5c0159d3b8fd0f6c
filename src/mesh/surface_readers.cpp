// SPDX-License-Identifier: MIT
// Surface mesh readers: Wavefront .obj, STL (ASCII and binary), PLY (ASCII and binary little
// and big endian). Every count in a file is checked against the bytes that are left before
// anything is reserved, so a hostile header cannot make us allocate gigabytes; every
// coordinate is checked for NaN/Inf and every index against the vertex count.
//
// This file picks the reader by extension; the readers are obj_reader.cpp, stl_reader.cpp and
// ply_reader.cpp, and triangle_soup.cpp welds what they read.
#include <string>
#include <vector>

#include "mesh_io.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {

Result<SurfaceMesh> readSurfaceMesh(const std::string& path, std::vector<MeshWarning>* warnings) {
  const std::string ext = detail::lowerExtension(path);
  if (ext == ".obj") return readObj(path, warnings);
  if (ext == ".stl") return readStl(path, warnings);
  if (ext == ".ply") return readPly(path, warnings);
  return badInput(path + ": error: unknown surface mesh extension " + detail::quoteToken(ext) +
                  ", expected .obj, .stl or .ply");
}

}  // namespace strike
