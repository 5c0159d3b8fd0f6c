// SPDX-License-Identifier: MIT
// Phase 3 of a render: the simulation, step by step, into the sound engine. This is the loop a
// game runs every physics step (see tools/cli/via_library.cpp for the same through libstrike's C
// API): the bodies' poses, the contacts the physics engine solved, then the audio that the
// physics has passed.
#include "playback.hpp"

#include <algorithm>
#include <cmath>

namespace strike {
namespace {

/// The built-in sound engine as a SoundOutput.
class EngineOutput final : public SoundOutput {
 public:
  explicit EngineOutput(const EngineSettings& settings) : engine_(settings) {
    planar_.assign(static_cast<size_t>(engine_.settings().channels) * engine_.settings().max_block_frames, 0.0f);
  }
  Status addVoice(uint32_t slot, const VoiceDesc& desc, const std::array<double, 3>& position_m,
                  const std::array<double, 4>& orientation_wxyz, const std::string&) override {
    VoiceDesc placed = desc;
    placed.pose.set(position_m.data(), orientation_wxyz.data());
    voices_.push_back(std::make_unique<Voice>(placed, engine_.settings()));
    engine_.install(slot, voices_.back().get());
    return {};
  }
  void setListener(const std::array<double, 3>& position_m, const std::array<double, 4>& orientation_wxyz) override {
    Pose listener;
    if (listener.set(position_m.data(), orientation_wxyz.data())) engine_.setListener(listener);
  }
  void beginStep(double step_end_s, double step_s) override { engine_.beginStep(step_end_s, step_s); }
  void setPose(uint32_t slot, const std::array<double, 3>& position_m, const std::array<double, 4>& orientation_wxyz,
               bool asleep) override {
    Pose pose;
    if (pose.set(position_m.data(), orientation_wxyz.data())) engine_.setPose(slot, pose, asleep);
  }
  void contact(const EngineContact& contact) override { engine_.contact(contact); }
  void endStep() override { engine_.endStep(); }
  Status render(float* interleaved, size_t frames) override {
    const uint32_t count = engine_.settings().channels;
    if (count == 1) {
      float* channels[1] = {interleaved};
      engine_.render(channels, frames);
      return {};
    }
    float* channels[kMaxOutputChannels] = {};
    for (uint32_t c = 0; c < count; ++c) channels[c] = planar_.data() + c * engine_.settings().max_block_frames;
    engine_.render(channels, frames);
    for (size_t n = 0; n < frames; ++n)
      for (uint32_t c = 0; c < count; ++c) interleaved[n * count + c] = channels[c][n];
    return {};
  }
  EngineStats stats() const override { return engine_.stats(); }

 private:
  SoundEngine engine_;
  std::vector<std::unique_ptr<Voice>> voices_;
  std::vector<float> planar_;  ///< channels x max_block_frames, for more than one channel
};

}  // namespace

std::unique_ptr<SoundOutput> makeEngineOutput(const EngineSettings& settings) {
  return std::make_unique<EngineOutput>(settings);
}

Status play(const Playback& p, SoundOutput& output, AudioBuffer& audio, const ProgressFn& progress) {
  // The events by physics step (they are in order of time_s, and an impact's time may fall in
  // the step before the one that solved it).
  const size_t steps = static_cast<size_t>(p.substeps);
  const double substep = p.substep_s;
  const std::vector<ContactEvent>& events = p.events;
  std::vector<size_t> step_first(steps + 1, 0);
  for (const ContactEvent& event : events)
    ++step_first[std::min<size_t>(steps - 1, static_cast<size_t>(std::llround(event.step_time_s / substep))) + 1];
  for (size_t k = 0; k < steps; ++k) step_first[k + 1] += step_first[k];
  std::vector<uint32_t> by_step(events.size());
  {
    std::vector<size_t> fill(step_first.begin(), step_first.end() - 1);
    for (size_t e = 0; e < events.size(); ++e) {
      const size_t k = std::min<size_t>(steps - 1, static_cast<size_t>(std::llround(events[e].step_time_s / substep)));
      by_step[fill[k]++] = static_cast<uint32_t>(e);
    }
  }
  const double rate = audio.sample_rate_hz;
  const size_t channels = static_cast<size_t>(std::max(audio.channels, 1));
  const size_t total = audio.frames();
  size_t rendered = 0;
  // Blocks whose end lies a physics step behind the step just fed: nothing later can land in them.
  auto renderUpTo = [&](size_t frame_end) -> Status {
    frame_end = std::min(frame_end, total);
    while (rendered + kRenderBlockFrames <= frame_end || (frame_end == total && rendered < frame_end)) {
      const size_t frames = std::min(kRenderBlockFrames, total - rendered);
      if (Status ok = output.render(audio.samples.data() + rendered * channels, frames); !ok) return ok;
      rendered += frames;
    }
    return {};
  };
  const size_t n = p.has_voice.size();
  double last_progress = -1.0;
  for (size_t k = 0; k < steps; ++k) {
    const double step_end = static_cast<double>(k + 1) * substep;
    output.beginStep(step_end, substep);
    for (size_t i = 0; i < n; ++i) {
      const SimBodyState& state = p.states[k * n + i];
      if (p.has_voice[i])
        output.setPose(static_cast<uint32_t>(i), state.position_m, state.orientation_wxyz, state.asleep);
    }
    for (size_t j = step_first[k]; j < step_first[k + 1]; ++j) {
      const ContactEvent& event = events[by_step[j]];
      for (int side = 0; side < 2; ++side) {
        const uint32_t index = side == 0 ? event.body_a : event.body_b;
        const uint32_t other = side == 0 ? event.body_b : event.body_a;
        if (index == kGroundBody || !p.has_voice[index]) continue;
        EngineContact contact;
        contact.voice = index;
        contact.point = side == 0 ? event.point_a_mesh : event.point_b_mesh;
        contact.impulse = side == 0 ? event.impulse_on_a_mesh : event.impulse_on_b_mesh;
        contact.normal_speed_m_s = event.normal_speed_m_s;
        contact.time_s = event.time_s;
        contact.partner = other == kGroundBody ? p.ground : p.partners[other];
        // Continuous contact state (rolling, sliding, scraping: contact_sources.cpp).
        contact.normal_force_n = event.normal_force_n;
        // a's surface moves at slip relative to b's, and the point travels track_velocity_a over a,
        // so track_velocity_a + slip over b.
        for (int axis = 0; axis < 3; ++axis) {
          const double slip = event.slip_velocity_m_s[axis], over_a = event.track_velocity_a_m_s[axis];
          contact.slip_velocity_m_s[axis] = side == 0 ? slip : -slip;
          contact.rolling_velocity_m_s[axis] = side == 0 ? over_a : over_a + slip;
        }
        contact.partner_point = side == 0 ? event.point_b_mesh : event.point_a_mesh;
        contact.patch_radius_m = event.patch_radius_m;
        output.contact(contact);
      }
    }
    output.endStep();
    const double safe_s = step_end - substep;  // the next step's contacts start no earlier
    if (Status ok = renderUpTo(safe_s > 0 ? static_cast<size_t>(std::floor(safe_s * rate)) : 0); !ok) return ok;
    const double fraction = static_cast<double>(rendered) / std::max<size_t>(total, 1);
    if (progress && fraction - last_progress >= 0.01) {
      progress("synthesize", fraction);
      last_progress = fraction;
    }
  }
  if (Status ok = renderUpTo(total); !ok) return ok;
  return {};
}

}  // namespace strike
