// SPDX-License-Identifier: MIT
// The real orthonormal spherical harmonics (acoustic_transfer.hpp): the recurrence, plain and
// with its constants tabulated, and for two or six directions at once. C++ standard library
// only, no allocation: libstrike evaluates them per impact.
#include <cmath>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <array>

#include "strike/transfer/acoustic_transfer.hpp"

namespace strike {

namespace {

// The recurrence's constants, one function each, so that the table and the direct evaluation get
// the same bits from them.
double sectoralFactor(int m) { return std::sqrt((2.0 * m + 1.0) / (2.0 * m)); }  // Q_m^m / Q_{m-1}^{m-1}
double firstFactor(int m) { return std::sqrt(2.0 * m + 3.0); }                   // Q_{m+1}^m / (z Q_m^m)
double stepA(int n, int m) {
  const double nn = n, mm = m;
  return std::sqrt((4.0 * nn * nn - 1.0) / (nn * nn - mm * mm));
}
double stepB(int n, int m) {
  const double nn = n, mm = m;
  return std::sqrt(((nn - 1.0) * (nn - 1.0) - mm * mm) / (4.0 * (nn - 1.0) * (nn - 1.0) - 1.0));
}

// Computes the constants as it goes.
struct DirectConstants {
  static constexpr bool kPairs = false;
  double sectoral(int m) const { return sectoralFactor(m); }
  double first(int m) const { return firstFactor(m); }
  double a(int n, int m) const { return stepA(n, m); }
  double b(int n, int m) const { return stepB(n, m); }
};

// Reads them from a table (SphericalHarmonicsTable's layout).
struct TableConstants {
#if defined(__SSE2__)
  static constexpr bool kPairs = true;  // columnPair
#else
  static constexpr bool kPairs = false;
#endif
  const SphericalHarmonicsTable& t;
  double sectoral(int m) const { return t.sectoral[static_cast<size_t>(m)]; }
  double first(int m) const { return t.first[static_cast<size_t>(m)]; }
  double a(int n, int m) const { return t.a[static_cast<size_t>(n * n + n + m)]; }
  double b(int n, int m) const { return t.b[static_cast<size_t>(n * n + n + m)]; }
};

/// One order m's column, n = m..n_max: out[n^2 + n + m] = Q_n^m cos_factor and, for m > 0,
/// out[n^2 + n - m] = Q_n^m sin_factor, from Q_m^m = q_mm up the three-term recurrence.
template <class Constants>
void column(const Constants& k, int m, int n_max, double z, double q_mm, double cos_factor, double sin_factor,
            double* out) {
  double q_prev = 0.0, q = q_mm;  // Q_{n-1}^m, Q_n^m
  for (int n = m; n <= n_max; ++n) {
    if (n == m + 1) {
      q_prev = q;
      q = k.first(m) * z * q_mm;
    } else if (n > m + 1) {
      const double next = k.a(n, m) * (z * q - k.b(n, m) * q_prev);
      q_prev = q;
      q = next;
    }
    out[n * n + n + m] = q * cos_factor;
    if (m > 0) out[n * n + n - m] = q * sin_factor;
  }
}

#if defined(__SSE2__)
/// The columns of m and m + 1 at once (m + 1 <= n_max), one in each lane of a register from
/// n = m + 3 on, where both take the general step and their table entries sit side by side.
/// Each lane does the scalar column's operations in its order: the same bits (tested).
class ColumnPair {
 public:
  /// Writes rows n <= m + 2 (one lane at a time) and readies the general step.
  ColumnPair(const TableConstants& k, int m, int n_max, double z, const double q_mm[2], const double cos_factor[2],
             const double sin_factor[2], double* out)
      : k_(k), m_(m), out_(out) {
    const int last = std::min(n_max, m + 2);
    column(k, m, last, z, q_mm[0], cos_factor[0], sin_factor[0], out);
    column(k, m + 1, last, z, q_mm[1], cos_factor[1], sin_factor[1], out);
    if (n_max < m + 3) return;  // no general step (and no table entry for row m + 2)
    // Q_{m+1}, Q_{m+2} of both lanes, as the scalar column has them (out holds them times a factor).
    const double q0_prev = k.first(m) * z * q_mm[0];
    const double q0 = k.a(m + 2, m) * (z * q0_prev - k.b(m + 2, m) * q_mm[0]);
    const double q1_prev = q_mm[1];
    const double q1 = k.first(m + 1) * z * q_mm[1];
    q_prev_ = _mm_set_pd(q1_prev, q0_prev), q_ = _mm_set_pd(q1, q0);  // (lane 0, lane 1) = (m, m + 1)
    z_ = _mm_set1_pd(z);
    cosines_ = _mm_set_pd(cos_factor[1], cos_factor[0]), sines_ = _mm_set_pd(sin_factor[1], sin_factor[0]);
  }
  /// Row n >= m + 3 of both columns.
  void step(int n) {
    const size_t at = static_cast<size_t>(n * n + n + m_);
    const __m128d next = _mm_mul_pd(_mm_loadu_pd(&k_.t.a[at]),
                                    _mm_sub_pd(_mm_mul_pd(z_, q_), _mm_mul_pd(_mm_loadu_pd(&k_.t.b[at]), q_prev_)));
    q_prev_ = q_;
    q_ = next;
    _mm_storeu_pd(out_ + at, _mm_mul_pd(q_, cosines_));
    const __m128d s = _mm_mul_pd(q_, sines_);  // m + 1's goes to n^2 + n - m - 1, m's to n^2 + n - m
    if (m_ > 0)
      _mm_storeu_pd(out_ + (at - static_cast<size_t>(2 * m_ + 1)), _mm_shuffle_pd(s, s, 1));
    else
      _mm_storeh_pd(out_ + (at - 1), s);
  }

 private:
  const TableConstants& k_;
  int m_;
  double* out_;
  __m128d q_prev_ = _mm_setzero_pd(), q_ = _mm_setzero_pd(), z_ = _mm_setzero_pd();
  __m128d cosines_ = _mm_setzero_pd(), sines_ = _mm_setzero_pd();
};

/// Columns m .. m + 5 (m + 5 <= n_max) as three pairs stepped in one loop: each pair's step waits
/// on its own previous one (a multiply, a subtraction, a multiply), so three independent chains
/// keep the processor busy where one pair at a time waited (4.3 -> 2.4 us for order 76). The
/// same operations as each pair alone: the same bits.
void columnSix(const TableConstants& k, int m, int n_max, double z, const double q_mm[6], const double cos_factor[6],
               const double sin_factor[6], double* out) {
  ColumnPair a(k, m, n_max, z, q_mm, cos_factor, sin_factor, out);
  ColumnPair b(k, m + 2, n_max, z, q_mm + 2, cos_factor + 2, sin_factor + 2, out);
  ColumnPair c(k, m + 4, n_max, z, q_mm + 4, cos_factor + 4, sin_factor + 4, out);
  int n = m + 3;
  for (; n <= std::min(n_max, m + 4); ++n) a.step(n);  // b's general step starts at m + 5, c's at m + 7
  for (; n <= std::min(n_max, m + 6); ++n) a.step(n), b.step(n);
  for (; n <= n_max; ++n) {
    a.step(n);
    b.step(n);
    c.step(n);
  }
}

void columnPair(const TableConstants& k, int m, int n_max, double z, const double q_mm[2], const double cos_factor[2],
                const double sin_factor[2], double* out) {
  ColumnPair pair(k, m, n_max, z, q_mm, cos_factor, sin_factor, out);
  for (int n = m + 3; n <= n_max; ++n) pair.step(n);
}
#endif

template <class Constants>
void sphericalHarmonics(int n_max, const double direction[3], const Constants& k, double* out) {
  double x = direction[0], y = direction[1], z = direction[2];
  const double length = std::sqrt(x * x + y * y + z * z);
  if (length > 0 && std::isfinite(length)) {
    x /= length;
    y /= length;
    z /= length;
  } else {
    x = 0.0;
    y = 0.0;
    z = 1.0;
  }
  // Fully normalized associated Legendre recurrences in z, times Re/Im (x + i y)^m, which is
  // sin^m(theta) cos/sin(m phi): no trigonometry, no pole special case, no Condon-Shortley phase
  // (so Y_11 = +sqrt(3/4pi) x). Q_n^m = N_n^m P_n^m / sin^m; stable to high order.
  double q_mm = 1.0 / std::sqrt(4.0 * M_PI);  // Q_0^0
  double c_m = 1.0, s_m = 0.0;                // Re, Im of (x + i y)^m
  double column_q[6], column_cos[6], column_sin[6];
  for (int m = 0; m <= n_max;) {
    // Columns six or two at a time where the table and SSE2 allow (columnSix, columnPair), else one.
    const int count = !Constants::kPairs ? 1 : m + 5 <= n_max ? 6 : m + 1 <= n_max ? 2 : 1;
    for (int l = 0; l < count; ++l) {
      if (m + l > 0) {
        q_mm *= k.sectoral(m + l);
        const double c = x * c_m - y * s_m;
        s_m = x * s_m + y * c_m;
        c_m = c;
      }
      column_q[l] = q_mm;
      column_cos[l] = m + l == 0 ? 1.0 : M_SQRT2 * c_m;
      column_sin[l] = M_SQRT2 * s_m;
    }
#if defined(__SSE2__)
    if constexpr (Constants::kPairs) {
      if (count == 6) {
        columnSix(k, m, n_max, z, column_q, column_cos, column_sin, out);
        m += 6;
        continue;
      }
      if (count == 2) {
        columnPair(k, m, n_max, z, column_q, column_cos, column_sin, out);
        m += 2;
        continue;
      }
    }
#endif
    column(k, m, n_max, z, column_q[0], column_cos[0], column_sin[0], out);
    m += 1;
  }
}

}  // namespace

void realSphericalHarmonics(uint32_t order, const double direction[3], double* out) {
  sphericalHarmonics(static_cast<int>(order), direction, DirectConstants{}, out);
}

SphericalHarmonicsTable sphericalHarmonicsTable(uint32_t order) {
  const int n_max = static_cast<int>(order);
  const size_t count = static_cast<size_t>(n_max + 1) * static_cast<size_t>(n_max + 1);
  SphericalHarmonicsTable t;
  t.order = order;
  t.sectoral.assign(static_cast<size_t>(n_max) + 1, 0.0);
  t.first.assign(static_cast<size_t>(n_max) + 1, 0.0);
  t.a.assign(count, 0.0);
  t.b.assign(count, 0.0);
  for (int m = 0; m <= n_max; ++m) {
    if (m > 0) t.sectoral[static_cast<size_t>(m)] = sectoralFactor(m);
    t.first[static_cast<size_t>(m)] = firstFactor(m);
    for (int n = m + 2; n <= n_max; ++n) {
      t.a[static_cast<size_t>(n * n + n + m)] = stepA(n, m);
      t.b[static_cast<size_t>(n * n + n + m)] = stepB(n, m);
    }
  }
  return t;
}

void realSphericalHarmonics(const SphericalHarmonicsTable& table, const double direction[3], double* out) {
  sphericalHarmonics(static_cast<int>(table.order), direction, TableConstants{table}, out);
}

}  // namespace strike
