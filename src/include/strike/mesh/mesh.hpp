// SPDX-License-Identifier: MIT
// Meshes: surface meshes (triangles), tetrahedral meshes (Tet4 / Tet10), primitives, and the
// loaders that turn a MESH argument of `strike modes` into a TetMesh.
//
// Target strike_mesh (Eigen only): readers, primitives, validation, surface extraction.
// Target strike_tetgen (links TetGen, AGPL): tetrahedralize() and loadTetMesh(), the dispatcher
// that also handles surface meshes.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "strike/core/progress.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// A closed triangle surface. V #V by 3 (metres), F #F by 3 (0-based, counter-clockwise seen
/// from outside, so normals point out).
struct SurfaceMesh {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
};

/// A tetrahedral mesh.
///  nodes    #N by 3, metres.
///  tets     #T by 4 (order 1) or #T by 10 (order 2). Corners 0..3 are positively oriented
///           (det[x1-x0, x2-x0, x3-x0] > 0). Tet10 mid-edge nodes 4..9 follow Gmsh's order:
///           edges (0,1) (1,2) (2,0) (3,0) (3,2) (3,1).
///  order    1 or 2.
///  surface  #F by 3 corner-node indices of the boundary triangles, outward (CCW from outside).
struct TetMesh {
  Eigen::MatrixXd nodes;
  Eigen::MatrixXi tets;
  int order = 1;
  Eigen::MatrixXi surface;
};

/// Default of MeshOptions::max_tets: a Tet10 mesh this size already needs tens of GB to solve.
constexpr int64_t kDefaultMaxTets = 2'000'000;

/// Options for turning a MESH argument into a TetMesh.
struct MeshOptions {
  /// 1: Tet4, 2: Tet10 (mid-edge nodes added, straight edges). 0: a tet file's own order, a mesh
  /// built here Tet4: what the precompute's automatic order (kAutoOrder) judges the shape on.
  int order = 1;
  double target_edge_m = 0.0;      ///< target tet edge length; 0 picks one from the bounding box
  double radius_edge_ratio = 1.4;  ///< TetGen quality bound (-q), smaller = better shaped tets
  /// Size cap (memory and time of the FEM and eigen-solve): a mesh with more tets, or a surface
  /// whose TetGen estimate exceeds it, is refused with a message naming the cap (`--max-tets`).
  int64_t max_tets = kDefaultMaxTets;
  /// Metres per unit of the mesh file's coordinates: 0.001 for a file in millimetres (the scene
  /// key "units": "mm", `strike modes --units mm`). Applied to the coordinates as read, before
  /// meshing, so target_edge_m stays in metres. Primitives are always in metres.
  double scale = 1.0;
  ProgressFn progress;  ///< optional
};

/// A warning about a mesh that was still usable (unreferenced nodes, duplicate vertices...).
struct MeshWarning {
  std::string message;
};

/// A loaded mesh with its warnings and provenance.
struct LoadedMesh {
  TetMesh mesh;
  std::vector<MeshWarning> warnings;
  uint64_t source_hash = 0;  ///< FNV-1a 64 of the input file bytes or of the primitive spec text
  double meshing_seconds = 0.0;
};

// ---- strike_mesh ---------------------------------------------------------------------------

/// True if `spec` names a primitive ("box:LX,LY,LZ", "sphere:R", "cylinder:R,H").
bool isPrimitiveSpec(const std::string& spec);

/// Primitives, centred at the origin, metres. Box: structured hex grid split into tets,
/// cells about target_edge_m (0: ~8 cells along the shortest side... see the implementation).
/// Sphere and cylinder: a closed, outward triangle surface (for tetrahedralize()), edges about
/// target_edge_m (0: a default), scaled so that the polyhedron encloses exactly the analytic
/// volume (so mass is right). Sphere: geodesic icosphere. Cylinder: axis z, height H.
Result<TetMesh> makeBox(double lx, double ly, double lz, const MeshOptions& options);
Result<SurfaceMesh> makeSphereSurface(double radius, double target_edge_m);
Result<SurfaceMesh> makeCylinderSurface(double radius, double height, double target_edge_m);

/// Surface readers: Wavefront .obj (v/f, polygons fan-triangulated), .stl (ASCII and binary),
/// .ply (ASCII and binary little/big endian, vertex x y z and face vertex_indices).
/// Readers return the triangles as stored (they do not check closedness; see
/// checkClosedSurface). STL vertices are welded (exactly equal coordinates become one vertex);
/// triangles that collapse to a line or point after welding are dropped, with a warning.
/// `warnings` may be null.
Result<SurfaceMesh> readObj(const std::string& path, std::vector<MeshWarning>* warnings = nullptr);
Result<SurfaceMesh> readStl(const std::string& path, std::vector<MeshWarning>* warnings = nullptr);
Result<SurfaceMesh> readPly(const std::string& path, std::vector<MeshWarning>* warnings = nullptr);
/// Dispatch on the extension (.obj .stl .ply, case-insensitive).
Result<SurfaceMesh> readSurfaceMesh(const std::string& path, std::vector<MeshWarning>* warnings = nullptr);

/// Tet mesh readers: Gmsh .msh 2.2 and 4.1 ASCII (element types 4 = Tet4, 11 = Tet10; other
/// elements ignored), TetGen .node + .ele (path may name either file or the common stem).
/// The result has the file's element order (Tet10 mid-edge nodes are put in Gmsh order; a
/// TetGen -o2 .ele lists them as edges (2,3) (0,3) (0,1) (1,2) (1,3) (0,2) and is reordered).
/// They check syntax, counts and index ranges but not geometry: call validateAndRepair().
Result<TetMesh> readGmsh(const std::string& path, std::vector<MeshWarning>* warnings);
Result<TetMesh> readTetgen(const std::string& path, std::vector<MeshWarning>* warnings);

/// Checks a tet mesh and repairs what is safe: fixes orientation of negatively oriented tets
/// (with a warning), rejects degenerate (near-zero volume) tets and NaN/Inf coordinates with
/// an error naming the tet and its volume, removes unreferenced nodes with a warning, and
/// (re)computes `surface`. `source` names the file in messages.
Status validateAndRepair(TetMesh& mesh, const std::string& source, std::vector<MeshWarning>* warnings);

/// Boundary triangles (faces used by exactly one tet), oriented outward. #F by 3 corner nodes.
Eigen::MatrixXi extractSurface(const Eigen::MatrixXi& tets);

/// Adds mid-edge nodes to a Tet4 mesh, giving a Tet10 mesh with straight edges.
TetMesh promoteToTet10(const TetMesh& tet4);

/// Checks a surface mesh is closed and manifold (every edge shared by exactly two triangles)
/// and has no degenerate triangles; the error names the first bad edge or triangle.
Status checkClosedSurface(const SurfaceMesh& surface, const std::string& source);

// ---- strike_tetgen (AGPL) -------------------------------------------------------------------

/// Tetrahedralizes a closed surface with TetGen ("pq<ratio>a<volume>", quiet), then
/// validates (and promotes to Tet10 when options.order == 2). Throws nothing; TetGen failures
/// become Errors. Before meshing, the surface must pass checkClosedSurface() and TetGen's own
/// self-intersection test (-d), because TetGen can crash or hang on such input.
/// Max tet volume: target_edge_m^3 / (6 sqrt 2) (a regular tet of that edge); when
/// target_edge_m == 0, the enclosed volume / 600, which gives a few thousand tets for a compact
/// object (more for thin-walled ones, where the surface sets the size).
Result<TetMesh> tetrahedralize(const SurfaceMesh& surface, const MeshOptions& options, const std::string& source);

/// Turns a MESH argument (a primitive spec or a file path) into a validated TetMesh of the
/// requested order. Surface files and sphere/cylinder primitives go through tetrahedralize().
/// Tet files keep their own order where it is higher: a Tet4 file with order 2 requested is
/// promoted, but a Tet10 file with order 1 requested stays Tet10 (with a warning), because its
/// mid-edge nodes may be curved geometry the user made on purpose. mesh.order tells which.
/// Primitive specs are strict ("box:0.3,0.02,0.02": no spaces, every length finite and > 0).
/// source_hash: FNV-1a 64 of the file bytes (.node then .ele for TetGen), or of the spec text.
Result<LoadedMesh> loadTetMesh(const std::string& spec, const MeshOptions& options);

}  // namespace strike
