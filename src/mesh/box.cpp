// SPDX-License-Identifier: MIT
// The box primitive: a structured grid of hexahedral cells, each split into 6 tets around its
// main diagonal (Kuhn / Freudenthal triangulation). Every cell is split the same way, so the
// split is conforming across cells without any parity bookkeeping (Freudenthal 1942; Kuhn 1960).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "strike/mesh/mesh.hpp"

namespace strike {

namespace {

// Why 4 cells across the thinnest side: Tet10 on a bar like box:0.3,0.02,0.02 then gets its
// first bending modes within ~0.5% of Timoshenko theory (see tests/unit/fem), and the default
// stays cheap. The cap keeps a default mesh of a chunky box at ~50k tets.
constexpr double kDefaultCellsAcrossThinnest = 4.0;
constexpr double kDefaultMaxCells = 8000.0;
constexpr int64_t kMaxNodes = 50'000'000;  // beyond this the FEM would not fit in memory anyway

std::string formatSize(const char* name, double value) {
  std::ostringstream s;
  s << "box: " << name << " must be a positive finite length in metres, got " << value;
  return s.str();
}

}  // namespace

Result<TetMesh> makeBox(double lx, double ly, double lz, const MeshOptions& options) {
  const double sizes_m[3] = {lx, ly, lz};
  const char* names[3] = {"LX", "LY", "LZ"};
  for (int a = 0; a < 3; ++a) {
    if (!(sizes_m[a] > 0.0) || !std::isfinite(sizes_m[a])) return badInput(formatSize(names[a], sizes_m[a]));
  }
  if (options.order != 1 && options.order != 2) {
    return badInput("box: element order must be 1 or 2, got " + std::to_string(options.order));
  }
  if (!(options.target_edge_m >= 0.0) || !std::isfinite(options.target_edge_m)) {
    std::ostringstream s;
    s << "box: target edge length must be >= 0 metres, got " << options.target_edge_m;
    return badInput(s.str());
  }

  double edge_m = options.target_edge_m;
  if (edge_m == 0.0) {
    edge_m = std::min({lx, ly, lz}) / kDefaultCellsAcrossThinnest;
    const double cells = (lx / edge_m) * (ly / edge_m) * (lz / edge_m);
    if (cells > kDefaultMaxCells) edge_m *= std::cbrt(cells / kDefaultMaxCells);
  }
  int64_t n[3];
  for (int a = 0; a < 3; ++a) {
    const double cells = std::round(sizes_m[a] / edge_m);
    if (!(cells < 1e6)) return badInput(formatSize("target edge length (too many cells)", edge_m));
    n[a] = std::max<int64_t>(1, static_cast<int64_t>(cells));
  }
  const int64_t num_nodes = (n[0] + 1) * (n[1] + 1) * (n[2] + 1);
  if (num_nodes > kMaxNodes) {
    std::ostringstream s;
    s << "box: target edge " << edge_m << " m gives " << num_nodes << " nodes, more than the limit " << kMaxNodes;
    return badInput(s.str());
  }
  const int64_t num_tets = 6 * n[0] * n[1] * n[2];
  if (num_tets > options.max_tets) {
    std::ostringstream s;
    s << "box: target edge " << edge_m << " m gives " << num_tets << " tets, more than the cap of " << options.max_tets
      << " (--max-tets); use a larger --size, or raise the cap with --max-tets N";
    return badInput(s.str());
  }

  TetMesh mesh;
  mesh.order = 1;
  mesh.nodes.resize(num_nodes, 3);
  auto node_id = [&](int64_t i, int64_t j, int64_t k) {
    return static_cast<int>(i + (n[0] + 1) * (j + (n[1] + 1) * k));
  };
  for (int64_t k = 0; k <= n[2]; ++k) {
    for (int64_t j = 0; j <= n[1]; ++j) {
      for (int64_t i = 0; i <= n[0]; ++i) {
        // Exact end points: the box spans [-L/2, L/2] on every axis.
        mesh.nodes.row(node_id(i, j, k)) << lx * (static_cast<double>(i) / n[0] - 0.5),
            ly * (static_cast<double>(j) / n[1] - 0.5), lz * (static_cast<double>(k) / n[2] - 0.5);
      }
    }
  }

  // Kuhn split: for each permutation (p0, p1, p2) of the axes, the tet
  // c, c + e_p0, c + e_p0 + e_p1, c + (1,1,1). Even permutations are positively oriented; odd
  // ones get corners 1 and 2 swapped.
  constexpr int kPerms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  const int64_t num_cells = n[0] * n[1] * n[2];
  mesh.tets.resize(6 * num_cells, 4);
  int64_t t = 0;
  for (int64_t k = 0; k < n[2]; ++k) {
    for (int64_t j = 0; j < n[1]; ++j) {
      for (int64_t i = 0; i < n[0]; ++i) {
        for (int p = 0; p < 6; ++p) {
          int64_t c[3] = {i, j, k};
          int corners[4];
          corners[0] = node_id(c[0], c[1], c[2]);
          ++c[kPerms[p][0]];
          corners[1] = node_id(c[0], c[1], c[2]);
          ++c[kPerms[p][1]];
          corners[2] = node_id(c[0], c[1], c[2]);
          corners[3] = node_id(i + 1, j + 1, k + 1);
          if (p >= 3) std::swap(corners[1], corners[2]);
          mesh.tets.row(t++) << corners[0], corners[1], corners[2], corners[3];
        }
      }
    }
  }
  mesh.surface = extractSurface(mesh.tets);
  if (options.order == 2) return promoteToTet10(mesh);
  return mesh;
}

}  // namespace strike
