// SPDX-License-Identifier: MIT
// Private to strike_precompute: sizing meshes for the error estimate (error_estimate.cpp) and the
// tolerance search (tolerance_search.cpp), both of which remesh the same shape finer or coarser.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "strike/mesh/mesh.hpp"
#include "strike/core/result.hpp"

namespace strike::detail {

inline double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Edge of a regular tet with the mesh's mean tet volume (V_regular = a^3 / (6 sqrt 2)).
double meanEdge(const TetMesh& mesh);

struct SizedMesh {
  LoadedMesh loaded;
  double target_edge_m = 0.0;
};

/// A mesh of `spec` with between `lo` and `hi` times `base_tets` tets, as near `want` times as
/// the search finds (mesh_sizing.cpp).
Result<SizedMesh> meshWithTetRatio(const std::string& spec, double scale, int order, int64_t max_tets, double base_tets,
                                   double start_edge, double lo, double hi, double want);

}  // namespace strike::detail
