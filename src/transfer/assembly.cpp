// SPDX-License-Identifier: MIT
// The collocation system's rows: near triangles from the cache, far pieces as points with
// their phase spread, the rest walked down the tree.
#include "assembly.hpp"

#include <cmath>

#include "quadrature.hpp"

namespace strike::transfer {

namespace {

/// int G and int dG/dn over the big triangles (BigTriangles) that take their far rule from x,
/// into w.big_g and w.big_dg: integrateTriangle's points, weights and arithmetic (kernel():
/// G = e^{ikr} (1/r / 4 pi), dG/dr / r = G (-1/r^2 + ik/r)), the sums in its order. The others
/// (and the near ones) are marked SIZE_MAX in w.big_first.
void integrateBigTriangles(const Surface& s, const BigTriangles& big, double k, const V3& x, size_t b_begin,
                           size_t b_end, RowScratch& w) {
  const size_t count = big.size();
  w.big_first.resize(count);
  std::fill(w.big_first.begin() + static_cast<std::ptrdiff_t>(b_begin),
            w.big_first.begin() + static_cast<std::ptrdiff_t>(b_end), SIZE_MAX);
  w.big_g.resize(count);
  w.big_dg.resize(count);
  for (auto* v : {&w.big_r, &w.big_w, &w.big_dn}) v->resize(big.first[b_end] - big.first[b_begin]);
  size_t points = 0;
  for (size_t b = b_begin; b < b_end; ++b) {
    const uint32_t t = big.tri[b];
    if (w.near_stamp[t] == w.stamp || !big.rule[b]) continue;  // near (in the cache), or no far rule
    if (ruleFor((x - big.centroid[b]).norm(), big.edge[b], k, 0).rule != big.rule[b]) continue;
    const V3& normal = s.tris[t].normal;
    const size_t b_points = big.first[b + 1] - big.first[b];
    bool finite = true;
    for (size_t i = 0; i < b_points; ++i) {
      const V3 yx = big.point[big.first[b] + i] - x;
      const double r = yx.norm();
      finite = finite && r > 0;
      w.big_r[points + i] = r;
      w.big_w[points + i] = big.weight[big.first[b] + i];
      w.big_dn[points + i] = yx.dot(normal);
    }
    if (!finite) continue;  // (x on the triangle: integrateTriangle skips that point)
    w.big_first[b] = points;
    points += b_points;
  }
  for (auto* v : {&w.big_phase, &w.big_sin, &w.big_cos, &w.big_g_re, &w.big_g_im, &w.big_dg_re, &w.big_dg_im})
    v->resize(points);
  for (size_t i = 0; i < points; ++i) w.big_phase[i] = k * w.big_r[i];
  sinCosArray(w.big_phase.data(), w.big_sin.data(), w.big_cos.data(), points);
  {
    const double* __restrict r_i = w.big_r.data();
    const double* __restrict w_i = w.big_w.data();
    const double* __restrict dn_i = w.big_dn.data();
    const double* __restrict sin_i = w.big_sin.data();
    const double* __restrict cos_i = w.big_cos.data();
    double* __restrict g_re_i = w.big_g_re.data();
    double* __restrict g_im_i = w.big_g_im.data();
    double* __restrict dg_re_i = w.big_dg_re.data();
    double* __restrict dg_im_i = w.big_dg_im.data();
    STRIKE_IVDEP
    for (size_t i = 0; i < points; ++i) {
      const double inv_r = 1.0 / r_i[i];
      const double scale = inv_r / kFourPi;
      const double g_re = cos_i[i] * scale, g_im = sin_i[i] * scale;
      const double a = -inv_r * inv_r, b = k * inv_r;
      const double dg_re = g_re * a - g_im * b, dg_im = g_re * b + g_im * a;
      g_re_i[i] = w_i[i] * g_re;
      g_im_i[i] = w_i[i] * g_im;
      dg_re_i[i] = (w_i[i] * dg_re) * dn_i[i];
      dg_im_i[i] = (w_i[i] * dg_im) * dn_i[i];
    }
  }
  for (size_t b = b_begin; b < b_end; ++b) {
    if (w.big_first[b] == SIZE_MAX) continue;
    double g_re = 0.0, g_im = 0.0, dg_re = 0.0, dg_im = 0.0;
    const size_t end = w.big_first[b] + (big.first[b + 1] - big.first[b]);
    for (size_t i = w.big_first[b]; i < end; ++i) {
      g_re += w.big_g_re[i];
      g_im += w.big_g_im[i];
      dg_re += w.big_dg_re[i];
      dg_im += w.big_dg_im[i];
    }
    w.big_g[b] = cd(g_re, g_im);
    w.big_dg[b] = cd(dg_re, dg_im);
  }
}

}  // namespace

void assembleSubtree(const Surface& s, const Cut& cut, const std::vector<NodeData>& data, double k, const V3& x,
                     int32_t start, cd* M, cd* lq, RowScratch& w) {
  const size_t rhs = data.size();
  w.stack.clear();
  w.stack.push_back(start);
  while (!w.stack.empty()) {
    const int32_t i = w.stack.back();
    w.stack.pop_back();
    const Node& n = s.nodes[i];
    const int32_t col = cut.cluster_of_node[i];
    const V3 yx = n.centroid - x;
    const double dist = yx.norm();
    const double diameter = 2.0 * n.radius;
    if (!n.leaf()) {
      if (col >= 0 && dist > kFarRatio * diameter && k * diameter <= kPointPhase && noNearLeaf(n, dist)) {
        const Kernel kr = kernel(k, dist);
        const cd spread = phaseSpread(k, n.cov, yx, dist);
        M[col] += kr.dg_dr * yx.dot(n.vector_area) * spread;
        for (size_t r = 0; r < rhs; ++r) lq[r] += (kr.g * data[r].Q[i] + kr.dg_dr * yx.dot(data[r].D[i])) * spread;
        continue;
      }
      w.stack.push_back(n.left);
      w.stack.push_back(n.right);
      continue;
    }
    const uint32_t t = s.order[n.begin];
    if (w.near_stamp[t] == w.stamp) continue;  // near: in the cache
    const Triangle& tri = s.tris[t];
    cd int_g = 0.0, int_dg = 0.0;
    integrateTriangle(x, tri.v[0], tri.v[1], tri.v[2], tri.normal, tri.area, k, 0, int_g, int_dg);
    M[col] += int_dg;
    for (size_t r = 0; r < rhs; ++r) lq[r] += int_g * data[r].q[t];
  }
}

namespace {

/// sum_j (a_re_j + i a_im_j) w_j + (b_re_j + i b_im_j) v_j in four fixed interleaved partial
/// sums (vectorizable without reassociating: the same order on every machine). v may be null.
cd sumTwo(const double* a_re, const double* a_im, const double* w, const double* b_re, const double* b_im,
          const double* v, size_t n) {
  double re[4] = {0, 0, 0, 0}, im[4] = {0, 0, 0, 0};
  size_t j = 0;
  for (; j + 4 <= n; j += 4)
    for (int l = 0; l < 4; ++l) {
      re[l] += a_re[j + l] * w[j + l] + (v ? b_re[j + l] * v[j + l] : 0.0);
      im[l] += a_im[j + l] * w[j + l] + (v ? b_im[j + l] * v[j + l] : 0.0);
    }
  for (int l = 0; j < n; ++j, ++l) {
    re[l] += a_re[j] * w[j] + (v ? b_re[j] * v[j] : 0.0);
    im[l] += a_im[j] * w[j] + (v ? b_im[j] * v[j] : 0.0);
  }
  return {(re[0] + re[1]) + (re[2] + re[3]), (im[0] + im[1]) + (im[2] + im[3])};
}

}  // namespace

void assembleRow(const Surface& s, const Cut& cut, const Pieces& p, const PieceData& pd, const BigTriangles& big,
                 const std::vector<NodeData>& data, const NearCache& near, size_t row, double k, const V3& x, cd* M,
                 cd* lq, RowScratch& w) {
  const RowRange all{0, p.size(), 0, cut.nodes.size(), 0, big.size(), true};
  assembleRowRange(s, cut, p, pd, big, data, near, row, k, x, all, M, lq, w);
}

RowRange rowRange(const BigTriangles& big, const std::vector<size_t>& piece_begin, size_t col_begin, size_t col_end,
                  bool near) {
  RowRange range;
  range.col_begin = col_begin;
  range.col_end = col_end;
  range.piece_begin = piece_begin[col_begin];
  range.piece_end = piece_begin[col_end];
  range.big_begin = big.size();
  range.big_end = big.size();
  for (size_t j = range.piece_begin; j < range.piece_end; ++j)
    if (big.of_piece[j] >= 0) {
      range.big_end = static_cast<size_t>(big.of_piece[j]) + 1;
      if (range.big_begin == big.size()) range.big_begin = static_cast<size_t>(big.of_piece[j]);
    }
  if (range.big_begin == big.size()) range.big_begin = range.big_end = 0;
  range.near = near;
  return range;
}

std::vector<size_t> pieceBegin(const Pieces& p, size_t clusters) {
  std::vector<size_t> begin(clusters + 1, p.size());
  for (size_t j = p.size(); j-- > 0;) begin[static_cast<size_t>(p.col[j])] = j;
  for (size_t c = clusters; c-- > 0;) begin[c] = std::min(begin[c], begin[c + 1]);
  return begin;
}

namespace {

/// The pieces of `range` in a row at x (the near triangles already stamped in w).
void assemblePieces(const Surface& s, const Cut& cut, const Pieces& p, const PieceData& pd, const BigTriangles& big,
                    const std::vector<NodeData>& data, double k, const V3& x, const RowRange& range, cd* M, cd* lq,
                    RowScratch& w) {
  const size_t pb = range.piece_begin, count = range.piece_end - range.piece_begin, rhs = data.size();
  const double x0 = x[0], x1 = x[1], x2 = x[2];
  const double inv_four_pi = 1.0 / kFourPi;
  for (auto* v : {&w.r, &w.phase, &w.sin_kr, &w.cos_kr, &w.far, &w.dx, &w.dy, &w.dz, &w.g_re, &w.g_im, &w.dg_re,
                  &w.dg_im, &w.m_re, &w.m_im})
    if (v->size() < count) v->resize(count);
  // The pieces: which are one point far from x (the others are done one by one below).
  STRIKE_IVDEP
  for (size_t j = 0; j < count; ++j) {
    w.dx[j] = p.x[pb + j] - x0;
    w.dy[j] = p.y[pb + j] - x1;
    w.dz[j] = p.z[pb + j] - x2;
    w.r[j] = std::sqrt(w.dx[j] * w.dx[j] + w.dy[j] * w.dy[j] + w.dz[j] * w.dz[j]);
    w.phase[j] = k * w.r[j];
  }
  for (size_t j = 0; j < count; ++j) {
    bool far = p.one_point[pb + j] != 0;
    if (p.leaf_tri[pb + j] >= 0)
      far = far && w.near_stamp[p.leaf_tri[pb + j]] != w.stamp;
    else
      far = far && w.r[j] > kFarRatio * p.diameter[pb + j] && w.r[j] > p.clear_of_near[pb + j];
    w.far[j] = far ? 1.0 : 0.0;
  }
  sinCosArray(w.phase.data(), w.sin_kr.data(), w.cos_kr.data(), count);
  const double half_kk = 0.5 * k * k;
  {
    // Restrict-qualified views (no aliasing between the arrays), so that this loop vectorizes.
    const double* __restrict far_j = w.far.data();
    const double* __restrict r_j = w.r.data();
    const double* __restrict cos_j = w.cos_kr.data();
    const double* __restrict sin_j = w.sin_kr.data();
    const double* __restrict dx_j = w.dx.data();
    const double* __restrict dy_j = w.dy.data();
    const double* __restrict dz_j = w.dz.data();
    const double* __restrict cxx = p.cxx.data() + pb;
    const double* __restrict cxy = p.cxy.data() + pb;
    const double* __restrict cxz = p.cxz.data() + pb;
    const double* __restrict cyy = p.cyy.data() + pb;
    const double* __restrict cyz = p.cyz.data() + pb;
    const double* __restrict czz = p.czz.data() + pb;
    const double* __restrict trace = p.trace.data() + pb;
    const double* __restrict ax = p.ax.data() + pb;
    const double* __restrict ay = p.ay.data() + pb;
    const double* __restrict az = p.az.data() + pb;
    double* __restrict g_re_j = w.g_re.data();
    double* __restrict g_im_j = w.g_im.data();
    double* __restrict dg_re_j = w.dg_re.data();
    double* __restrict dg_im_j = w.dg_im.data();
    double* __restrict m_re_j = w.m_re.data();
    double* __restrict m_im_j = w.m_im.data();
    STRIKE_IVDEP
    for (size_t j = 0; j < count; ++j) {
      const double far = far_j[j];
      const double r = far * r_j[j] + (1.0 - far);  // 1 for the others (no division by a near piece's 0)
      const double inv_r = 1.0 / r, inv_r2 = inv_r * inv_r;
      const double dx = dx_j[j], dy = dy_j[j], dz = dz_j[j];
      // G = e^{ikr} / (4 pi r); grad_y G = (y - x) G (ik/r - 1/r^2).
      const double g_re = far * cos_j[j] * inv_r * inv_four_pi, g_im = far * sin_j[j] * inv_r * inv_four_pi;
      const double a = -inv_r2, b = k * inv_r;
      const double dg_re = g_re * a - g_im * b, dg_im = g_re * b + g_im * a;
      // phaseSpread: 1 - k^2 rhat.C.rhat / 2 + ik (tr C - rhat.C.rhat) / (2r).
      const double along = (cxx[j] * dx * dx + cyy[j] * dy * dy + czz[j] * dz * dz +
                            2.0 * (cxy[j] * dx * dy + cxz[j] * dx * dz + cyz[j] * dy * dz)) *
                           inv_r2;
      const double sp_re = 1.0 - half_kk * along, sp_im = k * (trace[j] - along) * 0.5 * inv_r;
      g_re_j[j] = g_re * sp_re - g_im * sp_im;
      g_im_j[j] = g_re * sp_im + g_im * sp_re;
      const double ds_re = dg_re * sp_re - dg_im * sp_im, ds_im = dg_re * sp_im + dg_im * sp_re;
      dg_re_j[j] = ds_re;
      dg_im_j[j] = ds_im;
      const double along_va = dx * ax[j] + dy * ay[j] + dz * az[j];
      m_re_j[j] = ds_re * along_va;
      m_im_j[j] = ds_im * along_va;
    }
  }
  for (size_t j = 0; j < count; ++j) M[p.col[pb + j]] += cd(w.m_re[j], w.m_im[j]);
  for (size_t rr = 0; rr < rhs; ++rr) {
    const double* Q = pd.Q.data() + rr * p.size() + pb;
    const double* Dx = pd.Dx.data() + rr * p.size() + pb;
    const double* Dy = pd.Dy.data() + rr * p.size() + pb;
    const double* Dz = pd.Dz.data() + rr * p.size() + pb;
    for (size_t j = 0; j < count; ++j) w.phase[j] = w.dx[j] * Dx[j] + w.dy[j] * Dy[j] + w.dz[j] * Dz[j];
    lq[rr] += sumTwo(w.g_re.data(), w.g_im.data(), Q, w.dg_re.data(), w.dg_im.data(), w.phase.data(), count);
  }
  // The pieces not summed as one point.
  if (range.big_end > range.big_begin) integrateBigTriangles(s, big, k, x, range.big_begin, range.big_end, w);
  for (size_t j = 0; j < count; ++j) {
    if (w.far[j] > 0) continue;
    const Node& n = s.nodes[p.node[pb + j]];
    if (!n.leaf()) {
      assembleSubtree(s, cut, data, k, x, p.node[pb + j], M, lq, w);
      continue;
    }
    const uint32_t t = s.order[n.begin];
    if (w.near_stamp[t] == w.stamp) continue;  // near: done above
    if (p.quarter[pb + j] > 1) continue;       // (a quarter's triangle is done with its first)
    const Triangle& tri = s.tris[t];           // too large for one point at this k
    cd int_g = 0.0, int_dg = 0.0;
    const int32_t b = big.of_piece[pb + j];
    if (b >= 0 && w.big_first[static_cast<size_t>(b)] != SIZE_MAX) {
      int_g = w.big_g[static_cast<size_t>(b)];
      int_dg = w.big_dg[static_cast<size_t>(b)];
    } else {
      integrateTriangle(x, tri.v[0], tri.v[1], tri.v[2], tri.normal, tri.area, k, 0, int_g, int_dg);
    }
    M[p.col[pb + j]] += int_dg;
    for (size_t rr = 0; rr < rhs; ++rr) lq[rr] += int_g * data[rr].q[t];
  }
}

}  // namespace

void assembleRowRanges(const Surface& s, const Cut& cut, const Pieces& p, const PieceData& pd, const BigTriangles& big,
                       const std::vector<NodeData>& data, const NearCache& near, size_t row, double k, const V3& x,
                       const RowRange* ranges, size_t range_count, cd* M, cd* lq, RowScratch& w) {
  const size_t rhs = data.size();
  const double inv_four_pi = 1.0 / kFourPi;
  const bool with_near = range_count > 0 && ranges[0].near;
  const bool all_columns = range_count == 1 && ranges[0].col_begin == 0 && ranges[0].col_end == cut.nodes.size();
  if (!all_columns) {  // the columns in range, for the near triangles
    w.col_mark.resize(cut.nodes.size(), 0);
    ++w.col_stamp;
    for (size_t q = 0; q < range_count; ++q)
      for (size_t c = ranges[q].col_begin; c < ranges[q].col_end; ++c) w.col_mark[c] = w.col_stamp;
  }
  // The near triangles (of the columns in range).
  w.near_stamp.resize(s.tris.size(), 0);
  ++w.stamp;
  if (with_near)
    for (size_t i = near.near_begin[row]; i < near.near_begin[row + 1]; ++i) w.near_stamp[near.near_tris[i]] = w.stamp;
  const size_t first = near.begin[row], points = with_near ? near.begin[row + 1] - first : 0;
  for (auto* v : {&w.phase, &w.sin_kr, &w.cos_kr, &w.g_re, &w.g_im, &w.m_re, &w.m_im})
    if (v->size() < points) v->resize(points);
  if (with_near) {
    const double* r = near.r.data() + first;
    for (size_t i = 0; i < points; ++i) w.phase[i] = k * r[i];
    sinCosArray(w.phase.data(), w.sin_kr.data(), w.cos_kr.data(), points);
    const double* inv = near.inv_r.data() + first;
    const double* w_g = near.w_g.data() + first;
    const double* w_dn = near.w_dn.data() + first;
    STRIKE_IVDEP
    for (size_t i = 0; i < points; ++i) {
      const double inv_r = inv[i];
      const double g_re = w.cos_kr[i] * inv_r * inv_four_pi, g_im = w.sin_kr[i] * inv_r * inv_four_pi;
      const double a = -inv_r * inv_r, b = k * inv_r;  // dG/dr / r = G (-1/r^2 + ik/r)
      w.m_re[i] = w_dn[i] * (g_re * a - g_im * b);
      w.m_im[i] = w_dn[i] * (g_re * b + g_im * a);
      w.g_re[i] = w_g[i] * g_re;
      w.g_im[i] = w_g[i] * g_im;
    }
    // Per near triangle (its points are consecutive): one sum, then its cluster and data.
    for (size_t i = near.near_begin[row]; i < near.near_begin[row + 1]; ++i) {
      const uint32_t t = near.near_tris[i];
      const int32_t col = cut.cluster_of_node[s.leaf_of_tri[t]];
      if (!all_columns && w.col_mark[static_cast<size_t>(col)] != w.col_stamp) continue;
      double m_re = 0.0, m_im = 0.0, g_re = 0.0, g_im = 0.0;
      for (size_t at = near.near_first[i] - first; at < near.near_first[i + 1] - first; ++at) {
        m_re += w.m_re[at];
        m_im += w.m_im[at];
        g_re += w.g_re[at];
        g_im += w.g_im[at];
      }
      M[col] += cd(m_re, m_im);
      for (size_t rr = 0; rr < rhs; ++rr) lq[rr] += cd(g_re * data[rr].q[t], g_im * data[rr].q[t]);
    }
  }
  for (size_t q = 0; q < range_count; ++q) assemblePieces(s, cut, p, pd, big, data, k, x, ranges[q], M, lq, w);
}

void assembleRowRange(const Surface& s, const Cut& cut, const Pieces& p, const PieceData& pd, const BigTriangles& big,
                      const std::vector<NodeData>& data, const NearCache& near, size_t row, double k, const V3& x,
                      const RowRange& range, cd* M, cd* lq, RowScratch& w) {
  assembleRowRanges(s, cut, p, pd, big, data, near, row, k, x, &range, 1, M, lq, w);
}

}  // namespace strike::transfer
