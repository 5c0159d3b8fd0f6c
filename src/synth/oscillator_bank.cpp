// SPDX-License-Identifier: MIT
// The oscillator bank: every mode of every struck object advanced exactly and summed.
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
#include <cstring>
#include <memory>
#include <new>

#include "kernels.hpp"
#include "modal_math.hpp"
#include "strike/synth.hpp"

#if defined(STRIKE_SYNTH_X86)
#include <xmmintrin.h>
#endif

namespace strike {
namespace {

using detail::Complex;
constexpr size_t kBlock = kSynthAnchorBlock;
// Below ~-600 dB nothing is audible whatever the threshold; also keeps doubles out of denormals.
constexpr double kThresholdFloor = 1e-30;
// Contact-damping changes an object may have pending at once without allocating (a contact span
// opens and closes at most once per physics step, and only changes within the listener delay and
// the scheduling lead are pending).
constexpr size_t kDampingReserve = 64;

size_t roundUp(size_t n, size_t m) { return (n + m - 1) / m * m; }

// Four floats as one SSE register (the GCC/Clang vector extension, no instruction set beyond
// x86-64's SSE2): + - * act lane by lane, as IEEE single precision, like the scalar code.
typedef float Float4 __attribute__((vector_size(16)));
Float4 loadFloat4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
void storeFloat4(float* p, Float4 v) { std::memcpy(p, &v, sizeof v); }

// A fixed-size, 64-byte aligned, zero-initialized array that can only grow (outside render()).
template <typename T>
class AlignedBuffer {
 public:
  AlignedBuffer() = default;
  AlignedBuffer(const AlignedBuffer&) = delete;
  AlignedBuffer& operator=(const AlignedBuffer&) = delete;
  ~AlignedBuffer() { release(); }
  void grow(size_t n) {
    if (n <= size_) return;
    T* p = static_cast<T*>(::operator new (n * sizeof(T), std::align_val_t{64}));
    std::fill(p, p + n, T{});
    if (size_ > 0) std::copy(data_, data_ + size_, p);
    release();
    data_ = p;
    size_ = n;
  }
  T* data() { return data_; }
  const T* data_const() const { return data_; }
  T& operator[](size_t i) { return data_[i]; }
  size_t size() const { return size_; }

 private:
  void release() {
    if (data_) ::operator delete (data_, std::align_val_t{64});
    data_ = nullptr;
    size_ = 0;
  }
  T* data_ = nullptr;
  size_t size_ = 0;
};

enum class ModeKind : uint8_t { OutOfBand, Ringing, Damped };

struct ModeInfo {
  ModeKind kind = ModeKind::OutOfBand;
  double radiation = 0.0;  // R: output per unit modal acceleration
  double omega0 = 0.0;     // sqrt(lambda), rad/s
  double damping_c = 0.0;  // c, 1/s
  // Ringing: pole p, e^{p h}, e^{p B h}, and the output weight b = -i p^2 R / omega_d.
  Complex pole, step, block_step, out_weight;
  Complex base_pole, base_step;  // the material's pole and e^{p h}; `pole` adds contact damping
  // Damped: 2x2 per-sample transition in scaled coordinates, row-major.
  double phi[4] = {0, 0, 0, 0};
  int32_t slot = -1;  // index in the active set of its kind, -1 when asleep
  // A ringing mode's responses to its object's last pulse that depend only on the pole and the
  // pulse (addImpact): the state at the pulse's end, and the transient's one-sample step. An
  // impact heard along two paths (direct and the ground's image) asks for them twice with the
  // same pulse; each stamp says for which pulse (ObjectInfo::pulse_stamp) it holds, 0: none.
  uint64_t end_stamp = 0, step_stamp = 0;
  Complex pulse_end;
  detail::ExpPair pulse_step;
};

struct ObjectInfo {
  uint32_t first_mode = 0;
  uint32_t mode_count = 0;
  double delay_s = 0.0;
  // This object's scheduled contact damping: (sample, extra decay per s), sorted by sample.
  std::vector<std::pair<uint64_t, double>> damping_schedule;
  // The pulse its modes' pulse_end and pulse_step belong to: duration, contact damping (bits)
  // and shape; a new one takes a new stamp.
  double pulse_tau_s = -1.0, pulse_extra_damping = 0.0;
  bool pulse_box = false;
  uint64_t pulse_stamp = 0;
};

struct ModeHit {
  uint32_t mode;
  Complex value;  // ringing: yhat added at the injection sample; damped: (omega0 q, q') added
};

struct Impact {
  uint64_t start_sample = 0;  // first sample at or after t0
  uint64_t end_sample = 0;    // injection: first sample at or after t0 + tau
  std::vector<ModeHit> hits;
  std::vector<double> transient;  // output at samples [start_sample, end_sample)
  bool injected = false;
};

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

struct OscillatorBank::Impl {
  SynthSettings settings;
  double fs = 48000.0, h = 1.0 / 48000.0;
  double threshold = kThresholdFloor;
  bool use_double = false;
  detail::KernelTable kernels{};

  std::vector<ObjectInfo> objects;
  std::vector<ModeInfo> modes;
  size_t ringing_total = 0, damped_total = 0;

  // Active ringing modes, SoA by slot. Float path: st/co + double anchor (anc), block transition
  // (pb) and the block's injections carried to the block end (inj). Double path: state in anc,
  // coefficient in dco.
  size_t n_active = 0;
  AlignedBuffer<float> st_re, st_im, co_re, co_im;
  AlignedBuffer<double> anc_re, anc_im, pb_re, pb_im, inj_re, inj_im, dco_re, dco_im, mag2;
  AlignedBuffer<uint32_t> slot_mode;

  // Active damped modes: mode index and (omega0 q, q').
  std::vector<uint32_t> damped_mode;
  std::vector<double> damped_x;

  AlignedBuffer<float> acc;  // kBlock x lanes partial sums
  std::vector<double> mix;   // kBlock output samples being assembled

  // Impact records are pooled so that a reserved bank schedules impacts without allocating
  // (reserveImpacts, addImpactNoAlloc): records keep their vectors' capacity when recycled.
  std::vector<Impact> pool;
  std::vector<uint32_t> free_records;  // indices into pool; capacity >= pool.size()
  std::vector<uint32_t> pending;       // indices into pool, sorted by start_sample; capacity >= pool.size()
  size_t reserved_hits = 0, reserved_transient = 0;
  uint64_t pos = 0;  // next sample to render

  // Scheduled changes of an object's extra damping (contact damping), applied at block ends.
  struct DampingChange {
    uint64_t sample;
    uint32_t object;
    double extra_decay_per_s;
  };
  std::vector<DampingChange> damping_changes;  // pending, sorted by sample; capacity kDampingReserve per object
  SynthStats stats;

  // ---- continuous force input (issue 18; contact_noise.hpp) --------------------------------
  // A driven object's ringing modes get a second state, advanced with the force, summed with the
  // free state by linearity and merged into it after the force stops (forcedMerge). Kept apart so
  // that impacts, sleeping and the float anchors of the free modes are untouched.
  static constexpr size_t kForcedLanes = 8;
  static constexpr size_t kForcedGroups = kForcedLanes / 4;  // Float4s per group of modes
  static constexpr size_t kForcedPending = 8;                // weight changes pending per object
  struct ForcedObject {
    size_t count = 0, padded = 0;  // ringing modes, and rounded up to kForcedLanes
    std::vector<uint32_t> mode;    // global mode index per entry
    std::vector<uint32_t> local;   // object-local index per entry
    AlignedBuffer<float> y_re, y_im, z_re, z_im;
    AlignedBuffer<float> w_re, w_im;  // kForceChannels x padded: b g (e^{ph} - 1) / p
    std::vector<Complex> g;           // kForceChannels x mode_count: the weights in force, x transfer
    double feed[kForceChannels] = {};
    bool on[kForceChannels] = {};
    struct Pending {
      uint64_t sample;
      uint32_t channel, slot;
      bool on;
    };
    std::vector<Pending> pending;    // sorted by sample; capacity kForcedPending
    std::vector<Complex> pending_g;  // kForcedPending x mode_count
    uint32_t free_slots = (1u << kForcedPending) - 1;
    bool has_state = false;
    bool reserved() const { return !mode.empty() || padded > 0; }
    bool anyOn() const {
      for (bool b : on)
        if (b) return true;
      return false;
    }
  };
  std::vector<std::unique_ptr<ForcedObject>> forced;  // per object once any is reserved
  AlignedBuffer<float> forced_acc;                    // kBlock x kForcedLanes
  const float* const* cur_force = nullptr;
  uint64_t call_start = 0;  // pos at the start of the current render() call

  explicit Impl(const SynthSettings& s) : settings(s) {
    fs = (s.sample_rate_hz > 0.0 && std::isfinite(s.sample_rate_hz)) ? s.sample_rate_hz : 48000.0;
    settings.sample_rate_hz = fs;
    h = 1.0 / fs;
    threshold =
        std::isfinite(s.audibility_threshold) ? std::max(s.audibility_threshold, kThresholdFloor) : kThresholdFloor;
    use_double = s.double_precision;
    kernels = chooseKernels(s.simd);
    acc.grow(kBlock * detail::kKernelMaxLanes);
    mix.assign(kBlock, 0.0);
  }

  // --- setup (allocates) ------------------------------------------------------------------

  uint32_t addObject(const ModalObjectDesc& desc) {
    ObjectInfo obj;
    obj.first_mode = static_cast<uint32_t>(modes.size());
    obj.mode_count = static_cast<uint32_t>(desc.eigenvalues.size());
    obj.delay_s = (desc.delay_s >= 0.0 && std::isfinite(desc.delay_s)) ? desc.delay_s : 0.0;
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
    // Capacity for every mode being active at once: render() never allocates.
    const size_t cap = roundUp(ringing_total, detail::kKernelSlotAlign) + detail::kKernelSlotAlign;
    for (auto* b : {&st_re, &st_im, &co_re, &co_im}) b->grow(cap);
    for (auto* b : {&anc_re, &anc_im, &pb_re, &pb_im, &inj_re, &inj_im, &dco_re, &dco_im, &mag2}) b->grow(cap);
    slot_mode.grow(cap);
    damped_mode.reserve(damped_total);
    damped_x.reserve(2 * damped_total);
    damping_changes.reserve(kDampingReserve * (objects.size() + 1));
    objects.push_back(obj);
    objects.back().damping_schedule.reserve(kDampingReserve);  // after the copy: a copy keeps no capacity
    if (reserved_hits > 0 || reserved_transient > 0) reserveImpacts(pool.size(), reserved_transient);
    return static_cast<uint32_t>(objects.size() - 1);
  }

  // Every record can hold an impact on the largest object and a pulse of max_transient samples.
  void reserveImpacts(size_t records, size_t max_transient) {
    size_t max_modes = 0;
    for (const ObjectInfo& o : objects) max_modes = std::max<size_t>(max_modes, o.mode_count);
    const bool grew = max_modes > reserved_hits || max_transient > reserved_transient;
    reserved_hits = std::max(reserved_hits, max_modes);
    reserved_transient = std::max(reserved_transient, max_transient);
    const size_t old_size = pool.size();
    pool.reserve(records);
    free_records.reserve(records);
    while (pool.size() < records) {
      pool.emplace_back();
      free_records.push_back(static_cast<uint32_t>(pool.size() - 1));
    }
    pending.reserve(pool.size());
    free_records.reserve(pool.size());
    // Only new records need capacity unless the reservation itself grew.
    for (size_t i = grew ? 0 : old_size; i < pool.size(); ++i) {
      pool[i].hits.reserve(reserved_hits);
      pool[i].transient.reserve(reserved_transient);
    }
  }

  // The object's extra (contact) damping in force at `sample`: pulses and the oscillators they
  // feed must use the same pole.
  static double extraDampingAt(const ObjectInfo& obj, uint64_t sample) {
    const auto& schedule = obj.damping_schedule;
    auto after =
        std::upper_bound(schedule.begin(), schedule.end(), std::make_pair(sample, static_cast<double>(INFINITY)));
    return after != schedule.begin() ? std::prev(after)->second : 0.0;
  }

  // no_alloc: fail with NoCapacity rather than grow a record or the pool.
  ImpactResult addImpact(const ImpactDesc& desc, bool no_alloc) {
    if (desc.object >= objects.size()) return ImpactResult::BadObject;
    ObjectInfo& obj = objects[desc.object];  // its pulse stamp may move
    const double now = static_cast<double>(pos);
    double t0 = (desc.time_s + obj.delay_s) * fs;  // in samples
    if (!(t0 >= now)) t0 = now;                    // late (or NaN): start now
    double tau = desc.duration_s * fs;             // in samples
    if (!(tau > 0.0) || !std::isfinite(tau)) tau = 0.0;
    // Below 1e-9 samples a pulse is an impulse at its centroid to ~1e-18 relative.
    const bool ideal = tau < 1e-9;
    if (ideal) t0 += 0.5 * tau, tau = 0.0;
    // A sample counts as "at or after" an instant up to 1e-7 samples of rounding; the formulas
    // below are analytic, so evaluating them a hair before the instant is harmless.
    uint64_t start_sample = static_cast<uint64_t>(std::ceil(t0 - 1e-7));
    uint64_t end_sample = ideal ? start_sample : static_cast<uint64_t>(std::ceil(t0 + tau - 1e-7));
    start_sample = std::max<uint64_t>(start_sample, pos);
    end_sample = std::max(end_sample, start_sample);
    const size_t transient_len = static_cast<size_t>(end_sample - start_sample);
    if (desc.shape == PulseShape::Box && !ideal && !no_alloc && onlyRinging(desc)) return addBoxAsSteps(desc, t0, tau);
    if (free_records.empty()) {
      if (no_alloc) return ImpactResult::NoCapacity;
      reserveImpacts(std::max<size_t>(16, pool.size() * 2), 0);  // geometric: O(1) amortized
    }
    const uint32_t record = free_records.back();
    Impact& im = pool[record];
    if (no_alloc && (im.hits.capacity() < obj.mode_count || im.transient.capacity() < transient_len))
      return ImpactResult::NoCapacity;
    free_records.pop_back();
    ++stats.impacts;
    im.start_sample = start_sample;
    im.end_sample = end_sample;
    im.injected = false;
    im.hits.clear();
    im.transient.assign(transient_len, 0.0);  // within capacity: no allocation
    const double tau_s = tau * h;
    const double after_end_s = (static_cast<double>(im.end_sample) - (t0 + tau)) * h;
    const double first_u_s = (static_cast<double>(im.start_sample) - t0) * h;
    const bool box = desc.shape == PulseShape::Box && !ideal;
    // The augmented pulse state (f, f'/Om) rotates at Om for the half-sine and stays constant
    // (Om = 0) for the box.
    const double pulse_omega = ideal || box ? 0.0 : M_PI / tau_s;

    // Contact damping scheduled for this object at the pulse's start (setExtraDamping is called
    // before the impacts it covers), so pulses and the oscillators they feed use the same pole.
    const double extra_damping = extraDampingAt(obj, start_sample);
    if (std::memcmp(&obj.pulse_tau_s, &tau_s, sizeof tau_s) != 0 ||
        std::memcmp(&obj.pulse_extra_damping, &extra_damping, sizeof extra_damping) != 0 || obj.pulse_box != box) {
      obj.pulse_tau_s = tau_s, obj.pulse_extra_damping = extra_damping, obj.pulse_box = box;
      ++obj.pulse_stamp;
    }
    for (uint32_t j = 0; j < obj.mode_count && desc.modal_impulse; ++j) {
      const Complex factor = desc.modal_transfer ? desc.modal_transfer[j] : Complex(1.0, 0.0);
      const double g = desc.modal_impulse[j];
      if (g == 0.0 || !std::isfinite(g) || !(std::isfinite(factor.real()) && std::isfinite(factor.imag()))) continue;
      const uint32_t mi = obj.first_mode + j;
      ModeInfo& m = modes[mi];
      if (m.kind == ModeKind::Ringing) {
        // The pole in force when the pulse starts (contact damping may have moved it).
        const Complex pole = m.base_pole - extra_damping;
        const Complex step = extra_damping == 0.0 ? m.base_step : std::exp(pole * h);
        if (!ideal && m.end_stamp != obj.pulse_stamp) {
          m.pulse_end = box ? detail::boxResponse(pole, tau_s, tau_s) : detail::halfSineResponse(pole, tau_s, tau_s);
          m.end_stamp = obj.pulse_stamp;
        }
        const Complex y_end = ideal ? Complex(1.0, 0.0) : m.pulse_end;
        const Complex bg = g * m.out_weight * factor;
        const Complex v = bg * std::exp(pole * after_end_s) * y_end;
        if (!(std::abs(v) >= threshold)) continue;
        im.hits.push_back({mi, v});
        if (im.transient.empty()) continue;
        if (box) {
          // Transient of the box: y(U) = E(0, p, U) / tau, E(0, p, U + h) = e^{ph} E(0, p, U) + E(0, p, h).
          Complex e0 = detail::expDividedDifference(Complex(0.0, 0.0), pole, first_u_s);
          const Complex h0 = detail::expDividedDifference(Complex(0.0, 0.0), pole, h);
          const Complex k = bg / tau_s;
          // A box is a sustained force, so its feedthrough g R f (left out of the ringing output)
          // is added back while it acts: a constant force then gives exactly zero acceleration
          // once its onset has rung out, instead of a DC offset of -g R F. Point samples of the
          // half-open box [t0, t0 + tau) tile exactly when boxes are contiguous.
          const double feedthrough = g * factor.real() * m.radiation / tau_s;
          for (double& out : im.transient) {
            out += (k * e0).real() + feedthrough;
            e0 = step * e0 + h0;
          }
          continue;
        }
        // Transient: y(U) = K (E(i Om, p, U) - E(-i Om, p, U)) / 2i at U = first_u + n h, with
        // E(a, p, U + h) = e^{ph} E(a, p, U) + e^{aU} E(a, p, h): exact, stable recurrences.
        const Complex ia(0.0, pulse_omega);
        const detail::ExpPair first = detail::expDividedDifferencePair(ia, -ia, pole, first_u_s);
        if (m.step_stamp != obj.pulse_stamp) {
          m.pulse_step = detail::expDividedDifferencePair(ia, -ia, pole, h);
          m.step_stamp = obj.pulse_stamp;
        }
        const detail::ExpPair& one_step = m.pulse_step;
        Complex ep = first.plus, em = first.minus;
        const Complex hp = one_step.plus, hm = one_step.minus;
        Complex rot_p = first.exp_plus, rot_m = std::conj(rot_p);  // e^{i Om U}
        const Complex turn_p = one_step.exp_plus, turn_m = std::conj(turn_p);
        const Complex k = bg * (M_PI / (2.0 * tau_s)) / Complex(0.0, 2.0);
        for (double& out : im.transient) {
          out += (k * (ep - em)).real();
          ep = step * ep + rot_p * hp;
          em = step * em + rot_m * hm;
          rot_p *= turn_p;
          rot_m *= turn_m;
        }
      } else if (m.kind == ModeKind::Damped) {
        const detail::Mat4 a = detail::augmentedMatrix(m.omega0, m.damping_c, pulse_omega);
        // Half-sine: f = (pi / 2 tau) sin(Om u) enters as f'/Om = pi / (2 tau) at u = 0; box: f = 1 / tau.
        const std::array<double, 4> x0 = box ? std::array<double, 4>{0.0, 0.0, 1.0 / tau_s, 0.0}
                                             : std::array<double, 4>{0.0, 0.0, 0.0, ideal ? 0.0 : M_PI / (2.0 * tau_s)};
        std::array<double, 4> x_end{0.0, 1.0, 0.0, 0.0};
        if (!ideal) x_end = detail::mul4(detail::expm4(a, tau_s), x0);
        x_end[2] = x_end[3] = 0.0;  // the pulse is over
        const std::array<double, 4> x_inj =
            detail::mul4(detail::expm4(detail::augmentedMatrix(m.omega0, m.damping_c, 0.0), after_end_s), x_end);
        // A non-ringing mode has no phase to turn: its factor's real part scales it.
        const double gr = g * factor.real();
        const Complex v(gr * x_inj[0], gr * x_inj[1]);
        if (!(dampedAmplitude(m, v.real(), v.imag()) >= threshold)) continue;
        im.hits.push_back({mi, v});
        if (im.transient.empty()) continue;
        const detail::Mat4 step = detail::expm4(a, h);
        std::array<double, 4> x = detail::mul4(detail::expm4(a, first_u_s), x0);
        const double w = gr * m.radiation;
        for (double& out : im.transient) {
          // The box's feedthrough f = x[2] is part of the output while it acts (see above).
          out += w * (-m.omega0 * x[0] - m.damping_c * x[1] + (box ? x[2] : 0.0));
          x = detail::mul4(step, x);
        }
      }
    }
    if (im.hits.empty()) {
      ++stats.impacts_inaudible;
      free_records.push_back(record);
      return ImpactResult::Inaudible;
    }
    auto at = std::upper_bound(pending.begin(), pending.end(), im.start_sample,
                               [this](uint64_t s, uint32_t other) { return s < pool[other].start_sample; });
    pending.insert(at, record);  // capacity >= pool.size(): no allocation
    return ImpactResult::Scheduled;
  }

  // Mode j of `obj`'s share of a box or a force change whose modal input is `modal` (impulse or
  // force change) and per-mode factor `transfer`: the mode's index, b g times the factor, and its
  // pole under the contact damping. False for a zero or non-finite input or a mode that does not ring.
  struct RingingInput {
    uint32_t mode;
    Complex bg, pole;
  };
  bool ringingInput(const ObjectInfo& obj, uint32_t j, const double* modal, const Complex* transfer,
                    double extra_damping, RingingInput& out) const {
    const double g = modal[j];
    if (g == 0.0 || !std::isfinite(g)) return false;
    const uint32_t mi = obj.first_mode + j;
    const ModeInfo& m = modes[mi];
    if (m.kind != ModeKind::Ringing) return false;
    out = {mi, g * m.out_weight * (transfer ? transfer[j] : Complex(1.0, 0.0)), m.base_pole - extra_damping};
    return true;
  }

  // True when every mode the impact touches rings (no over- or critically damped ones).
  bool onlyRinging(const ImpactDesc& desc) const {
    const ObjectInfo& obj = objects[desc.object];
    for (uint32_t j = 0; j < obj.mode_count && desc.modal_impulse; ++j)
      if (modes[obj.first_mode + j].kind == ModeKind::Damped && desc.modal_impulse[j] != 0.0) return false;
    return true;
  }

  // A box of force g / tau on [t0, t0 + tau] is, for a ringing mode, exactly two steps: the
  // ringing part of its response is (e^{pU} - H(U - tau) e^{p(U - tau)}) / (p tau), and the rest,
  // the static deflection -1/(p tau) while it acts, cancels the box's own feedthrough g R / tau.
  // So it costs two ideal injections, +-b g / (p tau), however long it lasts (a body resting for
  // seconds), instead of a transient of tau * fs samples.
  ImpactResult addBoxAsSteps(const ImpactDesc& desc, double t0, double tau) {
    const ObjectInfo& obj = objects[desc.object];
    const double tau_s = tau * h;
    const double extra_damping =
        extraDampingAt(obj, std::max<uint64_t>(static_cast<uint64_t>(std::ceil(t0 - 1e-7)), pos));
    // With ramped edges (the box convolved with a unit box of r), each edge is two ramps and
    // the ringing part is e^{pU} / (p^2 tau r) at t0, t0 + r, t0 + tau, t0 + tau + r with signs
    // + - - +; the polynomial parts again cancel the feedthrough g R f. min_freq_hz >= 20 Hz keeps
    // |p r| >= 0.06 for r >= 0.5 ms, so the four injections cancel to at most ~250x float rounding.
    const double ramp = desc.ramp_s * fs;  // samples
    const bool ramped = ramp >= 1e-6 && std::isfinite(ramp);
    const double ramp_s = ramped ? ramp * h : 0.0;
    ++stats.impacts;
    bool audible = false;
    const int edges = ramped ? 4 : 2;
    for (int edge = 0; edge < edges; ++edge) {
      const double te =
          !ramped ? (edge == 0 ? t0 : t0 + tau) : t0 + (edge == 1 || edge == 3 ? ramp : 0.0) + (edge >= 2 ? tau : 0.0);
      if (free_records.empty()) reserveImpacts(std::max<size_t>(16, pool.size() * 2), 0);
      const uint32_t record = free_records.back();
      free_records.pop_back();
      Impact& im = pool[record];
      im.start_sample = im.end_sample = std::max<uint64_t>(static_cast<uint64_t>(std::ceil(te - 1e-7)), pos);
      im.injected = false;
      im.hits.clear();
      im.transient.clear();
      const double after_s = (static_cast<double>(im.start_sample) - te) * h;
      const double sign = (edge == 0 || edge == 3) ? 1.0 : -1.0;
      for (uint32_t j = 0; j < obj.mode_count && desc.modal_impulse; ++j) {
        RingingInput in;
        if (!ringingInput(obj, j, desc.modal_impulse, desc.modal_transfer, extra_damping, in)) continue;
        const Complex bg = in.bg, pole = in.pole;
        const Complex step_amplitude = ramped ? bg / (pole * pole * tau_s * ramp_s) : bg / (pole * tau_s);
        // Audible when the net ringing after the box, |b g (e^{p tau} - 1) / (p tau)|, is (one
        // audible mode is enough: the rest are not asked).
        if (edge == 0 && !audible && std::abs(bg * (std::exp(pole * tau_s) - 1.0) / (pole * tau_s)) >= threshold)
          audible = true;
        im.hits.push_back({in.mode, sign * step_amplitude * std::exp(pole * after_s)});
      }
      auto at = std::upper_bound(pending.begin(), pending.end(), im.start_sample,
                                 [this](uint64_t s0, uint32_t other) { return s0 < pool[other].start_sample; });
      pending.insert(at, record);
    }
    if (!audible) ++stats.impacts_inaudible;
    return ImpactResult::Scheduled;
  }

  // A change dF of a sustained force, ramped linearly over [t0, t0 + r] (r = 0: a step). For a
  // ringing mode the force ramp's response is, besides the static deflection that cancels the
  // force's own feedthrough (as for the box above), e^{pU} b g / (p^2 r) at t0 minus the same at
  // t0 + r, g = phi . dF; for r = 0 one injection b g / p. A non-ringing mode's deviation from its
  // new static deflection starts at (omega0 q, q') = (-g / omega0, 0), taken at the ramp's
  // centroid (such modes decay within a few periods, far shorter than anything heard of a ramp).
  // Cost: two or three injections, whatever the force.
  ImpactResult addForceStep(const ForceStepDesc& desc, bool no_alloc) {
    if (desc.object >= objects.size()) return ImpactResult::BadObject;
    const ObjectInfo& obj = objects[desc.object];
    double t0 = (desc.time_s + obj.delay_s) * fs;
    if (!(t0 >= static_cast<double>(pos))) t0 = static_cast<double>(pos);
    const double ramp = desc.ramp_s * fs;
    const bool ramped = ramp >= 1e-6 && std::isfinite(ramp);
    const double ramp_s = ramped ? ramp * h : 0.0;
    const int ringing_edges = ramped ? 2 : 1;
    bool has_damped = false;
    for (uint32_t j = 0; j < obj.mode_count && desc.modal_force_change; ++j)
      if (modes[obj.first_mode + j].kind == ModeKind::Damped && desc.modal_force_change[j] != 0.0) has_damped = true;
    const size_t records = static_cast<size_t>(ringing_edges) + (has_damped ? 1 : 0);
    if (free_records.size() < records) {
      if (no_alloc) return ImpactResult::NoCapacity;
      reserveImpacts(std::max<size_t>(16, pool.size() * 2 + records), 0);
    }
    if (no_alloc)
      for (size_t k = 0; k < records; ++k)
        if (pool[free_records[free_records.size() - 1 - k]].hits.capacity() < obj.mode_count)
          return ImpactResult::NoCapacity;
    const double extra_damping =
        extraDampingAt(obj, std::max<uint64_t>(static_cast<uint64_t>(std::ceil(t0 - 1e-7)), pos));
    ++stats.impacts;
    bool audible = false;
    auto schedule = [&](Impact& im, uint32_t record) {
      if (im.hits.empty()) {
        free_records.push_back(record);
        return;
      }
      auto at = std::upper_bound(pending.begin(), pending.end(), im.start_sample,
                                 [this](uint64_t s0, uint32_t other) { return s0 < pool[other].start_sample; });
      pending.insert(at, record);
    };
    auto take = [&](double at_sample) {
      const uint32_t record = free_records.back();
      free_records.pop_back();
      Impact& im = pool[record];
      im.start_sample = im.end_sample = std::max<uint64_t>(static_cast<uint64_t>(std::ceil(at_sample - 1e-7)), pos);
      im.injected = false;
      im.hits.clear();
      im.transient.clear();
      return record;
    };
    // The ramp's two edges share each mode's amplitude, and their sub-sample offsets are usually
    // the same bits (the edges a whole number of samples apart): one division per mode, and one
    // exponential where the offsets agree.
    uint32_t edge_record[2] = {0, 0};
    double edge_after_s[2] = {0.0, 0.0};
    for (int edge = 0; edge < ringing_edges; ++edge) {
      const double te = t0 + (edge == 1 ? ramp : 0.0);
      edge_record[edge] = take(te);
      edge_after_s[edge] = (static_cast<double>(pool[edge_record[edge]].start_sample) - te) * h;
    }
    const bool same_offset = std::memcmp(&edge_after_s[0], &edge_after_s[1], sizeof(double)) == 0;
    for (uint32_t j = 0; j < obj.mode_count && desc.modal_force_change; ++j) {
      RingingInput in;
      if (!ringingInput(obj, j, desc.modal_force_change, desc.modal_transfer, extra_damping, in)) continue;
      const Complex bg = in.bg, pole = in.pole;
      const Complex amplitude = ramped ? bg / (pole * pole * ramp_s) : bg / pole;
      // Audible when the net ringing after the ramp, |b g (e^{p r} - 1) / (p^2 r)|, is (one
      // audible mode is enough: the rest are not asked).
      if (!audible) {
        const Complex net = ramped ? amplitude * (std::exp(pole * ramp_s) - 1.0) : amplitude;
        audible = std::abs(net) >= threshold;
      }
      const Complex rise = std::exp(pole * edge_after_s[0]);
      pool[edge_record[0]].hits.push_back({in.mode, amplitude * rise});
      if (ringing_edges == 2) {
        const Complex fall = same_offset ? rise : std::exp(pole * edge_after_s[1]);
        pool[edge_record[1]].hits.push_back({in.mode, -amplitude * fall});
      }
    }
    for (int edge = 0; edge < ringing_edges; ++edge) schedule(pool[edge_record[edge]], edge_record[edge]);
    if (has_damped) {
      const double centroid = t0 + 0.5 * (ramped ? ramp : 0.0);
      // Injected at the ramp's end or later, evolved from the centroid.
      const uint32_t record = take(t0 + (ramped ? ramp : 0.0));
      Impact& im = pool[record];
      const double after_s = (static_cast<double>(im.start_sample) - centroid) * h;
      for (uint32_t j = 0; j < obj.mode_count && desc.modal_force_change; ++j) {
        const double g = desc.modal_force_change[j];
        const uint32_t mi = obj.first_mode + j;
        const ModeInfo& m = modes[mi];
        if (m.kind != ModeKind::Damped || g == 0.0 || !std::isfinite(g)) continue;
        const double gr = g * (desc.modal_transfer ? desc.modal_transfer[j].real() : 1.0);
        const std::array<double, 4> x0{-gr / m.omega0, 0.0, 0.0, 0.0};
        const std::array<double, 4> x =
            detail::mul4(detail::expm4(detail::augmentedMatrix(m.omega0, m.damping_c, 0.0), after_s), x0);
        if (!(dampedAmplitude(m, x[0], x[1]) >= threshold)) continue;
        audible = true;
        im.hits.push_back({mi, Complex(x[0], x[1])});
      }
      schedule(im, record);
    }
    if (!audible) {
      ++stats.impacts_inaudible;
      return ImpactResult::Inaudible;
    }
    return ImpactResult::Scheduled;
  }

  static double dampedAmplitude(const ModeInfo& m, double x1, double v) {
    return std::fabs(m.radiation) * (m.omega0 * std::fabs(x1) + m.damping_c * std::fabs(v));
  }

  // --- render (no allocation, no exceptions) ----------------------------------------------

  void activateRinging(uint32_t mode) {
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

  void removeRinging(size_t i) {
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

  void removeDamped(size_t i) {
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

  void inject(const Impact& im, size_t local) {
    for (const ModeHit& hit : im.hits) {
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
          damped_mode.push_back(hit.mode);  // capacity reserved in addObject
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
  void advance(size_t a, size_t b) {
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
                        roundUp(n_active, detail::kKernelSlotAlign), acc.data(), a, b);
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
  void renderSegment(uint64_t block_start, size_t s0, size_t s1) {
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
    if (!forced.empty()) forcedSegment(block_start, s0, s1);  // continuous force input
  }

  void endBlock() {
    if (use_double) {
      for (size_t i = 0; i < n_active; ++i) mag2[i] = anc_re[i] * anc_re[i] + anc_im[i] * anc_im[i];
    } else if (n_active > 0) {
      kernels.anchor(pb_re.data(), pb_im.data(), anc_re.data(), anc_im.data(), inj_re.data(), inj_im.data(),
                     st_re.data(), st_im.data(), mag2.data(), n_active);
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
  bool scheduleExtraDamping(uint32_t object, double time_s, double extra_decay_per_s, bool no_alloc) {
    if (object >= objects.size() || !(extra_decay_per_s >= 0.0) || !std::isfinite(extra_decay_per_s)) return false;
    const double t = (time_s + objects[object].delay_s) * fs;
    // Changes take effect at block ends: round up to the block grid so impacts know exactly
    // which pole is in force.
    uint64_t sample = t > static_cast<double>(pos) ? static_cast<uint64_t>(std::ceil(t)) : pos;
    sample = (sample + kBlock - 1) / kBlock * kBlock;
    auto& schedule = objects[object].damping_schedule;
    // Entries in the past matter only through the last of them (the pole in force now).
    size_t past = 0;
    while (past + 1 < schedule.size() && schedule[past + 1].first <= pos) ++past;
    if (past > 0) schedule.erase(schedule.begin(), schedule.begin() + static_cast<std::ptrdiff_t>(past));
    if (no_alloc && (schedule.size() == schedule.capacity() || damping_changes.size() == damping_changes.capacity()))
      return false;
    DampingChange change{sample, object, extra_decay_per_s};
    schedule.insert(
        std::upper_bound(schedule.begin(), schedule.end(), std::make_pair(sample, static_cast<double>(INFINITY))),
        std::make_pair(sample, extra_decay_per_s));
    auto at = std::upper_bound(damping_changes.begin(), damping_changes.end(), sample,
                               [](uint64_t s0, const DampingChange& c) { return s0 < c.sample; });
    damping_changes.insert(at, change);
    return true;
  }

  // Exact: the pole moves left by the extra rate, so the mode keeps its frequency and its state
  // continues from where it is; only its decay from here on changes.
  void applyDampingChanges() {
    size_t applied = 0;
    while (applied < damping_changes.size() && damping_changes[applied].sample <= pos) {
      const DampingChange& c = damping_changes[applied++];
      const ObjectInfo& obj = objects[c.object];
      for (uint32_t j = 0; j < obj.mode_count; ++j) {
        ModeInfo& m = modes[obj.first_mode + j];
        if (m.kind != ModeKind::Ringing) continue;
        m.pole = m.base_pole - c.extra_decay_per_s;
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

  // Squared output level of active entry k: ringing slots first, then damped modes.
  float level2(size_t k) const {
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

  size_t sleepModesAtOrBelow(float threshold2, float scale2) {
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

  // Nothing rings and nothing is pending: time passes, and only the contact-damping changes due
  // meanwhile take effect (they move poles of modes that are not ringing).
  void skipIdle(size_t frames) {
    pos += frames;
    applyDampingChanges();
  }

  void reset() {
    while (n_active > 0) removeRinging(n_active - 1);
    while (!damped_mode.empty()) removeDamped(damped_mode.size() - 1);
    for (uint32_t record : pending) free_records.push_back(record);
    pending.clear();
    for (auto& fp : forced) {
      ForcedObject& f = *fp;
      std::fill(f.y_re.data(), f.y_re.data() + f.y_re.size(), 0.0f);
      std::fill(f.y_im.data(), f.y_im.data() + f.y_im.size(), 0.0f);
      std::fill(std::begin(f.on), std::end(f.on), false);
      f.pending.clear();
      f.free_slots = (1u << kForcedPending) - 1;
      f.has_state = false;
    }
    damping_changes.clear();
    for (ObjectInfo& o : objects) o.damping_schedule.clear();
    for (ModeInfo& m : modes) {
      if (m.kind != ModeKind::Ringing) continue;
      m.pole = m.base_pole;
      m.step = m.base_step;
      m.block_step = std::exp(m.pole * (static_cast<double>(kBlock) * h));
    }
    pos = 0;
    stats.active_modes = 0;
  }

  void render(float* out, size_t frames, const float* const* force = nullptr) {
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

  // ---- continuous force input ---------------------------------------------------------------
  void reserveForceInput(uint32_t object) {
    if (object >= objects.size()) return;
    while (forced.size() < objects.size()) forced.push_back(std::make_unique<ForcedObject>());
    ForcedObject& f = *forced[object];
    if (f.reserved()) return;
    const ObjectInfo& obj = objects[object];
    for (uint32_t j = 0; j < obj.mode_count; ++j)
      if (modes[obj.first_mode + j].kind == ModeKind::Ringing)
        f.mode.push_back(obj.first_mode + j), f.local.push_back(j);
    f.count = f.mode.size();
    f.padded = std::max<size_t>(roundUp(f.count, kForcedLanes), kForcedLanes);
    for (auto* b : {&f.y_re, &f.y_im, &f.z_re, &f.z_im}) b->grow(f.padded);
    f.w_re.grow(kForceChannels * f.padded);
    f.w_im.grow(kForceChannels * f.padded);
    f.g.assign(kForceChannels * obj.mode_count, Complex(0.0, 0.0));
    f.pending.reserve(kForcedPending);
    f.pending_g.assign(kForcedPending * obj.mode_count, Complex(0.0, 0.0));
    forced_acc.grow(kBlock * kForcedLanes);
  }

  bool setForceWeights(const ForceWeightsDesc& d) {
    if (d.object >= forced.size() || d.channel >= kForceChannels || !forced[d.object]->reserved()) return false;
    ForcedObject& f = *forced[d.object];
    if (f.free_slots == 0 || f.pending.size() == f.pending.capacity()) return false;
    const ObjectInfo& obj = objects[d.object];
    double t = (d.time_s + obj.delay_s) * fs;
    if (!(t >= static_cast<double>(pos))) t = static_cast<double>(pos);
    uint64_t sample = static_cast<uint64_t>(std::ceil(t - 1e-7));
    sample = (sample + kBlock - 1) / kBlock * kBlock;
    uint32_t slot = 0;
    while (!(f.free_slots & (1u << slot))) ++slot;
    f.free_slots &= ~(1u << slot);
    Complex* g = f.pending_g.data() + static_cast<size_t>(slot) * obj.mode_count;
    for (uint32_t j = 0; j < obj.mode_count; ++j) {
      const Complex v = (d.modal_weight ? d.modal_weight[j] : 0.0) * (d.modal_transfer ? d.modal_transfer[j] : 1.0);
      g[j] = std::isfinite(v.real()) && std::isfinite(v.imag()) ? v : Complex(0.0, 0.0);
    }
    const ForcedObject::Pending p{sample, d.channel, slot, d.modal_weight != nullptr};
    auto at = std::upper_bound(f.pending.begin(), f.pending.end(), sample,
                               [](uint64_t s0, const ForcedObject::Pending& q) { return s0 < q.sample; });
    f.pending.insert(at, p);  // within capacity
    return true;
  }

  bool forceDriven() const {
    for (const auto& f : forced)
      if (f->has_state || !f->pending.empty()) return true;
    return false;
  }

  // At a block start: weight changes due, then the coefficients from the poles in force.
  void forcedBlockStart(uint32_t object, uint64_t block_start) {
    ForcedObject& f = *forced[object];
    const ObjectInfo& obj = objects[object];
    size_t applied = 0;
    while (applied < f.pending.size() && f.pending[applied].sample <= block_start) {
      const ForcedObject::Pending& p = f.pending[applied++];
      std::copy_n(f.pending_g.data() + static_cast<size_t>(p.slot) * obj.mode_count, obj.mode_count,
                  f.g.data() + static_cast<size_t>(p.channel) * obj.mode_count);
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
        const Complex g = f.on[c] ? f.g[static_cast<size_t>(c) * obj.mode_count + f.local[e]] : 0.0;
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

  // Local samples [s0, s1) of the block at block_start: every driven object's forced modes, into mix.
  void forcedSegment(uint64_t block_start, size_t s0, size_t s1) {
    for (uint32_t o = 0; o < forced.size(); ++o) {
      ForcedObject& f = *forced[o];
      if (!f.reserved()) continue;
      if (s0 == 0) forcedBlockStart(o, block_start);
      if (!f.has_state) continue;
      float force[kForceChannels][kBlock];
      bool any[kForceChannels] = {};
      for (uint32_t c = 0; c < kForceChannels; ++c) {
        const float* src = cur_force ? cur_force[o * kForceChannels + c] : nullptr;
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
  }

  // At a block end: an object no channel drives any more hands its forced state to its free modes.
  void forcedMerge() {
    for (auto& fp : forced) {
      ForcedObject& f = *fp;
      if (!f.has_state || f.anyOn()) continue;
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
  }
};

OscillatorBank::OscillatorBank(const SynthSettings& settings) : impl_(std::make_unique<Impl>(settings)) {}
OscillatorBank::~OscillatorBank() = default;
OscillatorBank::OscillatorBank(OscillatorBank&&) noexcept = default;
OscillatorBank& OscillatorBank::operator=(OscillatorBank&&) noexcept = default;

uint32_t OscillatorBank::addObject(const ModalObjectDesc& object) { return impl_->addObject(object); }
ImpactResult OscillatorBank::addImpact(const ImpactDesc& impact) { return impl_->addImpact(impact, false); }
ImpactResult OscillatorBank::addImpactNoAlloc(const ImpactDesc& impact) { return impl_->addImpact(impact, true); }
void OscillatorBank::reserveImpacts(size_t max_pending, double max_pulse_s) {
  const double samples = max_pulse_s * impl_->fs;
  const size_t transient = (samples > 0.0 && std::isfinite(samples)) ? static_cast<size_t>(std::ceil(samples)) + 2 : 2;
  impl_->reserveImpacts(max_pending, transient);
}
bool OscillatorBank::idle() const {
  return impl_->n_active == 0 && impl_->damped_mode.empty() && impl_->pending.empty() && !impl_->forceDriven();
}
void OscillatorBank::reserveForceInput(uint32_t object) { impl_->reserveForceInput(object); }
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
void OscillatorBank::setExtraDamping(uint32_t object, double time_s, double extra_decay_per_s) {
  (void)impl_->scheduleExtraDamping(object, time_s, extra_decay_per_s, false);
}
bool OscillatorBank::setExtraDampingNoAlloc(uint32_t object, double time_s, double extra_decay_per_s) {
  return impl_->scheduleExtraDamping(object, time_s, extra_decay_per_s, true);
}
ImpactResult OscillatorBank::addForceStep(const ForceStepDesc& step) { return impl_->addForceStep(step, false); }
ImpactResult OscillatorBank::addForceStepNoAlloc(const ForceStepDesc& step) { return impl_->addForceStep(step, true); }
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
