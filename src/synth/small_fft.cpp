// SPDX-License-Identifier: MIT
// The binaural filters' FFT (small_fft.hpp).
#include "small_fft.hpp"

#include <cmath>
#include <utility>

namespace strike::detail {

SmallFft::SmallFft(size_t size) : size_(size), reversed_(size) {
  uint32_t bits = 0;
  while ((size_t{1} << bits) < size) ++bits;
  for (size_t i = 0; i < size; ++i) {
    uint32_t r = 0;
    for (uint32_t b = 0; b < bits; ++b)
      if (i & (size_t{1} << b)) r |= 1u << (bits - 1 - b);
    reversed_[i] = r;
  }
  // Stage of half-length h (1, 2, 4, .. N/2): twiddles e^{-i pi j / h}, j < h, at offset h - 1.
  cos_.resize(size > 1 ? size - 1 : 0);
  sin_.resize(cos_.size());
  for (size_t h = 1; h < size; h *= 2)
    for (size_t j = 0; j < h; ++j) {
      const double angle = M_PI * static_cast<double>(j) / static_cast<double>(h);
      cos_[h - 1 + j] = static_cast<float>(std::cos(angle));
      sin_[h - 1 + j] = static_cast<float>(-std::sin(angle));
    }
}

void SmallFft::forward(float* re, float* im) const {
  for (size_t i = 0; i < size_; ++i) {
    const size_t r = reversed_[i];
    if (r > i) {
      std::swap(re[i], re[r]);
      std::swap(im[i], im[r]);
    }
  }
  for (size_t h = 1; h < size_; h *= 2) {
    const float* wr = cos_.data() + (h - 1);
    const float* wi = sin_.data() + (h - 1);
    for (size_t start = 0; start < size_; start += 2 * h) {
      float* ar = re + start;
      float* ai = im + start;
      float* br = ar + h;
      float* bi = ai + h;
      for (size_t j = 0; j < h; ++j) {
        const float tr = wr[j] * br[j] - wi[j] * bi[j];
        const float ti = wr[j] * bi[j] + wi[j] * br[j];
        br[j] = ar[j] - tr;
        bi[j] = ai[j] - ti;
        ar[j] = ar[j] + tr;
        ai[j] = ai[j] + ti;
      }
    }
  }
}

}  // namespace strike::detail
