// SPDX-License-Identifier: MIT
// The built-in contact models and what a model may do to a voice (contact_model.hpp). A model
// of src/synth is a file of its own plus its line in builtInContactModels() below.
#include <memory>
#include <vector>

#include "strike/synth/contact_model.hpp"
#include "voice_state.hpp"

namespace strike {
namespace {

/// A contact faster than the impact rule: a Hertz half-sine pulse whose length follows from the
/// two materials, radii, masses and the approach speed [Johnson 1985, eq. 11.24].
class HertzImpact final : public ContactModel {
 public:
  const char* name() const override { return "hertz impact"; }
  bool takes(const ResolvedContact& contact) const override { return contact.impact; }
  void play(const ResolvedContact& contact, VoiceInput& voice) override {
    const double* modal = voice.project(contact, Projection::Once);
    const EngineContact& c = *contact.reported;
    voice.pulse(modal, contact.time_s, voice.hertzDuration(c.partner, c.normal_speed_m_s), PulseShape::HalfSine,
                contact);
  }
};

/// A slower contact: its share of the body's load over the step (contact_scheduler.cpp), and
/// its rolling and sliding sound (contact_sources.cpp).
class SustainedLoad final : public ContactModel {
 public:
  const char* name() const override { return "sustained load"; }
  bool takes(const ResolvedContact& contact) const override { return !contact.impact; }
  void play(const ResolvedContact& contact, VoiceInput& voice) override {
    voice.sustain(contact, voice.project(contact, Projection::Remembered));
  }
};

}  // namespace

std::vector<std::unique_ptr<ContactModel>> builtInContactModels() {
  std::vector<std::unique_ptr<ContactModel>> models;
  models.push_back(std::make_unique<HertzImpact>());
  models.push_back(std::make_unique<SustainedLoad>());
  return models;
}

const ModeBank& VoiceInput::bank() const { return *voice_.bank_; }

const double* VoiceInput::project(const ResolvedContact& c, Projection how) {
  if (how == Projection::Once)
    voice_.projector_.projectOnce(c.point.data(), c.impulse.data(), voice_.modal_.data());
  else
    voice_.projector_.projectImpulseInto(c.point.data(), c.impulse.data(), voice_.modal_.data());
  return voice_.modal_.data();
}

double VoiceInput::hertzDuration(const ContactPartner& partner, double normal_speed_m_s) const {
  return engine_.hertzDuration(voice_, partner, normal_speed_m_s);
}

void VoiceInput::pulse(const double* modal, double time_s, double duration_s, PulseShape shape,
                       const ResolvedContact& c) {
  engine_.scheduleImpact(voice_, modal, time_s, duration_s, shape, c.world_point, c.impulse);
}

void VoiceInput::sustain(const ResolvedContact& c, const double* modal) { engine_.sustainedContact(voice_, c, modal); }

}  // namespace strike
