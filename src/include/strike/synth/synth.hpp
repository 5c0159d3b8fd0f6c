// SPDX-License-Identifier: MIT
// The oscillator bank: the modes of one struck object advanced exactly, sample by sample, and
// summed. Target strike_synth: C++ standard library only (SIMD intrinsics allowed); no allocation
// in render() once its capacity is set up.
//
// Each mode i of an object obeys  q'' + c q' + lambda q = g_i f(t)  (mass-normalized modal
// coordinate q, c = a1 lambda + a2, f a unit-area force pulse, g_i = phi_i(p) . J the modal
// impulse). The state advances by its exact discrete-time transition (a complex multiply for
// under-damped modes), so there is no step-size limit and any damping is stable.
#pragma once

#include <algorithm>
#include <array>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "strike/core/band.hpp"
#include "strike/bank/bank.hpp"
#include "strike/bank/radiation_strength.hpp"

namespace strike {

/// Which oscillator kernel render() uses. Auto picks the widest the CPU supports at run time; a
/// level the CPU lacks falls back to the next narrower one (see OscillatorBank::simdName()).
enum class SimdLevel { Auto, Scalar, Avx2, Avx512 };

/// What an oscillator bank does when a pulse, a force step or a damping change needs more than
/// it reserved (OscillatorBank::reserveImpacts): set once, for the bank's life.
enum class Allocation {
  Grow,      ///< offline renders: the reserve grows (allocates)
  Reserved,  ///< real time: never allocates, locks or throws; what does not fit is dropped
};

struct SynthSettings {
  double sample_rate_hz = kDefaultSampleRateHz;
  double min_freq_hz = 20.0;     ///< modes below are not synthesized
  double max_freq_hz = kDefaultMaxFreqHz;  ///< modes above synthesizedTopHz(this, sample rate) are not synthesized
  /// Output amplitude (same units as the output) below which a mode is not started and at which
  /// a ringing mode goes to sleep. Default ~ -120 dB re full scale 1.0.
  double audibility_threshold = 1e-6;
  bool double_precision = false;     ///< reference path: double state, no SIMD (for accuracy studies)
  SimdLevel simd = SimdLevel::Auto;  ///< float path only; for tests and benchmarks
  Allocation allocation = Allocation::Grow;
};

/// Samples between re-anchorings of the float oscillator state to its double-precision anchor
/// (oscillator_bank.cpp). Blocks lie on a fixed grid from sample 0, so the output does not depend
/// on how many frames each render() call asks for.
constexpr size_t kSynthAnchorBlock = 128;

/// The modes of one sounding object as the synth needs them.
struct ModalObjectDesc {
  std::vector<double> eigenvalues;  ///< lambda_i, rad^2/s^2
  double rayleigh_stiffness = 0.0;  ///< a1, s
  double rayleigh_mass = 0.0;       ///< a2, 1/s
  /// Optional per-mode damping c_i (1/s) instead of Rayleigh's: the acceleration-noise filters,
  /// whose damping is not a material's (engine.cpp).
  std::vector<double> damping_c;
  /// Per mode: output units per unit modal acceleration (m/s^2 * sqrt(kg)). Output sample =
  /// sum_i radiation_weight_i * q_i''(t - delay), where q'' excludes the feedthrough g_i f(t) of
  /// the force pulse itself (see oscillator_bank.cpp). Build it with radiationWeights(). Empty
  /// means 1 for every mode (output = modal acceleration); a shorter vector means 0 for the rest.
  std::vector<double> radiation_weight;
  double delay_s = 0.0;  ///< propagation delay to the listener
};

/// The time course of a contact force of unit area.
enum class PulseShape {
  /// (pi / (2 tau)) sin(pi t / tau): the Hertz impact of two elastic bodies [Johnson 1985].
  HalfSine,
  /// 1 / tau: a steady force over a physics step. Contiguous boxes of equal impulse add up to a
  /// constant force, which makes no sound once its onset has rung out (resting contact).
  Box,
};

/// One contact: a force pulse of `duration_s` (0 = ideal impulse) starting at `time_s`, of total
/// impulse 1 N s, scaled per mode by modal_impulse[i] = phi_i(p) . J.
struct ImpactDesc {
  double time_s = 0.0;
  double duration_s = 0.0;
  const double* modal_impulse = nullptr;  ///< one per mode of the object (N s / sqrt(kg))
  PulseShape shape = PulseShape::HalfSine;
  /// Box only: edges ramped linearly over ramp_s (the box convolved with a unit-area box of
  /// ramp_s), so a sequence of physics-step boxes becomes the linear interpolation of the step
  /// forces instead of a staircase whose steps ring at the step rate and its harmonics. The pulse
  /// spans [time_s, time_s + duration_s + ramp_s). 0 = sharp edges. Applied when every mode the
  /// impact touches rings; an object with over-damped modes gets the sharp box.
  double ramp_s = 0.0;
  /// Optional, one per mode: a complex factor on each mode's output from this impact, in the
  /// bank's e^{+i omega t} convention: a ringing mode's output Re(yhat) becomes Re(factor yhat),
  /// its radiation turned in phase and scaled (the acoustic transfer toward the listener, the
  /// conjugate of acoustic_transfer.hpp's F). Non-ringing modes take its real part. Null: 1.
  const std::complex<double>* modal_transfer = nullptr;
};

/// A change of a sustained contact force (a body coming to rest, carrying a load, being pushed),
/// ramped linearly from time_s to time_s + ramp_s; the new force then holds until the next change.
/// A constant force makes no sound once its onset has rung out, so a body resting for seconds
/// costs its one or two changes, not a pulse per physics step.
struct ForceStepDesc {
  double time_s = 0.0;
  double ramp_s = 0.0;  ///< 0: a sharp step
  /// One per mode of the object: phi_i(p) . dF summed over the contact points, N / sqrt(kg).
  const double* modal_force_change = nullptr;
  const std::complex<double>* modal_transfer = nullptr;  ///< as ImpactDesc::modal_transfer
};

/// Continuous force inputs of one object (rolling, sliding, scraping: contact_noise.hpp): each
/// channel is one contact's force signal, in newtons, driving every ringing mode of the object
/// with its own weight.
constexpr uint32_t kForceChannels = 4;

/// A channel's modal weights from a time on (OscillatorBank::setForceWeights).
struct ForceWeightsDesc {
  uint32_t channel = 0;  ///< < kForceChannels
  double time_s = 0.0;   ///< from the first 128-sample block boundary at or after it (plus the delay)
  /// One per mode of the object: g_i = phi_i(p) . d, the modal force per newton of the channel's
  /// signal (d: the direction of the force on the body, its normal plus its friction share),
  /// 1/sqrt(kg). Copied. Null: the channel stops (its modes ring on freely).
  const double* modal_weight = nullptr;
  /// As ImpactDesc::modal_transfer (the direction toward the listener), multiplied into each
  /// weight (the feedthrough follows, so a steady force stays silent). Copied. Null: 1.
  const std::complex<double>* modal_transfer = nullptr;
};

/// What addImpactNoAlloc() did with an impact.
enum class ImpactResult {
  Scheduled,   ///< will sound
  Inaudible,   ///< changed no mode above the audibility threshold; nothing scheduled
  NoCapacity,  ///< dropped: no free reserved record, or the pulse is longer than reserved
};

struct SynthStats {
  uint64_t modes_total = 0;        ///< of the object
  uint64_t modes_out_of_band = 0;  ///< never synthesized (below min or above max frequency)
  uint64_t impacts = 0;
  uint64_t impacts_inaudible = 0;  ///< changed no mode above the threshold
  uint64_t mode_starts = 0;        ///< a sleeping mode woken by an impact
  uint64_t mode_samples = 0;       ///< work done: active modes x samples rendered
  /// Of mode_samples, those of the copies a rolling or sliding contact drives (a mode may ring
  /// free and be driven by several contacts at once, so mode_samples may exceed modes x samples).
  uint64_t forced_mode_samples = 0;
  uint64_t max_active_modes = 0;
  uint64_t active_modes = 0;  ///< ringing now (after the last completed render call)
};

class OscillatorBank {
 public:
  /// The object's modes (a ModalObjectDesc with none: a bank that stays silent). Not real-time
  /// safe: allocates capacity for all of its modes being active at once, so render() never has to.
  OscillatorBank(const SynthSettings& settings, const ModalObjectDesc& object);
  ~OscillatorBank();
  OscillatorBank(OscillatorBank&&) noexcept;
  OscillatorBank& operator=(OscillatorBank&&) noexcept;

  /// Schedules an impact. Impacts may be added in any order, but not before the current render
  /// time (late ones start at the current sample). Copies modal_impulse. It integrates the pulse
  /// for every mode (O(modes x pulse samples)). Contributions below audibility_threshold are
  /// dropped (the mode is not woken). Allocation::Grow: may allocate. Allocation::Reserved:
  /// real-time safe [audio-thread], on the thread that calls render(); NoCapacity when no
  /// reserved record is free or the pulse is longer than reserved.
  ImpactResult addImpact(const ImpactDesc& impact);
  /// Preallocates records for max_pending impacts that are scheduled but not yet fully injected,
  /// each able to hold an impact on every mode with a pulse of up to max_pulse_s. Not real-time safe.
  void reserveImpacts(size_t max_pending, double max_pulse_s);
  /// Renders the next `frames` mono samples into out (overwrites). Sample n of the first call is
  /// time n / sample_rate. Output units are those of radiation_weight (Pa at the listener with
  /// radiationWeights()). [audio-thread] Never allocates, locks or throws; sets FTZ/DAZ in MXCSR
  /// for the call and restores it. Output is independent of how frames are split across calls.
  void render(float* out, size_t frames);
  /// render(), but when idle() only the clock moves (out gets zeros if not null): the same result
  /// at no cost. [audio-thread]
  void skip(float* out, size_t frames);
  /// Silences every mode, drops pending impacts and contact damping, and restarts the clock at
  /// 0 (the modes and reserves stay). Real-time safe.
  void reset();
  /// True when no mode is ringing and no impact is pending: render() would output zeros.
  bool idle() const;
  /// Modes ringing now (ringing and non-ringing kinds).
  size_t activeModeCount() const;
  /// Writes the squared output level (output units^2, before any gain applied outside) of up
  /// to `capacity` active modes, in an internal order; returns how many. Real-time safe.
  size_t activeModeLevels(float* level2, size_t capacity) const;
  /// Puts every active mode whose squared level times scale2 is <= level2 to sleep (budget
  /// culling; the float product is the same as level * scale2 computed by the caller from
  /// activeModeLevels()); returns how many. Real-time safe; call between render() calls.
  size_t sleepModesAtOrBelow(float level2, float scale2 = 1.0f);
  /// From time_s on, the object's ringing modes decay faster by extra_decay_per_s (1/s, amplitude;
  /// 0 restores the material's damping). Applied exactly at the first 128-sample block boundary
  /// at or after time_s (plus the object's delay): the pole moves left, the state carries on.
  /// Models energy an object loses into what it rests on (contact damping). Allocation::Reserved:
  /// real-time safe, false (nothing scheduled) when the object already has 64 changes pending.
  bool setExtraDamping(double time_s, double extra_decay_per_s);
  /// Schedules a change of sustained force (ForceStepDesc); Inaudible when no mode's ringing from
  /// it reaches the audibility threshold. Allocation::Grow: may grow the impact records.
  /// Allocation::Reserved: real-time safe, NoCapacity when fewer than three reserved impact
  /// records are free.
  ImpactResult addForceStep(const ForceStepDesc& step);
  /// Prepares the object for continuous force input (setForceWeights, render with force). Not
  /// real-time safe (allocates a state per ringing mode and channel weights).
  void reserveForceInput();
  /// Schedules a channel's weights (ForceWeightsDesc) without allocation [audio-thread]. False
  /// when the object was not reserved, the channel is out of range, or 8 changes are pending.
  bool setForceWeights(const ForceWeightsDesc& weights);
  /// render() with force signals: force[c] (or force itself, or any
  /// entry, null: zeros) holds `frames` samples of channel c, in newtons, each held over its
  /// sample. A driven mode advances exactly for the sample-held force, y <- e^{ph} y + F (e^{ph} -
  /// 1) / p, from a state of its own while any channel is on, summed with the mode's free state by
  /// linearity and merged into it at the first block end after the last channel stops; its
  /// output includes the force's feedthrough sum_i R_i g_i F (a slow force then gives the
  /// acceleration it should: almost none). Same guarantees as render(). [audio-thread]
  void render(float* out, size_t frames, const float* const* force);
  /// True while a force channel is on or a driven state is not yet merged.
  bool forceDriven() const;
  /// Time of the next sample to be rendered, s.
  double time() const;
  SynthStats stats() const;
  /// The kernel in use: "scalar", "avx2", "avx512" or "double".
  const char* simdName() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Modal impulse g_i = phi_i(p) . J for an impulse J (N s, mesh frame) at point p (metres, mesh
/// frame): p is projected onto the nearest surface triangle and the shapes are interpolated
/// barycentrically. Returns #modes values.
std::vector<double> projectImpulse(const ModeBank& bank, const double point[3], const double impulse[3]);

/// Finds the nearest surface point of a bank quickly (a uniform grid over its triangles), for
/// renders that project many contacts. Built once per bank (allocates); queries do not allocate.
/// The bank must outlive the locator.
class SurfaceLocator {
 public:
  explicit SurfaceLocator(const ModeBank& bank);
  /// The nearest point to `point` (mesh frame) as a triangle's vertices and barycentric weights.
  void nearest(const double point[3], uint32_t vertices[3], double weights[3]) const;
  /// projectImpulseInto with this locator: the same result, found in O(1) instead of O(#F).
  void projectImpulseInto(const double point[3], const double impulse[3], double* out) const;
  /// False when the bank has no usable triangles (projection falls back to the nearest vertex).
  bool hasTriangles() const { return !cell_tris_.empty(); }
  /// Whether it was built for this very bank object (it keeps a pointer to it).
  bool builtFor(const ModeBank& bank) const { return bank_ == &bank; }

 private:
  const ModeBank* bank_;
  double origin_[3] = {0, 0, 0};
  double cell_m_ = 1.0;
  int dims_[3] = {1, 1, 1};
  std::vector<uint32_t> cell_start_;  ///< CSR: triangles of cell c are cell_tris_[cell_start_[c] .. cell_start_[c+1])
  std::vector<uint32_t> cell_tris_;
};
/// SurfaceLocator::projectImpulseInto with a memory of the last `max_points` points: a resting
/// body's contacts sit on the same hull vertices step after step (the 20-plate render benchmark:
/// 230,000 sustained contacts at 1,600 distinct points), so a repeated point skips the nearest-
/// triangle search and reads its three vertices' shapes from one contiguous row instead of three
/// gathers 12 bytes x #V apart per mode. Same arithmetic, so the same result to the bit. The bank
/// must outlive the projector. The constructor reserves all its memory; projecting never allocates.
class ContactProjector {
 public:
  explicit ContactProjector(const ModeBank& bank, size_t max_points = 64);
  /// With a locator already built for this bank (SurfaceLocator::builtFor; else one is built):
  /// a render that located its contacts to read the shapes they touch builds it once.
  ContactProjector(const ModeBank& bank, std::shared_ptr<const SurfaceLocator> locator, size_t max_points = 64);
  /// Projects with these shape rows instead of bank.shapes (a bank opened with BankFile, whose
  /// shapes are read only at the vertices its contacts touch). The rows must hold every vertex
  /// locator().nearest() gives for the points projected; a missing vertex projects to zero.
  void useRows(ShapeRows rows);
  const SurfaceLocator& locator() const { return *locator_; }
  void projectImpulseInto(const double point[3], const double impulse[3], double* out);
  /// The same result without remembering the point: for a point that will not come back (an
  /// impact), where filling the memory's row (9 floats per mode) would cost more than it saves.
  void projectOnce(const double point[3], const double impulse[3], double* out) const;

 private:
  std::shared_ptr<const SurfaceLocator> locator_;
  const ModeBank* bank_;
  bool use_rows_ = false;
  ShapeRows rows_;
  size_t max_points_;
  size_t next_ = 0;              ///< slot to overwrite when full (round robin)
  std::vector<double> points_;   ///< 3 per remembered point
  std::vector<double> weights_;  ///< 3 barycentric weights per point
  std::vector<float> shapes_;    ///< per point: [vertex 0..2][xyz] planes of #modes
};
/// Same, at surface vertex v.
std::vector<double> projectImpulseAtVertex(const ModeBank& bank, size_t vertex, const double impulse[3]);
/// projectImpulse() into out[0 .. #modes) without allocating (real-time safe; O(#triangles +
/// #modes)).
void projectImpulseInto(const ModeBank& bank, const double point[3], const double impulse[3], double* out);
/// projectImpulseAtVertex() into out[0 .. #modes) without allocating (O(#modes)).
void projectImpulseAtVertexInto(const ModeBank& bank, size_t vertex, const double impulse[3], double* out);

/// Hertz contact duration of two elastic bodies meeting at normal speed v_n (m/s):
/// tau = 2.868 (m*^2 / (R* E*^2 v_n))^(1/5), 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2,
/// 1/R* = 1/R1 + 1/R2, 1/m* = 1/m1 + 1/m2 (Johnson, Contact Mechanics, 1985, ch. 11).
/// Pass infinite mass or radius for a half-space. Returns seconds; 0 (an ideal impulse) when the
/// speed is not positive or the input is degenerate (e.g. two half-spaces, NaN).
double hertzContactDuration(double youngs1_pa, double poisson1, double radius1_m, double mass1_kg, double youngs2_pa,
                            double poisson2, double radius2_m, double mass2_kg, double normal_speed_m_s);

/// The output level convention of the tools and (by default, output_full_scale_pa) of libstrike:
/// sample value 1.0 = 20 Pa (120 dB SPL, the threshold of pain) at the listener, so no physically
/// plausible level clips, and the synthesizer's default audibility threshold of 1e-6 full scale
/// is 20 uPa: the threshold of hearing (0 dB SPL).
constexpr double kFullScalePascal = 20.0;

/// Listener model, per mode, for a listener at distance_m from the object (see radiation.cpp for
/// the approximation and what it leaves out). Returns #modes weights for ModalObjectDesc
/// that make the output sound pressure in Pa; divide them by kFullScalePascal for full scale.
std::vector<double> radiationWeights(const ModeBank& bank, double distance_m);
/// Output units per pascal of a voice at `gain` on an output whose 1.0 is full_scale_pa pascals
/// (the tools: kFullScalePascal; libstrike: its output_full_scale_pa, the object's gain apart).
inline double outputPerPascal(double gain, double full_scale_pa = kFullScalePascal) { return gain / full_scale_pa; }
/// A voice's pressure weights (VoiceDesc::weights, with pressure_scale = output_per_pa): the
/// radiated pressure at reference_distance_m per unit modal acceleration, radiationWeights, in
/// output units. The one place the render, `strike hit` and libstrike turn pressure into output.
std::vector<double> pressureWeights(const ModeBank& bank, double reference_distance_m, double output_per_pa);
/// Per mode, the radiation efficiency of its acoustic transfer: radiated power over
/// rho c <|v_n|^2> S / 2, the power of the same surface velocity as a plane wave [Fahy &
/// Gardonio, Sound and Structural Vibration, 2007, sec. 3.4]. Zero for a mode without one.
std::vector<double> radiationEfficiency(const ModeBank& bank);

}  // namespace strike
