// SPDX-License-Identifier: MIT
// The float oscillator kernels, one set per instruction set, chosen at run time. Each set lives
// in its own translation unit compiled with its own -m flags; those TUs use only intrinsics and
// plain loops (no inline std:: templates), so no AVX code can leak into shared weak symbols.
#pragma once

#include <cstddef>

namespace strike::detail {

/// Modes are stored SoA by slot: state st (complex, float), coefficient co = e^{p h} (float).
/// A kernel advances `slots` modes (a multiple of kKernelSlotAlign, padding slots are zero) over
/// local samples [n0, n1) of the current block, accumulating Re(state) before each step into
/// acc[n * lanes + l] (lanes partial sums per sample, reduced by `reduce`).
struct KernelTable {
  const char* name;
  size_t lanes;
  void (*advance)(const float* co_re, const float* co_im, float* st_re, float* st_im, size_t slots, float* acc,
                  size_t n0, size_t n1);
  /// out[n - n0] += sum over lanes of acc[n * lanes + l], for n in [n0, n1).
  void (*reduce)(const float* acc, size_t n0, size_t n1, double* out);
  /// Block end: anc = pb * anc + inj; inj = 0; st = float(anc); mag2 = |anc|^2.
  void (*anchor)(const double* pb_re, const double* pb_im, double* anc_re, double* anc_im, double* inj_re,
                 double* inj_im, float* st_re, float* st_im, double* mag2, size_t slots);
};

/// Slots are allocated in multiples of this (the widest kernel's group of modes).
constexpr size_t kKernelSlotAlign = 64;
/// Largest lanes of any kernel (acc buffer stride).
constexpr size_t kKernelMaxLanes = 16;

KernelTable scalarKernels();
#if defined(STRIKE_SYNTH_X86)
KernelTable avx2Kernels();
KernelTable avx512Kernels();
#endif

}  // namespace strike::detail
