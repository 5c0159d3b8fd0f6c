// SPDX-License-Identifier: MIT
// The oscillator bank: every mode of one struck object advanced exactly and summed. This file
// sets up the object's modes and holds the public API; the other jobs are in the files named in
// oscillator_bank_impl.hpp.
//
// Modes (mass-normalized, Rayleigh damping): q'' + c q' + lambda q = g f(t), c = a1 lambda + a2.
//
// Ringing modes (omega_d = sqrt(lambda - c^2/4) > 0.1 c/2) use the complex form of van den Doel &
// Pai (1998): with pole p = -c/2 + i omega_d and y' = p y + f(t),  q = g Im(y) / omega_d  and
//   q'' = g Im(p^2 y) / omega_d  +  g f(t).
// The second term is the feedthrough of the force pulse itself. It is NOT in the output: it is
// band-unlimited (a contact of 0.1 ms puts energy far above Nyquist, an ideal impulse is a Dirac),
// while its audible part is already carried by the modes that are kept. The output weight is
// folded into the state, yhat = b y with b = -i p^2 R / omega_d, so the output is Re(yhat) and a
// sample costs one complex multiply and one add per mode: yhat[n+1] = e^{p h} yhat[n].
//
// Non-ringing modes (over-damped, critically damped, or omega_d <= 0.1 c/2, where 1/omega_d
// weights would amplify float rounding) are few, decay within a few periods and are rendered in
// double as a 2x2 real system in scaled coordinates x = (omega0 q, q'), output R (-lambda q - c q')
// (the same acceleration without feedthrough). Their transition exp(A h) comes from a matrix
// exponential, which is continuous through critical damping and has no 1/(r1 - r2) cancellation.
//
// Contact pulse. The half-sine force f(u) = (pi/(2 tau)) sin(pi u / tau) on [t0, t0 + tau] is
// integrated exactly: for ringing modes in closed form (two geometric sequences, modal_math.cpp),
// for the others by exponentiating the pulse-augmented 4x4 system. By linearity the pulse is
// split into (a) its transient, the exact output at the samples inside [t0, t0 + tau), computed
// once when the impact is added, and (b) an exact injection of the state at the first sample at
// or after t0 + tau, done sample-accurately in render(). Both are continuous in t0 and tau, and
// tau -> 0 gives the ideal impulse.
//
// Precision. Float SoA state is what makes the bank fast, but a float pole e^{p h} is off by up
// to ~4e-8 relative, which over 10 s at 192 kHz is a ~1e-1 rad phase error. Each ringing mode
// therefore keeps a double anchor advanced once per kSynthAnchorBlock samples by the exact block
// transition e^{p B h} (computed directly, not by powering); the float state restarts from it
// every block, so the float error is that of at most B = 128 steps (< ~5e-6 of the amplitude).
// Blocks are a fixed grid from sample 0, so output does not depend on render() call sizes.
// settings.double_precision replaces all of this by a plain double recurrence (reference path).
//
// Leaving out what is not heard [Raghuvanshi & Lin 2006]: modes outside the band are never
// synthesized; an impact's contribution to a mode below the audibility threshold is dropped; a
// mode whose |yhat| is below the threshold at a block end goes to sleep (swap-removed from the
// active arrays). Denormals are flushed (MXCSR FTZ/DAZ) during render().
#include <algorithm>
#include <cmath>
#include <memory>

#include "oscillator_bank_impl.hpp"

namespace strike {
namespace {

using detail::Complex;
using detail::kBlock;
using detail::ModeKind;

detail::KernelTable chooseKernels(SimdLevel level) {
#if defined(STRIKE_SYNTH_X86)
  const bool has_avx512 =
      __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl");
  const bool has_avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  if ((level == SimdLevel::Auto || level == SimdLevel::Avx512) && has_avx512) return detail::avx512Kernels();
  if (level != SimdLevel::Scalar && has_avx2) return detail::avx2Kernels();
#else
  (void)level;
#endif
  return detail::scalarKernels();
}

}  // namespace

OscillatorBank::Impl::Impl(const SynthSettings& s, const ModalObjectDesc& object) : settings(s) {
  fs = (s.sample_rate_hz > 0.0 && std::isfinite(s.sample_rate_hz)) ? s.sample_rate_hz : 48000.0;
  settings.sample_rate_hz = fs;
  h = 1.0 / fs;
  threshold = std::isfinite(s.audibility_threshold) ? std::max(s.audibility_threshold, detail::kThresholdFloor)
                                                    : detail::kThresholdFloor;
  use_double = s.double_precision;
  reserved = s.allocation == Allocation::Reserved;
  kernels = chooseKernels(s.simd);
  acc.grow(kBlock * detail::kKernelMaxLanes);
  mix.assign(kBlock, 0.0);
  setUpModes(object);
}

// Each mode's kind (out of band, ringing, damped), pole and transition; then capacity for every
// mode being active at once, so that render() never allocates.
void OscillatorBank::Impl::setUpModes(const ModalObjectDesc& desc) {
  delay_s = (desc.delay_s >= 0.0 && std::isfinite(desc.delay_s)) ? desc.delay_s : 0.0;
  const double f_max = synthesizedTopHz(settings.max_freq_hz, fs);
  for (size_t i = 0; i < desc.eigenvalues.size(); ++i) {
    ModeInfo m;
    const double r = desc.radiation_weight.empty()      ? 1.0
                     : i < desc.radiation_weight.size() ? desc.radiation_weight[i]
                                                        : 0.0;
    m.radiation = std::isfinite(r) ? r : 0.0;
    const double lambda = desc.eigenvalues[i];
    ++stats.modes_total;
    const double f0 = (lambda > 0.0 && std::isfinite(lambda)) ? std::sqrt(lambda) / (2.0 * M_PI) : -1.0;
    if (!(f0 >= settings.min_freq_hz && f0 <= f_max && f0 > 0.0)) {
      ++stats.modes_out_of_band;
      modes.push_back(m);
      continue;
    }
    double c = i < desc.damping_c.size() ? desc.damping_c[i]
                                         : rayleighDamping(desc.rayleigh_stiffness, desc.rayleigh_mass, lambda);
    if (!(c > 0.0) || !std::isfinite(c)) c = 0.0;  // negative damping (growth) is not physical here
    const double sigma = 0.5 * c, omega0 = std::sqrt(lambda);
    m.omega0 = omega0;
    m.damping_c = c;
    // omega_d^2 = lambda - sigma^2 as a product: no cancellation near critical damping.
    const double nu = (omega0 - sigma) * (omega0 + sigma);
    if (nu > 0.01 * sigma * sigma) {
      const double omega_d = std::sqrt(nu);
      m.kind = ModeKind::Ringing;
      m.pole = Complex(-sigma, omega_d);
      m.base_pole = m.pole;
      m.base_step = std::exp(m.pole * h);
      m.step = std::exp(m.pole * h);
      m.block_step = std::exp(m.pole * (static_cast<double>(kBlock) * h));
      m.out_weight = Complex(0.0, -1.0) * m.pole * m.pole * (m.radiation / omega_d);
      ++ringing_total;
    } else {
      m.kind = ModeKind::Damped;
      const detail::Mat4 e = detail::expm4(detail::augmentedMatrix(omega0, c, 0.0), h);
      m.phi[0] = e[0], m.phi[1] = e[1], m.phi[2] = e[4], m.phi[3] = e[5];
      ++damped_total;
    }
    modes.push_back(m);
  }
  const size_t cap = detail::roundUp(ringing_total, detail::kKernelSlotAlign) + detail::kKernelSlotAlign;
  for (auto* b : {&st_re, &st_im, &co_re, &co_im}) b->grow(cap);
  for (auto* b : {&anc_re, &anc_im, &pb_re, &pb_im, &inj_re, &inj_im, &dco_re, &dco_im, &mag2}) b->grow(cap);
  slot_mode.grow(cap);
  damped_mode.reserve(damped_total);
  damped_x.reserve(2 * damped_total);
  // As many again as the schedule, which also keeps the change in force.
  damping_changes.reserve(2 * detail::kDampingReserve);
  damping_schedule.reserve(detail::kDampingReserve);
}

void OscillatorBank::Impl::reset() {
  while (n_active > 0) removeRinging(n_active - 1);
  while (!damped_mode.empty()) removeDamped(damped_mode.size() - 1);
  for (uint32_t record : pending) free_records.push_back(record);
  pending.clear();
  if (forced.reserved()) {
    std::fill(forced.y_re.data(), forced.y_re.data() + forced.y_re.size(), 0.0f);
    std::fill(forced.y_im.data(), forced.y_im.data() + forced.y_im.size(), 0.0f);
    std::fill(std::begin(forced.on), std::end(forced.on), false);
    forced.pending.clear();
    forced.free_slots = (1u << detail::kForcedPending) - 1;
    forced.has_state = false;
  }
  damping_changes.clear();
  damping_schedule.clear();
  for (ModeInfo& m : modes) {
    if (m.kind != ModeKind::Ringing) continue;
    m.pole = m.base_pole;
    m.step = m.base_step;
    m.block_step = std::exp(m.pole * (static_cast<double>(kBlock) * h));
  }
  pos = 0;
  stats.active_modes = 0;
}

// Squared output level of active entry k: ringing slots first, then damped modes.
float OscillatorBank::Impl::level2(size_t k) const {
  if (k < n_active) {
    if (use_double)
      return static_cast<float>(anc_re.data_const()[k] * anc_re.data_const()[k] +
                                anc_im.data_const()[k] * anc_im.data_const()[k]);
    const float re = st_re.data_const()[k], im = st_im.data_const()[k];
    return re * re + im * im;
  }
  const size_t r = k - n_active;
  const double a = dampedAmplitude(modes[damped_mode[r]], damped_x[2 * r], damped_x[2 * r + 1]);
  return static_cast<float>(a * a);
}

size_t OscillatorBank::Impl::sleepModesAtOrBelow(float threshold2, float scale2) {
  size_t culled = 0;
  for (size_t i = 0; i < n_active;) {
    if (level2(i) * scale2 <= threshold2)
      removeRinging(i), ++culled;
    else
      ++i;
  }
  for (size_t r = 0; r < damped_mode.size();) {
    if (level2(n_active + r) * scale2 <= threshold2)
      removeDamped(r), ++culled;
    else
      ++r;
  }
  stats.active_modes = n_active + damped_mode.size();
  return culled;
}

OscillatorBank::OscillatorBank(const SynthSettings& settings, const ModalObjectDesc& object)
    : impl_(std::make_unique<Impl>(settings, object)) {}
OscillatorBank::~OscillatorBank() = default;
OscillatorBank::OscillatorBank(OscillatorBank&&) noexcept = default;
OscillatorBank& OscillatorBank::operator=(OscillatorBank&&) noexcept = default;

ImpactResult OscillatorBank::addImpact(const ImpactDesc& impact) { return impl_->addImpact(impact, impl_->reserved); }
void OscillatorBank::reserveImpacts(size_t max_pending, double max_pulse_s) {
  const double samples = max_pulse_s * impl_->fs;
  const size_t transient = (samples > 0.0 && std::isfinite(samples)) ? static_cast<size_t>(std::ceil(samples)) + 2 : 2;
  impl_->reserveImpacts(max_pending, transient);
}
bool OscillatorBank::idle() const {
  return impl_->n_active == 0 && impl_->damped_mode.empty() && impl_->pending.empty() && !impl_->forceDriven();
}
void OscillatorBank::reserveForceInput() { impl_->reserveForceInput(); }
bool OscillatorBank::setForceWeights(const ForceWeightsDesc& weights) { return impl_->setForceWeights(weights); }
void OscillatorBank::render(float* out, size_t frames, const float* const* force) {
  if (out && frames > 0) impl_->render(out, frames, force);
}
bool OscillatorBank::forceDriven() const { return impl_->forceDriven(); }
size_t OscillatorBank::activeModeCount() const { return impl_->n_active + impl_->damped_mode.size(); }
size_t OscillatorBank::activeModeLevels(float* level2, size_t capacity) const {
  const size_t n = std::min(capacity, activeModeCount());
  for (size_t k = 0; k < n; ++k) level2[k] = impl_->level2(k);
  return n;
}
size_t OscillatorBank::sleepModesAtOrBelow(float level2, float scale2) {
  return impl_->sleepModesAtOrBelow(level2, scale2);
}
bool OscillatorBank::setExtraDamping(double time_s, double extra_decay_per_s) {
  return impl_->scheduleExtraDamping(time_s, extra_decay_per_s, impl_->reserved);
}
ImpactResult OscillatorBank::addForceStep(const ForceStepDesc& step) {
  return impl_->addForceStep(step, impl_->reserved);
}
void OscillatorBank::render(float* out, size_t frames) {
  if (out && frames > 0) impl_->render(out, frames);
}
void OscillatorBank::skip(float* out, size_t frames) {
  if (!idle()) return render(out, frames);
  if (out) std::fill(out, out + frames, 0.0f);
  impl_->skipIdle(frames);
}
void OscillatorBank::reset() { impl_->reset(); }
double OscillatorBank::time() const { return static_cast<double>(impl_->pos) / impl_->fs; }
SynthStats OscillatorBank::stats() const { return impl_->stats; }
const char* OscillatorBank::simdName() const { return impl_->use_double ? "double" : impl_->kernels.name; }

}  // namespace strike
