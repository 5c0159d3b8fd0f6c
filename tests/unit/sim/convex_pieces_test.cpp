// SPDX-License-Identifier: MIT
// The convex decomposition of concave collision shapes (src/sim/convex_pieces.cpp), on an
// open-top tray whose material volume and hollow are known in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "convex_pieces.hpp"

namespace strike {
namespace {

struct Surface {
  std::vector<double> xyz;
  std::vector<uint32_t> triangles;
};

/// An open-top tray: outer a x a x h, walls and floor t thick; closed, CCW from outside.
Surface tray(double a, double h, double t) {
  Surface s;
  const double o = a / 2, b = a / 2 - t;
  const double pts[16][3] = {{-o, -o, 0}, {o, -o, 0}, {o, o, 0},   {-o, o, 0}, {-o, -o, h}, {o, -o, h},
                             {o, o, h},   {-o, o, h}, {-b, -b, h}, {b, -b, h}, {b, b, h},   {-b, b, h},
                             {-b, -b, t}, {b, -b, t}, {b, b, t},   {-b, b, t}};
  for (const auto& p : pts) s.xyz.insert(s.xyz.end(), {p[0], p[1], p[2]});
  const uint32_t quads[14][4] = {{0, 3, 2, 1},    {0, 1, 5, 4},     {1, 2, 6, 5},    {2, 3, 7, 6},    {3, 0, 4, 7},
                                 {4, 5, 9, 8},    {5, 6, 10, 9},    {6, 7, 11, 10},  {7, 4, 8, 11},   {12, 8, 9, 13},
                                 {13, 9, 10, 14}, {14, 10, 11, 15}, {15, 11, 8, 12}, {12, 13, 14, 15}};
  for (const auto& q : quads) s.triangles.insert(s.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  return s;
}

// The tray's material is a^2 h - (a - 2t)^2 (h - t); its hull, a^2 h, is 3x that and its hollow
// 2.1x. Pieces that cover the surface must hold the material (their volumes add to at least it)
// and leave the hollow empty: they overlap along the cuts (a triangle straddling a cut goes
// whole to one side, and edges are refined to 2.5 cm) and stand up to the tolerance proud of
// the inner surface, but together fill less than a quarter of the hollow (a tray taken whole,
// or cut only in slices, fills all of it).
TEST(ConvexPieces, TrayPiecesHoldTheMaterialAndLeaveTheHollow) {
  const double a = 0.2, h = 0.06, t = 0.01;
  const Surface s = tray(a, h, t);
  ConvexPiecesSettings settings;
  settings.max_concavity_m = 0.002;
  settings.max_edge_m = 0.025;
  const ConvexPieces pieces = convexPieces(s.xyz, s.triangles, settings);
  const double material = a * a * h - (a - 2 * t) * (a - 2 * t) * (h - t);
  const double hollow = (a - 2 * t) * (a - 2 * t) * (h - t);
  double sum = 0.0;
  for (double v : pieces.hull_volume_m3) sum += v;
  std::printf("[ pieces   ] %zu pieces, volume %.4g m^3 (material %.4g, hull %.4g), worst concavity %.3g m\n",
              pieces.hull_points.size(), sum, material, a * a * h, pieces.worst_concavity_m);
  EXPECT_GE(pieces.hull_points.size(), 5u);  // a floor and four walls at least
  EXPECT_LE(pieces.hull_points.size(), size_t(settings.max_pieces));
  EXPECT_LE(pieces.worst_concavity_m, settings.max_concavity_m);
  EXPECT_GE(sum, material * (1 - 1e-9));
  EXPECT_LE(sum, material + 0.25 * hollow);
  // Every surface vertex lies in or on some piece's box (a cheap necessary test of coverage).
  for (size_t v = 0; v < s.xyz.size() / 3; ++v) {
    bool inside = false;
    for (const std::vector<double>& points : pieces.hull_points) {
      bool in_box = true;
      for (int k = 0; k < 3; ++k) {
        double lo = INFINITY, hi = -INFINITY;
        for (size_t p = size_t(k); p < points.size(); p += 3) {
          lo = std::min(lo, points[p]);
          hi = std::max(hi, points[p]);
        }
        in_box = in_box && s.xyz[3 * v + size_t(k)] >= lo - 1e-12 && s.xyz[3 * v + size_t(k)] <= hi + 1e-12;
      }
      inside = inside || in_box;
    }
    EXPECT_TRUE(inside) << "vertex " << v;
  }
}

TEST(ConvexPieces, SameInputSamePieces) {
  const Surface s = tray(0.2, 0.06, 0.01);
  ConvexPiecesSettings settings;
  settings.max_concavity_m = 0.002;
  settings.max_edge_m = 0.025;
  EXPECT_EQ(convexPieces(s.xyz, s.triangles, settings).hull_points,
            convexPieces(s.xyz, s.triangles, settings).hull_points);
}

// A convex body is one piece: nothing to cut.
TEST(ConvexPieces, ABoxIsOnePiece) {
  Surface s = tray(0.2, 0.06, 0.01);
  s.xyz.resize(24);  // the tray's outer corners: a closed box
  s.triangles.clear();
  const uint32_t quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  for (const auto& q : quads) s.triangles.insert(s.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  ConvexPiecesSettings settings;
  settings.max_concavity_m = 1e-6;
  const ConvexPieces pieces = convexPieces(s.xyz, s.triangles, settings);
  ASSERT_EQ(pieces.hull_points.size(), 1u);
  EXPECT_NEAR(pieces.hull_volume_m3[0], 0.2 * 0.2 * 0.06, 1e-12);
  EXPECT_LE(pieces.worst_concavity_m, 1e-9);
}

}  // namespace
}  // namespace strike
