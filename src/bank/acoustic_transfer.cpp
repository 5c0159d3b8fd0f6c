// SPDX-License-Identifier: MIT
// AcousticTransfer's data helpers and its evaluation at a direction (acoustic_transfer.hpp).
// C++ standard library only, no allocation in the evaluation: libstrike calls it per impact.
#include "strike/acoustic_transfer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <array>

#include "far_field_kernels.hpp"

#if defined(STRIKE_BANK_X86)
#include <cpuid.h>
#endif

namespace strike {

uint32_t AcousticTransfer::maxOrder() const {
  uint32_t largest = 0;
  for (uint32_t n : order) largest = n > largest ? n : largest;
  return largest;
}

double AcousticTransfer::rmsFarField(size_t mode) const {
  if (mode + 1 >= offset.size() || offset[mode + 1] > coefficients.size()) return 0.0;
  double sum = 0.0;
  for (uint64_t j = offset[mode]; j < offset[mode + 1]; ++j) sum += std::norm(coefficients[j]);
  // Parseval over the unit sphere: int |F|^2 dOmega = sum |c|^2 (orthonormal Y_nm).
  return std::sqrt(sum / (4.0 * M_PI));
}

std::string AcousticTransfer::checkConsistency(size_t modes) const {
  if (order.size() != modes)
    return "transfer has " + std::to_string(order.size()) + " modes, the bank " + std::to_string(modes);
  if (offset.size() != modes + 1)
    return "transfer offsets: " + std::to_string(offset.size()) + " entries, expected " + std::to_string(modes + 1);
  if (relative_error.size() != modes)
    return "transfer errors: " + std::to_string(relative_error.size()) + " entries, expected " + std::to_string(modes);
  if (offset[0] != 0) return "transfer offset[0] = " + std::to_string(offset[0]) + " (must be 0)";
  for (size_t i = 0; i < modes; ++i) {
    const uint64_t count = uint64_t(order[i] + 1) * uint64_t(order[i] + 1);
    if (offset[i + 1] < offset[i] || offset[i + 1] - offset[i] != count)
      return "transfer mode " + std::to_string(i) + ": order " + std::to_string(order[i]) + " needs " +
             std::to_string(count) + " coefficients, offsets give " +
             std::to_string(static_cast<int64_t>(offset[i + 1] - offset[i]));
    if (!(relative_error[i] >= 0)) return "transfer mode " + std::to_string(i) + ": relative error is not >= 0";
  }
  if (offset[modes] != coefficients.size())
    return "transfer offsets end at " + std::to_string(offset[modes]) + ", " + std::to_string(coefficients.size()) +
           " coefficients stored";
  for (size_t j = 0; j < coefficients.size(); ++j)
    if (!std::isfinite(coefficients[j].real()) || !std::isfinite(coefficients[j].imag()))
      return "transfer coefficient " + std::to_string(j) + " is not finite";
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(centre_m[a])) return "transfer centre is not finite";
  for (double m : translation_dipole_m3)
    if (!std::isfinite(m)) return "transfer translation dipole is not finite";
  return {};
}

namespace {

// The recurrence's constants, one function each, so that the table and the direct evaluation get
// the same bits from them.
double sectoralFactor(int m) { return std::sqrt((2.0 * m + 1.0) / (2.0 * m)); }  // Q_m^m / Q_{m-1}^{m-1}
double firstFactor(int m) { return std::sqrt(2.0 * m + 3.0); }                    // Q_{m+1}^m / (z Q_m^m)
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

void evaluateFarField(const AcousticTransfer& transfer, const double* sh, std::complex<double>* out) {
  for (size_t i = 0; i < transfer.modeCount(); ++i) {
    const std::complex<float>* c = transfer.coefficients.data() + transfer.offset[i];
    const size_t count = static_cast<size_t>(transfer.offset[i + 1] - transfer.offset[i]);
    double re = 0.0, im = 0.0;
    for (size_t j = 0; j < count; ++j) {
      re += static_cast<double>(c[j].real()) * sh[j];
      im += static_cast<double>(c[j].imag()) * sh[j];
    }
    out[i] = {re, im};
  }
}

void farFieldWeights(const double* sh, size_t count, float* weights) {
  for (size_t j = 0; j < count; ++j) weights[j] = static_cast<float>(sh[j]);
}

uint16_t floatToHalf(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const uint16_t sign = static_cast<uint16_t>((bits >> 16) & 0x8000u);
  if (!(std::fabs(x) >= 0x1p-14f)) return sign;  // under the smallest normal half
  // Drop 13 of the float's 23 fraction bits, rounding to nearest even; a carry out of the
  // fraction moves into the exponent, as it should. Then rebias the exponent from 127 to 15.
  const uint32_t magnitude = bits & 0x7fffffffu;
  const uint32_t rounded = (magnitude + 0x0fffu + ((magnitude >> 13) & 1u)) >> 13;
  return static_cast<uint16_t>(sign | (rounded - ((127u - 15u) << 10)));
}

float halfToFloat(uint16_t h) {
  // A normal half's exponent rebiased from 15 to 127 and its fraction moved up by 13 bits; zero
  // stays zero. Exact, as F16C's conversion is.
  const uint32_t magnitude = h & 0x7fffu;
  const uint32_t bits = (magnitude != 0 ? (magnitude << 13) + ((127u - 15u) << 23) : 0u) | (uint32_t(h & 0x8000u) << 16);
  float x;
  std::memcpy(&x, &bits, sizeof x);
  return x;
}

namespace {

bool cpuHasF16c() {
#if defined(STRIKE_BANK_X86)
  // AVX2 (whose check includes the system's saving of the 256-bit registers) and F16C, read from
  // CPUID leaf 1 (ECX bit 29): clang's __builtin_cpu_supports has no "f16c".
  unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
  return __builtin_cpu_supports("avx2") && __get_cpuid(1, &eax, &ebx, &ecx, &edx) && (ecx & bit_F16C) != 0;
#else
  return false;
#endif
}

}  // namespace

CompactTransfer compactTransfer(const AcousticTransfer& transfer, bool allow_f16c) {
  CompactTransfer compact;
  compact.f16c = allow_f16c && cpuHasF16c();
  const size_t modes = transfer.modeCount();
  compact.offset = transfer.offset;
  compact.halves.resize(2 * transfer.coefficients.size());
  compact.scale.assign(modes, 1.0);
  const float* all = reinterpret_cast<const float*>(transfer.coefficients.data());
  for (size_t i = 0; i < modes; ++i) {
    const size_t from = 2 * static_cast<size_t>(transfer.offset[i]), to = 2 * static_cast<size_t>(transfer.offset[i + 1]);
    float largest = 0.0f;
    for (size_t k = from; k < to; ++k) largest = std::max(largest, std::fabs(all[k]));
    int exponent = 0;  // largest = f 2^exponent, f in [0.5, 1): largest 2^(15 - exponent) in [2^14, 2^15)
    if (largest > 0.0f) (void)std::frexp(largest, &exponent);
    const int shift = largest > 0.0f ? 15 - exponent : 0;
    compact.scale[i] = std::ldexp(1.0, -shift);
    // Exact in double; back in float exactly too, but for parts far under 2^-14 that are dropped.
    const double up = std::ldexp(1.0, shift);
    if (compact.f16c && shift >= -126 && shift <= 127)  // the same halves, eight at a time
      detail::halvesF16c(all + from, to - from, static_cast<float>(up), compact.halves.data() + from);
    else
      for (size_t k = from; k < to; ++k) compact.halves[k] = floatToHalf(static_cast<float>(double(all[k]) * up));
  }
  return compact;
}

namespace {

// The fast evaluation's arithmetic (acoustic_transfer.hpp) and its two forms, F16C with AVX2
// (far_field_f16c.cpp) and portable, which do the same single-precision operations in the same order.
constexpr size_t kPartialSums = 8;

/// One direction's partial sums, S_r at [2r] (real) and [2r + 1] (imaginary).
using PartialSums = std::array<float, 2 * kPartialSums>;

/// The coefficients past the last whole group of eight, each into its own partial sum, then the
/// fixed reduction: ((S0 + S2) + (S4 + S6)) + ((S1 + S3) + (S5 + S7)), the last addition in double.
std::complex<double> finishSum(PartialSums& s, const uint16_t* h, const float* w, size_t from, size_t count) {
  for (size_t j = from; j < count; ++j) {
    const size_t r = j % kPartialSums;
    s[2 * r] += halfToFloat(h[2 * j]) * w[j];
    s[2 * r + 1] += halfToFloat(h[2 * j + 1]) * w[j];
  }
  double part[2][2];  // [even or odd sums][re, im]
  for (int odd = 0; odd < 2; ++odd)
    for (int k = 0; k < 2; ++k) {
      const float* x = s.data() + 2 * odd + k;  // S_{odd}, S_{odd + 2}, ... at strides of 4 floats
      part[odd][k] = static_cast<double>((x[0] + x[4]) + (x[8] + x[12]));
    }
  return {part[0][0] + part[1][0], part[0][1] + part[1][1]};
}

/// Mode i's far field at `Directions` directions: out[d][i].
template <size_t Directions>
void evaluateMode(const uint16_t* h, size_t count, double scale, bool f16c, const float* const* w,
                  std::complex<double>* const* out, size_t i) {
  const size_t whole = count - count % kPartialSums;
  PartialSums s[Directions];
  if (f16c) {
    float sums[2 * 2 * kPartialSums];
    detail::farFieldSumsF16c(h, whole, Directions, w, sums);
    for (size_t d = 0; d < Directions; ++d) std::memcpy(s[d].data(), sums + 2 * kPartialSums * d, sizeof s[d]);
  } else {
    for (PartialSums& x : s) x.fill(0.0f);
    for (size_t j = 0; j < whole; j += kPartialSums)
      for (size_t r = 0; r < 2 * kPartialSums; ++r) {
        const float c = halfToFloat(h[2 * j + r]);
        for (size_t d = 0; d < Directions; ++d) s[d][r] += c * w[d][j + r / 2];
      }
  }
  for (size_t d = 0; d < Directions; ++d) out[d][i] = finishSum(s[d], h, w[d], whole, count) * scale;
}

template <size_t Directions>
void evaluateModes(const CompactTransfer& transfer, const float* const* w, std::complex<double>* const* out) {
  for (size_t i = 0; i < transfer.modeCount(); ++i)
    evaluateMode<Directions>(transfer.halves.data() + 2 * transfer.offset[i],
                             static_cast<size_t>(transfer.offset[i + 1] - transfer.offset[i]), transfer.scale[i],
                             transfer.f16c, w, out, i);
}

}  // namespace

void evaluateFarFields(const CompactTransfer& transfer, size_t directions, const float* const* weights,
                       std::complex<double>* const* out) {
  if (directions >= 2)
    evaluateModes<2>(transfer, weights, out);
  else if (directions == 1)
    evaluateModes<1>(transfer, weights, out);
}

}  // namespace strike
