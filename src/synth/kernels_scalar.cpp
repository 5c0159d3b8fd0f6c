// SPDX-License-Identifier: MIT
// Portable kernel: 8 independent modes per group in plain arrays (the compiler may vectorize).
#include "kernels.hpp"

namespace strike::detail {
namespace {

constexpr size_t kLanes = 8;

void advanceScalar(const float* co_re, const float* co_im, float* st_re, float* st_im, size_t slots, float* acc,
                   size_t n0, size_t n1) {
  for (size_t g = 0; g < slots; g += kLanes) {
    float pr[kLanes], pi[kLanes], xr[kLanes], xi[kLanes];
    for (size_t l = 0; l < kLanes; ++l) {
      pr[l] = co_re[g + l];
      pi[l] = co_im[g + l];
      xr[l] = st_re[g + l];
      xi[l] = st_im[g + l];
    }
    for (size_t n = n0; n < n1; ++n) {
      float* a = acc + n * kLanes;
      for (size_t l = 0; l < kLanes; ++l) {
        a[l] += xr[l];
        const float nr = pr[l] * xr[l] - pi[l] * xi[l];
        const float ni = pr[l] * xi[l] + pi[l] * xr[l];
        xr[l] = nr;
        xi[l] = ni;
      }
    }
    for (size_t l = 0; l < kLanes; ++l) {
      st_re[g + l] = xr[l];
      st_im[g + l] = xi[l];
    }
  }
}

void reduceScalar(const float* acc, size_t n0, size_t n1, double* out) {
  for (size_t n = n0; n < n1; ++n) {
    const float* a = acc + n * kLanes;
    // Fixed pairwise order, the same as the SIMD reductions' shape.
    const float s = ((a[0] + a[4]) + (a[2] + a[6])) + ((a[1] + a[5]) + (a[3] + a[7]));
    out[n - n0] += static_cast<double>(s);
  }
}

#include "kernel_anchor.inc"

}  // namespace

KernelTable scalarKernels() { return KernelTable{"scalar", kLanes, advanceScalar, reduceScalar, anchorLoop}; }

}  // namespace strike::detail
