// SPDX-License-Identifier: MIT
// Phase 3 of a render: the simulation played into a SoundOutput step by step, exactly as a game
// plays its physics engine's results into libstrike (playback.cpp).
#pragma once

#include <memory>
#include <vector>

#include "strike/audio/audio.hpp"
#include "strike/synth/engine.hpp"
#include "strike/core/progress.hpp"
#include "strike/scene/render.hpp"
#include "strike/sim/sim.hpp"

namespace strike {

/// What the simulation recorded, and who the bodies are to the sound engine.
struct Playback {
  const std::vector<ContactEvent>& events;  ///< in order of time_s
  const std::vector<SimBodyState>& states;  ///< states[k * bodies + i] after substep k
  uint64_t substeps = 0;
  double substep_s = 1e-3;
  const std::vector<bool>& has_voice;           ///< per body: added to the output (it sounds)
  const std::vector<ContactPartner>& partners;  ///< per body, as the other side of a contact
  ContactPartner ground;
};

/// Per physics step: every sounding body's pose, then each sounding side of each contact point,
/// then the audio blocks that the physics has passed by a step (kRenderBlockFrames each) into
/// `audio` (sized by the caller). Reports "synthesize" progress.
Status play(const Playback& playback, SoundOutput& output, AudioBuffer& audio, const ProgressFn& progress);

/// The built-in sound engine as a SoundOutput (what `strike render` uses without --via-library).
std::unique_ptr<SoundOutput> makeEngineOutput(const EngineSettings& settings);

}  // namespace strike
