// SPDX-License-Identifier: MIT
// The sound engine's voices, listener, mix and budget (the contacts are in
// contact_scheduler.cpp). Follow render(): each voice's level from its distance, its modes
// rendered, mixed with that level ramped over the call, then the budget of ringing modes.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "fractional_delay.hpp"
#include "strike/synth/contact_model.hpp"
#include "strike/synth/engine.hpp"
#include "voice_state.hpp"

namespace strike {
namespace {

constexpr size_t kHistogramBins = 4096;  // float bits >> 19 of a non-negative float

uint32_t histogramBin(float level2) {
  uint32_t bits;
  std::memcpy(&bits, &level2, sizeof bits);
  if (!(level2 > 0.0f)) return 0;
  return std::min<uint32_t>(bits >> 19, kHistogramBins - 1);  // monotonic for non-negative floats
}

}  // namespace

SoundEngine::SoundEngine(const EngineSettings& settings) : settings_(settings), models_(builtInContactModels()) {
  if (settings_.output == OutputFormat::Mono && settings_.channels == 2) settings_.output = OutputFormat::Stereo;
  settings_.channels = outputChannels(settings_.output);
  settings_.max_block_frames = std::max<uint32_t>(settings_.max_block_frames, 1);
  slots_.assign(settings_.max_voices, nullptr);
  histogram_.assign(kHistogramBins, 0);
  if (settings_.moving_sources) fractional_delay_ = std::make_shared<const FractionalDelay>();
}

SoundEngine::~SoundEngine() = default;

void SoundEngine::addContactModel(std::unique_ptr<ContactModel> model) {
  if (model) models_.insert(models_.begin(), std::move(model));
}

bool SoundEngine::install(uint32_t slot, Voice* voice) {
  if (slot >= slots_.size() || slots_[slot] || !voice) return false;
  slots_[slot] = voice;
  VoiceState& v = *voice->state_;
  v.fresh_ = true;
  // Its oscillators start on the engine's clock, so a contact's time means the same in every voice.
  const uint64_t at = static_cast<uint64_t>(std::llround(v.synth_.time() * settings_.synth.sample_rate_hz));
  if (frames_ > at) {
    v.synth_.skip(nullptr, static_cast<size_t>(frames_ - at));
    v.click_synth_.skip(nullptr, static_cast<size_t>(frames_ - at));
    if (v.image_) {
      v.image_->synth.skip(nullptr, static_cast<size_t>(frames_ - at));
      v.image_->click_synth.skip(nullptr, static_cast<size_t>(frames_ - at));
    }
  }
  followPose(v);
  return true;
}

VoiceState* SoundEngine::state(uint32_t slot) const {
  Voice* v = voice(slot);
  return v ? v->state_.get() : nullptr;
}

bool SoundEngine::imageApart(const VoiceState& v) const {
  return v.image_ && (outputHasDirections(settings_.output) || v.moving_);
}

OscillatorBank& SoundEngine::pathSynth(VoiceState& v, int path) const {
  return path > 0 && imageApart(v) ? v.image_->synth : v.synth_;
}

OscillatorBank& SoundEngine::pathClicks(VoiceState& v, int path) const {
  return path > 0 && imageApart(v) ? v.image_->click_synth : v.click_synth_;
}

Voice* SoundEngine::uninstall(uint32_t slot) {
  if (slot >= slots_.size()) return nullptr;
  Voice* v = slots_[slot];
  slots_[slot] = nullptr;
  return v;
}

void SoundEngine::setPose(uint32_t slot, const Pose& pose, bool asleep) {
  VoiceState* v = state(slot);
  if (!v) return;
  v->pose_ = pose;
  v->asleep_ = asleep;
  followPose(*v);
}

void SoundEngine::setGain(uint32_t slot, float gain) {
  if (VoiceState* v = state(slot)) v->gain_ = gain;
}

void SoundEngine::setListener(const Pose& pose) { listener_ = pose; }

double SoundEngine::time() const { return static_cast<double>(frames_) / settings_.synth.sample_rate_hz; }

double SoundEngine::delayTo(const std::array<double, 3>& world_point) const {
  return propagationDelay_s(distance(world_point, listener_.position_m));
}

// The listener model (strike/core/air.hpp): the level from the distance of the body's centre of mass
// now; each path's channel gains from its direction in the listener's frame (spatializer.hpp):
// the direct sound from the centre of mass, the ground's image from its mirror image.
void SoundEngine::updateGains(VoiceState& v) {
  const std::array<double, 3> centre = v.pose_.toWorld(v.centre_m_);
  const double d = distance(centre, listener_.position_m);
  const double g =
      static_cast<double>(v.gain_) * distanceGain(d, settings_.reference_distance_m, settings_.min_distance_m);
  v.level_gain2_ = static_cast<float>(g * g);
  const OutputFormat format = settings_.output;
  if (format == OutputFormat::Mono)
    v.target_gain_[0] = static_cast<float>(g);
  else
    spatialGains(format, listener_.toLocalPoint(centre), d, g, v.target_gain_);
  if (v.binaural_[0].ready()) v.binaural_[0].aim(listener_.toLocalPoint(centre), v.fresh_);
  std::array<double, 3> image;
  if (v.image_ && imageOf(centre, image)) {
    spatialGains(format, listener_.toLocalPoint(image), distance(image, listener_.position_m), g,
                 v.image_->target_gain);
    if (v.binaural_[1].ready()) v.binaural_[1].aim(listener_.toLocalPoint(image), v.fresh_);
  }
  if (v.fresh_) {
    std::copy(v.target_gain_, v.target_gain_ + settings_.channels, v.cur_gain_);
    if (v.image_) std::copy(v.image_->target_gain, v.image_->target_gain + settings_.channels, v.image_->cur_gain);
    v.fresh_ = false;
  }
}

bool SoundEngine::imageOf(const std::array<double, 3>& point, std::array<double, 3>& image) const {
  const GroundReflection& ground = settings_.ground;
  if (!ground.enabled) return false;
  const std::array<double, 3>& n = ground.normal;
  const double height = n[0] * point[0] + n[1] * point[1] + n[2] * point[2] - ground.height_m;
  for (int k = 0; k < 3; ++k) image[k] = point[k] - 2.0 * height * n[k];
  return true;
}

void SoundEngine::mixPath(float* m, float* cur, const float* target, BinauralPath& binaural, float* const* out,
                          size_t frames) const {
  const float inv = 1.0f / static_cast<float>(frames);
  if (binaural.ready()) {  // both ears' level is one gain; the direction is in the filters
    const float g0 = cur[0], dg = (target[0] - g0) * inv;
    for (size_t n = 0; n < frames; ++n) m[n] *= g0 + dg * static_cast<float>(n + 1);
    binaural.process(m, frames, out[0], out[1]);
    std::copy(target, target + settings_.channels, cur);
    return;
  }
  for (uint32_t c = 0; c < settings_.channels; ++c) {
    const float g0 = cur[c], dg = (target[c] - g0) * inv;
    float* o = out[c];
    if (dg == 0.0f) {
      for (size_t n = 0; n < frames; ++n) o[n] += g0 * m[n];
    } else {
      for (size_t n = 0; n < frames; ++n) o[n] += (g0 + dg * static_cast<float>(n + 1)) * m[n];
    }
    cur[c] = target[c];
  }
}

// A silent path's filters still hold its last samples: they ring out through zeros.
void SoundEngine::flushBinaural(VoiceState& v, int path, float* const* out, size_t frames) const {
  BinauralPath& binaural = v.binaural_[path];
  if (!binaural.ready()) return;
  if (!binaural.ringing()) {
    binaural.skip(frames);
    return;
  }
  std::fill(v.mono_.begin(), v.mono_.begin() + static_cast<std::ptrdiff_t>(frames), 0.0f);
  binaural.process(v.mono_.data(), frames, out[0], out[1]);
}

void SoundEngine::render(float* const* out, size_t frames) {
  frames = std::min<size_t>(frames, settings_.max_block_frames);
  const uint32_t channels = settings_.channels;
  for (uint32_t c = 0; c < channels; ++c) std::fill(out[c], out[c] + frames, 0.0f);
  uint64_t active = 0;
  for (Voice* installed : slots_) {
    VoiceState* v = installed ? installed->state_.get() : nullptr;
    if (!v) continue;
    if (v->moving_) {  // heard through its delay lines (moving_source.cpp)
      if (frames > 0) renderMoving(*v, out, frames, active);
      continue;
    }
    updateGains(*v);
    if (frames == 0) continue;
    bool image_sounds = false;  // this call's image is in image->signal
    if (VoiceState::ImagePath* image = v->image_.get()) {
      const bool clicking = !image->click_synth.idle();
      if (image->synth.idle() && !clicking) {
        std::copy(image->target_gain, image->target_gain + channels, image->cur_gain);
        image->synth.skip(nullptr, frames);
        image->click_synth.skip(nullptr, frames);
        flushBinaural(*v, 1, out, frames);
      } else {
        float* signal = image->signal.data();
        image->synth.skip(signal, frames);
        if (clicking) {
          image->click_synth.render(v->click_mono_.data(), frames);
          for (size_t n = 0; n < frames; ++n) signal[n] += v->click_mono_[n];
        } else {
          image->click_synth.skip(nullptr, frames);
        }
        std::copy(signal, signal + frames, v->mono_.begin());
        mixPath(v->mono_.data(), image->cur_gain, image->target_gain, v->binaural_[1], out, frames);
        active += image->synth.activeModeCount();
        image_sounds = true;
      }
    }
    const bool driven = renderContactForces(*v, frames);  // continuous contacts' forces
    const bool clicking = !v->click_synth_.idle();
    if (!driven && v->synth_.idle() && !clicking && !image_sounds) {
      std::copy(v->target_gain_, v->target_gain_ + channels, v->cur_gain_);
      v->synth_.skip(nullptr, frames);  // keeps its clock: its next pulse lands at the right sample
      v->click_synth_.skip(nullptr, frames);
      flushBinaural(*v, 0, out, frames);
      continue;
    }
    if (driven)
      v->synth_.render(v->mono_.data(), frames, v->force_ptrs_.data());
    else
      v->synth_.skip(v->mono_.data(), frames);  // renders, or writes zeros when idle
    if (clicking) {
      v->click_synth_.render(v->click_mono_.data(), frames);
      for (size_t n = 0; n < frames; ++n) v->mono_[n] += v->click_mono_[n];
    } else {
      v->click_synth_.skip(nullptr, frames);
    }
    if (image_sounds) {  // synth_ carries both paths: the direct sound is the rest
      const float* image = v->image_->signal.data();
      for (size_t n = 0; n < frames; ++n) v->mono_[n] -= image[n];
    }
    mixPath(v->mono_.data(), v->cur_gain_, v->target_gain_, v->binaural_[0], out, frames);
    active += v->synth_.activeModeCount();
  }
  enforceBudget(active);
  stats_.active_modes = active;
  stats_.max_active_modes = std::max(stats_.max_active_modes, active);
  frames_ += frames;
}

// When more modes ring than the budget allows, a histogram of their squared levels at the
// listener (float bits, 1/16-octave bins of level^2) finds the cut, and every mode at or below it
// sleeps: the quietest go first, and the whole boundary bin (within 0.4 dB) goes, so the count
// lands at or just under the budget.
void SoundEngine::enforceBudget(uint64_t& active) {
  const uint64_t budget = settings_.max_active_modes;
  if (budget == 0 || active <= budget) return;
  std::fill(histogram_.begin(), histogram_.end(), 0u);
  for (Voice* installed : slots_) {
    VoiceState* v = installed ? installed->state_.get() : nullptr;
    if (!v) continue;
    const size_t n = v->synth_.activeModeLevels(v->levels_.data(), v->levels_.size());
    for (size_t k = 0; k < n; ++k) ++histogram_[histogramBin(v->levels_[k] * v->level_gain2_)];
    if (v->image_) {
      const size_t m = v->image_->synth.activeModeLevels(v->levels_.data(), v->levels_.size());
      for (size_t k = 0; k < m; ++k) ++histogram_[histogramBin(v->levels_[k] * v->level_gain2_)];
    }
  }
  // Keep the loudest bins while they fit; cull the first bin that does not, and all below it.
  uint64_t kept = 0;
  size_t cut = kHistogramBins;
  for (size_t b = kHistogramBins; b-- > 0;) {
    if (kept + histogram_[b] > budget) {
      cut = b;
      break;
    }
    kept += histogram_[b];
  }
  if (cut == kHistogramBins) return;
  // Largest float in bin `cut`; +inf (cull all) for the top bin.
  const uint32_t top_bits = static_cast<uint32_t>((cut + 1) << 19) - 1u;
  float threshold;
  std::memcpy(&threshold, &top_bits, sizeof threshold);
  if (cut == kHistogramBins - 1) threshold = HUGE_VALF;
  active = 0;
  for (Voice* installed : slots_) {
    VoiceState* v = installed ? installed->state_.get() : nullptr;
    if (!v) continue;
    stats_.modes_culled += v->synth_.sleepModesAtOrBelow(threshold, v->level_gain2_);
    active += v->synth_.activeModeCount();
    if (v->image_) {
      stats_.modes_culled += v->image_->synth.sleepModesAtOrBelow(threshold, v->level_gain2_);
      active += v->image_->synth.activeModeCount();
    }
  }
}

EngineStats SoundEngine::stats() const {
  EngineStats s = stats_;
  s.modes_total = s.modes_out_of_band = s.mode_samples = s.forced_mode_samples = s.image_mode_samples = 0;
  for (const Voice* installed : slots_) {
    const VoiceState* v = installed ? installed->state_.get() : nullptr;
    if (!v) continue;
    const SynthStats vs = v->synth_.stats();
    s.modes_total += vs.modes_total;
    s.modes_out_of_band += vs.modes_out_of_band;
    s.mode_samples += vs.mode_samples;
    s.forced_mode_samples += vs.forced_mode_samples;
    if (v->image_) {
      const SynthStats is = v->image_->synth.stats();
      s.mode_samples += is.mode_samples;
      s.image_mode_samples += is.mode_samples - is.forced_mode_samples;
      s.forced_mode_samples += is.forced_mode_samples;
    }
  }
  return s;
}

}  // namespace strike
