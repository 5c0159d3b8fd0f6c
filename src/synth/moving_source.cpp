// SPDX-License-Identifier: MIT
// Moving sources: a body that moves while it sounds is heard with its Doppler shift, and from
// where it was when the sound left it.
//
// At rest, each pulse is scheduled at its time plus its path's delay r / c, exactly to the
// sample's fraction (sound_paths.cpp). That cannot follow a body that moves while it rings: the
// delay is fixed when the pulse is scheduled. So a body that starts moving while it is silent
// switches to delay lines: its pulses are scheduled when they happen, each path's signal as it
// leaves the body is written to a delay line of its own, and the listener hears, at time t,
// what left at the emission time t_e that solves
//     t - t_e = r_k(t_e) / c,
// r_k the path's length (to the listener, or to its mirror image in the ground) from where the
// body was at t_e. Its frequencies are then f c / (c - v_r), v_r the speed at which the body
// approached the listener at t_e (d t / d t_e = 1 - v_r / c), and its level and direction are
// those of the body at t_e: the retarded position of a moving source [Morse & Ingard 1968,
// sec. 11.2]. The level follows 1 / r_k(t_e); the convective amplification of a moving
// monopole, (1 - M_r)^-2, is left out: what leaves the body is its at-rest radiation.
//
// The trajectory is the poses the voice was given, at the engine time of the physics step they
// end (or now, outside a step), one kept every kKeyframeSpacing_s and linear between them. The
// emission time is solved at every kSegmentFrames-th frame of the engine's clock (a contraction
// by v / c per iteration), once, and is linear between them. The lines are read with a windowed sinc
// (fractional_delay.hpp). A body that comes to rest goes back to scheduled delays once it is
// silent and its lines have been heard to the end: at rest, the same bytes as never moving.
#include <algorithm>
#include <cmath>

#include "fractional_delay.hpp"
#include "strike/synth/engine.hpp"
#include "voice_state.hpp"

namespace strike {
namespace {

constexpr size_t kKeyframes = 1024;
constexpr double kKeyframeSpacing_s = 0.002;  // 2 s of trajectory: longer than kMaxMovingDelay_s
/// Beyond the newest pose the body goes on at its last velocity for at most this long, then
/// stays (a host that stops sending poses).
constexpr double kMaxExtrapolation_s = 0.1;
constexpr uint64_t kSegmentFrames = 32;
constexpr int kEmissionIterations = 8;  // error (v / c)^8 of the delay: 1e-10 at 20 m/s

}  // namespace

void VoiceState::setUpMovingSource(const EngineSettings& settings) {
  keys_.assign(kKeyframes, Keyframe{});
  const double frames =
      kMaxMovingDelay_s * settings.synth.sample_rate_hz + settings.max_block_frames + 2.0 * FractionalDelay::kTaps;
  uint64_t size = 1;
  while (static_cast<double>(size) < frames) size <<= 1;
  line_mask_ = size - 1;
  // Real time: nothing may allocate later. Offline, a body that never moves needs no lines.
  if (settings.realtime)
    for (size_t k = 0; k < (image_ ? 2u : 1u); ++k) line_[k].assign(size, 0.0f);
}

bool SoundEngine::silent(const VoiceState& v) const {
  if (!v.synth_.idle() || !v.click_synth_.idle()) return false;
  if (v.image_ && (!v.image_->synth.idle() || !v.image_->click_synth.idle())) return false;
  for (const VoiceState::Source& s : v.sources_)
    if (s.used) return false;
  return true;
}

void SoundEngine::followPose(VoiceState& v) {
  if (v.keys_.empty()) return;  // settings_.moving_sources off
  const double t = step_.open ? step_.end_s : time();
  const bool directional = !v.far_field_[0].empty();
  const std::array<double, 3> position = v.pose_.toWorld(directional ? v.bank_->transfer.centre_m : v.centre_m_);
  auto key = [&](size_t i) -> VoiceState::Keyframe& { return v.keys_[(v.key_first_ + i) % kKeyframes]; };
  if (v.key_count_ > 0 && t < key(v.key_count_ - 1).time_s) v.key_count_ = 0;  // the clock restarted
  const bool moved = v.key_count_ > 0 && key(v.key_count_ - 1).position_m != position;
  // The newest pose replaces the one before it until that one is kKeyframeSpacing_s old.
  const bool replace =
      v.key_count_ > 0 &&
      (key(v.key_count_ - 1).time_s == t ||
       (v.key_count_ > 1 && key(v.key_count_ - 1).time_s - key(v.key_count_ - 2).time_s < kKeyframeSpacing_s));
  if (!replace) {
    if (v.key_count_ == kKeyframes)
      v.key_first_ = (v.key_first_ + 1) % kKeyframes;
    else
      ++v.key_count_;
  }
  key(v.key_count_ - 1) = {t, position};

  if (!v.moving_ && moved && silent(v)) {
    for (size_t k = 0; k < (v.image_ ? 2u : 1u); ++k) {
      if (v.line_[k].empty()) v.line_[k].assign(v.line_mask_ + 1, 0.0f);  // offline only (setUpMovingSource)
      std::fill(v.line_[k].begin(), v.line_[k].end(), 0.0f);
    }
    v.sound_end_frame_ = frames_;
    v.heard_to_frame_ = static_cast<double>(frames_);
    v.read_map_ = {};
    v.moving_ = true;
  } else if (v.moving_ && !moved && silent(v) &&
             v.heard_to_frame_ >= static_cast<double>(v.sound_end_frame_) + FractionalDelay::kTaps) {
    v.moving_ = false;  // heard to the end: at rest again
  }
}

std::array<double, 3> SoundEngine::positionAt(const VoiceState& v, double t_s) const {
  auto key = [&](size_t i) -> const VoiceState::Keyframe& { return v.keys_[(v.key_first_ + i) % kKeyframes]; };
  const size_t n = v.key_count_;
  if (n == 0) return v.pose_.toWorld(v.centre_m_);
  if (n == 1 || t_s <= key(0).time_s) return key(0).position_m;
  // The last keyframe at or before t_s.
  size_t lo = 0, hi = n - 1;
  if (t_s >= key(hi).time_s) {
    lo = hi - 1;
  } else {
    while (hi - lo > 1) {
      const size_t mid = lo + (hi - lo) / 2;
      if (key(mid).time_s <= t_s)
        lo = mid;
      else
        hi = mid;
    }
  }
  const VoiceState::Keyframe& a = key(lo);
  const VoiceState::Keyframe& b = key(lo + 1);
  const double span = b.time_s - a.time_s;
  const double until = std::min(t_s, b.time_s + kMaxExtrapolation_s);
  const double w = span > 0.0 ? (until - a.time_s) / span : 1.0;
  std::array<double, 3> p;
  for (int k = 0; k < 3; ++k) p[k] = a.position_m[k] + w * (b.position_m[k] - a.position_m[k]);
  return p;
}

double SoundEngine::emissionFrame(const VoiceState& v, int path, uint64_t frame) const {
  const double fs = settings_.synth.sample_rate_hz;
  std::array<double, 3> listener = listener_.position_m;
  if (path > 0) (void)imageOf(listener_.position_m, listener);  // the image path: to the listener's mirror image
  const double t = static_cast<double>(frame) / fs;
  double delay = distance(positionAt(v, t), listener) / kSpeedOfSoundAir_m_s;
  for (int i = 0; i < kEmissionIterations; ++i)
    delay = distance(positionAt(v, t - delay), listener) / kSpeedOfSoundAir_m_s;
  // At least the interpolator's look-ahead (a body within 12 cm at 48 kHz is heard that late).
  const double shortest = (FractionalDelay::kLookahead + 1) / fs;
  delay = std::clamp(delay, shortest, kMaxMovingDelay_s);
  return static_cast<double>(frame) - delay * fs;
}

double SoundEngine::hearPath(VoiceState& v, int path, float* heard, size_t frames) {
  const float* line = v.line_[static_cast<size_t>(path)].data();
  // The map from output frame to emission frame is linear over each segment, and each segment's
  // ends are solved once: a pose that arrives later (or replaces the newest) bends the map from
  // the next segment on and never moves a sample already mapped, so the read position never jumps.
  VoiceState::ReadMap& m = v.read_map_[static_cast<size_t>(path)];
  const uint64_t base = frames_ - frames_ % kSegmentFrames;
  if (m.valid && m.base + kSegmentFrames == base) {
    m.base = base;
    m.from = m.to;
    m.to = emissionFrame(v, path, base + kSegmentFrames);
  } else if (!m.valid || m.base != base) {
    m.base = base;
    m.from = emissionFrame(v, path, base);
    m.to = emissionFrame(v, path, base + kSegmentFrames);
    m.valid = true;
  }
  double x = m.from;
  for (size_t n = 0; n < frames; ++n) {
    const uint64_t frame = frames_ + n;
    if (frame == m.base + kSegmentFrames) {
      m.base += kSegmentFrames;
      m.from = m.to;
      m.to = emissionFrame(v, path, m.base + kSegmentFrames);
    }
    x = m.from + (m.to - m.from) * (static_cast<double>(frame - m.base) / static_cast<double>(kSegmentFrames));
    heard[n] = fractional_delay_->read(line, v.line_mask_, x);
  }
  v.heard_from_m_[static_cast<size_t>(path)] = positionAt(v, x / settings_.synth.sample_rate_hz);
  return x;
}

void SoundEngine::updateMovingGains(VoiceState& v) {
  const std::array<double, 3>& listener = listener_.position_m;
  const OutputFormat format = settings_.output;
  const std::array<double, 3>& direct = v.heard_from_m_[0];
  const double d = distance(direct, listener);
  const double g =
      static_cast<double>(v.gain_) * distanceGain(d, settings_.reference_distance_m, settings_.min_distance_m);
  v.level_gain2_ = static_cast<float>(g * g);
  spatialGains(format, listener_.toLocalPoint(direct), d, g, v.target_gain_);
  if (v.binaural_[0].ready()) v.binaural_[0].aim(listener_.toLocalPoint(direct), v.fresh_);
  std::array<double, 3> image;
  if (imageApart(v) && imageOf(v.heard_from_m_[1], image)) {
    const double di = distance(image, listener);
    const double gi =
        static_cast<double>(v.gain_) * distanceGain(di, settings_.reference_distance_m, settings_.min_distance_m);
    spatialGains(format, listener_.toLocalPoint(image), di, gi, v.image_->target_gain);
    if (v.binaural_[1].ready()) v.binaural_[1].aim(listener_.toLocalPoint(image), v.fresh_);
  }
  if (v.fresh_) {
    std::copy(v.target_gain_, v.target_gain_ + settings_.channels, v.cur_gain_);
    if (v.image_) std::copy(v.image_->target_gain, v.image_->target_gain + settings_.channels, v.image_->cur_gain);
    v.fresh_ = false;
  }
}

void SoundEngine::hearNothing(VoiceState& v, float* const* out, size_t frames) {
  const uint64_t end = frames_ + frames;
  for (int k = 0; k < (imageApart(v) ? 2 : 1); ++k)
    v.heard_from_m_[static_cast<size_t>(k)] = positionAt(v, emissionFrame(v, k, end) / settings_.synth.sample_rate_hz);
  v.read_map_ = {};
  updateMovingGains(v);
  // As mixPath leaves them after mixing silence.
  std::copy(v.target_gain_, v.target_gain_ + settings_.channels, v.cur_gain_);
  if (v.image_) std::copy(v.image_->target_gain, v.image_->target_gain + settings_.channels, v.image_->cur_gain);
  flushBinaural(v, 0, out, frames);
  if (imageApart(v)) flushBinaural(v, 1, out, frames);
}

void SoundEngine::renderMoving(VoiceState& v, float* const* out, size_t frames, uint64_t& active) {
  VoiceState::ImagePath* image = imageApart(v) ? v.image_.get() : nullptr;
  float* direct = v.mono_.data();
  float* click = v.click_mono_.data();
  // The paths' signals as they leave the body: synth_ carries both, the direct one is the rest.
  if (image) {
    image->synth.skip(image->signal.data(), frames);  // zeros when idle
    if (!image->click_synth.idle()) {
      image->click_synth.render(click, frames);
      for (size_t n = 0; n < frames; ++n) image->signal[n] += click[n];
    } else {
      image->click_synth.skip(nullptr, frames);
    }
  }
  if (renderContactForces(v, frames))
    v.synth_.render(direct, frames, v.force_ptrs_.data());
  else
    v.synth_.skip(direct, frames);
  if (!v.click_synth_.idle()) {
    v.click_synth_.render(click, frames);
    for (size_t n = 0; n < frames; ++n) direct[n] += click[n];
  } else {
    v.click_synth_.skip(nullptr, frames);
  }
  if (image)
    for (size_t n = 0; n < frames; ++n) direct[n] -= image->signal[n];
  // Into the delay lines, then out at each path's emission times.
  const int paths = image ? 2 : 1;
  const bool heard_out = v.heard_to_frame_ >= static_cast<double>(v.sound_end_frame_) + FractionalDelay::kTaps;
  const uint64_t sound_end = v.sound_end_frame_;
  for (int k = 0; k < paths; ++k) {
    const float* sent = k == 0 ? direct : image->signal.data();
    std::vector<float>& line = v.line_[static_cast<size_t>(k)];
    bool sounds = false;
    for (size_t n = 0; n < frames; ++n) {
      line[(frames_ + n) & v.line_mask_] = sent[n];
      sounds = sounds || sent[n] != 0.0f;
    }
    if (sounds) v.sound_end_frame_ = frames_ + frames;
  }
  active += v.synth_.activeModeCount() + (image ? image->synth.activeModeCount() : 0);
  if (heard_out && v.sound_end_frame_ == sound_end) {
    // Nothing sent since what has been heard to the end: every tap reads zeros, so the paths
    // are silent without reading them (the map is solved afresh when sound is sent again).
    hearNothing(v, out, frames);
    return;
  }
  // The longer path (the image's) is heard last.
  v.heard_to_frame_ = hearPath(v, 0, direct, frames);
  if (image) v.heard_to_frame_ = std::min(v.heard_to_frame_, hearPath(v, 1, image->signal.data(), frames));
  updateMovingGains(v);
  mixPath(direct, v.cur_gain_, v.target_gain_, v.binaural_[0], out, frames);
  if (image) mixPath(image->signal.data(), image->cur_gain, image->target_gain, v.binaural_[1], out, frames);
}

}  // namespace strike
