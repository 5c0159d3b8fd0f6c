// SPDX-License-Identifier: MIT
// `strike render --via-library`: the scene's simulation, step by step, through libstrike's public
// C API (strike.h), exactly as a game would drive it: load each sounding body's bank, add it as
// an object, and every physics step report the bodies' poses and the contacts the physics engine
// solved (resting ones included) with strike_step(); pull audio in blocks of 256 frames with
// strike_render(). The output equals `strike render`'s within -100 dB re peak (a test), which
// shows that the tools and the library are one engine. Read it as a template for integrators.
#include "via_library.hpp"

#include <cstdio>
#include <string>
#include <vector>

#include "strike/bank/bank.hpp"
#include "strike/strike.h"

namespace strike::cli {
namespace {

class LibraryOutput final : public SoundOutput {
 public:
  ~LibraryOutput() override {
    strike_context_destroy(ctx_);  // objects first, then the banks (either order is allowed)
    for (strike_bank bank : banks_) strike_bank_destroy(bank);
  }

  static Result<std::unique_ptr<SoundOutput>> make(const EngineSettings& engine, double gain) {
    auto out = std::unique_ptr<LibraryOutput>(new LibraryOutput());
    out->gain_ = static_cast<float>(gain);
    strike_context_config c = strike_context_config_default();
    c.sample_rate_hz = engine.synth.sample_rate_hz;
    c.max_block_frames = static_cast<uint32_t>(kRenderBlockFrames);
    c.channels = 1;
    c.max_objects = std::max<uint32_t>(engine.max_voices, 1);
    c.min_freq_hz = engine.synth.min_freq_hz;
    c.max_freq_hz = engine.synth.max_freq_hz;
    c.audibility_threshold = engine.synth.audibility_threshold;
    c.reference_distance_m = engine.reference_distance_m;
    c.min_distance_m = engine.min_distance_m;
    c.contact_damping_per_s = engine.contact_damping_per_s;
    c.max_contact_duration_s = engine.max_contact_duration_s;
    c.ground_reflects = engine.ground.enabled ? 1 : 0;
    for (int k = 0; k < 3; ++k) c.ground_normal[k] = engine.ground.normal[k];
    c.ground_height_m = engine.ground.height_m;
    c.ground_reflection = engine.ground.reflection;
    // Offline, nothing may be dropped or deferred: no mode budget, every impact of a render call
    // prepared in it, room for every step's records and every pulse in flight.
    c.max_active_modes = 0;
    c.max_impacts_per_render = 0;
    c.contact_queue_capacity = 1u << 20;
    c.max_pending_impacts_per_object = 4096;
    c.log = [](void*, int32_t, const char* message) { std::fprintf(stderr, "libstrike: %s\n", message); };
    strike_output_desc output = strike_output_desc_default();
    switch (engine.output) {
      case OutputFormat::Mono: output.format = STRIKE_OUTPUT_MONO; break;
      case OutputFormat::Stereo: output.format = STRIKE_OUTPUT_STEREO; break;
      case OutputFormat::Ambix1: output.format = STRIKE_OUTPUT_AMBIX1; break;
      case OutputFormat::Ambix2: output.format = STRIKE_OUTPUT_AMBIX2; break;
      case OutputFormat::Ambix3: output.format = STRIKE_OUTPUT_AMBIX3; break;
      case OutputFormat::Binaural: output.format = STRIKE_OUTPUT_BINAURAL; break;
    }
    // A binaural output's responses, as the host read them (the SOFA file, read by the render).
    std::vector<double> directions;
    if (engine.output == OutputFormat::Binaural && engine.hrtf) {
      const HrtfSet& hrtf = *engine.hrtf;
      for (const std::array<double, 3>& d : hrtf.directions) directions.insert(directions.end(), d.begin(), d.end());
      output.hrtf_count = static_cast<uint32_t>(hrtf.directions.size());
      output.hrtf_length = hrtf.taps;
      output.hrtf_directions = directions.data();
      output.hrtf_left = hrtf.left.data();
      output.hrtf_right = hrtf.right.data();
    }
    output.air_absorption = engine.air_absorption ? 1 : 0;
    output.air_temperature_c = engine.air.temperature_c;
    output.air_relative_humidity_percent = engine.air.relative_humidity_percent;
    output.air_pressure_kpa = engine.air.pressure_kpa;
    out->channels_ = outputChannels(engine.output);
    out->planar_.assign(static_cast<size_t>(out->channels_) * kRenderBlockFrames, 0.0f);
    if (strike_status s = strike_context_create_with_output(&c, &output, &out->ctx_); s != STRIKE_OK)
      return badInput(std::string("--via-library: strike_context_create: ") + strike_status_string(s));
    return std::unique_ptr<SoundOutput>(std::move(out));
  }

  Status addVoice(uint32_t slot, const VoiceDesc& voice, const std::array<double, 3>& position_m,
                  const std::array<double, 4>& orientation_wxyz, const std::string& name) override {
    // A game ships bank files and loads them; here the render's bank, as the bytes of its file.
    const std::vector<uint8_t> bytes = encodeBank(*voice.bank);
    strike_bank bank = nullptr;
    if (strike_bank_load_memory(ctx_, bytes.data(), bytes.size(), &bank) != STRIKE_OK)
      return badInput("objects \"" + name + "\": --via-library: " + strike_context_last_error(ctx_));
    banks_.push_back(bank);
    strike_object_config config = strike_object_config_default();
    config.bank = bank;
    for (int k = 0; k < 3; ++k) config.position[k] = position_m[k];
    for (int k = 0; k < 4; ++k) config.orientation[k] = orientation_wxyz[k];
    config.gain = gain_;
    config.contact_radius_m = voice.contact_radius_m;
    config.is_static = voice.is_static ? 1 : 0;
    config.roughness_rms_m = voice.roughness.rms_m;
    config.roughness_correlation_m = voice.roughness.correlation_m;
    config.roughness_seed = voice.roughness.seed;
    config.restitution = voice.restitution;
    strike_object_id id{};
    if (strike_object_add(ctx_, &config, &id) != STRIKE_OK)
      return badInput("objects \"" + name + "\": --via-library: " + strike_context_last_error(ctx_));
    if (slot >= ids_.size()) ids_.resize(slot + 1, strike_object_id{0, 0});
    ids_[slot] = id;
    return {};
  }

  void setListener(const std::array<double, 3>& position_m, const std::array<double, 4>& orientation_wxyz) override {
    strike_listener_set_pose(ctx_, position_m.data(), orientation_wxyz.data());
  }

  void beginStep(double step_end_s, double step_s) override {
    step_ = strike_step_desc_default();
    step_.end_time_s = step_end_s;
    step_.duration_s = step_s;
    states_.clear();
    contacts_.clear();
  }

  void setPose(uint32_t slot, const std::array<double, 3>& position_m, const std::array<double, 4>& orientation_wxyz,
               bool asleep) override {
    strike_body_state state{};
    state.object = idOf(slot);
    for (int k = 0; k < 3; ++k) state.position[k] = position_m[k];
    for (int k = 0; k < 4; ++k) state.orientation[k] = orientation_wxyz[k];
    state.asleep = asleep ? 1 : 0;
    states_.push_back(state);
  }

  void contact(const EngineContact& from) override {
    strike_contact c = strike_contact_default();
    c.object = idOf(from.voice);
    c.partner = from.partner.voice != kNoVoice ? idOf(from.partner.voice) : strike_object_id{0, 0};
    c.frame = from.world_frame ? STRIKE_FRAME_WORLD : STRIKE_FRAME_OBJECT;
    for (int k = 0; k < 3; ++k) c.point[k] = from.point[k], c.impulse[k] = from.impulse[k];
    c.normal_speed_m_s = from.normal_speed_m_s;
    c.time_s = from.time_s;
    c.partner_youngs_pa = from.partner.youngs_pa;
    c.partner_poisson = from.partner.poisson;
    c.partner_radius_m = from.partner.radius_m;
    c.partner_mass_kg = from.partner.mass_kg;
    // Rolling, sliding and scraping: the same velocities (the sound engine's contact record is
    // strike_contact's, field for field).
    c.normal_force_n = from.normal_force_n;
    for (int k = 0; k < 3; ++k)
      c.slip_velocity_m_s[k] = from.slip_velocity_m_s[k], c.rolling_velocity_m_s[k] = from.rolling_velocity_m_s[k];
    for (int k = 0; k < 3; ++k) c.partner_point[k] = from.partner_point[k];
    c.patch_radius_m = from.patch_radius_m;
    c.partner_roughness_rms_m = from.partner.roughness.rms_m;
    c.partner_roughness_correlation_m = from.partner.roughness.correlation_m;
    c.partner_roughness_seed = from.partner.roughness.seed;
    c.partner_restitution = from.partner.restitution;
    contacts_.push_back(c);
  }

  void endStep() override {
    step_.states = states_.data();
    step_.state_count = static_cast<uint32_t>(states_.size());
    step_.contacts = contacts_.data();
    step_.contact_count = static_cast<uint32_t>(contacts_.size());
    if (strike_step(ctx_, &step_) != STRIKE_OK) ++failed_steps_;
  }

  Status render(float* interleaved, size_t frames) override {
    float* channels[kMaxOutputChannels] = {};
    for (uint32_t c = 0; c < channels_; ++c)
      channels[c] = channels_ == 1 ? interleaved : planar_.data() + c * kRenderBlockFrames;
    if (strike_status s = strike_render(ctx_, channels, channels_, static_cast<uint32_t>(frames)); s != STRIKE_OK)
      return badInput(std::string("--via-library: strike_render: ") + strike_status_string(s));
    if (channels_ > 1)
      for (size_t n = 0; n < frames; ++n)
        for (uint32_t c = 0; c < channels_; ++c) interleaved[n * channels_ + c] = channels[c][n];
    return {};
  }

  EngineStats stats() const override {
    strike_stats s{};
    s.struct_size = sizeof s;
    EngineStats e;
    if (strike_context_get_stats(ctx_, &s) != STRIKE_OK) return e;
    e.impacts = s.impacts_scheduled;
    e.impacts_inaudible = s.impacts_inaudible;
    e.impacts_dropped = s.impacts_dropped_capacity;
    e.sustained_contacts = s.sustained_contacts;
    e.load_changes = s.load_changes;
    e.load_holds = s.load_holds;
    e.modes_culled = s.modes_culled;
    return e;
  }

  std::vector<std::string> warnings() const override {
    strike_stats s{};
    s.struct_size = sizeof s;
    std::vector<std::string> out;
    if (strike_context_get_stats(ctx_, &s) != STRIKE_OK) return out;
    if (failed_steps_ > 0 || s.contacts_dropped_queue_full > 0 || s.impacts_dropped_capacity > 0)
      out.push_back("--via-library: libstrike dropped " + std::to_string(s.contacts_dropped_queue_full) +
                    " contacts (queue full) and " + std::to_string(s.impacts_dropped_capacity) +
                    " pulses (reserve full); the output is not the render's");
    return out;
  }

 private:
  LibraryOutput() = default;
  strike_object_id idOf(uint32_t slot) const { return slot < ids_.size() ? ids_[slot] : strike_object_id{0, 0}; }

  strike_context ctx_ = nullptr;
  std::vector<strike_bank> banks_;
  std::vector<strike_object_id> ids_;  ///< by body index; {0, 0}: not an object (not heard)
  float gain_ = 1.0f;
  uint32_t channels_ = 1;
  std::vector<float> planar_;  ///< channels_ x kRenderBlockFrames, for more than one channel
  strike_step_desc step_{};
  std::vector<strike_body_state> states_;
  std::vector<strike_contact> contacts_;
  size_t failed_steps_ = 0;
};

}  // namespace

SoundOutputFactory libraryOutput(double gain) {
  return [gain](const EngineSettings& engine) { return LibraryOutput::make(engine, gain); };
}

}  // namespace strike::cli
