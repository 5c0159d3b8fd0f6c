// SPDX-License-Identifier: MIT
// The contact-model seam of the sound engine: what a contact sounds like. Target strike_synth
// (C++ standard library only).
//
// The engine resolves each contact once (its point and impulse in the body's frame, the world
// point, its time, the impact rule) and asks its contact models in order whether they take it;
// the first that does plays it into the voice through a VoiceInput: projecting the impulse onto
// the modes, sending a force pulse along every path to the listener, or adding it to the body's
// sustained load. The built-in models (contact_models.cpp) are
//  - "hertz impact": a contact faster than the impact rule is a Hertz half-sine pulse of the
//    contact time of the two bodies [Johnson 1985, Contact Mechanics, eq. 11.24];
//  - "sustained load": a slower one is part of its body's load over the step (load tracking,
//    contact damping, rolling and sliding sources: contact_scheduler.cpp, contact_sources.cpp).
// A model of one's own is a ContactModel added with SoundEngine::addContactModel (asked before
// the built-in ones); a built-in one is a file of src/synth plus its line in
// builtInContactModels() (docs/architecture.md, "Adding a contact model").
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "strike/synth/engine.hpp"

namespace strike {

/// One contact on one voice, resolved once by the engine for every model.
struct ResolvedContact {
  const EngineContact* reported = nullptr;  ///< as the physics reported it (partner, speeds, loads)
  std::array<double, 3> point{};            ///< in the body's mesh frame, m
  std::array<double, 3> impulse{};          ///< applied to the body over the step, mesh frame, N s
  std::array<double, 3> world_point{};      ///< m
  double time_s = 0.0;                      ///< engine clock: the reported time, or now
  bool impact = false;                      ///< the engine's impact rule (EngineSettings::isImpact)
};

/// How a model projects a contact onto the modes: once (an impact, whose point will not come
/// back), or remembering the point (a resting body's contacts return step after step).
/// The same values either way (ContactProjector).
enum class Projection { Once, Remembered };

/// What a contact model may do to the voice a contact is on. The engine makes one for each
/// contact it hands a model; every method runs on the engine's thread (the audio thread in
/// libstrike) without allocating, locking or throwing.
class VoiceInput {
 public:
  const ModeBank& bank() const;
  /// The modal impulse g_i = phi_i(p) . J of the contact (N s / sqrt(kg), #modes values): the
  /// voice's scratch, valid until the next projection on this voice.
  const double* project(const ResolvedContact& contact, Projection how);
  /// The Hertz contact time of this voice struck by `partner` at normal_speed_m_s, capped at
  /// EngineSettings::max_contact_duration_s, s.
  double hertzDuration(const ContactPartner& partner, double normal_speed_m_s) const;
  /// A force pulse of unit area at time_s (engine clock) lasting duration_s (0: an ideal
  /// impulse), scaled per mode by modal[i]: heard along every path to the listener, with the far
  /// field toward it, the ground's image and, for a half-sine, the click of the body's rigid
  /// acceleration (sound_paths.cpp).
  void pulse(const double* modal, double time_s, double duration_s, PulseShape shape, const ResolvedContact& contact);
  /// The contact as a part of its body's sustained load over the open step: a force whose
  /// changes are heard (load tracking), contact damping, and the rolling and sliding sound.
  void sustain(const ResolvedContact& contact, const double* modal);

 private:
  friend class SoundEngine;
  VoiceInput(SoundEngine& engine, VoiceState& voice) : engine_(engine), voice_(voice) {}
  SoundEngine& engine_;
  VoiceState& voice_;
};

/// A way a contact sounds.
class ContactModel {
 public:
  virtual ~ContactModel() = default;
  /// A short name for messages and docs ("hertz impact").
  virtual const char* name() const = 0;
  /// Whether it plays this contact. The engine asks its models in order and the first that
  /// takes a contact plays it; a contact none takes is silent.
  virtual bool takes(const ResolvedContact& contact) const = 0;
  /// Plays the contact into its voice. Engine thread: no allocation, locks or exceptions.
  virtual void play(const ResolvedContact& contact, VoiceInput& voice) = 0;
};

/// The engine's own models, in the order it asks them (contact_models.cpp).
std::vector<std::unique_ptr<ContactModel>> builtInContactModels();

}  // namespace strike
