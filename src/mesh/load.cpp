// SPDX-License-Identifier: MIT
// loadTetMesh(): the MESH argument of `strike modes` -> a validated TetMesh.
//
// Element order: a tet file keeps the order it was written with. A Tet4 file with order 2
// requested is promoted (straight mid-edge nodes). A Tet10 file with order 1 requested stays
// Tet10, with a warning: its mid-edge nodes may be curved (a deliberately made quadratic mesh)
// and dropping them would throw away geometry and accuracy the user paid for. The returned
// mesh.order says which order was used, and the bank records it. Order 0 keeps a file's order
// without a word and builds Tet4 (the precompute's automatic order decides from that mesh).
#include <chrono>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "mesh_io.hpp"
#include "strike/core/hash.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {

namespace {

std::string expectedForm(const std::string& kind) {
  if (kind == "box") return "box:LX,LY,LZ";
  if (kind == "sphere") return "sphere:R";
  return "cylinder:R,H";
}

// Strict: "box:0.3,0.02,0.02". Every field must be a finite number > 0 with nothing around it.
Result<std::vector<double>> parsePrimitive(const std::string& spec, std::string& kind) {
  const size_t colon = spec.find(':');
  kind = spec.substr(0, colon);
  const std::string form = expectedForm(kind);
  const size_t want = kind == "box" ? 3 : kind == "sphere" ? 1 : 2;
  const char* names_box[3] = {"LX", "LY", "LZ"};
  const char* names_cyl[2] = {"R", "H"};
  const char* names_sphere[1] = {"R"};
  const char** names = kind == "box" ? names_box : kind == "sphere" ? names_sphere : names_cyl;
  std::vector<std::string> fields;
  const std::string rest = spec.substr(colon + 1);
  size_t start = 0;
  while (true) {
    const size_t comma = rest.find(',', start);
    fields.push_back(rest.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (fields.size() != want) {
    return badInput("primitive \"" + spec + "\": got " + std::to_string(fields.size()) + " number(s), expected " +
                    std::to_string(want) + " (" + form + ", lengths in metres > 0)");
  }
  std::vector<double> values;
  for (size_t i = 0; i < fields.size(); ++i) {
    double v = 0.0;
    if (!detail::parseDouble(fields[i], v) || fields[i].front() == '+') {
      return badInput("primitive \"" + spec + "\": " + names[i] + " = " + detail::quoteToken(fields[i]) +
                      " is not a number, expected " + form + " with lengths in metres > 0");
    }
    if (!std::isfinite(v) || !(v > 0.0)) {
      std::ostringstream s;
      s << v;
      return badInput("primitive \"" + spec + "\": " + names[i] + " = " + s.str() +
                      " (must be a finite length in metres > 0), expected " + form);
    }
    values.push_back(v);
  }
  return values;
}

void keepFileOrder(TetMesh& mesh, const MeshOptions& options, const std::string& path,
                   std::vector<MeshWarning>& warnings) {
  if (mesh.order == 1 && options.order == 2) {
    mesh = promoteToTet10(mesh);
  } else if (mesh.order == 2 && options.order == 1) {
    warnings.push_back({path + ": warning: the file has quadratic (Tet10) elements; keeping order 2 (order 1 was "
                               "requested, but dropping the mid-edge nodes would discard the file's geometry)"});
  }
}

}  // namespace

Result<LoadedMesh> loadTetMesh(const std::string& spec, const MeshOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.order != 0 && options.order != 1 && options.order != 2) {
    return badInput("element order " + std::to_string(options.order) + " (must be 1 or 2)");
  }
  MeshOptions built = options;  // what a mesh built here (primitive, surface file) is made with
  if (built.order == 0) built.order = 1;
  if (!std::isfinite(options.target_edge_m) || options.target_edge_m < 0.0) {
    std::ostringstream s;
    s << "mesh size " << options.target_edge_m << " m (must be >= 0; 0 picks one automatically)";
    return badInput(s.str());
  }
  if (!(options.scale > 0.0) || !std::isfinite(options.scale)) {
    std::ostringstream s;
    s << "mesh unit scale " << options.scale << " m per unit (must be a finite number > 0)";
    return badInput(s.str());
  }
  LoadedMesh loaded;
  auto finish = [&]() -> Result<LoadedMesh> {
    const int64_t tets = static_cast<int64_t>(loaded.mesh.tets.rows());
    if (tets > options.max_tets)
      return badInput(spec + ": error: mesh has " + std::to_string(tets) + " tets, more than the cap of " +
                      std::to_string(options.max_tets) +
                      " (--max-tets); raise it with --max-tets N or use a coarser mesh");
    loaded.meshing_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return std::move(loaded);
  };

  if (isPrimitiveSpec(spec)) {
    std::string kind;
    Result<std::vector<double>> values = parsePrimitive(spec, kind);
    if (!values) return values.error();
    loaded.source_hash = fnv1a64(spec.data(), spec.size());
    const std::vector<double>& v = *values;
    if (kind == "box") {
      Result<TetMesh> mesh = makeBox(v[0], v[1], v[2], built);
      if (!mesh) return mesh.error();
      loaded.mesh = std::move(*mesh);
      return finish();
    }
    // The surface's edge follows the tet edge so that boundary and interior match.
    Result<SurfaceMesh> surface = kind == "sphere" ? makeSphereSurface(v[0], options.target_edge_m)
                                                   : makeCylinderSurface(v[0], v[1], options.target_edge_m);
    if (!surface) return surface.error();
    Result<TetMesh> mesh = tetrahedralize(*surface, built, spec);
    if (!mesh) return mesh.error();
    loaded.mesh = std::move(*mesh);
    return finish();
  }

  namespace fs = std::filesystem;
  const std::string ext = detail::lowerExtension(spec);
  std::error_code ec;
  const bool is_tetgen =
      ext == ".node" || ext == ".ele" || (ext.empty() && !fs::exists(spec, ec) && fs::exists(spec + ".node", ec));
  if (!is_tetgen) {
    if (!fs::exists(spec, ec))
      return badInput(spec + ": error: mesh file not found (and not a primitive such as box:LX,LY,LZ)");
    if (fs::is_directory(spec, ec)) return badInput(spec + ": error: is a directory, expected a mesh file");
  }
  if (ext == ".obj" || ext == ".stl" || ext == ".ply") {
    Result<std::string> bytes = detail::readWholeFile(spec);
    if (!bytes) return bytes.error();
    loaded.source_hash = fnv1a64(bytes->data(), bytes->size());
    Result<SurfaceMesh> surface = readSurfaceMesh(spec, &loaded.warnings);
    if (!surface) return surface.error();
    if (options.scale != 1.0) surface->V *= options.scale;  // to metres before TetGen sizes anything
    Result<TetMesh> mesh = tetrahedralize(*surface, built, spec);
    if (!mesh) return mesh.error();
    loaded.mesh = std::move(*mesh);
    return finish();
  }
  if (ext == ".msh" || is_tetgen) {
    Result<TetMesh> mesh = is_tetgen ? readTetgen(spec, &loaded.warnings) : readGmsh(spec, &loaded.warnings);
    if (!mesh) return mesh.error();
    if (options.scale != 1.0) mesh->nodes *= options.scale;
    if (is_tetgen) {
      // Hash both files, in a fixed order, so that editing either one changes the hash.
      const std::string stem = ext.empty() ? spec : spec.substr(0, spec.size() - ext.size());
      uint64_t hash = 0xcbf29ce484222325ull;
      for (const char* suffix : {".node", ".ele"}) {
        Result<std::string> bytes = detail::readWholeFile(stem + suffix);
        if (!bytes) return bytes.error();
        hash = fnv1a64(bytes->data(), bytes->size(), hash);
      }
      loaded.source_hash = hash;
    } else {
      Result<std::string> bytes = detail::readWholeFile(spec);
      if (!bytes) return bytes.error();
      loaded.source_hash = fnv1a64(bytes->data(), bytes->size());
    }
    if (Status s = validateAndRepair(*mesh, spec, &loaded.warnings); !s) return s.error();
    keepFileOrder(*mesh, options, spec, loaded.warnings);
    loaded.mesh = std::move(*mesh);
    return finish();
  }
  return badInput(spec + ": error: unknown mesh file extension " + detail::quoteToken(ext) +
                  ", expected .obj, .stl, .ply, .msh, .node/.ele, or a primitive box:LX,LY,LZ, sphere:R, cylinder:R,H");
}

}  // namespace strike
