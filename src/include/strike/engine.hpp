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
// listener model (listener.hpp) gives each voice a level from its distance, ramped over each
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

#include "strike/air_absorption.hpp"
#include "strike/bank.hpp"
#include "strike/contact_noise.hpp"
#include "strike/listener.hpp"
#include "strike/spatializer.hpp"
#include "strike/synth.hpp"

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
};

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
  /// Contact points that `locator` has located already (ContactProjector::useLocated); used only
  /// with that locator.
  LocatedPoints located;
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

/// One sounding body. Built off the audio thread (allocates everything it will need).
class Voice {
 public:
  Voice(const VoiceDesc& desc, const EngineSettings& settings);
  ~Voice();
  Voice(const Voice&) = delete;
  Voice& operator=(const Voice&) = delete;
  const ModeBank& bank() const { return *bank_; }
  SynthStats synthStats() const { return synth_.stats(); }

 private:
  friend class SoundEngine;
  friend class VoiceInput;
  void setUpRadiation(const VoiceDesc& desc, const EngineSettings& settings);  // sound_paths.cpp's data
  std::shared_ptr<const ModeBank> bank_;
  OscillatorBank synth_;
  OscillatorBank click_synth_;     ///< acceleration noise: three filters, one per axis (sound_paths.cpp)
  bool rings_ = false;             ///< has a mode in the synthesized band
  std::vector<float> click_mono_;  ///< max_block_frames
  ContactProjector projector_;
  std::vector<double> modal_;       ///< #modes: projection scratch
  std::vector<double> step_force_;  ///< #modes: this step's sustained modal force (N / sqrt(kg))
  std::vector<double> held_force_;  ///< #modes: the sustained modal force in force now
  std::vector<float> mono_;         ///< max_block_frames
  std::vector<float> levels_;       ///< #modes: budget scratch
  // Radiation toward the listener (radiation.cpp).
  bool pressure_ = false;             ///< output is pressure (VoiceDesc::pressure_scale > 0)
  std::vector<double> sh_;            ///< spherical harmonics scratch, (max order + 1)^2
  SphericalHarmonicsTable sh_table_;  ///< their recurrence's constants to the max order
  CompactTransfer transfer_;          ///< the bank's transfer as evaluations read it
  /// Scratch for one pass over the transfer's coefficients, which evaluates up to two directions
  /// (the paths that need it): each one's farFieldWeights of sh_, and its F_i for the #modes.
  std::array<std::vector<float>, 2> weights_;
  std::array<std::vector<std::complex<double>>, 2> far_field_;
  /// The per-mode factors handed to the oscillators for one path (direct, ground image), kept
  /// with the direction and gain they were evaluated for: a body that has not turned relative to
  /// the listener since its last event (resting, static, or several events in one physics step)
  /// reuses them, bit for bit, instead of evaluating its far field again.
  struct PathTransfer {
    std::vector<std::complex<double>> factor;  ///< #modes
    std::array<double, 3> direction{};
    double gain = 0.0;
    bool valid = false;
  };
  std::array<PathTransfer, 2> path_transfer_;
  /// Air absorption (EngineSettings::air_absorption): per mode, nepers of amplitude per metre;
  /// and per path, the factors with the air's gain in them (scratch).
  std::vector<double> air_np_per_m_;
  std::array<std::vector<std::complex<double>>, 2> air_factor_;
  std::vector<double> inv_rms_;                           ///< #modes: 1 / rms_d |F_i| (0 for a silent mode)
  bool clicks_ = false;                                   ///< acceleration noise (a free body with mass)
  std::array<std::array<double, 3>, 3> click_axis_{};     ///< principal axes of the dipole tensor, mesh frame
  std::array<double, 3> click_moment_m3_{};               ///< its eigenvalues
  std::array<std::complex<double>, 3> click_gain_{};      ///< lambda_j / p_j of each click filter
  std::array<double, 3> click_force_{};                   ///< scratch: rigid acceleration impulse per axis
  std::array<std::complex<double>, 3> click_transfer_{};  ///< scratch
  std::array<double, 3> centre_m_{};                      ///< centre of mass, mesh frame
  double size_m_ = 1.0;                                   ///< largest extent of its surface (load moments over it)
  double youngs_pa_ = 0, poisson_ = 0, mass_kg_ = 0, contact_radius_m_ = 0;
  bool is_static_ = false;
  // Pose and level (engine thread).
  Pose pose_;
  bool asleep_ = false;
  float gain_ = 1.0f;
  float cur_gain_[kMaxOutputChannels] = {}, target_gain_[kMaxOutputChannels] = {};
  /// The ground's image as a signal of its own (an output with directions and a ground: it
  /// arrives from below), with its own oscillators, clicks and gains; null otherwise, when the
  /// image is mixed into synth_ with the direct sound.
  struct ImagePath {
    ImagePath(const SynthSettings& s, const ModalObjectDesc& modes) : synth(s, modes), click_synth(s, {}) {}
    OscillatorBank synth;
    OscillatorBank click_synth;
    float cur_gain[kMaxOutputChannels] = {}, target_gain[kMaxOutputChannels] = {};
  };
  std::unique_ptr<ImagePath> image_;
  float level_gain2_ = 0.0f;
  bool fresh_ = true;
  // Contact scheduler state (contact_scheduler.cpp).
  bool in_step_ = false;                ///< has sustained contact in the open step
  std::array<double, 6> step_load_{};   ///< force (N) and moment / size (N) of the open step
  std::array<double, 6> held_load_{};   ///< of the held force
  bool holding_ = false;                ///< held_force_ is not zero
  std::array<uint32_t, 8> partners_{};  ///< voices it touched in its last sustained step
  uint32_t partner_count_ = 0;
  bool partners_overflow_ = false;  ///< more than 8: a static body keeps no load when they sleep
  double last_sustained_s_ = -1.0;  ///< time of its last sustained contact
  bool span_open_ = false;          ///< contact damping in force
  // Continuous contacts (contact_sources.cpp): one generator per partner it rolls or slides on,
  // each a force channel of its oscillator bank.
  struct Source {
    bool used = false;
    uint64_t key = 0;  ///< partner voice, or the partner's surface seed
    RoughContact generator;
    double delay_s = 0.0;
    // This step's contact points, summed.
    bool stepped = false;
    double force_n = 0.0, speed_n = 0.0, partner_speed_n = 0.0, patch_n = 0.0;  // * N
    std::array<double, 3> spot_n{}, partner_spot_n{}, world_n{};                // * N
    std::vector<double> modal;                                                  ///< #modes: the step's modal impulses
    ContactPartner partner;
  };
  SurfaceRoughness roughness_;
  double restitution_ = 0.5;
  std::array<Source, kForceChannels> sources_;
  std::vector<float> force_;  ///< kForceChannels x max_block_frames
  std::array<const float*, kForceChannels> force_ptrs_{};
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
  /// A sustained contact's share of its body's load over the open step (VoiceInput::sustain).
  void sustainedContact(Voice& v, const ResolvedContact& c, const double* modal);
  void endStepFor(Voice& v);
  void scheduleImpact(Voice& v, const double* modal, double time_s, double duration_s, PulseShape shape,
                      const std::array<double, 3>& world_point, const std::array<double, 3>& impulse_local);
  void scheduleForceStep(Voice& v, const double* modal_change, double time_s, double ramp_s,
                         const std::array<double, 3>& world_point);
  double hertzDuration(const Voice& v, const ContactPartner& p, double speed) const;
  // Continuous contacts (contact_sources.cpp).
  void continuousContact(Voice& v, const EngineContact& c, const std::array<double, 3>& world);
  void continuousEndStep(Voice& v, bool load_change_follows);
  bool renderContactForces(Voice& v, size_t frames);
  void resetContinuous(Voice& v);
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
  int arrivals(const Voice& v, const std::array<double, 3>& world_point, Arrival out[2]) const;
  /// The per-mode factors for the arrivals along paths [0, count) (0: direct, 1: ground image)
  /// into factors[path]; nullptr when the factor is 1 for every mode. Impacts and load changes
  /// reuse a path's last factors only for the same direction to the bit; a continuous (rolling,
  /// sliding) source also within a bounded angle. The paths that need an evaluation share one
  /// pass over the transfer's coefficients (sound_paths.cpp). Paths [count, also_to) are
  /// evaluated (same-direction rule) only when that pass happens anyway, and kept for a load
  /// change later in the step: the pass reads memory, so a second direction is nearly free.
  enum class Reuse { SameDirection, WithinTolerance };
  static constexpr double kContinuousTransferTolerance = 1e-3;  ///< of a mode's loudest far field
  void radiationToward(Voice& v, const Arrival paths[], int count, const std::complex<double>* factors[2],
                       Reuse reuse = Reuse::SameDirection, int also_to = 0);
  void scheduleClick(Voice& v, int path, const Arrival& a, double time_s, double duration_s,
                     const std::array<double, 3>& impulse_local);
  void updateGains(Voice& v);
  /// The path's factors times each mode's air absorption over distance_m (the voice's scratch),
  /// or `factors` itself when the air absorbs nothing.
  const std::complex<double>* throughAir(Voice& v, int path, const std::complex<double>* factors, double distance_m);
  /// Mixes `mono` (the voice's path signal) into out with gains ramped from cur to target.
  void mixPath(const float* mono, float* cur, const float* target, float* const* out, size_t frames) const;
  /// Where the ground's mirror image of `point` is, when the image path exists for it.
  bool imageOf(const std::array<double, 3>& point, std::array<double, 3>& image) const;
  /// The synth a path's pulses go to: synth_ for the direct sound, and for the image too unless
  /// it has its own signal.
  OscillatorBank& pathSynth(Voice& v, int path) const { return path > 0 && v.image_ ? v.image_->synth : v.synth_; }
  OscillatorBank& pathClicks(Voice& v, int path) const {
    return path > 0 && v.image_ ? v.image_->click_synth : v.click_synth_;
  }
  /// Contact damping on from time_s (event time, before the delay) heard from world_point.
  void setExtraDamping(Voice& v, double time_s, const std::array<double, 3>& world_point, double per_s);
  void enforceBudget(uint64_t& active);

  EngineSettings settings_;
  std::vector<std::unique_ptr<ContactModel>> models_;  ///< asked in order
  std::vector<Voice*> slots_;
  Pose listener_;
  Step step_;
  uint64_t frames_ = 0;
  std::vector<uint32_t> histogram_;
  EngineStats stats_;
};

}  // namespace strike
