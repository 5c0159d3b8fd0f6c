// SPDX-License-Identifier: MIT
// Binaural output: head-related impulse responses (HRIRs) measured in a set of directions (an
// AES69 SOFA file's, which the host reads: libstrike reads no file), interpolated to each path's
// direction of arrival and convolved with the path's signal, one filter per ear
// (docs/listener.md).
//
// Interpolation: modified Shepard weighting of the three measured directions nearest to the
// direction of arrival [Franke & Nielson 1980, "Smooth interpolation of large sets of scattered
// data", Int. J. Numer. Meth. Eng. 15]: w_i = ((a_4 - a_i) / (a_4 a_i))^2 over the angles a_i to
// them and a_4 to the fourth nearest, normalised. It is exact at a measured direction and
// continuous everywhere (a direction's weight reaches 0 as it stops being among the three
// nearest). Before they are weighted, the responses are aligned on their onsets (the first
// sample at 10% of the response's peak, a threshold onset), and the weighted mean onset,
// rounded to a sample, is put back: the interaural delay is interpolated as a delay, not as
// a blend of two pulses at different times.
//
// Cost: 2 x taps multiply-adds per sample per sounding path (the direct sound and the ground's
// image of each voice), twice that in a render call whose direction changed (the old and the
// new filters are both run and cross-faded over the call), nothing for a silent path once its
// last input has left the filter.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace strike {

/// Measured head-related impulse responses, at the engine's sample rate.
struct HrtfSet {
  double sample_rate_hz = 0.0;
  uint32_t taps = 0;  ///< samples per response
  /// Where each was measured from, as given (any length): the source seen from the head's
  /// centre in the SOFA (and AmbiX) frame, x forward, y left, z up.
  std::vector<std::array<double, 3>> directions;
  std::vector<float> left, right;  ///< directions.size() x taps each
  // Made by prepareHrtfSet from the above:
  std::vector<std::array<double, 3>> unit_directions;
  /// Per direction and ear, the first sample at 10% of that response's peak.
  std::vector<uint32_t> onset_left, onset_right;
};

/// Checks a set (at least 4 directions of non-zero finite length, taps 1..16384, finite
/// responses) and prepares it: unit directions and onsets. Returns "" or what is wrong.
std::string prepareHrtfSet(HrtfSet& set);

/// The measured directions that make up one direction's responses and their weights (sum 1).
struct HrtfBlend {
  std::array<uint32_t, 3> index{};
  std::array<double, 3> weight{};
  bool operator==(const HrtfBlend& other) const { return index == other.index && weight == other.weight; }
};

/// The blend for unit direction `u` (SOFA frame).
HrtfBlend hrtfBlend(const HrtfSet& set, const std::array<double, 3>& u);

/// The interpolated responses of a blend: set.taps values into each of left and right.
void hrtfResponses(const HrtfSet& set, const HrtfBlend& blend, float* left, float* right);

/// One path's binaural filter: the interpolated responses for its direction, and its input's
/// history. Allocates in init(), nothing after.
class BinauralPath {
 public:
  void init(std::shared_ptr<const HrtfSet> set, size_t max_block_frames);
  bool ready() const { return set_ != nullptr; }
  /// Forgets the past input (SoundEngine::reset).
  void clear();
  /// The direction for the next block: `local` is the source relative to the listener in the
  /// listener's frame (x right, y forward, z up), m; at the listener: straight ahead. `at_once`
  /// switches without a cross-fade (a path's first block).
  void aim(const std::array<double, 3>& local, bool at_once);
  /// Convolves `in` (frames, <= max_block_frames) with the path's responses and adds the result
  /// to left and right. A changed direction is cross-faded linearly over the block.
  void process(const float* in, size_t frames, float* left, float* right);
  /// Samples of past input still in the filter: a silent path needs process() with zeros until
  /// this is false.
  bool ringing() const { return set_ && quiet_run_ < set_->taps; }

 private:
  void convolve(const float* h, size_t frames, float* out) const;
  std::shared_ptr<const HrtfSet> set_;
  HrtfBlend blend_{}, next_blend_{};
  bool changed_ = false;
  std::vector<float> h_[2], next_h_[2];  ///< left, right
  std::vector<float> history_;           ///< taps - 1 past samples, then the block's
  std::vector<float> scratch_[2];
  size_t quiet_run_ = 0;  ///< trailing zero input samples
};

}  // namespace strike
