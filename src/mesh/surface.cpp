// SPDX-License-Identifier: MIT
// Boundary extraction: a face of a conforming tet mesh is on the boundary exactly when one tet
// uses it. Faces are matched by their sorted corner triple; sorting the 4T keys (instead of a
// hash map) keeps memory flat and the output deterministic.
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "strike/mesh/mesh.hpp"

namespace strike {

namespace {

// Faces of a positively oriented tet (0,1,2,3), each listed counter-clockwise seen from
// outside: the face opposite corner k has its normal pointing away from corner k.
constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct FaceKey {
  std::array<int, 3> sorted;
  int64_t id;  // 4 * tet + local face, for the oriented triple and a stable order
};

}  // namespace

Eigen::MatrixXi extractSurface(const Eigen::MatrixXi& tets) {
  const int64_t num_tets = tets.rows();
  if (num_tets == 0 || tets.cols() < 4) return Eigen::MatrixXi(0, 3);
  std::vector<FaceKey> faces;
  faces.reserve(static_cast<size_t>(4 * num_tets));
  for (int64_t t = 0; t < num_tets; ++t) {
    for (int f = 0; f < 4; ++f) {
      std::array<int, 3> key = {tets(t, kTetFaces[f][0]), tets(t, kTetFaces[f][1]), tets(t, kTetFaces[f][2])};
      std::sort(key.begin(), key.end());
      faces.push_back({key, 4 * t + f});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const FaceKey& a, const FaceKey& b) {
    return a.sorted != b.sorted ? a.sorted < b.sorted : a.id < b.id;
  });
  std::vector<int64_t> boundary;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].sorted == faces[i].sorted) ++j;
    if (j - i == 1) boundary.push_back(faces[i].id);
    i = j;
  }
  // Output in tet order so that the surface follows the mesh numbering.
  std::sort(boundary.begin(), boundary.end());
  Eigen::MatrixXi surface(static_cast<Eigen::Index>(boundary.size()), 3);
  for (size_t i = 0; i < boundary.size(); ++i) {
    const int64_t t = boundary[i] / 4;
    const int f = static_cast<int>(boundary[i] % 4);
    for (int c = 0; c < 3; ++c) surface(static_cast<Eigen::Index>(i), c) = tets(t, kTetFaces[f][c]);
  }
  return surface;
}

}  // namespace strike
