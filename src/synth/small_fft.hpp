// SPDX-License-Identifier: MIT
// A complex fast Fourier transform of one power-of-two size, for the binaural filters'
// partitioned convolution (hrtf.cpp). libstrike builds with nothing but a compiler, so no FFTW
// here: an iterative radix-2 decimation-in-time transform [Cooley & Tukey 1965, "An algorithm
// for the machine calculation of complex Fourier series", Math. Comp. 19] on split real and
// imaginary float arrays, each stage's twiddles stored contiguously so that its butterflies
// vectorize without reordering any sum (the same bits with or without SIMD).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace strike::detail {

class SmallFft {
 public:
  /// size: a power of two >= 2. Allocates.
  explicit SmallFft(size_t size);
  size_t size() const { return size_; }
  /// In place: X[k] = sum_n x[n] e^{-2 pi i k n / N}.
  void forward(float* re, float* im) const;
  /// In place, unscaled: x[n] = sum_k X[k] e^{+2 pi i k n / N} (N times the inverse).
  void inverse(float* re, float* im) const { forward(im, re); }  // swapping re and im conjugates

 private:
  size_t size_;
  std::vector<uint32_t> reversed_;  ///< the bit-reversed index of each index
  std::vector<float> cos_, sin_;    ///< per stage of half-length h: cos, -sin(pi j / h), j < h
};

}  // namespace strike::detail
