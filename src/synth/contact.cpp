// SPDX-License-Identifier: MIT
// Contact: where an impulse lands on the surface (modal projection, O'Brien et al. 2002;
// van den Doel & Pai 1998) and how long it lasts (Hertz theory, Johnson 1985).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "strike/synth/synth.hpp"

namespace strike {
namespace {

struct Barycentric {
  double w[3];
  double dist2;
};

// Closest point of triangle (a, b, c) to p, as barycentric weights (Ericson, Real-Time Collision
// Detection, 2005, 5.1.5): every Voronoi region of the triangle handled, so degenerate (zero-area)
// triangles give a point on an edge instead of NaN.
Barycentric closestOnTriangle(const double* p, const double* a, const double* b, const double* c) {
  auto sub = [](const double* u, const double* v, double* out) {
    for (int i = 0; i < 3; ++i) out[i] = u[i] - v[i];
  };
  auto dot = [](const double* u, const double* v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  sub(b, a, ab);
  sub(c, a, ac);
  sub(p, a, ap);
  Barycentric r{{1.0, 0.0, 0.0}, 0.0};
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    r.w[0] = 1, r.w[1] = 0, r.w[2] = 0;
  } else {
    sub(p, b, bp);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    sub(p, c, cp);
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d3 >= 0.0 && d4 <= d3) {
      r.w[0] = 0, r.w[1] = 1, r.w[2] = 0;
    } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
      const double v = d1 / (d1 - d3);
      r.w[0] = 1 - v, r.w[1] = v, r.w[2] = 0;
    } else if (d6 >= 0.0 && d5 <= d6) {
      r.w[0] = 0, r.w[1] = 0, r.w[2] = 1;
    } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
      const double w = d2 / (d2 - d6);
      r.w[0] = 1 - w, r.w[1] = 0, r.w[2] = w;
    } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
      const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
      r.w[0] = 0, r.w[1] = 1 - w, r.w[2] = w;
    } else {
      const double denom = 1.0 / (va + vb + vc);
      const double v = vb * denom, w = vc * denom;
      r.w[0] = 1 - v - w, r.w[1] = v, r.w[2] = w;
    }
  }
  double d2sum = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double q = r.w[0] * a[i] + r.w[1] * b[i] + r.w[2] * c[i];
    d2sum += (q - p[i]) * (q - p[i]);
  }
  r.dist2 = d2sum;
  return r;
}

}  // namespace

void projectImpulseAtVertexInto(const ModeBank& bank, size_t vertex, const double impulse[3], double* out) {
  const size_t nm = bank.modeCount();
  std::fill(out, out + nm, 0.0);
  if (vertex >= bank.surfaceVertexCount() || bank.shapes.size() < nm * bank.surfaceVertexCount() * 3) return;
  for (size_t m = 0; m < nm; ++m) {
    const float* phi = bank.shapeAt(m, vertex);
    out[m] = phi[0] * impulse[0] + phi[1] * impulse[1] + phi[2] * impulse[2];
  }
}

void projectImpulseInto(const ModeBank& bank, const double point[3], const double impulse[3], double* out) {
  const size_t nv = bank.surfaceVertexCount();
  const size_t nm = bank.modeCount();
  std::fill(out, out + nm, 0.0);
  if (nv == 0 || bank.shapes.size() < nm * nv * 3) return;
  // Brute force over triangles: a strike is projected once per contact event, and banks have a
  // few thousand surface triangles at most.
  const double* pos = bank.surface_positions.data();
  double best = std::numeric_limits<double>::infinity();
  uint32_t best_v[3] = {0, 0, 0};
  double best_w[3] = {1.0, 0.0, 0.0};
  for (size_t t = 0; t + 2 < bank.surface_triangles.size(); t += 3) {
    const uint32_t* tri = &bank.surface_triangles[t];
    if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) continue;
    const Barycentric b = closestOnTriangle(point, pos + 3 * tri[0], pos + 3 * tri[1], pos + 3 * tri[2]);
    if (b.dist2 < best) {
      best = b.dist2;
      for (int i = 0; i < 3; ++i) best_v[i] = tri[i], best_w[i] = b.w[i];
    }
  }
  if (!(best < std::numeric_limits<double>::infinity())) {
    // No triangles: nearest vertex.
    for (size_t v = 0; v < nv; ++v) {
      double d2 = 0.0;
      for (int i = 0; i < 3; ++i) d2 += (pos[3 * v + i] - point[i]) * (pos[3 * v + i] - point[i]);
      if (d2 < best) best = d2, best_v[0] = static_cast<uint32_t>(v);
    }
    projectImpulseAtVertexInto(bank, best_v[0], impulse, out);
    return;
  }
  for (size_t m = 0; m < nm; ++m) {
    double s = 0.0;
    for (int k = 0; k < 3; ++k) {
      const float* phi = bank.shapeAt(m, best_v[k]);
      s += best_w[k] * (phi[0] * impulse[0] + phi[1] * impulse[1] + phi[2] * impulse[2]);
    }
    out[m] = s;
  }
}

SurfaceLocator::SurfaceLocator(const ModeBank& bank) : bank_(&bank) {
  const size_t nv = bank.surfaceVertexCount();
  const size_t nt = bank.surface_triangles.size() / 3;
  const double* pos = bank.surface_positions.data();
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], pos[3 * v + k]), hi[k] = std::max(hi[k], pos[3 * v + k]);
  if (nt == 0 || !(hi[0] >= lo[0])) {
    cell_start_.assign(2, 0);
    return;
  }
  // About one triangle per cell on a surface: cell ~ sqrt(area / triangles), from the box.
  const double ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  const double area = 2.0 * (ext[0] * ext[1] + ext[1] * ext[2] + ext[0] * ext[2]);
  cell_m_ = std::max(std::sqrt(area / static_cast<double>(nt)), 1e-9 * std::max({ext[0], ext[1], ext[2], 1e-12}));
  for (int k = 0; k < 3; ++k) {
    origin_[k] = lo[k];
    dims_[k] = std::clamp(static_cast<int>(ext[k] / cell_m_) + 1, 1, 256);
  }
  const size_t cells = static_cast<size_t>(dims_[0]) * dims_[1] * dims_[2];
  // Each vertex's cell, once: a triangle's range of cells is then the least and the greatest of
  // its corners' cells, the same cells as from its bounding box ((x - origin) / cell, the
  // truncation and the clamp are all non-decreasing in x), for a third of the divisions.
  std::vector<std::array<uint8_t, 3>> vertex_cell(nv);
  for (size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k)
      vertex_cell[v][k] =
          static_cast<uint8_t>(std::clamp(static_cast<int>((pos[3 * v + k] - origin_[k]) / cell_m_), 0, dims_[k] - 1));
  auto cellRange = [&](const uint32_t* tri, int from[3], int to[3]) {
    for (int k = 0; k < 3; ++k) {
      const int a = vertex_cell[tri[0]][k], b = vertex_cell[tri[1]][k], c = vertex_cell[tri[2]][k];
      from[k] = std::min({a, b, c});
      to[k] = std::max({a, b, c});
    }
  };
  // Count, then fill (CSR). Each triangle's range of cells (dims_ <= 256: a byte an axis) is
  // computed once, in the count, and kept for the fill.
  cell_start_.assign(cells + 1, 0);
  std::vector<std::array<uint8_t, 6>> ranges(nt);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &bank.surface_triangles[3 * t];
    if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) {
      ranges[t] = {1, 1, 1, 0, 0, 0};  // an empty range: from > to
      continue;
    }
    int from[3], to[3];
    cellRange(tri, from, to);
    for (int k = 0; k < 3; ++k) ranges[t][k] = static_cast<uint8_t>(from[k]), ranges[t][3 + k] = static_cast<uint8_t>(to[k]);
    for (int x = from[0]; x <= to[0]; ++x)
      for (int y = from[1]; y <= to[1]; ++y)
        for (int z = from[2]; z <= to[2]; ++z) ++cell_start_[(static_cast<size_t>(x) * dims_[1] + y) * dims_[2] + z + 1];
  }
  for (size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  std::vector<uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  cell_tris_.resize(cell_start_[cells]);
  for (size_t t = 0; t < nt; ++t) {
    const std::array<uint8_t, 6>& r = ranges[t];
    for (int x = r[0]; x <= r[3]; ++x)
      for (int y = r[1]; y <= r[4]; ++y)
        for (int z = r[2]; z <= r[5]; ++z)
          cell_tris_[fill[(static_cast<size_t>(x) * dims_[1] + y) * dims_[2] + z]++] = static_cast<uint32_t>(t);
  }
}

void SurfaceLocator::nearest(const double point[3], uint32_t vertices[3], double weights[3]) const {
  const ModeBank& bank = *bank_;
  const double* pos = bank.surface_positions.data();
  vertices[0] = vertices[1] = vertices[2] = 0;
  weights[0] = 1.0, weights[1] = weights[2] = 0.0;
  if (cell_tris_.empty()) return;
  int home[3];
  for (int k = 0; k < 3; ++k)
    home[k] = std::clamp(static_cast<int>(std::floor((point[k] - origin_[k]) / cell_m_)), 0, dims_[k] - 1);
  // Distance from the point to the grid box (when it lies outside), so ring r is at least
  // (r - 1) cells + that far away.
  double outside2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double below = origin_[k] - point[k], above = point[k] - (origin_[k] + dims_[k] * cell_m_);
    const double d = std::max({below, above, 0.0});
    outside2 += d * d;
  }
  // How far the point lies inside its home cell from the cell's nearest face, m (0 when the
  // point is outside the grid and home was clamped). A triangle not listed in any cell within
  // Chebyshev distance r - 1 of home lies wholly beyond one face of that block of cells (its
  // cells come from its bounding box), so it is at least inside_m + (r - 1) cells away: ring 1 is
  // skipped whenever the nearest triangle of the home cell is closer than the cell's faces, which
  // for a contact point on the surface is almost always (the ring-1 scan of 26 cells was ~90% of
  // a render's projection time). The margin covers the rounding of the cells' bounds; a skipped
  // triangle is strictly farther than the best one, so the answer is the same to the bit.
  double inside_m = INFINITY;
  for (int k = 0; k < 3; ++k) {
    const double low = origin_[k] + home[k] * cell_m_;
    inside_m = std::min({inside_m, point[k] - low, low + cell_m_ - point[k]});
  }
  inside_m = std::max(0.0, inside_m - 1e-9 * cell_m_);
  double best = INFINITY;
  const int max_ring = std::max({dims_[0], dims_[1], dims_[2]});
  for (int r = 0; r <= max_ring; ++r) {
    // Cells in ring r (Chebyshev distance r from home) are at least (r - 1) cells away.
    const double reach = std::max(0, r - 1) * cell_m_;
    const double block_m = r > 0 ? inside_m + reach : 0.0;
    if (best < INFINITY && std::max(reach * reach + outside2, block_m * block_m) > best) break;
    for (int x = home[0] - r; x <= home[0] + r; ++x) {
      if (x < 0 || x >= dims_[0]) continue;
      for (int y = home[1] - r; y <= home[1] + r; ++y) {
        if (y < 0 || y >= dims_[1]) continue;
        for (int z = home[2] - r; z <= home[2] + r; ++z) {
          if (z < 0 || z >= dims_[2]) continue;
          if (std::max({std::abs(x - home[0]), std::abs(y - home[1]), std::abs(z - home[2])}) != r) continue;
          const size_t c = (static_cast<size_t>(x) * dims_[1] + y) * dims_[2] + z;
          for (uint32_t i = cell_start_[c]; i < cell_start_[c + 1]; ++i) {
            const uint32_t* tri = &bank.surface_triangles[3 * cell_tris_[i]];
            const Barycentric b = closestOnTriangle(point, pos + 3 * tri[0], pos + 3 * tri[1], pos + 3 * tri[2]);
            if (b.dist2 < best) {
              best = b.dist2;
              for (int k = 0; k < 3; ++k) vertices[k] = tri[k], weights[k] = b.w[k];
            }
          }
        }
      }
    }
  }
}

void SurfaceLocator::projectImpulseInto(const double point[3], const double impulse[3], double* out) const {
  const ModeBank& bank = *bank_;
  const size_t nm = bank.modeCount();
  if (cell_tris_.empty() || bank.shapes.size() < nm * bank.surfaceVertexCount() * 3) {
    strike::projectImpulseInto(bank, point, impulse, out);
    return;
  }
  uint32_t v[3];
  double w[3];
  nearest(point, v, w);
  for (size_t m = 0; m < nm; ++m) {
    double s = 0.0;
    for (int k = 0; k < 3; ++k) {
      const float* phi = bank.shapeAt(m, v[k]);
      s += w[k] * (phi[0] * impulse[0] + phi[1] * impulse[1] + phi[2] * impulse[2]);
    }
    out[m] = s;
  }
}

ContactProjector::ContactProjector(const ModeBank& bank, size_t max_points)
    : ContactProjector(bank, nullptr, max_points) {}

ContactProjector::ContactProjector(const ModeBank& bank, std::shared_ptr<const SurfaceLocator> locator,
                                   size_t max_points)
    : locator_(locator && locator->builtFor(bank) ? std::move(locator) : std::make_shared<const SurfaceLocator>(bank)),
      bank_(&bank),
      max_points_(std::max<size_t>(max_points, 1)) {
  // All the memory it will use, now: projecting never allocates (libstrike's audio thread).
  points_.reserve(3 * max_points_);
  weights_.reserve(3 * max_points_);
  shapes_.reserve(bank.modeCount() * 9 * max_points_);
}

void ContactProjector::useRows(ShapeRows rows) {
  rows_ = std::move(rows);
  use_rows_ = true;
}

void ContactProjector::projectImpulseInto(const double point[3], const double impulse[3], double* out) {
  const ModeBank& bank = *bank_;
  const size_t nm = bank.modeCount();
  if (nm == 0) return;  // a bank with no mode in the band (a marble): nothing to find the point for
  const bool has_shapes = use_rows_ ? rows_.modes == nm : bank.shapes.size() >= nm * bank.surfaceVertexCount() * 3;
  if (!has_shapes || !locator_->hasTriangles()) {
    locator_->projectImpulseInto(point, impulse, out);  // degenerate banks: the plain path handles them
    return;
  }
  const size_t remembered = points_.size() / 3;
  size_t slot = remembered;
  for (size_t p = 0; p < remembered; ++p)
    if (points_[3 * p] == point[0] && points_[3 * p + 1] == point[1] && points_[3 * p + 2] == point[2]) {
      slot = p;
      break;
    }
  if (slot == remembered) {
    uint32_t v[3];
    double w[3];
    locator_->nearest(point, v, w);
    if (remembered < max_points_) {
      points_.resize(points_.size() + 3);
      weights_.resize(weights_.size() + 3);
      shapes_.resize(shapes_.size() + nm * 9);
    } else {
      slot = next_;
      next_ = (next_ + 1) % max_points_;
    }
    // Nine planes of #modes floats, [vertex k][x y z][m], so that the sum below runs over the
    // modes in contiguous loads and vectorizes. Every point of a rolling or sliding contact is
    // new, so this fill runs once per contact point and step: one plain loop per source, with no
    // test inside (a test of a member inside would be reloaded after every store).
    float* planes = shapes_.data() + slot * nm * 9;
    for (int k = 0; k < 3; ++k) {
      float* px = planes + (3 * k) * nm;
      float* py = px + nm;
      float* pz = py + nm;
      const float* read = use_rows_ ? rows_.row(v[k]) : nullptr;
      if (use_rows_ && read == nullptr) {
        std::fill(px, px + 3 * nm, 0.0f);
      } else if (use_rows_) {
        for (size_t m = 0; m < nm; ++m) px[m] = read[m * 3], py[m] = read[m * 3 + 1], pz[m] = read[m * 3 + 2];
      } else {
        for (size_t m = 0; m < nm; ++m) {
          const float* phi = bank.shapeAt(m, v[k]);
          px[m] = phi[0], py[m] = phi[1], pz[m] = phi[2];
        }
      }
    }
    for (int c = 0; c < 3; ++c) points_[3 * slot + c] = point[c], weights_[3 * slot + c] = w[c];
  }
  const double* w = &weights_[3 * slot];
  const float* planes = shapes_.data() + slot * nm * 9;
  // The same sums in the same order as SurfaceLocator::projectImpulseInto, mode by mode.
  for (size_t m = 0; m < nm; ++m) {
    double s = 0.0;
    for (int k = 0; k < 3; ++k) {
      const float* p = planes + (3 * k) * nm + m;
      s += w[k] * (p[0] * impulse[0] + p[nm] * impulse[1] + p[2 * nm] * impulse[2]);
    }
    out[m] = s;
  }
}

void ContactProjector::projectOnce(const double point[3], const double impulse[3], double* out) const {
  const size_t nm = bank_->modeCount();
  if (!use_rows_ || rows_.modes != nm || !locator_->hasTriangles()) {
    if (use_rows_ && rows_.modes != nm)
      std::fill_n(out, nm, 0.0);
    else
      locator_->projectImpulseInto(point, impulse, out);
    return;
  }
  uint32_t v[3];
  double w[3];
  locator_->nearest(point, v, w);
  const float* read[3] = {rows_.row(v[0]), rows_.row(v[1]), rows_.row(v[2])};
  // The same sums in the same order as projectImpulseInto (a missing row projects to zero).
  for (size_t m = 0; m < nm; ++m) {
    double s = 0.0;
    for (int k = 0; k < 3; ++k) {
      const float zero[3] = {0.0f, 0.0f, 0.0f};
      const float* phi = read[k] ? read[k] + m * 3 : zero;
      s += w[k] * (phi[0] * impulse[0] + phi[1] * impulse[1] + phi[2] * impulse[2]);
    }
    out[m] = s;
  }
}

std::vector<double> projectImpulseAtVertex(const ModeBank& bank, size_t vertex, const double impulse[3]) {
  std::vector<double> g(bank.modeCount(), 0.0);
  projectImpulseAtVertexInto(bank, vertex, impulse, g.data());
  return g;
}

std::vector<double> projectImpulse(const ModeBank& bank, const double point[3], const double impulse[3]) {
  std::vector<double> g(bank.modeCount(), 0.0);
  projectImpulseInto(bank, point, impulse, g.data());
  return g;
}

double hertzContactDuration(double youngs1_pa, double poisson1, double radius1_m, double mass1_kg, double youngs2_pa,
                            double poisson2, double radius2_m, double mass2_kg, double normal_speed_m_s) {
  // Johnson 1985, eq. 11.24: duration of an elastic Hertzian impact, t = 2.868 (m*^2/(R* E*^2 v))^(1/5).
  // 1/x of an infinite radius or mass is 0 (a half-space, or an immovable body).
  const double inv_e = (1.0 - poisson1 * poisson1) / youngs1_pa + (1.0 - poisson2 * poisson2) / youngs2_pa;
  const double inv_r = 1.0 / radius1_m + 1.0 / radius2_m;
  const double inv_m = 1.0 / mass1_kg + 1.0 / mass2_kg;
  if (!(inv_e > 0.0) || !(inv_r > 0.0) || !(inv_m > 0.0) || !(normal_speed_m_s > 0.0) || !std::isfinite(inv_e) ||
      !std::isfinite(inv_r) || !std::isfinite(inv_m) || !std::isfinite(normal_speed_m_s))
    return 0.0;  // no contact, or nonsense input: the caller gets an ideal impulse
  const double m_star = 1.0 / inv_m, r_star = 1.0 / inv_r, e_star = 1.0 / inv_e;
  return 2.868 * std::pow(m_star * m_star / (r_star * e_star * e_star * normal_speed_m_s), 0.2);
}

}  // namespace strike
