// SPDX-License-Identifier: MIT
// AcousticTransfer's data helpers and its evaluation at a direction (acoustic_transfer.hpp).
// C++ standard library only, no allocation in the evaluation: libstrike calls it per impact.
#include "strike/acoustic_transfer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <array>

#include "far_field_kernels.hpp"

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
  double sectoral(int m) const { return sectoralFactor(m); }
  double first(int m) const { return firstFactor(m); }
  double a(int n, int m) const { return stepA(n, m); }
  double b(int n, int m) const { return stepB(n, m); }
};

// Reads them from a table (SphericalHarmonicsTable's layout).
struct TableConstants {
  const SphericalHarmonicsTable& t;
  double sectoral(int m) const { return t.sectoral[static_cast<size_t>(m)]; }
  double first(int m) const { return t.first[static_cast<size_t>(m)]; }
  double a(int n, int m) const { return t.a[static_cast<size_t>(n * n + n + m)]; }
  double b(int n, int m) const { return t.b[static_cast<size_t>(n * n + n + m)]; }
};

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
  for (int m = 0; m <= n_max; ++m) {
    if (m > 0) {
      q_mm *= k.sectoral(m);
      const double c = x * c_m - y * s_m;
      s_m = x * s_m + y * c_m;
      c_m = c;
    }
    const double cos_factor = m == 0 ? 1.0 : M_SQRT2 * c_m;
    const double sin_factor = M_SQRT2 * s_m;
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
  for (size_t j = 0; j < count; ++j) weights[2 * j] = weights[2 * j + 1] = static_cast<float>(sh[j]);
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
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("f16c");
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
    s[2 * r] += halfToFloat(h[2 * j]) * w[2 * j];
    s[2 * r + 1] += halfToFloat(h[2 * j + 1]) * w[2 * j + 1];
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
        for (size_t d = 0; d < Directions; ++d) s[d][r] += c * w[d][2 * j + r];
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
