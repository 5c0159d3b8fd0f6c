// SPDX-License-Identifier: MIT
// tetrahedralize(): a closed triangle surface -> a quality Tet4 mesh through TetGen's library
// API. This file links TetGen (AGPL-3.0); the strike_tetgen target is used by the command-line
// tool only, never by the runtime library (see README, Licence).
//
// TetGen reports failure by throwing an int (its terminatetetgen() in TETLIBRARY mode) and may
// loop or crash on surfaces that are open or self-intersecting, so the surface is checked first
// and everything TetGen throws is caught here.
#include <tetgen.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <new>
#include <sstream>
#include <string>

#include <Eigen/Geometry>  // cross()

#include "strike/core/format.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {

namespace {

// Refuse requests that could not be solved anyway: volume / maxvolume above this means TetGen
// would make several million tets.
// Default resolution: about this many "regular tet volumes" in the body. TetGen's quality
// refinement produces roughly 2-4x more tets than volume / maxvolume, so this lands typical
// objects in the low thousands of tets.
constexpr double kDefaultRegularTets = 600.0;

std::string tetgenErrorText(int code) {
  switch (code) {
    case 1: return "out of memory";
    case 2: return "internal error (please report it with the input mesh)";
    case 3: return "the surface intersects itself";
    case 4: return "the surface has a very small feature (tiny edge or face) compared to its size";
    case 5: return "two facets of the surface are very close to each other or overlap";
    case 10: return "the input is invalid";
    default: return "TetGen error code " + std::to_string(code);
  }
}

// TetGen prints diagnostics on stdout even with -Q; stdout is reserved for data (the CLI's
// JSON), so its output is routed to stderr while it runs.
class StdoutToStderr {
 public:
  StdoutToStderr() {
    std::fflush(stdout);
    saved_ = dup(1);
    if (saved_ >= 0) dup2(2, 1);
  }
  ~StdoutToStderr() {
    std::fflush(stdout);
    if (saved_ >= 0) {
      dup2(saved_, 1);
      close(saved_);
    }
  }
  StdoutToStderr(const StdoutToStderr&) = delete;
  StdoutToStderr& operator=(const StdoutToStderr&) = delete;

 private:
  int saved_ = -1;
};

/// The largest tet volume TetGen may make: a regular tet of the target edge, or the enclosed
/// volume over kDefaultRegularTets; or why the options or the surface are refused.
Result<double> maxTetVolume(const SurfaceMesh& surface, const MeshOptions& options, const std::string& source) {
  if (options.order != 1 && options.order != 2) {
    return badInput(source + ": error: element order " + std::to_string(options.order) + ", expected 1 or 2");
  }
  if (!std::isfinite(options.target_edge_m) || options.target_edge_m < 0.0) {
    return badInput(source + ": error: target edge length " + formatNumber(options.target_edge_m, 6) +
                    " m, expected >= 0 (0 = automatic)");
  }
  // Below ~1.1 TetGen's refinement may never terminate; above ~10 the bound does nothing.
  if (!(options.radius_edge_ratio >= 1.1 && options.radius_edge_ratio <= 10.0)) {
    return badInput(source + ": error: radius-edge ratio " + formatNumber(options.radius_edge_ratio, 6) +
                    ", expected 1.1 .. 10");
  }
  if (Status s = checkClosedSurface(surface, source); !s) return s.error();

  double volume = 0.0;
  for (Eigen::Index f = 0; f < surface.F.rows(); ++f) {
    const Eigen::Vector3d a = surface.V.row(surface.F(f, 0)), b = surface.V.row(surface.F(f, 1)),
                          c = surface.V.row(surface.F(f, 2));
    volume += a.dot(b.cross(c)) / 6.0;
  }
  volume = std::abs(volume);  // TetGen does not care about the winding
  const double extent = (surface.V.colwise().maxCoeff() - surface.V.colwise().minCoeff()).norm();
  if (!(volume > 1e-12 * extent * extent * extent)) {
    return badInput(source + ": error: the closed surface encloses volume " + formatNumber(volume, 6) +
                    " m^3, expected a solid");
  }
  const double regular_tet = 1.0 / (6.0 * std::sqrt(2.0));  // volume of a regular tet of edge 1
  double max_volume = 0.0;
  if (options.target_edge_m > 0.0) {
    max_volume = regular_tet * std::pow(options.target_edge_m, 3);
  } else {
    max_volume = volume / kDefaultRegularTets;
  }
  const double max_tets = static_cast<double>(options.max_tets);
  if (volume / max_volume > max_tets) {
    return badInput(source + ": error: target edge " + formatNumber(options.target_edge_m, 6) +
                    " m would give more than " + formatNumber(max_tets, 6) + " tets (the --max-tets cap) for volume " +
                    formatNumber(volume, 6) + " m^3; use a larger --size, or raise the cap with --max-tets N");
  }
  return max_volume;
}

/// The closed surface as TetGen's piecewise linear complex: its points, one triangle a facet.
void fillTetgenInput(const SurfaceMesh& surface, tetgenio& in) {
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(surface.V.rows());
  in.pointlist = new REAL[static_cast<size_t>(3 * surface.V.rows())];
  for (Eigen::Index i = 0; i < surface.V.rows(); ++i) {
    for (int c = 0; c < 3; ++c) in.pointlist[3 * i + c] = surface.V(i, c);
  }
  in.numberoffacets = static_cast<int>(surface.F.rows());
  in.facetlist = new tetgenio::facet[static_cast<size_t>(surface.F.rows())];
  for (Eigen::Index f = 0; f < surface.F.rows(); ++f) {
    tetgenio::facet& facet = in.facetlist[f];
    tetgenio::init(&facet);
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&facet.polygonlist[0]);
    facet.polygonlist[0].numberofvertices = 3;
    facet.polygonlist[0].vertexlist = new int[3];
    for (int c = 0; c < 3; ++c) facet.polygonlist[0].vertexlist[c] = surface.F(f, c);
  }
}

/// TetGen meshing a self-intersecting surface can crash (it segfaults on two overlapping
/// cubes), so its own intersection test (-d) runs first; it lists the offending faces.
Status checkSelfIntersections(tetgenio& in, const std::string& source) {
  tetgenio diagnosis;
  tetgenbehavior detect;
  char detect_switches[] = "pdQ";
  if (!detect.parse_commandline(detect_switches)) return internalError("TetGen rejected the switches pdQ");
  try {
    StdoutToStderr redirect;
    ::tetrahedralize(&detect, &in, &diagnosis);
  } catch (int code) {
    return badInput(source + ": error: TetGen could not check the surface (-pdQ): " + tetgenErrorText(code));
  } catch (...) {
    return internalError(source + ": error: TetGen failed while checking the surface for self-intersections");
  }
  if (diagnosis.numberoftrifaces > 0 && diagnosis.trifacelist) {
    std::string where;
    for (int c = 0; c < 3; ++c) {
      const int v = diagnosis.trifacelist[c] - diagnosis.firstnumber;
      if (v < 0 || v >= in.numberofpoints) continue;
      where += (c ? ", " : "") + std::to_string(v) + " (" + formatNumber(in.pointlist[3 * v], 6) + ", " +
               formatNumber(in.pointlist[3 * v + 1], 6) + ", " + formatNumber(in.pointlist[3 * v + 2], 6) + ")";
    }
    return badInput(source + ": error: the surface intersects itself: TetGen found " +
                    std::to_string(diagnosis.numberoftrifaces) + " intersecting triangles, the first with vertices " +
                    where + "; expected a closed surface without self-intersections");
  }
  return {};
}

/// TetGen's output as a linear tet mesh.
TetMesh meshFromTetgen(const tetgenio& out) {
  TetMesh mesh;
  mesh.order = 1;
  mesh.nodes.resize(out.numberofpoints, 3);
  for (int i = 0; i < out.numberofpoints; ++i) {
    for (int c = 0; c < 3; ++c) mesh.nodes(i, c) = out.pointlist[3 * i + c];
  }
  mesh.tets.resize(out.numberoftetrahedra, 4);
  const int base = out.firstnumber;
  for (int t = 0; t < out.numberoftetrahedra; ++t) {
    for (int c = 0; c < 4; ++c) mesh.tets(t, c) = out.tetrahedronlist[4 * t + c] - base;
  }
  return mesh;
}

}  // namespace

Result<TetMesh> tetrahedralize(const SurfaceMesh& surface, const MeshOptions& options, const std::string& source) {
  Result<double> max_volume_or = maxTetVolume(surface, options, source);
  if (!max_volume_or) return max_volume_or.error();
  const double max_volume = *max_volume_or;

  tetgenio in, out;
  fillTetgenInput(surface, in);

  // Switches: p (piecewise linear complex), q (quality, radius-edge ratio), a (max volume),
  // Q (quiet). The numbers are set as fields rather than printed into the switch string, so
  // that no formatting of small numbers (1e-9) can be misread by TetGen's parser.
  tetgenbehavior behavior;
  char switches[] = "pqQ";
  const std::string shown = "pq" + formatNumber(options.radius_edge_ratio, 6) + "a" + formatNumber(max_volume, 6) + "Q";
  if (!behavior.parse_commandline(switches)) return internalError("TetGen rejected the switches " + shown);
  behavior.quality = 1;
  behavior.minratio = options.radius_edge_ratio;
  behavior.fixedvolume = 1;
  behavior.maxvolume = max_volume;

  if (options.progress) options.progress("tetrahedralize", 0.0);
  if (Status clean = checkSelfIntersections(in, source); !clean) return clean.error();
  try {
    StdoutToStderr redirect;
    ::tetrahedralize(&behavior, &in, &out);
  } catch (int code) {
    return badInput(source + ": error: TetGen could not mesh the surface (-" + shown + "): " + tetgenErrorText(code));
  } catch (const std::bad_alloc&) {
    return internalError(source + ": error: out of memory in TetGen (-" + shown + ")");
  } catch (const std::exception& e) {
    return internalError(source + ": error: TetGen failed (-" + shown + "): " + e.what());
  } catch (...) {
    return internalError(source + ": error: TetGen failed with an unknown exception (-" + shown + ")");
  }
  if (options.progress) options.progress("tetrahedralize", 1.0);

  if (out.numberoftetrahedra <= 0 || out.numberofcorners != 4 || out.numberofpoints <= 0) {
    return badInput(source + ": error: TetGen produced " + std::to_string(out.numberoftetrahedra) +
                    " tetrahedra from a closed surface of " + std::to_string(surface.F.rows()) + " triangles (-" +
                    shown + ")");
  }
  TetMesh mesh = meshFromTetgen(out);
  std::vector<MeshWarning> ignored;
  if (Status s = validateAndRepair(mesh, source, &ignored); !s) return s.error();
  if (options.order == 2) mesh = promoteToTet10(mesh);
  return mesh;
}

}  // namespace strike
