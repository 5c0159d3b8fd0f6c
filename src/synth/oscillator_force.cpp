// SPDX-License-Identifier: MIT
// The oscillator bank's continuous force input (rolling, sliding, scraping: contact_noise.hpp):
// each force channel drives the object's ringing modes with its own complex weights, from a
// state of their own summed with the free modes by linearity and merged into them once every
// channel has stopped.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "oscillator_bank_impl.hpp"

namespace strike {
namespace {

using detail::Complex;
using detail::ForcedModes;
using detail::kBlock;
using detail::kForcedGroups;
using detail::kForcedLanes;
using detail::kForcedPending;
using detail::ModeKind;

// Four floats as one SSE register (the GCC/Clang vector extension, no instruction set beyond
// x86-64's SSE2): + - * act lane by lane, as IEEE single precision, like the scalar code.
typedef float Float4 __attribute__((vector_size(16)));
Float4 loadFloat4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
void storeFloat4(float* p, Float4 v) { std::memcpy(p, &v, sizeof v); }

}  // namespace

void OscillatorBank::Impl::reserveForceInput() {
  ForcedModes& f = forced;
  if (f.reserved()) return;
  const size_t mode_count = modes.size();
  for (uint32_t j = 0; j < mode_count; ++j)
    if (modes[j].kind == ModeKind::Ringing) f.mode.push_back(j);
  f.count = f.mode.size();
  f.padded = std::max<size_t>(detail::roundUp(f.count, kForcedLanes), kForcedLanes);
  for (auto* b : {&f.y_re, &f.y_im, &f.z_re, &f.z_im}) b->grow(f.padded);
  f.w_re.grow(kForceChannels * f.padded);
  f.w_im.grow(kForceChannels * f.padded);
  f.g.assign(kForceChannels * mode_count, Complex(0.0, 0.0));
  f.pending.reserve(kForcedPending);
  f.pending_g.assign(kForcedPending * mode_count, Complex(0.0, 0.0));
  forced_acc.grow(kBlock * kForcedLanes);
}

bool OscillatorBank::Impl::setForceWeights(const ForceWeightsDesc& d) {
  if (d.channel >= kForceChannels || !forced.reserved()) return false;
  ForcedModes& f = forced;
  if (f.free_slots == 0 || f.pending.size() == f.pending.capacity()) return false;
  const size_t mode_count = modes.size();
  double t = (d.time_s + delay_s) * fs;
  if (!(t >= static_cast<double>(pos))) t = static_cast<double>(pos);
  uint64_t sample = static_cast<uint64_t>(std::ceil(t - 1e-7));
  sample = (sample + kBlock - 1) / kBlock * kBlock;
  uint32_t slot = 0;
  while (!(f.free_slots & (1u << slot))) ++slot;
  f.free_slots &= ~(1u << slot);
  Complex* g = f.pending_g.data() + static_cast<size_t>(slot) * mode_count;
  for (uint32_t j = 0; j < mode_count; ++j) {
    const Complex v = (d.modal_weight ? d.modal_weight[j] : 0.0) * (d.modal_transfer ? d.modal_transfer[j] : 1.0);
    g[j] = std::isfinite(v.real()) && std::isfinite(v.imag()) ? v : Complex(0.0, 0.0);
  }
  const ForcedModes::Pending p{sample, d.channel, slot, d.modal_weight != nullptr};
  auto at = std::upper_bound(f.pending.begin(), f.pending.end(), sample,
                             [](uint64_t s0, const ForcedModes::Pending& q) { return s0 < q.sample; });
  f.pending.insert(at, p);  // within capacity
  return true;
}

// At a block start: weight changes due, then the coefficients from the poles in force.
void OscillatorBank::Impl::forcedBlockStart(uint64_t block_start) {
  ForcedModes& f = forced;
  const size_t mode_count = modes.size();
  size_t applied = 0;
  while (applied < f.pending.size() && f.pending[applied].sample <= block_start) {
    const ForcedModes::Pending& p = f.pending[applied++];
    std::copy_n(f.pending_g.data() + static_cast<size_t>(p.slot) * mode_count, mode_count,
                f.g.data() + static_cast<size_t>(p.channel) * mode_count);
    f.on[p.channel] = p.on;
    f.free_slots |= 1u << p.slot;
  }
  f.pending.erase(f.pending.begin(), f.pending.begin() + static_cast<std::ptrdiff_t>(applied));
  if (!f.anyOn()) return;
  f.has_state = true;
  for (uint32_t c = 0; c < kForceChannels; ++c) f.feed[c] = 0.0;
  for (size_t e = 0; e < f.count; ++e) {
    const ModeInfo& m = modes[f.mode[e]];
    f.z_re[e] = static_cast<float>(m.step.real());
    f.z_im[e] = static_cast<float>(m.step.imag());
    // Sample-held force F over [n, n + 1): y(n + 1) = e^{ph} y(n) + F (e^{ph} - 1) / p.
    const Complex d = m.out_weight * (m.step - 1.0) / m.pole;
    for (uint32_t c = 0; c < kForceChannels; ++c) {
      const Complex g = f.on[c] ? f.g[static_cast<size_t>(c) * mode_count + f.mode[e]] : 0.0;
      const Complex w = d * g;
      f.w_re[c * f.padded + e] = static_cast<float>(w.real());
      f.w_im[c * f.padded + e] = static_cast<float>(w.imag());
      // Feedthrough R g F, so that a steady force is silent: the sample-held state settles at
      // y = -F / p, whose output Re(b g y) it cancels. With a complex g (directivity) that is
      // Re(b g / p) = R Re(g (1 + i sigma / omega_d)) at the mode's own pole.
      const Complex settle(1.0, -m.base_pole.real() / m.base_pole.imag());
      f.feed[c] += m.radiation * (g * settle).real();
    }
  }
}

// Local samples [s0, s1) of the block at block_start: the forced modes, into mix.
void OscillatorBank::Impl::forcedSegment(uint64_t block_start, size_t s0, size_t s1) {
  ForcedModes& f = forced;
  if (s0 == 0) forcedBlockStart(block_start);
  if (!f.has_state) return;
  float force[kForceChannels][kBlock];
  bool any[kForceChannels] = {};
  for (uint32_t c = 0; c < kForceChannels; ++c) {
    const float* src = cur_force ? cur_force[c] : nullptr;
    any[c] = f.on[c] && src;
    for (size_t n = s0; n < s1; ++n) force[c][n] = any[c] ? src[block_start + n - call_start] : 0.0f;
    if (any[c])
      for (size_t n = s0; n < s1; ++n) mix[n] += f.feed[c] * static_cast<double>(force[c][n]);
  }
  float* acc_l = forced_acc.data();
  std::fill(acc_l + s0 * kForcedLanes, acc_l + s1 * kForcedLanes, 0.0f);
  // Four lanes per Float4, kForcedGroups of them per group of modes: the same IEEE operations
  // lane by lane, in the same order, as the scalar loop this replaces (so the same bits on
  // every x86-64; no fused multiply-add: -ffp-contract=off), but in SSE registers, which GCC
  // did not find in the scalar loop (48 scalar multiplies, none packed).
  for (size_t e0 = 0; e0 < f.padded; e0 += kForcedLanes) {
    Float4 yr[kForcedGroups], yi[kForcedGroups], zr[kForcedGroups], zi[kForcedGroups];
    for (size_t g = 0; g < kForcedGroups; ++g) {
      yr[g] = loadFloat4(f.y_re.data() + e0 + 4 * g), yi[g] = loadFloat4(f.y_im.data() + e0 + 4 * g);
      zr[g] = loadFloat4(f.z_re.data() + e0 + 4 * g), zi[g] = loadFloat4(f.z_im.data() + e0 + 4 * g);
    }
    for (size_t n = s0; n < s1; ++n) {
      Float4 ir[kForcedGroups] = {}, ii[kForcedGroups] = {};  // the input b g (e^{ph} - 1) / p F
      for (uint32_t c = 0; c < kForceChannels; ++c) {
        if (!any[c]) continue;
        const float F = force[c][n];
        const Float4 force4 = {F, F, F, F};
        const float* wr = f.w_re.data() + c * f.padded + e0;
        const float* wi = f.w_im.data() + c * f.padded + e0;
        for (size_t g = 0; g < kForcedGroups; ++g) {
          ir[g] += loadFloat4(wr + 4 * g) * force4;
          ii[g] += loadFloat4(wi + 4 * g) * force4;
        }
      }
      float* a = acc_l + n * kForcedLanes;
      for (size_t g = 0; g < kForcedGroups; ++g) {
        storeFloat4(a + 4 * g, loadFloat4(a + 4 * g) + yr[g]);
        const Float4 nr = zr[g] * yr[g] - zi[g] * yi[g] + ir[g];
        yi[g] = zr[g] * yi[g] + zi[g] * yr[g] + ii[g];
        yr[g] = nr;
      }
    }
    for (size_t g = 0; g < kForcedGroups; ++g) {
      storeFloat4(f.y_re.data() + e0 + 4 * g, yr[g]);
      storeFloat4(f.y_im.data() + e0 + 4 * g, yi[g]);
    }
  }
  for (size_t n = s0; n < s1; ++n) {
    double sum = 0.0;
    for (size_t l = 0; l < kForcedLanes; ++l) sum += acc_l[n * kForcedLanes + l];
    mix[n] += sum;
  }
  stats.mode_samples += static_cast<uint64_t>(f.count) * (s1 - s0);
  stats.forced_mode_samples += static_cast<uint64_t>(f.count) * (s1 - s0);
}

// At a block end: when no channel drives the object any more, its forced state goes to its free modes.
void OscillatorBank::Impl::forcedMerge() {
  ForcedModes& f = forced;
  if (!f.has_state || f.anyOn()) return;
  for (size_t e = 0; e < f.count; ++e) {
    const Complex y(f.y_re[e], f.y_im[e]);
    f.y_re[e] = f.y_im[e] = 0.0f;
    if (!(std::abs(y) >= threshold)) continue;
    ModeInfo& m = modes[f.mode[e]];
    if (m.slot < 0) activateRinging(f.mode[e]);
    const size_t i = static_cast<size_t>(m.slot);
    anc_re[i] += y.real();
    anc_im[i] += y.imag();
    st_re[i] = static_cast<float>(anc_re[i]);
    st_im[i] = static_cast<float>(anc_im[i]);
    mag2[i] = anc_re[i] * anc_re[i] + anc_im[i] * anc_im[i];
  }
  f.has_state = false;
}

}  // namespace strike
