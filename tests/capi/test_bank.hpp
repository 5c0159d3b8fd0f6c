// SPDX-License-Identifier: MIT
// A hand-made mode bank for the C API tests, benchmarks and examples: a 0.2 m square steel plate
// as a 3x3 vertex grid (8 triangles) with modes at known frequencies and simple shapes that are
// non-zero at every vertex (the centre vertex 4 excites all of them).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "strike/bank/bank.hpp"

namespace strike::test {

inline const std::vector<double>& testBankFrequencies() {
  static const std::vector<double> f = {440.0, 1000.0, 2500.0, 5200.0};
  return f;
}

/// freqs_hz ascending; shapes: mode m at vertex v has z = 1 + 0.25 m (v % 3) / 2 (1/sqrt(kg)).
inline ModeBank makeTestBank(const std::vector<double>& freqs_hz = testBankFrequencies()) {
  ModeBank b;
  b.material.name = "steel";
  b.material.youngs_pa = 2.0e11;
  b.material.poisson = 0.3;
  b.material.density_kg_m3 = 7850.0;
  b.material.rayleigh_stiffness = 1e-9;  // s
  b.material.rayleigh_mass = 4.0;        // 1/s
  b.mesh_source = "test:plate3x3";
  b.mass_kg = 1.0;
  b.volume_m3 = 1.0 / 7850.0;
  b.tool_version = "strike capi test";
  for (double f : freqs_hz) b.eigenvalues.push_back(std::pow(2.0 * M_PI * f, 2));
  const double h = 0.1;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      b.surface_positions.insert(b.surface_positions.end(), {(i - 1) * h, (j - 1) * h, 0.0});
      b.surface_normals.insert(b.surface_normals.end(), {0.0f, 0.0f, 1.0f});
      b.surface_node_index.push_back(static_cast<uint32_t>(3 * j + i));
    }
  for (uint32_t j = 0; j < 2; ++j)
    for (uint32_t i = 0; i < 2; ++i) {
      const uint32_t a = 3 * j + i, bb = a + 1, c = a + 3, d = a + 4;
      b.surface_triangles.insert(b.surface_triangles.end(), {a, bb, d, a, d, c});
    }
  for (size_t m = 0; m < freqs_hz.size(); ++m)
    for (size_t v = 0; v < 9; ++v)
      b.shapes.insert(b.shapes.end(), {0.0f, 0.0f, static_cast<float>(1.0 + 0.25 * m * (v % 3) / 2.0)});
  return b;
}

}  // namespace strike::test
