// SPDX-License-Identifier: MIT
// The transfer solver's shared types and its Green's function kernels: G = e^{ikr} / (4 pi r)
// and its gradient, a branch-free sin/cos, fixed-order sums, and the phase spread of a piece.
#pragma once

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstddef>
#include <cstdint>

namespace strike::transfer {

using cd = std::complex<double>;
using V3 = Eigen::Vector3d;
constexpr double kFourPi = 4.0 * M_PI;

// The loops over arrays below write arrays that GCC cannot prove apart from what they read:
// this tells it they are (GCC only; other compilers ignore the hint's absence).
#if defined(__GNUC__) && !defined(__clang__)
#define STRIKE_IVDEP _Pragma("GCC ivdep")
#else
#define STRIKE_IVDEP
#endif

inline double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// sin and cos of a phase (|x| < 2^30; ours are below ~1e4): Cody & Waite's range reduction by
/// pi/2 in three parts, then the minimax polynomials of Cephes (S. Moshier, sin.c) on
/// [-pi/4, pi/4]; within 1 ulp of 1 absolute. Plain branch-free arithmetic (rounding by the
/// 1.5 * 2^52 trick, no floor()), so loops over it vectorize with the baseline instruction set,
/// and the same bits on every x86-64 (no FMA: -ffp-contract=off; libm picks FMA code at run time).
inline void sinCos(double x, double& sin_out, double& cos_out) {
  constexpr double kTwoOverPi = 0.63661977236758134308;
  constexpr double kRound = 6755399441055744.0;   // 1.5 * 2^52: (v + kRound) - kRound rounds v
  constexpr double kP1 = 1.5707963267341256e+00;  // pi/2 = kP1 + kP2 + kP3 (kP1, kP2: 24 bits)
  constexpr double kP2 = 6.0771005065061922e-11;
  constexpr double kP3 = 2.0222662487959506e-21;
  const double q = (x * kTwoOverPi + kRound) - kRound;
  const double r = ((x - q * kP1) - q * kP2) - q * kP3;
  const double z = r * r;
  const double sr = r + r * z *
                            (-1.66666666666666307295e-1 +
                             z * (8.33333333332211858878e-3 +
                                  z * (-1.98412698295895385996e-4 +
                                       z * (2.75573136213857245213e-6 +
                                            z * (-2.50507477628578072866e-8 + z * 1.58962301576546568060e-10)))));
  const double cr = 1.0 - 0.5 * z +
                    z * z *
                        (4.16666666666665929218e-2 +
                         z * (-1.38888888888730564116e-3 +
                              z * (2.48015872888517045348e-5 +
                                   z * (-2.75573141792967388112e-7 +
                                        z * (2.08757008419747316778e-9 - z * 1.13585365213876817300e-11)))));
  const int32_t quadrant = static_cast<int32_t>(q) & 3;
  const double sv = (quadrant & 1) ? cr : sr, cv = (quadrant & 1) ? sr : cr;
  sin_out = (quadrant & 2) ? -sv : sv;
  cos_out = ((quadrant + 1) & 2) ? -cv : cv;
}

inline cd unitPhase(double x) {  // e^{ix}
  double s = 0.0, c = 0.0;
  sinCos(x, s, c);
  return {c, s};
}

inline void sinCosArray(const double* x, double* sin_out, double* cos_out, size_t n) {
  for (size_t i = 0; i < n; ++i) sinCos(x[i], sin_out[i], cos_out[i]);
}

/// sum_j a_j w_j and sum_j b_j w_j in four fixed interleaved partial sums (vectorizable without
/// reassociating: the same order on every machine).
inline void dotTwo(const double* a, const double* b, const double* w, size_t n, double& sum_a, double& sum_b) {
  double pa[4] = {0, 0, 0, 0}, pb[4] = {0, 0, 0, 0};
  size_t j = 0;
  for (; j + 4 <= n; j += 4)
    for (int l = 0; l < 4; ++l) {
      pa[l] += a[j + l] * w[j + l];
      pb[l] += b[j + l] * w[j + l];
    }
  for (int l = 0; j < n; ++j, ++l) {
    pa[l] += a[j] * w[j];
    pb[l] += b[j] * w[j];
  }
  sum_a = (pa[0] + pa[1]) + (pa[2] + pa[3]);
  sum_b = (pb[0] + pb[1]) + (pb[2] + pb[3]);
}

struct Kernel {
  cd g;      // G(x, y)
  cd dg_dr;  // dG/dr divided by r: grad_y G = dg_dr * (y - x)
};

inline Kernel kernel(double k, double r) {
  const cd e = unitPhase(k * r);
  const double inv_r = 1.0 / r;
  const cd g = e * (inv_r / kFourPi);
  return {g, g * cd(-inv_r * inv_r, k * inv_r)};  // e^{ikr}(ikr - 1) / (4 pi r^3)
}

/// The mean of e^{ik(r(y) - r(c))} over a piece with centroid c and covariance C, seen from x at
/// distance r along rhat: to second order, 1 - k^2 rhat.C.rhat / 2 (the phase's spread across the
/// piece) + ik (tr C - rhat.C.rhat) / (2r) (the wavefront's curvature). It lets one point stand
/// for a piece up to k D ~ 2 (the next term, k^4 <(rhat.d)^4> / 24, is ~0.3% there).
inline cd phaseSpread(double k, const Eigen::Matrix3d& cov, const V3& yx, double r) {
  const V3 rhat = yx / r;
  const double along = rhat.dot(cov * rhat);
  return cd(1.0 - 0.5 * k * k * along, k * (cov.trace() - along) / (2.0 * r));
}

}  // namespace strike::transfer
