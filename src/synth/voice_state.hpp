// SPDX-License-Identifier: MIT
// What a voice holds (private to src/synth): its modes, pose and level, and the engine's parts,
// each with the state it owns:
//  - LoadTracker: the body's sustained load and contact damping (contact_scheduler.cpp);
//  - ContinuousSources: its rolling and sliding generators (contact_sources.cpp);
//  - PathTransfers: its far field toward the listener along each path and the air's share
//    (sound_paths.cpp, radiation.cpp);
//  - AccelerationClicks: the click of its rigid acceleration (sound_paths.cpp);
//  - MovingSource: its trajectory and, while it moves, the delay lines its paths are heard
//    through (moving_source.cpp).
// Built off the audio thread with all the memory it will ever use (voice.cpp).
#pragma once

#include <array>
#include <complex>
#include <cstdint>
#include <memory>
#include <vector>

#include "strike/synth/engine.hpp"

namespace strike {

struct LoadTracker {
  std::vector<double> step_force_;      ///< #modes: this step's sustained modal force (N / sqrt(kg))
  std::vector<double> held_force_;      ///< #modes: the sustained modal force in force now
  bool in_step_ = false;                ///< has sustained contact in the open step
  std::array<double, 6> step_load_{};   ///< force (N) and moment / size (N) of the open step
  std::array<double, 6> held_load_{};   ///< of the held force
  bool holding_ = false;                ///< held_force_ is not zero
  std::array<uint32_t, 8> partners_{};  ///< voices it touched in its last sustained step
  uint32_t partner_count_ = 0;
  bool partners_overflow_ = false;  ///< more than 8: a static body keeps no load when they sleep
  double last_sustained_s_ = -1.0;  ///< time of its last sustained contact
  bool span_open_ = false;          ///< contact damping in force
  /// Lets go of every load and contact damping (SoundEngine::reset).
  void resetLoad() {
    std::fill(step_force_.begin(), step_force_.end(), 0.0);
    std::fill(held_force_.begin(), held_force_.end(), 0.0);
    step_load_ = {};
    held_load_ = {};
    holding_ = in_step_ = span_open_ = false;
    partner_count_ = 0;
    last_sustained_s_ = -1.0;
  }
};

// One generator per partner it rolls or slides on, each a force channel of its oscillator bank.
struct ContinuousSources {
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

// Radiation toward the listener (radiation.cpp, sound_paths.cpp).
struct PathTransfers {
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
  std::vector<double> inv_rms_;  ///< #modes: 1 / rms_d |F_i| (0 for a silent mode)
};

// Acceleration noise: three filters, one per principal axis of the body's dipole tensor.
struct AccelerationClicks {
  explicit AccelerationClicks(const SynthSettings& s) : click_synth_(s, {}) {}
  OscillatorBank click_synth_;
  bool clicks_ = false;                                   ///< a free body with mass
  std::vector<float> click_mono_;                         ///< max_block_frames
  std::array<std::array<double, 3>, 3> click_axis_{};     ///< principal axes of the dipole tensor, mesh frame
  std::array<double, 3> click_moment_m3_{};               ///< its eigenvalues
  std::array<std::complex<double>, 3> click_gain_{};      ///< lambda_j / p_j of each click filter
  std::array<double, 3> click_force_{};                   ///< scratch: rigid acceleration impulse per axis
  std::array<std::complex<double>, 3> click_transfer_{};  ///< scratch
};

// A body that moves is heard through a delay line per path, read at the emission time of each
// output sample (moving_source.cpp); at rest its pulses carry their delay (moving_ false).
struct MovingSource {
  /// Its paths are heard through the delay lines: pulses are scheduled when they happen.
  bool moving_ = false;
  /// Where its sound leaves from (the transfer's centre, else the centre of mass), world, at a
  /// time on the engine's clock: the poses it was given, one kept every kKeyframeSpacing_s.
  struct Keyframe {
    double time_s = 0.0;
    std::array<double, 3> position_m{};
  };
  std::vector<Keyframe> keys_;  ///< ring of kKeyframes, oldest first from key_first_
  size_t key_first_ = 0, key_count_ = 0;
  /// Per path (direct, ground image): the emitted signal, sample j at j & line_mask_.
  std::array<std::vector<float>, 2> line_;
  uint64_t line_mask_ = 0;
  uint64_t sound_end_frame_ = 0;  ///< just after the last non-zero sample written
  double heard_to_frame_ = 0.0;   ///< emission position of the last sample read (both paths)
  /// Per path: the emission frame at the ends of the current kSegmentFrames-long segment of the
  /// engine's clock (frames base and base + kSegmentFrames), solved once each.
  struct ReadMap {
    bool valid = false;
    uint64_t base = 0;
    double from = 0.0, to = 0.0;
  };
  std::array<ReadMap, 2> read_map_{};
  /// Each path's source position at the emission time of this render call's last sample.
  std::array<std::array<double, 3>, 2> heard_from_m_{};
};

/// One sounding body as the engine plays it: its parts, and what they share.
struct VoiceState : LoadTracker, ContinuousSources, PathTransfers, AccelerationClicks, MovingSource {
  VoiceState(const VoiceDesc& desc, const EngineSettings& settings);
  VoiceState(const VoiceState&) = delete;
  VoiceState& operator=(const VoiceState&) = delete;
  void setUpRadiation(const VoiceDesc& desc, const EngineSettings& settings);  // sound_paths.cpp's data
  void setUpMovingSource(const EngineSettings& settings);                      // moving_source.cpp's data

  std::shared_ptr<const ModeBank> bank_;
  OscillatorBank synth_;
  bool rings_ = false;  ///< has a mode in the synthesized band
  ContactProjector projector_;
  std::vector<double> modal_;         ///< #modes: projection scratch
  std::vector<float> mono_;           ///< max_block_frames
  std::vector<float> levels_;         ///< #modes: budget scratch
  std::array<double, 3> centre_m_{};  ///< centre of mass, mesh frame
  double size_m_ = 1.0;               ///< largest extent of its surface (load moments over it)
  double youngs_pa_ = 0, poisson_ = 0, mass_kg_ = 0, contact_radius_m_ = 0;
  bool is_static_ = false;
  // Pose and level (engine thread).
  Pose pose_;
  bool asleep_ = false;
  float gain_ = 1.0f;
  float cur_gain_[kMaxOutputChannels] = {}, target_gain_[kMaxOutputChannels] = {};
  /// The ground's image as a signal of its own (an output with directions and a ground: it
  /// arrives from below; or a moving body's, heard through its own delay line), with its own
  /// oscillators, clicks and gains; null otherwise (SoundEngine::imageApart: in use). The image
  /// rings in synth_ too, as in mono: synth_ carries both paths and the direct sound is synth_'s
  /// signal less the image's. Both paths' modes then sleep when their sum does, as in mono, and
  /// the sum of the paths (the omni channel) is the mono render to the rounding of a float.
  struct ImagePath {
    ImagePath(const SynthSettings& s, const ModalObjectDesc& modes, size_t max_block_frames)
        : synth(s, modes), click_synth(s, {}), signal(max_block_frames, 0.0f) {}
    OscillatorBank synth;
    OscillatorBank click_synth;
    std::vector<float> signal;  ///< max_block_frames: this render call's image, oscillators and clicks
    float cur_gain[kMaxOutputChannels] = {}, target_gain[kMaxOutputChannels] = {};
  };
  std::unique_ptr<ImagePath> image_;
  /// A binaural output's filters of each path (direct, ground image); not ready() otherwise.
  std::array<BinauralPath, 2> binaural_;
  float level_gain2_ = 0.0f;
  bool fresh_ = true;
};

}  // namespace strike
