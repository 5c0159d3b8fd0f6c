// SPDX-License-Identifier: MIT
// The oscillator bank's state, shared by the files that each do one of its jobs (private to
// src/synth; the method and its maths are described in oscillator_bank.cpp):
//  - oscillator_bank.cpp  the object's modes (setup), the public API, reset and budget culling;
//  - oscillator_pulses.cpp  scheduling: Hertz and box pulses, force steps, contact damping;
//  - oscillator_render.cpp  the render loop: injections, the kernels, block ends, sleeping;
//  - oscillator_force.cpp  continuous force input (rolling, sliding; contact_noise.hpp).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <new>
#include <utility>
#include <vector>

#include "kernels.hpp"
#include "modal_math.hpp"
#include "strike/synth/synth.hpp"

namespace strike::detail {

constexpr size_t kBlock = kSynthAnchorBlock;
// Below ~-600 dB nothing is audible whatever the threshold; also keeps doubles out of denormals.
constexpr double kThresholdFloor = 1e-30;
// Contact-damping changes the object may have pending at once without allocating (a contact
// span opens and closes at most once per physics step, and only changes within the listener
// delay and the scheduling lead are pending).
constexpr size_t kDampingReserve = 64;

inline size_t roundUp(size_t n, size_t m) { return (n + m - 1) / m * m; }

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
  // A ringing mode's responses to the object's last pulse that depend only on the pole and the
  // pulse (addImpact): the state at the pulse's end, and the transient's one-sample step. An
  // impact heard along two paths (direct and the ground's image) asks for them twice with the
  // same pulse; each stamp says for which pulse (PulseMemo::stamp) it holds, 0: none.
  uint64_t end_stamp = 0, step_stamp = 0;
  Complex pulse_end;
  ExpPair pulse_step;
};

// The pulse the modes' pulse_end and pulse_step belong to: duration, contact damping (bits)
// and shape; a new one takes a new stamp.
struct PulseMemo {
  double tau_s = -1.0, extra_damping = 0.0;
  bool box = false;
  uint64_t stamp = 0;
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

// Continuous force input: the object's ringing modes get a second state, advanced with the
// force, summed with the free state by linearity and merged into it after the force stops
// (forcedMerge). Kept apart so that impacts, sleeping and the float anchors of the free modes
// are untouched.
constexpr size_t kForcedLanes = 8;
constexpr size_t kForcedGroups = kForcedLanes / 4;  // Float4s per group of modes
constexpr size_t kForcedPending = 8;                // weight changes pending
struct ForcedModes {
  size_t count = 0, padded = 0;  // ringing modes, and rounded up to kForcedLanes
  std::vector<uint32_t> mode;    // mode index per entry
  AlignedBuffer<float> y_re, y_im, z_re, z_im;
  AlignedBuffer<float> w_re, w_im;  // kForceChannels x padded: b g (e^{ph} - 1) / p
  std::vector<Complex> g;           // kForceChannels x mode count: the weights in force, x transfer
  double feed[kForceChannels] = {};
  bool on[kForceChannels] = {};
  struct Pending {
    uint64_t sample;
    uint32_t channel, slot;
    bool on;
  };
  std::vector<Pending> pending;    // sorted by sample; capacity kForcedPending
  std::vector<Complex> pending_g;  // kForcedPending x mode count
  uint32_t free_slots = (1u << kForcedPending) - 1;
  bool has_state = false;
  bool reserved() const { return !mode.empty() || padded > 0; }
  bool anyOn() const {
    for (bool b : on)
      if (b) return true;
    return false;
  }
};

}  // namespace strike::detail

namespace strike {

struct OscillatorBank::Impl {
  using Complex = detail::Complex;
  using ModeInfo = detail::ModeInfo;
  using Impact = detail::Impact;
  template <typename T>
  using AlignedBuffer = detail::AlignedBuffer<T>;

  SynthSettings settings;
  double fs = 48000.0, h = 1.0 / 48000.0;
  double threshold = detail::kThresholdFloor;
  bool use_double = false;
  bool reserved = false;  // Allocation::Reserved: scheduling never grows the pool
  detail::KernelTable kernels{};

  // The object: its modes, its delay to the listener, its scheduled contact damping ((sample,
  // extra decay per s), sorted by sample) and the pulse its modes remember.
  std::vector<ModeInfo> modes;
  double delay_s = 0.0;
  std::vector<std::pair<uint64_t, double>> damping_schedule;
  detail::PulseMemo pulse;
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

  // Scheduled changes of the extra damping (contact damping), applied at block ends: (sample,
  // extra decay per s), sorted by sample; capacity kDampingReserve.
  std::vector<std::pair<uint64_t, double>> damping_changes;
  SynthStats stats;

  // Continuous force input (oscillator_force.cpp); reserved by reserveForceInput.
  detail::ForcedModes forced;
  AlignedBuffer<float> forced_acc;  // kBlock x kForcedLanes
  const float* const* cur_force = nullptr;
  uint64_t call_start = 0;  // pos at the start of the current render() call

  // oscillator_bank.cpp: the object's modes, every buffer sized for all of them at once.
  Impl(const SynthSettings& s, const ModalObjectDesc& object);
  void setUpModes(const ModalObjectDesc& desc);
  void reset();
  float level2(size_t k) const;
  size_t sleepModesAtOrBelow(float threshold2, float scale2);
  static double dampedAmplitude(const ModeInfo& m, double x1, double v) {
    return std::fabs(m.radiation) * (m.omega0 * std::fabs(x1) + m.damping_c * std::fabs(v));
  }

  // oscillator_pulses.cpp: scheduling (no_alloc, from `reserved`: NoCapacity rather than growing
  // the pool).
  void reserveImpacts(size_t records, size_t max_transient);
  double extraDampingAt(uint64_t sample) const;
  ImpactResult addImpact(const ImpactDesc& desc, bool no_alloc);
  struct PulseTiming;
  void ringingHit(uint32_t mode, double g, Complex factor, const PulseTiming& pulse_timing, Impact& im);
  void dampedHit(uint32_t mode, double g_real, const PulseTiming& pulse_timing, Impact& im) const;
  struct RingingInput {
    uint32_t mode;
    Complex bg, pole;
  };
  bool ringingInput(uint32_t j, const double* modal, const Complex* transfer, double extra_damping,
                    RingingInput& out) const;
  bool onlyRinging(const ImpactDesc& desc) const;
  ImpactResult addBoxAsSteps(const ImpactDesc& desc, double t0, double tau);
  ImpactResult addForceStep(const ForceStepDesc& desc, bool no_alloc);
  void insertPending(uint32_t record);
  uint32_t takeRecord(double at_sample);
  bool scheduleExtraDamping(double time_s, double extra_decay_per_s, bool no_alloc);

  // oscillator_render.cpp: the render loop (no allocation, no exceptions).
  void render(float* out, size_t frames, const float* const* force = nullptr);
  void skipIdle(size_t frames);
  void activateRinging(uint32_t mode);
  void removeRinging(size_t i);
  void removeDamped(size_t i);
  void inject(const Impact& im, size_t local);
  void advance(size_t a, size_t b);
  void renderSegment(uint64_t block_start, size_t s0, size_t s1);
  void endBlock();
  void applyDampingChanges();

  // oscillator_force.cpp: continuous force input.
  void reserveForceInput();
  bool setForceWeights(const ForceWeightsDesc& d);
  bool forceDriven() const { return forced.has_state || !forced.pending.empty(); }
  void forcedBlockStart(uint64_t block_start);
  void forcedSegment(uint64_t block_start, size_t s0, size_t s1);
  void forcedMerge();
};

}  // namespace strike
