// SPDX-License-Identifier: MIT
// The sound engine: what `strike render`, `strike hit` and libstrike all run. Target
// strike_synth (C++ standard library only).
//
// A physics engine reports, every step, where its bodies are (setPose) and the contacts it
// solved (beginStep, contact, endStep). The engine resolves each contact once and its contact
// models (contact_model.hpp) decide what it is; the built-in ones make it
//  - an impact, when the surfaces approach faster than kImpactSpeed_m_s: a Hertz pulse whose
//    length follows from the two materials, radii, masses and the speed [Johnson 1985];
//  - sustained contact otherwise: the step's impulses are a force over the step. A force that
//    stays steady (a body resting) is silent; a change of load is a ramped force step;
//  - while a body is in sustained contact its modes lose energy into what it touches (contact
//    damping), and a body that falls asleep keeps its load;
//  - a sustained contact whose surfaces move over each other (rolling, sliding, scraping) also
//    drives the body's modes at audio rate with the force of its rough surfaces
//    (contact_noise.hpp; contact_sources.cpp): one generator per touching pair and body.
// Each sounding body is a Voice: its modes in an OscillatorBank, its pose, its gain. The
// listener model (strike/core/air.hpp) gives each voice a level from its distance, ramped over each
// render call, and each contact a delay from its own distance. render() mixes the voices and
// keeps the number of ringing modes within a budget, quietest first.
//
// What each impact sends toward the listener (radiation.cpp, for voices whose output is pressure):
//  - a bank with an acoustic transfer (format 5): each mode's far field in the listener's
//    direction in the body frame at the moment of the impact, one complex weight per mode;
//    older banks: the direction-averaged weight;
//  - acceleration noise: the body's rigid translation during the Hertz pulse radiates a click
//    (a dipole with the body's added mass, low-passed as by a sphere of its size) [Chadwick,
//    Zheng & James 2012];
//  - a ground reflection: the same from the listener's mirror image in the ground plane, later
//    and weaker by the path and the reflection coefficient (EngineSettings::ground).
//
// Threads: the engine belongs to one thread (the audio thread in libstrike). Voices are built
// anywhere (makeVoice allocates) and installed by slot; with EngineSettings::realtime nothing
// after that allocates, locks or throws.
#pragma once

#include <array>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "strike/bank/bank.hpp"
#include "strike/core/air.hpp"
#include "strike/synth/air_absorption.hpp"
#include "strike/synth/contact_noise.hpp"
#include "strike/synth/hrtf.hpp"
#include "strike/synth/spatializer.hpp"
#include "strike/synth/synth.hpp"

namespace strike {

/// A contact approaching faster than this is an impact (a Hertz pulse); slower ones are sustained
/// contact. Gravity alone adds g * step = 10 mm/s per 1 ms step to a resting body, five times
/// less; a physics engine may spread one impact over several steps, so the approach speed, not
/// a "new contact" flag, decides.
constexpr double kImpactSpeed_m_s = 0.05;
/// Sustained contacts closer in time than this belong to one contact span (contact damping).
constexpr double kContactGap_s = 0.02;
/// A body's sustained load is steady while its net contact force and moment (about its centre
/// of mass, moment over the body's size) change by less than this fraction of the load since the
/// last change: a physics engine's contact points come and go between steps (2 to 4 points under
/// a resting glass), which moves the load between points without changing it.
constexpr double kSteadyLoadTolerance = 0.02;

constexpr uint32_t kNoVoice = 0xffffffffu;

class ContactModel;  // contact_model.hpp
class VoiceInput;
struct ResolvedContact;

/// World from object (the bank's mesh frame).
struct Pose {
  std::array<double, 3> position_m{};
  std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  ///< row-major
  /// From a position and a quaternion (w, x, y, z; normalized here). False when not finite or
  /// a zero quaternion (pose unchanged).
  bool set(const double position[3], const double orientation_wxyz[4]);
  std::array<double, 3> toWorld(const std::array<double, 3>& local) const;
  std::array<double, 3> toLocalDirection(const std::array<double, 3>& world) const;
  std::array<double, 3> toLocalPoint(const std::array<double, 3>& world) const;
};

/// A flat ground that reflects sound: the plane normal . x = height_m. An image source of every
/// sounding body behind it, weighted by `reflection` (pressure reflection coefficient, 1 =
/// rigid) [Kinsler et al. 2000, sec. 6.3; Allen & Berkley 1979 for image sources].
struct GroundReflection {
  bool enabled = false;
  std::array<double, 3> normal{0, 0, 1};  ///< unit, pointing into the air
  double height_m = 0.0;
  double reflection = 1.0;
};

struct EngineSettings {
  SynthSettings synth;    ///< sample rate, band, audibility threshold, kernel
  uint32_t channels = 1;  ///< 1, or 2: stereo (when `output` is Mono; kept for older callers)
  /// How each path reaches the output's channels (spatializer.hpp); its channel count wins over
  /// `channels`. With directions and a ground, the ground's image is a signal of its own.
  OutputFormat output = OutputFormat::Mono;
  /// The head-related responses of a binaural output, at synth.sample_rate_hz (prepareHrtfSet
  /// done); a binaural output without them hears both ears alike.
  std::shared_ptr<const HrtfSet> hrtf;
  uint32_t max_voices = 64;
  uint32_t max_block_frames = 1024;  ///< largest render() call
  /// Ringing modes over all voices; above it at the end of a render call the quietest (at the
  /// listener) sleep first. 0: no budget.
  uint64_t max_active_modes = 0;
  double reference_distance_m = kReferenceDistance_m;  ///< where the voices' weights hold
  double min_distance_m = kMinListenerDistance_m;      ///< 1/d stops growing here
  double max_contact_duration_s = 0.005;               ///< longer Hertz pulses are shortened to this
  /// Extra modal decay while in sustained contact, 1/s (amplitude); 0 = none. [scene file
  /// "contact_damping"]
  double contact_damping_per_s = 0.0;
  /// The impact rule, decided here and nowhere else: a contact whose surfaces approach faster
  /// than this is an impact (a Hertz pulse), slower a part of its body's load. The render hands
  /// it to the simulation, which times impacts within the step by it.
  double impact_speed_m_s = kImpactSpeed_m_s;
  bool isImpact(double normal_speed_m_s) const { return normal_speed_m_s > impact_speed_m_s; }
  /// No allocation after makeVoice/install: impacts, force steps and damping changes beyond the
  /// reserve are dropped and counted. false (offline renders): the reserve grows.
  bool realtime = true;
  uint32_t max_pending_impacts_per_voice = 32;  ///< realtime reserve of pulses in flight per voice
  GroundReflection ground;                      ///< off unless enabled
  /// Air absorption on every path of every mode (ISO 9613-1, air_absorption.hpp); off: none.
  bool air_absorption = false;
  AirConditions air;
  /// A body that moves while it sounds is heard through a delay line per path that follows its
  /// distance sample by sample: its Doppler shift, and its direction and level from where it
  /// was when the sound left it (docs/listener.md, "Moving sources"). A body at rest sounds as
  /// with this off, to the bit. Off: every contact's delay is fixed when it happens.
  bool moving_sources = true;
};

/// The longest path a moving body's delay line holds: farther, it is heard this late.
constexpr double kMaxMovingDelay_s = 1.0;

/// What a voice is made of. The bank must outlive the voice (libstrike keeps it in a shared
/// pointer, the renderer in its body list).
struct VoiceDesc {
  std::shared_ptr<const ModeBank> bank;
  /// Shapes read only at the surface vertices the contacts touch (ContactProjector::useRows);
  /// empty: the bank's own shapes.
  ShapeRows rows;
  bool use_rows = false;
  /// A SurfaceLocator built for this very `bank` object, or null: the voice builds its own (one
  /// per bank surface: ~5 M instructions for a few thousand triangles).
  std::shared_ptr<const SurfaceLocator> locator;
  /// Per mode: output units per unit modal acceleration at the reference distance (pressure
  /// weights over the output's full scale); empty means 1 (modal acceleration).
  std::vector<double> weights;
  /// Output units per pascal when `weights` are radiationWeights(bank, reference) times this
  /// (a render: gain / kFullScalePascal). 0: the output is not pressure (modal acceleration, or
  /// weights of the caller's own), so no directivity, acceleration noise or ground reflection.
  double pressure_scale = 0.0;
  bool is_static = false;         ///< immovable (a table): infinite mass for Hertz
  double contact_radius_m = 0.0;  ///< curvature radius at contacts; 0 = flat
  Pose pose;
  float gain = 1.0f;
  /// Its surface's roughness (rolling and sliding sound); rms 0: smooth. The seed names the
  /// surface: the same seed, the same profile.
  SurfaceRoughness roughness;
  double restitution = 0.5;  ///< of its material on itself: damps the contact resonance
};

/// The other body in a contact, as the Hertz contact time needs it.
struct ContactPartner {
  double youngs_pa = 0.0;  ///< 0: the same material as the struck body
  double poisson = 0.3;
  double radius_m = 0.0;  ///< 0: flat (a half-space)
  double mass_kg = 0.0;   ///< 0: immovable
  /// Its voice, if it is one: a static body keeps carrying a load whose bodies fell asleep.
  uint32_t voice = kNoVoice;
  /// When it is not a voice: its surface's roughness (the ground's, a silent body's) and
  /// restitution; a voice partner's come from its VoiceDesc.
  SurfaceRoughness roughness;
  double restitution = 0.5;
};

/// The striker of a tap whose caller names none. `strike hit`, the Python package's strike.hit(),
/// libstrike's strike_impact_desc_default() and the LV2 plugin all strike with it, so the same
/// tap sounds the same from each: a steel ball 5 mm in radius (4.11 g), free, that meets the
/// object at the speed giving the tap's impulse in an elastic rebound (tapSpeed). Steel as in
/// assets/materials.json (a test checks that they agree).
constexpr double kDefaultStrikerRadius_m = 0.005;
constexpr double kDefaultStrikerYoungs_pa = 2.0e11;
constexpr double kDefaultStrikerPoisson = 0.29;
constexpr double kDefaultStrikerDensity_kg_m3 = 7850.0;

/// Mass of a ball, kg.
double ballMass(double density_kg_m3, double radius_m);
/// The default striker (kDefaultStriker*) as a contact partner.
ContactPartner defaultStriker();
/// The speed at which a free striker of mass striker_kg (0: immovable) meets a free object of
/// mass object_kg when it rebounds elastically with normal impulse j_normal: J = 2 m* v, with m*
/// the reduced mass. 0 when there is no mass to move.
double tapSpeed(double j_normal_n_s, double striker_kg, double object_kg);

/// One body's side of one contact point in one physics step.
struct EngineContact {
  uint32_t voice = 0;
  bool world_frame = false;         ///< point and impulse in the world (else the mesh frame)
  std::array<double, 3> point{};    ///< m
  std::array<double, 3> impulse{};  ///< applied to this body over the step, N s
  double normal_speed_m_s = 0.0;    ///< approach speed along the normal (> kImpactSpeed_m_s: impact)
  /// When it happened on the engine's clock (seconds since the first sample), the moment the
  /// surfaces met for an impact; < 0: now. Late times start now.
  double time_s = -1.0;
  ContactPartner partner;
  // Continuous contact (rolling, sliding, scraping; contact_sources.cpp). normal_force_n 0: none.
  double normal_force_n = 0.0;  ///< this point's normal load over the step, N
  /// Velocity of this body's surface relative to the partner's at the point, in the tangent
  /// plane, m/s: 0 while they stick (strike_contact::slip_velocity_m_s).
  std::array<double, 3> slip_velocity_m_s{};
  /// Velocity at which the point travels over this body's surface, in the tangent plane, m/s
  /// (strike_contact::rolling_velocity_m_s): a ball rolling at v, v; a block sliding, 0. Only
  /// lengths are used, so any frame: the point travels trackSpeed() over this body and
  /// partnerTrackSpeed() = |rolling + slip| over the partner.
  std::array<double, 3> rolling_velocity_m_s{};
  /// The point in the partner's mesh frame (the world for the ground or a non-voice body), m:
  /// where the partner's roughness is read.
  std::array<double, 3> partner_point{};
  double patch_radius_m = 0.0;  ///< Hertz contact radius, m; 0: from the load
};

/// How fast a contact's point travels over its body's surface, m/s: |rolling_velocity_m_s|.
double trackSpeed(const EngineContact& contact);
/// ...and over the partner's: |rolling_velocity_m_s + slip_velocity_m_s|.
double partnerTrackSpeed(const EngineContact& contact);

/// An explicit contact pulse (strike_impact, `strike hit`): no scheduling, no load tracking.
struct EngineImpact {
  uint32_t voice = 0;
  bool world_frame = false;
  int32_t surface_vertex = -1;  ///< >= 0: at this surface vertex (point ignored)
  std::array<double, 3> point{}, impulse{};
  /// Approach speed for the Hertz time; <= 0: the partner's tapSpeed for the impulse's component
  /// along the surface normal where it strikes (the partner then needs a mass).
  double normal_speed_m_s = 1.0;
  double contact_duration_s = -1.0;  ///< < 0: Hertz; 0: ideal impulse; > 0: this long
  ContactPartner partner;
  double time_s = -1.0;  ///< engine clock; < 0: now
  PulseShape shape = PulseShape::HalfSine;
};

struct EngineStats {
  uint64_t impacts = 0;  ///< contacts that struck (Hertz pulses scheduled)
  uint64_t impacts_inaudible = 0;
  uint64_t impacts_dropped = 0;      ///< realtime reserve full
  uint64_t sustained_contacts = 0;   ///< contact points of sustained contact
  uint64_t load_changes = 0;         ///< force steps scheduled (a load starting, changing, ending)
  uint64_t load_holds = 0;           ///< steps a sleeping body's load was kept
  uint64_t modes_culled = 0;         ///< by the budget
  uint64_t stale = 0;                ///< contacts or impacts on an empty slot
  uint64_t mode_samples = 0;         ///< active modes x samples, voices installed now
  uint64_t forced_mode_samples = 0;  ///< of mode_samples, driven by rolling and sliding (SynthStats)
  uint64_t image_mode_samples = 0;   ///< of mode_samples, the ground image's own free oscillators
  uint64_t modes_total = 0, modes_out_of_band = 0;
  uint64_t max_active_modes = 0;         ///< of any render call's end, all voices
  uint64_t active_modes = 0;             ///< after the last render call
  uint64_t continuous_contacts = 0;      ///< rolling/sliding contact generators started
  uint64_t continuous_dropped = 0;       ///< ...not started: the voice's kForceChannels were in use
  uint64_t continuous_samples = 0;       ///< generator samples computed (cost)
  uint64_t continuous_lost_samples = 0;  ///< samples in which a rough contact lost contact
  /// Engine time just after the last sample in which any continuous contact's force was not 0, s
  /// (-1: none yet): where the rolling and sliding sound stops (the modes then ring on freely).
  double continuous_last_force_s = -1.0;
};

struct VoiceState;      // src/synth/voice_state.hpp
class FractionalDelay;  // src/synth/fractional_delay.hpp

/// One sounding body. Built off the audio thread (allocates everything it will need).
class Voice {
 public:
  Voice(const VoiceDesc& desc, const EngineSettings& settings);
  ~Voice();
  Voice(const Voice&) = delete;
  Voice& operator=(const Voice&) = delete;
  const ModeBank& bank() const;
  SynthStats synthStats() const;

 private:
  friend class SoundEngine;
  std::unique_ptr<VoiceState> state_;
};

class SoundEngine {
 public:
  explicit SoundEngine(const EngineSettings& settings);
  ~SoundEngine();
  SoundEngine(const SoundEngine&) = delete;
  SoundEngine& operator=(const SoundEngine&) = delete;
  const EngineSettings& settings() const { return settings_; }

  // ---- voices (no allocation) ------------------------------------------------------------
  /// Puts a voice in an empty slot < max_voices; the engine does not own it. False if taken.
  bool install(uint32_t slot, Voice* voice);
  /// Empties a slot; returns its voice (the caller frees it, later, off the audio thread).
  Voice* uninstall(uint32_t slot);
  Voice* voice(uint32_t slot) const { return slot < slots_.size() ? slots_[slot] : nullptr; }
  void setPose(uint32_t slot, const Pose& pose, bool asleep = false);
  void setGain(uint32_t slot, float gain);
  void setListener(const Pose& pose);

  // ---- one physics step's contacts ------------------------------------------------------
  /// A step of step_s seconds ending at step_end_s (engine clock). Contacts outside
  /// beginStep/endStep open a step of their own at their time.
  void beginStep(double step_end_s, double step_s);
  /// Resolves the contact once and hands it to the first contact model that takes it
  /// (contact_model.hpp).
  void contact(const EngineContact& contact);
  void endStep();
  /// Asks `model` before the models added earlier and the built-in ones (contact_model.hpp).
  /// Not real-time safe: call before the first contact.
  void addContactModel(std::unique_ptr<ContactModel> model);
  void impact(const EngineImpact& impact);
  /// The Hertz contact time of the voice in `slot` struck by `partner` at normal_speed_m_s
  /// (capped at max_contact_duration_s), s; what contact() and impact() use. 0 for an empty slot.
  double contactDuration(uint32_t slot, const ContactPartner& partner, double normal_speed_m_s) const;

  // ---- audio ---------------------------------------------------------------------------
  /// Renders the next frames (<= max_block_frames) into `channels` planar buffers (overwrites).
  void render(float* const* out, size_t frames);
  double time() const;
  EngineStats stats() const;
  /// Silences everything (modes, pending pulses, loads) and restarts the clock at 0; keeps
  /// the voices and the listener.
  void reset();

 private:
  struct Step {
    bool open = false;
    double end_s = 0.0, length_s = 0.0;
  };
  friend class VoiceInput;
  /// The state of the voice in `slot`, or null.
  VoiceState* state(uint32_t slot) const;
  /// A sustained contact's share of its body's load over the open step (VoiceInput::sustain).
  void sustainedContact(VoiceState& v, const ResolvedContact& c, const double* modal);
  void endStepFor(VoiceState& v);
  void scheduleImpact(VoiceState& v, const double* modal, double time_s, double duration_s, PulseShape shape,
                      const std::array<double, 3>& world_point, const std::array<double, 3>& impulse_local);
  void scheduleForceStep(VoiceState& v, const double* modal_change, double time_s, double ramp_s,
                         const std::array<double, 3>& world_point);
  double hertzDuration(const VoiceState& v, const ContactPartner& p, double speed) const;
  // Continuous contacts (contact_sources.cpp).
  void continuousContact(VoiceState& v, const EngineContact& c, const std::array<double, 3>& world);
  void continuousEndStep(VoiceState& v, bool load_change_follows);
  bool renderContactForces(VoiceState& v, size_t frames);
  void resetContinuous(VoiceState& v);
  double delayTo(const std::array<double, 3>& world_point) const;
  /// The paths from a voice's source point to the listener: the direct one and, with a ground,
  /// its image (sound_paths.cpp; only for a voice whose output is pressure). Returns how many (1
  /// or 2).
  struct Arrival {
    double delay_s = 0.0;               ///< propagation delay
    double gain = 1.0;                  ///< relative to the voice's distance gain
    double distance_m = 0.0;            ///< the path's length
    std::array<double, 3> direction{};  ///< toward the (image) listener, mesh frame, unit
  };
  int arrivals(const VoiceState& v, const std::array<double, 3>& world_point, Arrival out[2]) const;
  /// The per-mode factors for the arrivals along paths [0, count) (0: direct, 1: ground image)
  /// into factors[path]; nullptr when the factor is 1 for every mode. Impacts and load changes
  /// reuse a path's last factors only for the same direction to the bit; a continuous (rolling,
  /// sliding) source also within a bounded angle. The paths that need an evaluation share one
  /// pass over the transfer's coefficients (sound_paths.cpp). Paths [count, also_to) are
  /// evaluated (same-direction rule) only when that pass happens anyway, and kept for a load
  /// change later in the step: the pass reads memory, so a second direction is nearly free.
  enum class Reuse { SameDirection, WithinTolerance };
  static constexpr double kContinuousTransferTolerance = 1e-3;  ///< of a mode's loudest far field
  void radiationToward(VoiceState& v, const Arrival paths[], int count, const std::complex<double>* factors[2],
                       Reuse reuse = Reuse::SameDirection, int also_to = 0);
  void scheduleClick(VoiceState& v, int path, const Arrival& a, double time_s, double duration_s,
                     const std::array<double, 3>& impulse_local);
  void updateGains(VoiceState& v);
  /// The path's factors times each mode's air absorption over distance_m (the voice's scratch),
  /// or `factors` itself when the air absorbs nothing.
  const std::complex<double>* throughAir(VoiceState& v, int path, const std::complex<double>* factors,
                                         double distance_m);
  /// Mixes `mono` (the voice's path signal) into out with gains ramped from cur to target, then
  /// through the path's binaural filters when they are ready (`mono` is scaled in place then).
  void mixPath(float* mono, float* cur, const float* target, BinauralPath& binaural, float* const* out,
               size_t frames) const;
  /// Runs a silent path's binaural filters on zeros while its last input is still in them.
  void flushBinaural(VoiceState& v, int path, float* const* out, size_t frames) const;
  /// The ground's image has oscillators and a signal of its own now (an output with directions,
  /// or a moving body).
  bool imageApart(const VoiceState& v) const;
  // Moving sources (moving_source.cpp).
  /// Keeps the voice's new position on its trajectory and starts or ends its delay lines.
  void followPose(VoiceState& v);
  /// No mode rings, no pulse is pending, nothing drives it: a mode change loses nothing.
  bool silent(const VoiceState& v) const;
  /// Where the voice's sound left from at engine time t_s (its trajectory, linear between the
  /// poses kept, and beyond the newest at its last velocity).
  std::array<double, 3> positionAt(const VoiceState& v, double t_s) const;
  /// The emission time, as a frame on the engine's clock, of what path `path` brings to the
  /// listener at frame `frame`: t - r(t_e) / c = t_e, solved by fixed-point iteration.
  double emissionFrame(const VoiceState& v, int path, uint64_t frame) const;
  /// A moving voice's render: its paths' signals as they leave it, through their delay lines.
  void renderMoving(VoiceState& v, float* const* out, size_t frames, uint64_t& active);
  /// Reads one path's delay line for this call's frames into `heard`; returns the emission
  /// position (frame) of the last one.
  double hearPath(VoiceState& v, int path, float* heard, size_t frames);
  /// A moving voice's call when its lines hold only zeros where they are read: gains and
  /// binaural tails only.
  void hearNothing(VoiceState& v, float* const* out, size_t frames);
  /// updateGains for a moving voice: level and direction of each path from where it was heard.
  void updateMovingGains(VoiceState& v);
  /// Where the ground's mirror image of `point` is, when the image path exists for it.
  bool imageOf(const std::array<double, 3>& point, std::array<double, 3>& image) const;
  /// The synth a path's pulses go to: synth_ for the direct sound, and for the image when it has
  /// no signal of its own (when it has, its pulses go to synth_ as well: voice_state.hpp).
  OscillatorBank& pathSynth(VoiceState& v, int path) const;
  OscillatorBank& pathClicks(VoiceState& v, int path) const;
  /// Contact damping on from time_s (event time, before the delay) heard from world_point.
  void setExtraDamping(VoiceState& v, double time_s, const std::array<double, 3>& world_point, double per_s);
  void enforceBudget(uint64_t& active);

  EngineSettings settings_;
  std::vector<std::unique_ptr<ContactModel>> models_;  ///< asked in order
  std::vector<Voice*> slots_;
  Pose listener_;
  Step step_;
  uint64_t frames_ = 0;
  std::vector<uint32_t> histogram_;
  EngineStats stats_;
  std::shared_ptr<const FractionalDelay> fractional_delay_;  ///< moving voices' interpolator
};

}  // namespace strike
