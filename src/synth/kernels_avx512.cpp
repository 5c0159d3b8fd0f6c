// SPDX-License-Identifier: MIT
// AVX-512F kernel (this TU is compiled with -mavx512f -mavx512dq -mavx512vl -mfma; it runs only
// when the CPU reports avx512f). A group of 8 zmm = 128 modes keeps its state and coefficients in
// registers for the whole block: per sample and vector one complex multiply (2 mul + 2 FMA)
// and one add into a 16-lane per-sample accumulator that stays in L1.
#include <immintrin.h>

#include "kernels.hpp"

namespace strike::detail {
namespace {

constexpr size_t kLanes = 16;
// 8 zmm (128 modes) per group measured ~7% faster than 4 (more independent chains to hide the
// mul -> FMA latency); the coefficients partly live in L1 as memory operands. A 64-mode tail
// uses 4 zmm, so slots stay a multiple of 64.
constexpr int kBigVectors = 8;

template <int K>
void advanceGroup(const float* co_re, const float* co_im, float* st_re, float* st_im, float* acc, size_t n0,
                  size_t n1) {
  __m512 pr[K], pi[K], xr[K], xi[K];
  for (int k = 0; k < K; ++k) {
    pr[k] = _mm512_loadu_ps(co_re + k * kLanes);
    pi[k] = _mm512_loadu_ps(co_im + k * kLanes);
    xr[k] = _mm512_loadu_ps(st_re + k * kLanes);
    xi[k] = _mm512_loadu_ps(st_im + k * kLanes);
  }
  for (size_t n = n0; n < n1; ++n) {
    float* a = acc + n * kLanes;
    // Pairwise sums, then a chain over the pairs (K is even).
    __m512 s = _mm512_add_ps(xr[0], xr[1]);
    for (int k = 2; k < K; k += 2) s = _mm512_add_ps(s, _mm512_add_ps(xr[k], xr[k + 1]));
    _mm512_store_ps(a, _mm512_add_ps(_mm512_load_ps(a), s));
    for (int k = 0; k < K; ++k) {
      const __m512 t = _mm512_mul_ps(pi[k], xi[k]);
      const __m512 u = _mm512_mul_ps(pi[k], xr[k]);
      const __m512 nr = _mm512_fmsub_ps(pr[k], xr[k], t);
      xi[k] = _mm512_fmadd_ps(pr[k], xi[k], u);
      xr[k] = nr;
    }
  }
  for (int k = 0; k < K; ++k) {
    _mm512_storeu_ps(st_re + k * kLanes, xr[k]);
    _mm512_storeu_ps(st_im + k * kLanes, xi[k]);
  }
}

void advanceAvx512(const float* co_re, const float* co_im, float* st_re, float* st_im, size_t slots, float* acc,
                   size_t n0, size_t n1) {
  size_t g = 0;
  for (; g + kBigVectors * kLanes <= slots; g += kBigVectors * kLanes)
    advanceGroup<kBigVectors>(co_re + g, co_im + g, st_re + g, st_im + g, acc, n0, n1);
  for (; g < slots; g += 4 * kLanes) advanceGroup<4>(co_re + g, co_im + g, st_re + g, st_im + g, acc, n0, n1);
}

// Permutation that halves the lanes per row: with `row_lanes` lanes per row in each input
// (rows_in = 16 / row_lanes rows), lo gathers the first half of every row of a then b.
__m512i halvingIndex(int row_lanes, int offset) {
  alignas(64) int idx[16];
  const int half = row_lanes / 2, rows_in = 16 / row_lanes;
  for (int j = 0; j < 16; ++j) {
    const int row = j / half, lane = j % half;
    idx[j] = row < rows_in ? row * row_lanes + lane + offset : 16 + (row - rows_in) * row_lanes + lane + offset;
  }
  return _mm512_load_si512(idx);
}

void reduceAvx512(const float* acc, size_t n0, size_t n1, double* out) {
  size_t n = n0;
  if (n1 - n0 >= 16) {
    __m512i lo_idx[4], hi_idx[4];
    for (int level = 0; level < 4; ++level) {
      lo_idx[level] = halvingIndex(16 >> level, 0);
      hi_idx[level] = halvingIndex(16 >> level, (16 >> level) / 2);
    }
    // 16 samples at a time: a 4-level transpose-and-add tree gives the 16 row sums in one vector.
    for (; n + 16 <= n1; n += 16) {
      __m512 v[16];
      for (int r = 0; r < 16; ++r) v[r] = _mm512_load_ps(acc + (n + r) * kLanes);
      int count = 16;
      for (int level = 0; level < 4; ++level) {
        for (int i = 0; i < count / 2; ++i) {
          const __m512 lo = _mm512_permutex2var_ps(v[2 * i], lo_idx[level], v[2 * i + 1]);
          const __m512 hi = _mm512_permutex2var_ps(v[2 * i], hi_idx[level], v[2 * i + 1]);
          v[i] = _mm512_add_ps(lo, hi);
        }
        count /= 2;
      }
      alignas(64) float sums[16];
      _mm512_store_ps(sums, v[0]);
      for (int r = 0; r < 16; ++r) out[n + r - n0] += static_cast<double>(sums[r]);
    }
  }
  for (; n < n1; ++n) {
    // Same tree shape as above for one row: halve 16 -> 8 -> 4 -> 2 -> 1.
    const float* a = acc + n * kLanes;
    float t[16];
    for (int l = 0; l < 16; ++l) t[l] = a[l];
    for (int w = 8; w >= 1; w /= 2)
      for (int l = 0; l < w; ++l) t[l] = t[l] + t[l + w];
    out[n - n0] += static_cast<double>(t[0]);
  }
}

#include "kernel_anchor.inc"

}  // namespace

KernelTable avx512Kernels() { return KernelTable{"avx512", kLanes, advanceAvx512, reduceAvx512, anchorLoop}; }

}  // namespace strike::detail
