// SPDX-License-Identifier: MIT
// Binaural output (hrtf.hpp): the measured responses interpolated to a direction, and one path's
// convolution with them.
#include "strike/hrtf.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace strike {
namespace {

constexpr uint32_t kMaxHrtfTaps = 16384;

uint32_t thresholdOnset(const float* response, uint32_t taps) {
  float peak = 0.0f;
  for (uint32_t n = 0; n < taps; ++n) peak = std::max(peak, std::fabs(response[n]));
  for (uint32_t n = 0; n < taps; ++n)
    if (std::fabs(response[n]) >= 0.1f * peak) return n;
  return 0;
}

// The blend's responses of one ear, each moved from its own onset to the blend's mean onset D:
// y[n] = sum_j w_j h_j(n - D + o_j). D is fractional; each h_j is read between its samples by
// four-point Lagrange interpolation (exact at whole samples; at half a sample -0.2 dB at a sixth
// of the sample rate, -1.1 dB at a quarter [Laakso et al. 1996, "Splitting the unit delay",
// IEEE Signal Processing Magazine 13(1)]), so the interaural delay moves smoothly with the
// direction instead of by whole samples.
void blendEar(const HrtfSet& set, const HrtfBlend& blend, const std::vector<float>& responses,
              const std::vector<uint32_t>& onsets, float* out) {
  const int taps = static_cast<int>(set.taps);
  double mean_onset = 0.0;
  for (int j = 0; j < 3; ++j) mean_onset += blend.weight[j] * onsets[blend.index[j]];
  const double whole = std::floor(mean_onset);
  const double p = 1.0 - (mean_onset - whole);  // where we read, past sample k - 1, in (0, 1]
  const double lagrange[4] = {-p * (p - 1.0) * (p - 2.0) / 6.0, (p + 1.0) * (p - 1.0) * (p - 2.0) / 2.0,
                              -(p + 1.0) * p * (p - 2.0) / 2.0, (p + 1.0) * p * (p - 1.0) / 6.0};
  const int shift = static_cast<int>(whole);
  for (int n = 0; n < taps; ++n) {
    double sum = 0.0;
    for (int j = 0; j < 3; ++j) {
      if (blend.weight[j] == 0.0) continue;
      const float* h = responses.data() + static_cast<size_t>(blend.index[j]) * set.taps;
      const int k = n - shift + static_cast<int>(onsets[blend.index[j]]);  // h(k - 1 + p)
      double value = 0.0;
      for (int m = 0; m < 4; ++m) {
        const int at = k - 2 + m;
        if (at >= 0 && at < taps) value += lagrange[m] * h[at];
      }
      sum += blend.weight[j] * value;
    }
    out[n] = static_cast<float>(sum);
  }
}

}  // namespace

std::string prepareHrtfSet(HrtfSet& set) {
  const size_t count = set.directions.size();
  if (!(set.sample_rate_hz > 0.0) || !std::isfinite(set.sample_rate_hz)) return "sample rate must be positive";
  if (set.taps == 0 || set.taps > kMaxHrtfTaps)
    return "taps = " + std::to_string(set.taps) + " (must be 1 .. " + std::to_string(kMaxHrtfTaps) + ")";
  if (count < 4) return std::to_string(count) + " directions (at least 4 are needed)";
  if (set.left.size() != count * set.taps || set.right.size() != count * set.taps)
    return "responses: " + std::to_string(set.left.size()) + " and " + std::to_string(set.right.size()) +
           " values (must be directions x taps = " + std::to_string(count * set.taps) + " each)";
  set.unit_directions.resize(count);
  for (size_t i = 0; i < count; ++i) {
    const std::array<double, 3>& d = set.directions[i];
    const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(length > 0.0) || !std::isfinite(length))
      return "direction " + std::to_string(i) + " is not a finite non-zero vector";
    for (int k = 0; k < 3; ++k) set.unit_directions[i][k] = d[k] / length;
  }
  for (size_t k = 0; k < set.left.size(); ++k)
    if (!std::isfinite(set.left[k]) || !std::isfinite(set.right[k]))
      return "response of direction " + std::to_string(k / set.taps) + " is not finite";
  set.onset_left.resize(count);
  set.onset_right.resize(count);
  for (size_t i = 0; i < count; ++i) {
    set.onset_left[i] = thresholdOnset(set.left.data() + i * set.taps, set.taps);
    set.onset_right[i] = thresholdOnset(set.right.data() + i * set.taps, set.taps);
  }
  return "";
}

HrtfBlend hrtfBlend(const HrtfSet& set, const std::array<double, 3>& u) {
  // The four nearest by the cosine of the angle (ties: the lower index), then the angles.
  uint32_t nearest[4] = {0, 0, 0, 0};
  double cosine[4] = {-2.0, -2.0, -2.0, -2.0};
  for (uint32_t i = 0; i < set.unit_directions.size(); ++i) {
    const std::array<double, 3>& d = set.unit_directions[i];
    const double c = d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
    if (!(c > cosine[3])) continue;
    int at = 3;
    while (at > 0 && c > cosine[at - 1]) {
      cosine[at] = cosine[at - 1];
      nearest[at] = nearest[at - 1];
      --at;
    }
    cosine[at] = c;
    nearest[at] = i;
  }
  double angle[4];  // atan2(|u x d|, u . d): accurate near 0, where acos is not
  for (int j = 0; j < 4; ++j) {
    const std::array<double, 3>& d = set.unit_directions[nearest[j]];
    const double x = u[1] * d[2] - u[2] * d[1], y = u[2] * d[0] - u[0] * d[2], z = u[0] * d[1] - u[1] * d[0];
    angle[j] = std::atan2(std::sqrt(x * x + y * y + z * z), cosine[j]);
  }
  HrtfBlend blend;
  for (int j = 0; j < 3; ++j) blend.index[j] = nearest[j];
  if (angle[0] < 1e-9) {  // a measured direction
    blend.weight = {1.0, 0.0, 0.0};
    return blend;
  }
  double total = 0.0;
  for (int j = 0; j < 3; ++j) {
    const double w = (angle[3] - angle[j]) / (angle[3] * angle[j]);
    blend.weight[j] = w * w;
    total += blend.weight[j];
  }
  if (!(total > 0.0)) {  // all four equally near: the three alike
    blend.weight = {1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0};
    return blend;
  }
  for (double& w : blend.weight) w /= total;
  return blend;
}

void hrtfResponses(const HrtfSet& set, const HrtfBlend& blend, float* left, float* right) {
  blendEar(set, blend, set.left, set.onset_left, left);
  blendEar(set, blend, set.right, set.onset_right, right);
}

void BinauralPath::init(std::shared_ptr<const HrtfSet> set, size_t max_block_frames) {
  set_ = std::move(set);
  const size_t taps = set_->taps;
  for (int ear = 0; ear < 2; ++ear) {
    h_[ear].assign(taps, 0.0f);
    next_h_[ear].assign(taps, 0.0f);
    scratch_[ear].assign(max_block_frames, 0.0f);
  }
  history_.assign(taps - 1 + max_block_frames, 0.0f);
  quiet_run_ = taps;
  changed_ = false;
}

void BinauralPath::clear() {
  if (!set_) return;
  std::fill(history_.begin(), history_.end(), 0.0f);
  quiet_run_ = set_->taps;
  changed_ = false;
}

void BinauralPath::aim(const std::array<double, 3>& local, bool at_once) {
  const double length = std::sqrt(local[0] * local[0] + local[1] * local[1] + local[2] * local[2]);
  std::array<double, 3> u = {1.0, 0.0, 0.0};  // the listener's frame to SOFA's (x forward, y left)
  if (length > 1e-9) u = {local[1] / length, -local[0] / length, local[2] / length};
  const HrtfBlend blend = hrtfBlend(*set_, u);
  if (at_once) {
    blend_ = next_blend_ = blend;
    hrtfResponses(*set_, blend, h_[0].data(), h_[1].data());
    changed_ = false;
  } else if (blend == blend_) {
    changed_ = false;
  } else if (!changed_ || !(blend == next_blend_)) {
    next_blend_ = blend;
    hrtfResponses(*set_, blend, next_h_[0].data(), next_h_[1].data());
    changed_ = true;
  }
}

// y[n] = sum_k h[k] x[n - k], the sum over k in increasing order for every n (the loop over n
// inside vectorizes without reordering any sum: the same bits with or without SIMD).
void BinauralPath::convolve(const float* h, size_t frames, float* out) const {
  const size_t taps = set_->taps;
  std::fill(out, out + frames, 0.0f);
  const float* x = history_.data() + (taps - 1);
  for (size_t k = 0; k < taps; ++k) {
    const float hk = h[k];
    const float* xk = x - k;
    for (size_t n = 0; n < frames; ++n) out[n] += hk * xk[n];
  }
}

void BinauralPath::process(const float* in, size_t frames, float* left, float* right) {
  const size_t taps = set_->taps;
  std::copy(in, in + frames, history_.begin() + static_cast<std::ptrdiff_t>(taps - 1));
  size_t trailing = 0;
  while (trailing < frames && in[frames - 1 - trailing] == 0.0f) ++trailing;
  quiet_run_ = trailing == frames ? quiet_run_ + frames : trailing;
  float* out[2] = {left, right};
  for (int ear = 0; ear < 2; ++ear) {
    convolve(h_[ear].data(), frames, scratch_[ear].data());
    const float* y = scratch_[ear].data();
    if (!changed_) {
      for (size_t n = 0; n < frames; ++n) out[ear][n] += y[n];
      continue;
    }
    // The old filter's output fades out as the new one's fades in.
    float* fresh = scratch_[1 - ear].data();  // free: the other ear's is done or not begun
    convolve(next_h_[ear].data(), frames, fresh);
    const float inv = 1.0f / static_cast<float>(frames);
    for (size_t n = 0; n < frames; ++n) {
      const float t = static_cast<float>(n + 1) * inv;
      out[ear][n] += (1.0f - t) * y[n] + t * fresh[n];
    }
  }
  if (changed_) {
    h_[0].swap(next_h_[0]);
    h_[1].swap(next_h_[1]);
    blend_ = next_blend_;
    changed_ = false;
  }
  // Keep the last taps - 1 samples for the next block.
  std::memmove(history_.data(), history_.data() + frames, (taps - 1) * sizeof(float));
}

}  // namespace strike
