// SPDX-License-Identifier: MIT
// The far field's evaluation at a direction (acoustic_transfer.hpp): the plain sum, and the fast
// form from half-precision coefficients (portable, or the F16C kernel chosen at run time).
// C++ standard library only, no allocation in the evaluation: libstrike calls it per impact.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "far_field_kernels.hpp"
#include "strike/transfer/acoustic_transfer.hpp"

#if defined(STRIKE_BANK_X86)
#include <cpuid.h>
#endif

namespace strike {

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
  const uint32_t bits =
      (magnitude != 0 ? (magnitude << 13) + ((127u - 15u) << 23) : 0u) | (uint32_t(h & 0x8000u) << 16);
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
    const size_t from = 2 * static_cast<size_t>(transfer.offset[i]),
                 to = 2 * static_cast<size_t>(transfer.offset[i + 1]);
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
