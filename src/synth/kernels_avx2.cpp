// SPDX-License-Identifier: MIT
// AVX2 + FMA kernel (this TU is compiled with -mavx2 -mfma; it runs only when the CPU reports
// both). Groups of 4 ymm = 32 modes; with 16 ymm registers the coefficients may be re-read from
// L1 as memory operands, which costs load slots, not FMA slots.
#include <immintrin.h>

#include "kernels.hpp"

namespace strike::detail {
namespace {

constexpr size_t kLanes = 8;
constexpr int kVectors = 4;

void advanceAvx2(const float* co_re, const float* co_im, float* st_re, float* st_im, size_t slots, float* acc,
                 size_t n0, size_t n1) {
  constexpr size_t kGroup = kLanes * kVectors;
  for (size_t g = 0; g < slots; g += kGroup) {
    __m256 pr[kVectors], pi[kVectors], xr[kVectors], xi[kVectors];
    for (int k = 0; k < kVectors; ++k) {
      pr[k] = _mm256_loadu_ps(co_re + g + k * kLanes);
      pi[k] = _mm256_loadu_ps(co_im + g + k * kLanes);
      xr[k] = _mm256_loadu_ps(st_re + g + k * kLanes);
      xi[k] = _mm256_loadu_ps(st_im + g + k * kLanes);
    }
    for (size_t n = n0; n < n1; ++n) {
      float* a = acc + n * kLanes;
      const __m256 s = _mm256_add_ps(_mm256_add_ps(xr[0], xr[1]), _mm256_add_ps(xr[2], xr[3]));
      _mm256_store_ps(a, _mm256_add_ps(_mm256_load_ps(a), s));
      for (int k = 0; k < kVectors; ++k) {
        const __m256 t = _mm256_mul_ps(pi[k], xi[k]);
        const __m256 u = _mm256_mul_ps(pi[k], xr[k]);
        const __m256 nr = _mm256_fmsub_ps(pr[k], xr[k], t);
        xi[k] = _mm256_fmadd_ps(pr[k], xi[k], u);
        xr[k] = nr;
      }
    }
    for (int k = 0; k < kVectors; ++k) {
      _mm256_storeu_ps(st_re + g + k * kLanes, xr[k]);
      _mm256_storeu_ps(st_im + g + k * kLanes, xi[k]);
    }
  }
}

void reduceAvx2(const float* acc, size_t n0, size_t n1, double* out) {
  size_t n = n0;
  // 8 samples at a time: hadd tree + cross-lane fold gives the 8 row sums in one vector.
  for (; n + 8 <= n1; n += 8) {
    const float* a = acc + n * kLanes;
    const __m256 h01 = _mm256_hadd_ps(_mm256_load_ps(a + 0), _mm256_load_ps(a + 8));
    const __m256 h23 = _mm256_hadd_ps(_mm256_load_ps(a + 16), _mm256_load_ps(a + 24));
    const __m256 h45 = _mm256_hadd_ps(_mm256_load_ps(a + 32), _mm256_load_ps(a + 40));
    const __m256 h67 = _mm256_hadd_ps(_mm256_load_ps(a + 48), _mm256_load_ps(a + 56));
    const __m256 q0 = _mm256_hadd_ps(h01, h23);
    const __m256 q1 = _mm256_hadd_ps(h45, h67);
    const __m256 lo = _mm256_permute2f128_ps(q0, q1, 0x20);
    const __m256 hi = _mm256_permute2f128_ps(q0, q1, 0x31);
    alignas(32) float sums[8];
    _mm256_store_ps(sums, _mm256_add_ps(lo, hi));
    for (int r = 0; r < 8; ++r) out[n + r - n0] += static_cast<double>(sums[r]);
  }
  for (; n < n1; ++n) {
    const float* a = acc + n * kLanes;
    const float s = ((a[0] + a[1]) + (a[2] + a[3])) + ((a[4] + a[5]) + (a[6] + a[7]));
    out[n - n0] += static_cast<double>(s);
  }
}

#include "kernel_anchor.inc"

}  // namespace

KernelTable avx2Kernels() { return KernelTable{"avx2", kLanes, advanceAvx2, reduceAvx2, anchorLoop}; }

}  // namespace strike::detail
