// SPDX-License-Identifier: MIT
// The boundary data per node, and the pieces of a solve: the nodes (or triangles) that one
// point with its moments can stand for at a wavenumber, laid out as arrays.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "clusters.hpp"
#include "surface.hpp"

namespace strike::transfer {

/// Per-node integrals of the boundary data q = dp/dn (real: the shapes are real): Q = int q dS
/// and the first moment D = int (y - centroid) q dS.
struct NodeData {
  std::vector<double> q;  // per triangle
  std::vector<double> Q;  // per node
  std::vector<V3> D;      // per node
};

void nodeData(const Surface& s, NodeData& data);

/// The pieces of a solve at wavenumber k: the largest nodes inside one cluster that one point
/// with its moments can stand for (k D <= kPointPhase), or single triangles too large for that.
/// They are the same for every collocation point, so each row is one flat loop over them
/// (structure of arrays), and the far field is summed over them too.
struct Pieces {
  std::vector<int32_t> node, col;
  std::vector<char> one_point;                              // k D <= kPointPhase: one point with its moments will do
  std::vector<int8_t> quarter;                              // 1-4: a quarter of the leaf triangle (0: the whole node)
  std::vector<int64_t> leaf_tri;                            // the triangle of a leaf node (-1: a larger node)
  std::vector<double> clear_of_near;                        // a larger node: beyond this none of its triangles is near
  std::vector<double> x, y, z;                              // centroid
  std::vector<double> ax, ay, az;                           // vector area
  std::vector<double> cxx, cxy, cxz, cyy, cyz, czz, trace;  // covariance of the piece's points
  std::vector<double> diameter;
  size_t size() const { return node.size(); }
};

Pieces makePieces(const Surface& s, const Cut& cut, double k);

/// The triangles too large in wavelengths for one point or for their quarters as points
/// (k D > 2 kPointPhase: the plate's 2 cm triangles at its top modes), which integrateTriangle
/// integrates row by row. From an x beyond kFarRatio of its diameters it gives such a triangle
/// the product rule of its k D (ruleFor): those points do not depend on x, so they are laid out
/// here once per solve, and a row evaluates their kernels in vectorized passes with
/// integrateTriangle's own arithmetic, in its order (the same bits). A triangle nearer x (or
/// too large for every product rule) goes through integrateTriangle.
struct BigTriangles {
  std::vector<int32_t> of_piece;          // per piece: its index here, or -1
  std::vector<uint32_t> tri;              // per big triangle
  std::vector<V3> centroid;               // (a + b + c) / 3, as integrateTriangle computes it
  std::vector<double> edge;               // longest edge (ruleFor's d)
  std::vector<const double (*)[4]> rule;  // its rule from far (null: none, split)
  std::vector<size_t> first;              // its points: [first[b], first[b + 1])
  std::vector<V3> point;                  // in integrateTriangle's order
  std::vector<double> weight;
  size_t size() const { return tri.size(); }
};

BigTriangles bigTriangles(const Surface& s, const Pieces& p, double k);

/// The boundary data of several modes at one wavenumber, per piece: Q = int q dS and the first
/// moment D = int (y - centroid) q dS (index rhs * pieces + piece).
struct PieceData {
  std::vector<double> Q, Dx, Dy, Dz;
};

PieceData pieceData(const Surface& s, const Pieces& p, const std::vector<NodeData>& data);

}  // namespace strike::transfer
