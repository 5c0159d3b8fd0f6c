// SPDX-License-Identifier: MIT
// Continuous contact sound: the audio-rate force of a rolling, sliding or scraping contact
// (src/synth/contact_noise.cpp; the model and its derivations are in docs/contact.md, "Rolling,
// sliding and scraping"). Target strike_synth (C++ standard library only).
//
// Each surface has a random height profile: an exponentially correlated (Ornstein-Uhlenbeck)
// process along whatever track the contact draws on it, whose one-sided spatial spectrum
// S(k) = 4 sigma^2 l / (1 + (2 pi k l)^2) falls as k^-2 above 1 / (2 pi l): the spectrum measured
// for a wide range of machined, ground, sawn and natural surfaces [Sayles & Thomas 1978, Nature
// 271, 431-434]. Its random numbers come from a hash of the cells of a cubic grid in the body's
// frame that the contact point crosses, so the same spot of a surface always has the same
// roughness. The contact patch (Hertz radius a) averages the summed profile of both surfaces;
// the result drives a mass (the reduced mass of the two bodies) on the nonlinear contact spring
// (Hertz, F ~ delta^(3/2), or a rough flat contact, F ~ delta) that loses contact when a pit is
// deeper than the static compression [Rath & Rocchesso 2005; van den Doel, Kry & Pai 2001 for
// the profile as the force's source]. The output is the fluctuation of the normal force about the
// mean load, F(t) - N(t), in newtons: the mean itself is the sustained load the contact scheduler
// already carries.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace strike {

/// A surface's roughness (assets/materials.json "roughness_rms_m", "roughness_correlation_m").
struct SurfaceRoughness {
  double rms_m = 0.0;          ///< R_q: rms height of the profile, m. 0: smooth (makes no sound)
  double correlation_m = 0.0;  ///< correlation length l of the profile, m (> 0 when rms_m > 0)
  uint64_t seed = 0;           ///< which surface: the same seed, the same profile
};

/// What a continuous contact between surfaces a and b is made of (fixed while it lasts).
struct RoughContactDesc {
  SurfaceRoughness a, b;
  /// Reduced mass m1 m2 / (m1 + m2) of the bodies along the normal, kg; infinite when neither
  /// can move (a kinematic body on a static one): the contact then follows the profile exactly.
  double mass_kg = INFINITY;
  double modulus_pa = 0.0;     ///< E*: 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2
  double radius_m = INFINITY;  ///< R*: 1/R* = 1/R1 + 1/R2; infinite: flat on flat
  /// Damping ratio of the contact resonance; from the pair's restitution e by
  /// contactDampingRatio(e), so that one bounce on the linearized contact loses what e says.
  double damping_ratio = 0.1;
  double sample_rate_hz = 48000.0;
};

/// The contact at one moment (one physics step), on the generator's sample clock.
struct RoughContactState {
  double normal_force_n = 0.0;                  ///< mean normal load N, N
  double speed_a_m_s = 0.0, speed_b_m_s = 0.0;  ///< how fast the contact point moves over a and b
  std::array<double, 3> spot_a{}, spot_b{};     ///< the contact point in a's and b's frames, m
  double patch_radius_m = 0.0;                  ///< Hertz radius; 0: from the load, E* and R*
};

/// zeta = -ln e / sqrt(pi^2 + ln^2 e): the damping ratio of a linear oscillator whose half
/// period (one bounce) returns the fraction e of the approach speed. e <= 0 gives 1, e >= 1 gives 0.
double contactDampingRatio(double restitution);

/// The audio-rate force of one continuous contact. No allocation: a fixed ring of states.
class RoughContact {
 public:
  static constexpr size_t kMaxStates = 64;
  /// A state older than this (s) with none after it: the contact has ended and the force fades.
  static constexpr double kHold_s = 0.02;
  /// Below this track speed (m/s) a surface is taken to be still (no profile moves).
  static constexpr double kStillSpeed_m_s = 1e-3;
  /// Both surfaces still for this long: the force is 0 (the contact resonance has rung out).
  static constexpr double kSettle_s = 0.01;

  /// Starts a contact at sample `first_sample` of the generator's clock (resets everything).
  void start(const RoughContactDesc& desc, uint64_t first_sample);
  /// Adds the contact's state at (fractional) sample `at`; states must come in time order.
  /// False (dropped) when the ring is full.
  bool push(double at, const RoughContactState& state);
  /// Writes F(t) - N(t) at the next `frames` samples into out (N) and advances.
  void generate(float* out, size_t frames);
  /// Still sounding or still fed: false once it has ended and rung out.
  bool active() const { return active_; }
  uint64_t position() const { return pos_; }
  /// Samples so far in which the contact was lost (a bump threw the bodies apart).
  uint64_t lostSamples() const { return lost_samples_; }
  /// Linear stiffness of the contact at load N and patch a, N/m; 0 when undefined.
  static double stiffness(const RoughContactDesc& desc, double normal_force_n, double patch_radius_m);
  /// Correlation length of the patch filter (two cascaded one-pole spatial low-passes) for
  /// patch radius a: 0.41 a, the roll-off at low wavenumber of the average over the patch diameter.
  static double patchLength(const RoughContactDesc& desc, double patch_radius_m);

 private:
  struct Track {
    double cell_m = 0.0;  // grid spacing in use
    int64_t cell[3] = {0, 0, 0};
    bool placed = false;
    double since_m = 0.0;  // track length since the last new cell
    double h = 0.0;        // profile height, m
  };
  void sampleState(double at, RoughContactState& out, bool& ended) const;
  void advanceTrack(Track& t, const SurfaceRoughness& r, const std::array<double, 3>& spot, double ds_m, double cell_m,
                    int level);

  RoughContactDesc desc_{};
  double fs_ = 48000.0, h_ = 1.0 / 48000.0;
  uint64_t pos_ = 0;
  bool active_ = false;
  std::array<double, kMaxStates> at_{};
  std::array<RoughContactState, kMaxStates> states_{};
  size_t head_ = 0, count_ = 0;  // ring
  Track ta_, tb_;
  double lp1_ = 0.0, lp2_ = 0.0, lp_prev_ = 0.0;  // patch filter and its previous output
  double x_ = 0.0, v_ = 0.0;                      // displacement of the mass away from the surface
  int level_ = -1000;
  double cell_m_ = 0.0;  // the grid spacing of level_, kCellUnit_m * 2^level_
  uint64_t lost_samples_ = 0;
  uint64_t still_samples_ = 0;
};

}  // namespace strike
