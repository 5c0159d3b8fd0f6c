// SPDX-License-Identifier: MIT
// The acoustic transfer's memory forecast and its budget check (precompute.hpp). The figure is
// the transfer solver's: whoever changes what the solver holds changes it here in the same commit.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "../transfer/quadrature.hpp"
#include "strike/modal/modal.hpp"
#include "strike/precompute/precompute.hpp"

namespace strike {

namespace {

/// The points of a rule for a piece of k e from two to three edges away (transfer::ruleFor): 7
/// up to k e = 2.5, then the product rule's n^2, split in four while k e is above them all.
double rulePoints(double ke) {
  double pieces = 1.0;
  while (ke > 2.5 && transfer::productOrder(ke, false) == 0) {
    pieces *= 4.0;
    ke *= 0.5;
  }
  const int n = ke > 2.5 ? transfer::productOrder(ke, false) : 0;
  return pieces * (n > 0 ? n * n : 7.0);
}

/// A near triangle's points: its rule up to k e = 2.5; above, its rule for the half of them two
/// to three edges away and its quarters' for the half nearer (areas 5 : 4 on a flat surface).
double nearPointsOf(double ke) { return ke <= 2.5 ? 7.0 : 0.5 * rulePoints(ke) + 0.5 * 4.0 * rulePoints(0.5 * ke); }

}  // namespace

double transferMemoryForecastBytes(const ModeBank& bank, const TransferSettings& settings) {
  // What the solver holds at its peak (the largest group's solves; TransferModeStats counts
  // both for a test): its system (transferSystemBytes: dense, or the hierarchical matrix above
  // direct_max_elements) and the near quadrature caches, which are most of it on coarse
  // surfaces at high ka; beside them the surface's quadrature data (~1 KB a triangle) and each
  // mode's far field (a few KB).
  const double elements =
      std::min<double>(settings.fixed_elements > 0 ? settings.fixed_elements : settings.max_elements,
                       static_cast<double>(bank.surface_triangles.size() / 3));
  const double system =
      transferSystemBytes(static_cast<uint64_t>(elements), settings.direct_max_elements, settings.hierarchical);
  // The near caches (near_quadrature.hpp) at the top heard wavenumber (modes up to 20 kHz have a
  // transfer): per collocation point, the triangles t within kFarRatio (3) of their longest edge
  // e_t, about (pi (3 e_t)^2 / area) of each on a surface seen as flat, each given its rule
  // (nearPointsOf: 7 points, or the product rule of its k e; its quarters' nearer than two
  // edges); twice that for the levels rounded up and the
  // pieces nearer still; 36 bytes a point, twice for the vectors' growth; the caches of a
  // group's refinement steps (x 2.5 unknowns each) held together: 1 + 0.4 + 0.16.
  const double top_hz = bank.max_freq_hz > 0 ? std::min(bank.max_freq_hz, 20000.0) : 20000.0;
  const double k = 2.0 * M_PI * top_hz / settings.speed_of_sound_m_s;
  double area = 0.0, points_per_row = 0.0;
  const size_t triangles = bank.surface_triangles.size() / 3;
  std::vector<double> edge2(triangles, 0.0);
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t* v = &bank.surface_triangles[3 * t];
    double p[3][3];
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) p[c][d] = bank.surface_positions[3 * v[c] + d];
    double longest2 = 0.0, e[2][3];
    for (int c = 0; c < 3; ++c) {
      double l2 = 0.0;
      for (int d = 0; d < 3; ++d) {
        const double diff = p[(c + 1) % 3][d] - p[c][d];
        l2 += diff * diff;
        if (c < 2) e[c][d] = diff;
      }
      longest2 = std::max(longest2, l2);
    }
    const double cx = e[0][1] * e[1][2] - e[0][2] * e[1][1], cy = e[0][2] * e[1][0] - e[0][0] * e[1][2],
                 cz = e[0][0] * e[1][1] - e[0][1] * e[1][0];
    area += 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
    edge2[t] = longest2;
  }
  if (area > 0)
    for (double e2 : edge2) {
      const double ke = k * std::sqrt(e2);
      points_per_row += std::min(1.0, M_PI * 9.0 * e2 / area) * 2.0 * nearPointsOf(ke);
    }
  const double rows = 1.1 * elements;
  const double near = rows * points_per_row * 36.0 * 2.0 * 1.56;
  const double surface = 1024.0 * static_cast<double>(triangles);
  const double far_fields = 8192.0 * static_cast<double>(bank.modeCount());
  return system + near + surface + far_fields;
}

Status checkTransferMemory(const ModeBank& bank, const TransferSettings& settings, double max_bytes) {
  const double forecast = transferMemoryForecastBytes(bank, settings);
  if (!(max_bytes > 0.0) || forecast <= max_bytes) return {};
  return badInput("the acoustic transfer of " + std::to_string(bank.modeCount()) + " modes would need about " +
                  memoryText(forecast) + ": more than the memory budget of " + memoryText(max_bytes) +
                  ". Raise --max-memory (default: the memory available), or skip the transfer (--no-transfer)");
}

}  // namespace strike
