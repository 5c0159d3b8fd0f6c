// SPDX-License-Identifier: MIT
// Binaural output (hrtf.hpp): the measured responses interpolated to a direction, and one path's
// convolution with them.
#include "strike/synth/hrtf.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "small_fft.hpp"

namespace strike {
namespace {

constexpr uint32_t kMaxHrtfTaps = 16384;
// cos(0.5 degree): the change of direction that builds a new filter (BinauralPath::aim).
constexpr double kHrtfSameDirectionCosine = 0.9999619230641713;

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

BinauralPath::BinauralPath() = default;
BinauralPath::~BinauralPath() = default;
BinauralPath::BinauralPath(BinauralPath&&) noexcept = default;
BinauralPath& BinauralPath::operator=(BinauralPath&&) noexcept = default;

void BinauralPath::init(std::shared_ptr<const HrtfSet> set) {
  set_ = std::move(set);
  const size_t taps = set_->taps;
  partitions_ = taps > kPartition ? (taps - 1) / kPartition : 0;
  fft_ = std::make_unique<detail::SmallFft>(kSpectrum);
  for (Filter& f : filter_) {
    for (std::vector<float>& head : f.head) head.assign(kPartition, 0.0f);
    f.re.assign(partitions_ * kSpectrum, 0.0f);
    f.im.assign(partitions_ * kSpectrum, 0.0f);
  }
  for (std::vector<float>& r : responses_) r.assign(taps, 0.0f);
  history_.assign(2 * kPartition - 1, 0.0f);
  block_.assign(kSpectrum, 0.0f);
  spectra_re_.assign(partitions_ * kSpectrum, 0.0f);
  spectra_im_.assign(partitions_ * kSpectrum, 0.0f);
  work_re_.assign(kSpectrum, 0.0f);
  work_im_.assign(kSpectrum, 0.0f);
  for (auto& filter : tail_)
    for (std::vector<float>& ear : filter) ear.assign(kPartition, 0.0f);
  for (auto& filter : out_)
    for (std::vector<float>& ear : filter) ear.assign(kPartition, 0.0f);
  newest_ = phase_ = 0;
  fading_ = block_started_ = aimed_ = false;
  quiet_run_ = silentAfter();
}

size_t BinauralPath::silentAfter() const { return (partitions_ + 3) * kPartition; }

void BinauralPath::clear() {
  if (!set_) return;
  std::fill(history_.begin(), history_.end(), 0.0f);
  std::fill(block_.begin(), block_.end(), 0.0f);
  std::fill(spectra_re_.begin(), spectra_re_.end(), 0.0f);
  std::fill(spectra_im_.begin(), spectra_im_.end(), 0.0f);
  for (auto& filter : tail_)
    for (std::vector<float>& ear : filter) std::fill(ear.begin(), ear.end(), 0.0f);
  if (fading_) {
    std::swap(filter_[0], filter_[1]);
    blend_ = next_blend_;
  }
  newest_ = phase_ = 0;
  fading_ = block_started_ = false;
  quiet_run_ = silentAfter();
}

void BinauralPath::aim(const std::array<double, 3>& local, bool at_once) {
  const double length = std::sqrt(local[0] * local[0] + local[1] * local[1] + local[2] * local[2]);
  std::array<double, 3> u = {1.0, 0.0, 0.0};  // the listener's frame to SOFA's (x forward, y left)
  if (length > 1e-9) u = {local[1] / length, -local[0] / length, local[2] / length};
  // A direction within kHrtfSameDirection of the one last taken keeps its filter: a moving body
  // would otherwise search the measured directions and build a filter (8 FFTs for KEMAR) every
  // call for changes far below the set's spacing (5 degrees and more for KEMAR).
  if (!at_once && aimed_) {
    const double dot = u[0] * aimed_at_[0] + u[1] * aimed_at_[1] + u[2] * aimed_at_[2];
    if (dot >= kHrtfSameDirectionCosine) return;
  }
  aimed_ = true;
  aimed_at_ = u;
  wanted_ = hrtfBlend(*set_, u);
  if (!at_once) return;  // taken at the next block's start
  blend_ = wanted_;
  makeFilter(blend_, filter_[0]);
  fading_ = false;
  if (block_started_) tailOf(filter_[0], tail_[0][0].data(), tail_[0][1].data());
}

void BinauralPath::makeFilter(const HrtfBlend& blend, Filter& filter) {
  const size_t taps = set_->taps;
  hrtfResponses(*set_, blend, responses_[0].data(), responses_[1].data());
  for (int ear = 0; ear < 2; ++ear)
    for (size_t k = 0; k < kPartition; ++k) filter.head[ear][k] = k < taps ? responses_[ear][k] : 0.0f;
  const float scale = 1.0f / static_cast<float>(kSpectrum);  // the inverse transform's 1 / N
  for (size_t p = 0; p < partitions_; ++p) {
    for (size_t k = 0; k < kPartition; ++k) {
      const size_t tap = (p + 1) * kPartition + k;
      work_re_[k] = tap < taps ? responses_[0][tap] : 0.0f;
      work_im_[k] = tap < taps ? responses_[1][tap] : 0.0f;
    }
    std::fill(work_re_.begin() + kPartition, work_re_.end(), 0.0f);
    std::fill(work_im_.begin() + kPartition, work_im_.end(), 0.0f);
    fft_->forward(work_re_.data(), work_im_.data());
    for (size_t k = 0; k < kSpectrum; ++k) {
      filter.re[p * kSpectrum + k] = work_re_[k] * scale;
      filter.im[p * kSpectrum + k] = work_im_[k] * scale;
    }
  }
}

// Overlap-save [Oppenheim & Schafer, Discrete-Time Signal Processing, sec. 8.7.3]: with X_j the
// spectrum of input blocks j - 1 and j, and H_p that of partition p (taps p B .. p B + B - 1,
// zero-padded), the last B samples of the inverse of H_p X_j are partition p's output over block
// j + p. Block k's output from partitions 1..P is then the inverse of sum_p H_p X_{k-p}: blocks
// that are complete when block k begins. Both ears in one transform: the responses are packed as
// left + i right, the input is real, so the real part of the result is the left ear's output and
// the imaginary part the right's.
void BinauralPath::tailOf(const Filter& filter, float* left, float* right) {
  if (partitions_ == 0) {
    std::fill(left, left + kPartition, 0.0f);
    std::fill(right, right + kPartition, 0.0f);
    return;
  }
  std::fill(work_re_.begin(), work_re_.end(), 0.0f);
  std::fill(work_im_.begin(), work_im_.end(), 0.0f);
  float* yr = work_re_.data();
  float* yi = work_im_.data();
  for (size_t p = 0; p < partitions_; ++p) {
    const size_t slot = (newest_ + partitions_ - p) % partitions_;  // X_{k-1-p}
    const float* xr = spectra_re_.data() + slot * kSpectrum;
    const float* xi = spectra_im_.data() + slot * kSpectrum;
    const float* hr = filter.re.data() + p * kSpectrum;
    const float* hi = filter.im.data() + p * kSpectrum;
    for (size_t k = 0; k < kSpectrum; ++k) {
      yr[k] += xr[k] * hr[k] - xi[k] * hi[k];
      yi[k] += xr[k] * hi[k] + xi[k] * hr[k];
    }
  }
  fft_->inverse(yr, yi);
  std::copy(yr + kPartition, yr + kSpectrum, left);
  std::copy(yi + kPartition, yi + kSpectrum, right);
}

void BinauralPath::startBlock() {
  if (!(wanted_ == blend_)) {
    next_blend_ = wanted_;
    makeFilter(next_blend_, filter_[1]);
    fading_ = true;
  }
  tailOf(filter_[0], tail_[0][0].data(), tail_[0][1].data());
  if (fading_) tailOf(filter_[1], tail_[1][0].data(), tail_[1][1].data());
  block_started_ = true;
}

void BinauralPath::endBlock() {
  if (partitions_ > 0) {
    newest_ = (newest_ + 1) % partitions_;
    float* xr = spectra_re_.data() + newest_ * kSpectrum;
    float* xi = spectra_im_.data() + newest_ * kSpectrum;
    const bool silent = std::all_of(block_.begin(), block_.end(), [](float x) { return x == 0.0f; });
    if (silent) {
      std::fill(xr, xr + kSpectrum, 0.0f);
      std::fill(xi, xi + kSpectrum, 0.0f);
    } else {
      std::copy(block_.begin(), block_.end(), xr);
      std::fill(xi, xi + kSpectrum, 0.0f);
      fft_->forward(xr, xi);
    }
  }
  std::copy(block_.begin() + kPartition, block_.end(), block_.begin());
  if (fading_) {
    std::swap(filter_[0], filter_[1]);
    blend_ = next_blend_;
    fading_ = false;
  }
  block_started_ = false;
  phase_ = 0;
}

void BinauralPath::process(const float* in, size_t frames, float* left, float* right) {
  float* out[2] = {left, right};
  size_t done = 0;
  while (done < frames) {
    if (!block_started_) startBlock();
    const size_t run = std::min(kPartition - phase_, frames - done);
    const float* x = in + done;
    std::copy(x, x + run, history_.begin() + (kPartition - 1));
    std::copy(x, x + run, block_.begin() + static_cast<std::ptrdiff_t>(kPartition + phase_));
    size_t trailing = 0;
    while (trailing < run && x[run - 1 - trailing] == 0.0f) ++trailing;
    quiet_run_ = trailing == run ? quiet_run_ + run : trailing;
    // y[n] = tail[n] + sum_k h[k] x[n - k], the sum over k in increasing order for every n (the
    // loop over n inside vectorizes without reordering any sum: the same bits with or without SIMD).
    const float* now = history_.data() + (kPartition - 1);
    const int filters = fading_ ? 2 : 1;
    for (int f = 0; f < filters; ++f)
      for (int ear = 0; ear < 2; ++ear) {
        float* y = out_[f][ear].data();
        std::copy(tail_[f][ear].begin() + static_cast<std::ptrdiff_t>(phase_),
                  tail_[f][ear].begin() + static_cast<std::ptrdiff_t>(phase_ + run), y);
        const float* h = filter_[f].head[ear].data();
        for (size_t k = 0; k < kPartition; ++k) {
          const float hk = h[k];
          const float* xk = now - k;
          for (size_t n = 0; n < run; ++n) y[n] += hk * xk[n];
        }
      }
    for (int ear = 0; ear < 2; ++ear) {
      float* o = out[ear] + done;
      const float* y = out_[0][ear].data();
      if (!fading_) {
        for (size_t n = 0; n < run; ++n) o[n] += y[n];
        continue;
      }
      // The old filter's output fades out as the new one's fades in, over the block.
      const float* fresh = out_[1][ear].data();
      const float inv = 1.0f / static_cast<float>(kPartition);
      for (size_t n = 0; n < run; ++n) {
        const float t = static_cast<float>(phase_ + n + 1) * inv;
        o[n] += (1.0f - t) * y[n] + t * fresh[n];
      }
    }
    // Keep the last kPartition - 1 samples for the next run.
    std::copy(history_.begin() + static_cast<std::ptrdiff_t>(run),
              history_.begin() + static_cast<std::ptrdiff_t>(run + kPartition - 1), history_.begin());
    phase_ += run;
    done += run;
    if (phase_ == kPartition) endBlock();
  }
}

// Silence through a filter with nothing in it: only the block count and a change of direction
// (which a block of silence would have faded to) move.
void BinauralPath::skip(size_t frames) {
  quiet_run_ += frames;
  while (frames > 0) {
    if (!block_started_) {
      if (!(wanted_ == blend_)) {
        blend_ = wanted_;
        makeFilter(blend_, filter_[0]);
      }
      block_started_ = true;
    }
    const size_t run = std::min(kPartition - phase_, frames);
    phase_ += run;
    frames -= run;
    if (phase_ == kPartition) {
      if (fading_) {
        std::swap(filter_[0], filter_[1]);
        blend_ = next_blend_;
        fading_ = false;
      }
      block_started_ = false;
      phase_ = 0;
    }
  }
}

}  // namespace strike
