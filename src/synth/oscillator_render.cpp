// SPDX-License-Identifier: MIT
// The oscillator bank's render loop: pulse transients and sample-accurate injections, the
// kernels over the active modes, the float state re-anchored at each block end, modes put to
// sleep below the audibility threshold, contact-damping changes at block ends. Never allocates,
// locks or throws (oscillator_bank.cpp describes the method).
#include <algorithm>
#include <cmath>

#include "oscillator_bank_impl.hpp"

#if defined(STRIKE_SYNTH_X86)
#include <xmmintrin.h>
#endif

namespace strike {
namespace {

using detail::Complex;
using detail::kBlock;
using detail::ModeKind;

class DenormalGuard {
 public:
#if defined(STRIKE_SYNTH_X86)
  // FTZ (bit 15) and DAZ (bit 6): decaying states must never hit the slow denormal path.
  DenormalGuard() : csr_(_mm_getcsr()) { _mm_setcsr(csr_ | 0x8040u); }
  ~DenormalGuard() { _mm_setcsr(csr_); }

 private:
  unsigned csr_;
#else
  DenormalGuard() = default;
#endif
};

}  // namespace

void OscillatorBank::Impl::activateRinging(uint32_t mode) {
  const size_t i = n_active++;
  const ModeInfo& m = modes[mode];
  slot_mode[i] = mode;
  co_re[i] = static_cast<float>(m.step.real());
  co_im[i] = static_cast<float>(m.step.imag());
  st_re[i] = st_im[i] = 0.0f;
  anc_re[i] = anc_im[i] = inj_re[i] = inj_im[i] = 0.0;
  pb_re[i] = m.block_step.real();
  pb_im[i] = m.block_step.imag();
  dco_re[i] = m.step.real();
  dco_im[i] = m.step.imag();
  modes[mode].slot = static_cast<int32_t>(i);
  ++stats.mode_starts;
}

void OscillatorBank::Impl::removeRinging(size_t i) {
  const size_t last = n_active - 1;
  modes[slot_mode[i]].slot = -1;
  if (i != last) {
    st_re[i] = st_re[last], st_im[i] = st_im[last], co_re[i] = co_re[last], co_im[i] = co_im[last];
    anc_re[i] = anc_re[last], anc_im[i] = anc_im[last], pb_re[i] = pb_re[last], pb_im[i] = pb_im[last];
    inj_re[i] = inj_re[last], inj_im[i] = inj_im[last], dco_re[i] = dco_re[last], dco_im[i] = dco_im[last];
    mag2[i] = mag2[last];
    slot_mode[i] = slot_mode[last];
    modes[slot_mode[i]].slot = static_cast<int32_t>(i);
  }
  // Padding slots must stay zero: the kernels run over whole groups.
  st_re[last] = st_im[last] = co_re[last] = co_im[last] = 0.0f;
  anc_re[last] = anc_im[last] = pb_re[last] = pb_im[last] = 0.0;
  inj_re[last] = inj_im[last] = dco_re[last] = dco_im[last] = mag2[last] = 0.0;
  --n_active;
}

void OscillatorBank::Impl::removeDamped(size_t i) {
  const size_t last = damped_mode.size() - 1;
  modes[damped_mode[i]].slot = -1;
  if (i != last) {
    damped_mode[i] = damped_mode[last];
    damped_x[2 * i] = damped_x[2 * last];
    damped_x[2 * i + 1] = damped_x[2 * last + 1];
    modes[damped_mode[i]].slot = static_cast<int32_t>(i);
  }
  damped_mode.pop_back();  // never reallocates
  damped_x.pop_back();
  damped_x.pop_back();
}

void OscillatorBank::Impl::inject(const Impact& im, size_t local) {
  for (const detail::ModeHit& hit : im.hits) {
    ModeInfo& m = modes[hit.mode];
    if (m.kind == ModeKind::Ringing) {
      if (m.slot < 0) activateRinging(hit.mode);
      const size_t i = static_cast<size_t>(m.slot);
      if (use_double) {
        anc_re[i] += hit.value.real();
        anc_im[i] += hit.value.imag();
      } else {
        st_re[i] += static_cast<float>(hit.value.real());
        st_im[i] += static_cast<float>(hit.value.imag());
        // Carried to the block end exactly: the anchor never sees float rounding.
        const Complex carried = hit.value * std::exp(m.pole * (static_cast<double>(kBlock - local) * h));
        inj_re[i] += carried.real();
        inj_im[i] += carried.imag();
      }
    } else {
      if (m.slot < 0) {
        m.slot = static_cast<int32_t>(damped_mode.size());
        damped_mode.push_back(hit.mode);  // capacity reserved in setUpModes
        damped_x.push_back(0.0);
        damped_x.push_back(0.0);
        ++stats.mode_starts;
      }
      const size_t i = static_cast<size_t>(m.slot);
      damped_x[2 * i] += hit.value.real();
      damped_x[2 * i + 1] += hit.value.imag();
    }
  }
  const uint64_t active = n_active + damped_mode.size();
  stats.max_active_modes = std::max(stats.max_active_modes, active);
}

// Advance every active mode over local samples [a, b), accumulating into acc (float path) or
// mix (double path, damped modes).
void OscillatorBank::Impl::advance(size_t a, size_t b) {
  if (a >= b) return;
  if (n_active > 0) {
    if (use_double) {
      for (size_t i = 0; i < n_active; ++i) {
        double yr = anc_re[i], yi = anc_im[i];
        const double pr = dco_re[i], pi = dco_im[i];
        for (size_t n = a; n < b; ++n) {
          mix[n] += yr;
          const double nr = pr * yr - pi * yi;
          yi = pr * yi + pi * yr;
          yr = nr;
        }
        anc_re[i] = yr;
        anc_im[i] = yi;
      }
    } else {
      kernels.advance(co_re.data(), co_im.data(), st_re.data(), st_im.data(),
                      detail::roundUp(n_active, detail::kKernelSlotAlign), acc.data(), a, b);
    }
  }
  for (size_t r = 0; r < damped_mode.size(); ++r) {
    const ModeInfo& m = modes[damped_mode[r]];
    double x1 = damped_x[2 * r], v = damped_x[2 * r + 1];
    for (size_t n = a; n < b; ++n) {
      mix[n] += m.radiation * (-m.omega0 * x1 - m.damping_c * v);
      const double n1 = m.phi[0] * x1 + m.phi[1] * v;
      v = m.phi[2] * x1 + m.phi[3] * v;
      x1 = n1;
    }
    damped_x[2 * r] = x1;
    damped_x[2 * r + 1] = v;
  }
  stats.mode_samples += static_cast<uint64_t>(n_active + damped_mode.size()) * (b - a);
}

// Render local samples [s0, s1) of the block starting at block_start into mix[s0, s1).
void OscillatorBank::Impl::renderSegment(uint64_t block_start, size_t s0, size_t s1) {
  std::fill(mix.begin() + static_cast<std::ptrdiff_t>(s0), mix.begin() + static_cast<std::ptrdiff_t>(s1), 0.0);
  const size_t lanes = kernels.lanes;
  if (!use_double) std::fill(acc.data() + s0 * lanes, acc.data() + s1 * lanes, 0.0f);
  const uint64_t seg_begin = block_start + s0, seg_end = block_start + s1;

  // Pulse transients (precomputed, exact) overlapping this segment.
  for (size_t k = 0; k < pending.size() && pool[pending[k]].start_sample < seg_end; ++k) {
    const Impact& im = pool[pending[k]];
    const uint64_t from = std::max(im.start_sample, seg_begin), to = std::min(im.end_sample, seg_end);
    for (uint64_t n = from; n < to; ++n) mix[n - block_start] += im.transient[n - im.start_sample];
  }

  // Sample-accurate injections: split the sample loop at each injection sample.
  size_t a = s0;
  while (a < s1) {
    const uint64_t abs_a = block_start + a;
    uint64_t next = seg_end;
    for (size_t k = 0; k < pending.size() && pool[pending[k]].start_sample < seg_end; ++k) {
      Impact& im = pool[pending[k]];
      if (im.injected) continue;
      if (im.end_sample <= abs_a) {
        inject(im, a);
        im.injected = true;
      } else {
        next = std::min(next, im.end_sample);
      }
    }
    const size_t b = static_cast<size_t>(next - block_start);
    advance(a, b);
    a = b;
  }
  // Recycle injected records (their transients are over: they end where injection happens).
  size_t kept = 0;
  for (size_t k = 0; k < pending.size(); ++k) {
    if (pool[pending[k]].injected)
      free_records.push_back(pending[k]);  // capacity >= pool.size()
    else
      pending[kept++] = pending[k];
  }
  pending.resize(kept);  // shrinking: no allocation
  if (!use_double) kernels.reduce(acc.data(), s0, s1, mix.data() + s0);
  if (forced.reserved()) forcedSegment(block_start, s0, s1);  // continuous force input
}

void OscillatorBank::Impl::endBlock() {
  if (use_double) {
    for (size_t i = 0; i < n_active; ++i) mag2[i] = anc_re[i] * anc_re[i] + anc_im[i] * anc_im[i];
  } else if (n_active > 0) {
    kernels.anchor(pb_re.data(), pb_im.data(), anc_re.data(), anc_im.data(), inj_re.data(), inj_im.data(), st_re.data(),
                   st_im.data(), mag2.data(), n_active);
  }
  const double threshold2 = threshold * threshold;
  for (size_t i = 0; i < n_active;) {
    if (mag2[i] < threshold2)
      removeRinging(i);  // the moved-in slot is checked next
    else
      ++i;
  }
  for (size_t r = 0; r < damped_mode.size();) {
    if (dampedAmplitude(modes[damped_mode[r]], damped_x[2 * r], damped_x[2 * r + 1]) < threshold)
      removeDamped(r);
    else
      ++r;
  }
}

// no_alloc: refuse (false) rather than grow the schedules beyond what addObject reserved.
void OscillatorBank::Impl::applyDampingChanges() {
  size_t applied = 0;
  while (applied < damping_changes.size() && damping_changes[applied].first <= pos) {
    const double extra_decay_per_s = damping_changes[applied++].second;
    for (ModeInfo& m : modes) {
      if (m.kind != ModeKind::Ringing) continue;
      m.pole = m.base_pole - extra_decay_per_s;
      m.step = std::exp(m.pole * h);
      m.block_step = std::exp(m.pole * (static_cast<double>(kBlock) * h));
      if (m.slot < 0) continue;
      const size_t i = static_cast<size_t>(m.slot);
      co_re[i] = static_cast<float>(m.step.real());
      co_im[i] = static_cast<float>(m.step.imag());
      pb_re[i] = m.block_step.real();
      pb_im[i] = m.block_step.imag();
      dco_re[i] = m.step.real();
      dco_im[i] = m.step.imag();
    }
  }
  damping_changes.erase(damping_changes.begin(), damping_changes.begin() + static_cast<std::ptrdiff_t>(applied));
}

void OscillatorBank::Impl::skipIdle(size_t frames) {
  pos += frames;
  applyDampingChanges();
}
void OscillatorBank::Impl::render(float* out, size_t frames, const float* const* force) {
  DenormalGuard guard;
  cur_force = force;
  call_start = pos;
  size_t done = 0;
  while (done < frames) {
    const uint64_t block_start = pos - pos % kBlock;
    const size_t s0 = static_cast<size_t>(pos - block_start);
    const size_t s1 = std::min(kBlock, s0 + (frames - done));
    renderSegment(block_start, s0, s1);
    for (size_t n = s0; n < s1; ++n) out[done + n - s0] = static_cast<float>(mix[n]);
    done += s1 - s0;
    pos = block_start + s1;
    if (s1 == kBlock) {
      endBlock();
      forcedMerge();
      applyDampingChanges();
    }
  }
  cur_force = nullptr;
  stats.active_modes = n_active + damped_mode.size();
}
}  // namespace strike
