// SPDX-License-Identifier: MIT
// The far field's partial sums (evaluateFarFields, acoustic_transfer.hpp) with F16C and AVX2:
// 8 halves to 8 floats in one instruction. An evaluation reads every coefficient of the body
// once per direction and is bound by that reading, which half precision halves; converting the
// halves with integer steps instead (SSE2) costs more than it saves. Compiled with -mavx2 -mf16c
// in its own translation unit, chosen at run time (compactTransfer); only intrinsics and plain
// loops here, so no AVX code can leak into a shared inline function.
#include <immintrin.h>

#include "far_field_kernels.hpp"

namespace strike::detail {
namespace {

constexpr size_t kPrefetchAhead_bytes = 8192;

// A 256-bit register holds four coefficients (re, im, ...): two registers are the eight partial
// sums S_0..S_3 and S_4..S_7, each lane the same float product and addition, in the same order,
// as the portable loop's.
template <size_t Directions>
void sums(const uint16_t* halves, size_t whole, const float* const* weights, float* out) {
  __m256 low[Directions], high[Directions];
  for (size_t d = 0; d < Directions; ++d) low[d] = high[d] = _mm256_setzero_ps();
  const __m256i first_four = _mm256_setr_epi32(0, 0, 1, 1, 2, 2, 3, 3),
                last_four = _mm256_setr_epi32(4, 4, 5, 5, 6, 6, 7, 7);
  for (size_t j = 0; j < whole; j += 8) {
    // Ask for the coefficients 8 KB ahead into L2 (a hint: no fault past the end). The hardware's
    // own prefetch stops at each 4 KB page, and a pass reads a body's whole transfer (0.9 MB for a
    // bench plate) that other bodies' passes have pushed out of the caches since: from memory,
    // 65 us a pass without the hint, 33 us with it, 17 us from L2 (20 plates taking turns, one core).
    _mm_prefetch(reinterpret_cast<const char*>(halves + 2 * j) + kPrefetchAhead_bytes, _MM_HINT_T1);
    const __m256 c0 = _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(halves + 2 * j)));
    const __m256 c1 = _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(halves + 2 * j + 8)));
    for (size_t d = 0; d < Directions; ++d) {  // every coefficient read once for all directions
      // Y_j .. Y_j+7, each put beside itself for a coefficient's real and imaginary parts.
      const __m256 y = _mm256_loadu_ps(weights[d] + j);
      low[d] = _mm256_add_ps(low[d], _mm256_mul_ps(c0, _mm256_permutevar8x32_ps(y, first_four)));
      high[d] = _mm256_add_ps(high[d], _mm256_mul_ps(c1, _mm256_permutevar8x32_ps(y, last_four)));
    }
  }
  for (size_t d = 0; d < Directions; ++d) {
    _mm256_storeu_ps(out + 16 * d, low[d]);
    _mm256_storeu_ps(out + 16 * d + 8, high[d]);
  }
}

}  // namespace

void farFieldSumsF16c(const uint16_t* halves, size_t whole, size_t directions, const float* const* weights,
                      float* out) {
  if (directions >= 2)
    sums<2>(halves, whole, weights, out);
  else
    sums<1>(halves, whole, weights, out);
}

void halvesF16c(const float* values, size_t count, float up, uint16_t* halves) {
  const __m256 sign = _mm256_set1_ps(-0.0f), smallest = _mm256_set1_ps(0x1p-14f), factor = _mm256_set1_ps(up);
  size_t k = 0;
  for (; k + 8 <= count; k += 8) {
    const __m256 x = _mm256_mul_ps(_mm256_loadu_ps(values + k), factor);
    const __m256 keep = _mm256_cmp_ps(_mm256_andnot_ps(sign, x), smallest, _CMP_GE_OQ);
    const __m256 kept = _mm256_or_ps(_mm256_and_ps(x, keep), _mm256_and_ps(x, sign));  // under 2^-14: a signed zero
    _mm_storeu_si128(reinterpret_cast<__m128i*>(halves + k),
                     _mm256_cvtps_ph(kept, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
  }
  for (; k < count; ++k) {  // the last few, one at a time in the low lane
    const __m128 x = _mm_mul_ss(_mm_set_ss(values[k]), _mm_set_ss(up));
    const __m128 keep = _mm_cmpge_ss(_mm_andnot_ps(_mm_set_ss(-0.0f), x), _mm_set_ss(0x1p-14f));
    const __m128 kept = _mm_or_ps(_mm_and_ps(x, keep), _mm_and_ps(x, _mm_set_ss(-0.0f)));
    halves[k] =
        static_cast<uint16_t>(_mm_extract_epi16(_mm_cvtps_ph(kept, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC), 0));
  }
}

}  // namespace strike::detail
