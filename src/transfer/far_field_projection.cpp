// SPDX-License-Identifier: MIT
// The far field's sums at the directions of a product rule, and their projection.
#include "far_field_projection.hpp"

#include <array>

#include "quadrature.hpp"
#include "strike/transfer/acoustic_transfer.hpp"

namespace strike::transfer {

namespace {

/// The far field's points, structure of arrays (projectFarField).
struct FarPoints {
  size_t count = 0;
  std::vector<double> y0, y1, y2;                    // position relative to the centre
  std::vector<double> cxx, cxy, cxz, cyy, cyz, czz;  // second moment C
  std::vector<double> vx, vy, vz;                    // vector area
  std::vector<double> Q, Dx, Dy, Dz;                 // per solution r and point j: [r * count + j]
  std::vector<size_t> segment_begin;                 // runs of one cluster: their begins, then count
  std::vector<int32_t> segment_col;                  // each run's cluster
};

/// One direction's far fields of one solution: F(d), F(-d), and the coarse difference's.
struct FarFields {
  cd F, G, Fd, Gd;
};

/// A thread's work arrays for farFieldsAt.
struct FarScratch {
  std::vector<double> phase, spread, sin_e, cos_e, dD, ex;
  std::vector<cd> U;  // per cluster run: d.U_c
  void resize(size_t points, size_t segments) {
    for (auto* v : {&phase, &spread, &sin_e, &cos_e, &dD, &ex}) v->resize(points);
    U.resize(segments);
  }
};

/// The far fields of every solution at the direction d (unit) and its opposite -d, into
/// out[r] (formulas in projectFarField). Reads only its arguments and writes only `w` and `out`.
void farFieldsAt(const FarPoints& pts, double k, const double* d, const std::vector<Eigen::VectorXcd>& p,
                 const std::vector<Eigen::VectorXcd>& p_diff, FarScratch& w, FarFields* out) {
  const size_t np = pts.count, segments = pts.segment_col.size(), rhs = p.size();
  const double d0 = d[0], d1 = d[1], d2 = d[2];
  const double kk = k * k;
  const cd ik(0.0, k);
  double* phase = w.phase.data();
  double* spread = w.spread.data();
  double* sin_e = w.sin_e.data();
  double* cos_e = w.cos_e.data();
  double* ex = w.ex.data();
  // The scratch's arrays and the points' never overlap (STRIKE_IVDEP: vectorized without the
  // run-time overlap tests, too many for the compiler to make).
  STRIKE_IVDEP
  for (size_t j = 0; j < np; ++j) {
    phase[j] = -k * (d0 * pts.y0[j] + d1 * pts.y1[j] + d2 * pts.y2[j]);
    const double along = pts.cxx[j] * d0 * d0 + pts.cyy[j] * d1 * d1 + pts.czz[j] * d2 * d2 +
                         2.0 * (pts.cxy[j] * d0 * d1 + pts.cxz[j] * d0 * d2 + pts.cyz[j] * d1 * d2);
    spread[j] = 1.0 - 0.5 * kk * along;
  }
  sinCosArray(phase, sin_e, cos_e, np);
  STRIKE_IVDEP
  for (size_t j = 0; j < np; ++j) {
    cos_e[j] *= spread[j];
    sin_e[j] *= spread[j];
    ex[j] = d0 * pts.vx[j] + d1 * pts.vy[j] + d2 * pts.vz[j];  // d.va
  }
  // Per cluster: d.U_c = sum E_j d.va_j (one complex number: d is known here).
  for (size_t c = 0; c < segments; ++c) {
    double re = 0.0, im = 0.0;
    for (size_t j = pts.segment_begin[c]; j < pts.segment_begin[c + 1]; ++j) {
      re += cos_e[j] * ex[j];
      im += sin_e[j] * ex[j];
    }
    w.U[c] = cd(re, im);
  }
  for (size_t r = 0; r < rhs; ++r) {
    const double* Dxr = &pts.Dx[r * np];
    const double* Dyr = &pts.Dy[r * np];
    const double* Dzr = &pts.Dz[r * np];
    double* dD = w.dD.data();
    STRIKE_IVDEP
    for (size_t j = 0; j < np; ++j) dD[j] = d0 * Dxr[j] + d1 * Dyr[j] + d2 * Dzr[j];
    double q_re = 0.0, q_im = 0.0, d_re = 0.0, d_im = 0.0;
    dotTwo(cos_e, sin_e, &pts.Q[r * np], np, q_re, q_im);
    dotTwo(cos_e, sin_e, dD, np, d_re, d_im);
    const cd SQ(q_re, q_im), SD(d_re, d_im);
    // sum_c p_c d.U_c and sum_c p_c conj(d.U_c), and the same with p_diff.
    double t_re = 0, t_im = 0, u_re = 0, u_im = 0, td_re = 0, td_im = 0, ud_re = 0, ud_im = 0;
    const cd* pr = p[r].data();
    const cd* dr = p_diff[r].data();
    for (size_t c = 0; c < segments; ++c) {
      const double a_re = pr[pts.segment_col[c]].real(), a_im = pr[pts.segment_col[c]].imag();
      const double b_re = dr[pts.segment_col[c]].real(), b_im = dr[pts.segment_col[c]].imag();
      const double x_re = w.U[c].real(), x_im = w.U[c].imag();
      t_re += a_re * x_re - a_im * x_im;
      t_im += a_re * x_im + a_im * x_re;
      u_re += a_re * x_re + a_im * x_im;  // a conj(x)
      u_im += a_im * x_re - a_re * x_im;
      td_re += b_re * x_re - b_im * x_im;
      td_im += b_re * x_im + b_im * x_re;
      ud_re += b_re * x_re + b_im * x_im;
      ud_im += b_im * x_re - b_re * x_im;
    }
    out[r].F = -SQ + ik * SD - ik * cd(t_re, t_im);
    out[r].G = -std::conj(SQ) - ik * std::conj(SD) + ik * cd(u_re, u_im);
    out[r].Fd = -ik * cd(td_re, td_im);
    out[r].Gd = ik * cd(ud_re, ud_im);
  }
}

}  // namespace

void projectFarField(const Surface& s, const Pieces& pc, const PieceData& pd, const std::vector<NodeData>& data,
                     double k, int n_cap, const std::vector<Eigen::VectorXcd>& p,
                     const std::vector<Eigen::VectorXcd>& p_diff, std::vector<std::vector<cd>>& coef,
                     std::vector<std::vector<cd>>& dcoef, TwoParts& parts) {
  const size_t rhs = data.size();
  const size_t count = static_cast<size_t>((n_cap + 1) * (n_cap + 1));
  coef.assign(rhs, std::vector<cd>(count, 0.0));
  dcoef.assign(rhs, std::vector<cd>(count, 0.0));
  // Points: the one-point pieces with their moments, and a 7-point rule on each larger triangle.
  struct Point {
    V3 y;   // relative to the centre
    V3 va;  // vector area
    double cxx, cxy, cxz, cyy, cyz, czz;
    int32_t col;
    int32_t piece;  // moments Q, D from the piece (-1: a rule point of triangle `tri`)
    uint32_t tri;
    double weight;  // of a rule point: its share of the triangle's area
  };
  std::vector<Point> points;
  points.reserve(pc.size());
  for (size_t j = 0; j < pc.size(); ++j) {
    if (pc.one_point[j] || pc.col[j] < 0) {
      points.push_back({V3(pc.x[j], pc.y[j], pc.z[j]) - s.centre, V3(pc.ax[j], pc.ay[j], pc.az[j]), pc.cxx[j],
                        pc.cxy[j], pc.cxz[j], pc.cyy[j], pc.cyz[j], pc.czz[j], pc.col[j], static_cast<int32_t>(j), 0,
                        1.0});
      continue;
    }
    // A triangle too large for one point: 3 points (degree 2) up to twice that, else 7 (degree 5).
    const uint32_t t = s.order[s.nodes[pc.node[j]].begin];
    const Triangle& tri = s.tris[t];
    const bool three = k * tri.diameter <= 2.0 * kPointPhase;
    const double(*rule)[4] = three ? kRule3 : kRule7;
    for (int i = 0; i < (three ? 3 : 7); ++i) {
      const V3 y = rule[i][0] * tri.v[0] + rule[i][1] * tri.v[1] + rule[i][2] * tri.v[2];
      points.push_back(
          {y - s.centre, tri.normal * (rule[i][3] * tri.area), 0, 0, 0, 0, 0, 0, pc.col[j], -1, t, rule[i][3]});
    }
  }
  // With E_j = e^{-ik d.y_j} (1 - k^2 d.C_j.d / 2) at point j (real weights after it):
  //   F(d)  = -S_Q + ik S_D - ik sum_c p_c d.U_c,   S_Q = sum_j E_j Q_j, S_D = sum_j E_j d.D_j,
  //   F(-d) = -conj(S_Q) - ik conj(S_D) + ik sum_c p_c d.conj(U_c),   U_c = sum_{j in c} E_j va_j,
  // and the coarse difference likewise with p_diff alone: the pressure's term is summed per
  // cluster (the points of a cluster are consecutive), shared by every solution.
  const size_t np = points.size();
  FarPoints fp;
  fp.count = np;
  for (auto* v : {&fp.y0, &fp.y1, &fp.y2, &fp.cxx, &fp.cxy, &fp.cxz, &fp.cyy, &fp.cyz, &fp.czz, &fp.vx, &fp.vy, &fp.vz})
    v->resize(np);
  for (size_t j = 0; j < np; ++j) {
    const Point& pt = points[j];
    fp.y0[j] = pt.y[0];
    fp.y1[j] = pt.y[1];
    fp.y2[j] = pt.y[2];
    fp.cxx[j] = pt.cxx;
    fp.cxy[j] = pt.cxy;
    fp.cxz[j] = pt.cxz;
    fp.cyy[j] = pt.cyy;
    fp.cyz[j] = pt.cyz;
    fp.czz[j] = pt.czz;
    fp.vx[j] = pt.va[0];
    fp.vy[j] = pt.va[1];
    fp.vz[j] = pt.va[2];
    if (j == 0 || pt.col != points[j - 1].col) {
      fp.segment_begin.push_back(j);
      fp.segment_col.push_back(pt.col);
    }
  }
  fp.segment_begin.push_back(np);
  for (auto* v : {&fp.Q, &fp.Dx, &fp.Dy, &fp.Dz}) v->resize(rhs * np);
  for (size_t r = 0; r < rhs; ++r)
    for (size_t j = 0; j < np; ++j) {
      const Point& pt = points[j];
      const size_t at = r * np + j;
      if (pt.piece >= 0) {
        const size_t from = r * pc.size() + static_cast<size_t>(pt.piece);
        fp.Q[at] = pd.Q[from];
        fp.Dx[at] = pd.Dx[from];
        fp.Dy[at] = pd.Dy[from];
        fp.Dz[at] = pd.Dz[from];
      } else {
        fp.Q[at] = data[r].q[pt.tri] * s.tris[pt.tri].area * pt.weight;
        fp.Dx[at] = fp.Dy[at] = fp.Dz[at] = 0.0;
      }
    }
  const int rings = n_cap + 2, around = 2 * n_cap + 4;
  std::vector<double> cos_theta, ring_weight;
  gaussLegendre(rings, cos_theta, ring_weight);
  const double dphi = 2.0 * M_PI / around;
  // The directions d of the rule's upper half (each with its opposite -d), in the order their
  // contributions are summed below.
  std::vector<int> direction_ring;
  std::vector<double> direction;  // d0, d1, d2 of each
  for (int i = 0; i < (rings + 1) / 2; ++i) {
    const double ct = cos_theta[i], st = std::sqrt(std::max(0.0, 1.0 - ct * ct));
    const bool middle = 2 * i + 1 == rings;  // its opposite directions are on the ring itself
    const int phis = middle ? around / 2 : around;
    for (int l = 0; l < phis; ++l) {
      const double phi = dphi * l;
      const cd around_z = unitPhase(phi);
      direction_ring.push_back(i);
      direction.insert(direction.end(), {st * around_z.real(), st * around_z.imag(), ct});
    }
  }
  const size_t directions = direction_ring.size();
  // Per direction and solution: F(d), F(-d), and the coarse difference's two (`FarFields`).
  // Each direction's values are sums over the points for that direction alone, so the two
  // halves of the directions (always the same halves) are computed at once, each with its own
  // scratch, into entries the other never touches; the projection on the harmonics then adds
  // them up in the directions' order, on this thread. The same bits with or without the helper
  // thread, and the same as revision 3's single loop (every operation and its order unchanged).
  std::vector<FarFields> fields(directions * rhs);
  std::array<FarScratch, 2> scratch;
  for (FarScratch& w : scratch) w.resize(np, fp.segment_col.size());
  parts.run(directions, directions / 2, [&](size_t begin, size_t end, int part) {
    FarScratch& w = scratch[static_cast<size_t>(part)];
    for (size_t t = begin; t < end; ++t) farFieldsAt(fp, k, &direction[3 * t], p, p_diff, w, &fields[t * rhs]);
  });

  std::vector<double> Y(count);
  for (size_t t = 0; t < directions; ++t) {
    const double d0 = direction[3 * t], d1 = direction[3 * t + 1], d2 = direction[3 * t + 2];
    const double weight = ring_weight[static_cast<size_t>(direction_ring[t])] * dphi / kFourPi;
    for (int side = 0; side < 2; ++side) {
      const double dd[3] = {side ? -d0 : d0, side ? -d1 : d1, side ? -d2 : d2};
      realSphericalHarmonics(static_cast<uint32_t>(n_cap), dd, Y.data());
      for (size_t r = 0; r < rhs; ++r) {
        const FarFields& v = fields[t * rhs + r];
        const cd f = (side ? v.G : v.F) * weight, fd = (side ? v.Gd : v.Fd) * weight;
        cd* co = coef[r].data();
        cd* dc = dcoef[r].data();
        for (size_t m = 0; m < count; ++m) {
          co[m] += f * Y[m];
          dc[m] += fd * Y[m];
        }
      }
    }
  }
}

}  // namespace strike::transfer
