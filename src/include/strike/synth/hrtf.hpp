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
// Cost, per sounding path (the direct sound and the ground's image of each voice) and per block
// of kPartition (64) samples: 2 x 64 x 64 multiply-adds for the responses' first 64 taps, one
// forward and one inverse complex FFT of 128 points, and 128 complex multiply-adds per further
// partition (8 for KEMAR's 558 taps at 48 kHz): about a fifth of the direct convolution's 2 x 558
// per sample (docs/listener.md). A block whose direction changed runs the old and the new filters
// and cross-fades them; a silent path costs nothing once its last input has left the filter.
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

namespace detail {
class SmallFft;
}

/// One path's binaural filter: the interpolated responses for its direction, and its input's
/// history. The convolution is uniformly partitioned (hrtf.cpp): the responses' first
/// kHrtfPartition taps run directly on each sample, the rest as partitions of that length
/// multiplied with the input's blocks in the frequency domain, one block late, so nothing is
/// delayed. Allocates in init(), nothing after.
class BinauralPath {
 public:
  /// Samples per partition and per block of the frequency-domain part.
  static constexpr size_t kPartition = 64;
  static constexpr size_t kSpectrum = 2 * kPartition;  ///< the transforms' size
  BinauralPath();
  ~BinauralPath();
  BinauralPath(BinauralPath&&) noexcept;
  BinauralPath& operator=(BinauralPath&&) noexcept;
  void init(std::shared_ptr<const HrtfSet> set);
  bool ready() const { return set_ != nullptr; }
  /// Forgets the past input (SoundEngine::reset).
  void clear();
  /// The direction from the next block of kPartition samples on: `local` is the source relative
  /// to the listener in the listener's frame (x right, y forward, z up), m; at the listener:
  /// straight ahead. `at_once` switches without a cross-fade (a path's first block). A direction
  /// within 0.5 degree of the one last taken keeps the filter (hrtf.cpp).
  void aim(const std::array<double, 3>& local, bool at_once);
  /// Convolves `in` (any number of frames) with the path's responses and adds the result to left
  /// and right. A changed direction is cross-faded linearly over the block of kPartition samples
  /// where it takes effect. The blocks are counted from the path's first sample: the output does
  /// not depend on how the input is split into calls.
  void process(const float* in, size_t frames, float* left, float* right);
  /// Advances a path that is not ringing() by `frames` of silence without computing them.
  void skip(size_t frames);
  /// Samples of past input still in the filter: a silent path needs process() with zeros until
  /// this is false.
  bool ringing() const { return set_ && quiet_run_ < silentAfter(); }

 private:
  /// One direction's responses: the first kPartition taps of each ear, and the spectra of the
  /// further partitions, both ears in one (left + i right, zero-padded to 2 kPartition, scaled by
  /// 1 / (2 kPartition) for the inverse transform).
  struct Filter {
    std::vector<float> head[2];
    std::vector<float> re, im;  ///< partitions_ x 2 kPartition
  };
  void makeFilter(const HrtfBlend& blend, Filter& filter);
  size_t silentAfter() const;
  void startBlock();
  void endBlock();
  void tailOf(const Filter& filter, float* left, float* right);
  std::shared_ptr<const HrtfSet> set_;
  std::unique_ptr<detail::SmallFft> fft_;
  size_t partitions_ = 0;             ///< of the taps after the first kPartition
  HrtfBlend blend_{}, next_blend_{};  ///< filter_[0]'s and filter_[1]'s
  HrtfBlend wanted_{};                ///< the last aim()'s
  std::array<double, 3> aimed_at_{};  ///< the direction of wanted_, SOFA frame, unit
  bool aimed_ = false;
  bool fading_ = false;                         ///< this block cross-fades from filter_[0] to filter_[1]
  bool block_started_ = false;                  ///< the block's tails are computed
  Filter filter_[2];                            ///< in use, and the one fading in
  std::vector<float> responses_[2];             ///< taps: scratch for makeFilter
  std::vector<float> history_;                  ///< kPartition - 1 past samples, then up to kPartition new
  std::vector<float> block_;                    ///< 2 kPartition: the previous and the current input block
  std::vector<float> spectra_re_, spectra_im_;  ///< partitions_ x 2 kPartition: the last blocks' spectra
  size_t newest_ = 0;                           ///< the ring's slot of the last completed block
  std::vector<float> work_re_, work_im_;        ///< 2 kPartition
  std::vector<float> tail_[2][2];               ///< [filter][ear] kPartition: this block's output of the partitions
  std::vector<float> out_[2][2];                ///< [filter][ear] kPartition: scratch
  size_t phase_ = 0;                            ///< samples of the current block done
  size_t quiet_run_ = 0;                        ///< trailing zero input samples
};

}  // namespace strike
