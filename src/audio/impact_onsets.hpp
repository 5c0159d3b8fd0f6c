// SPDX-License-Identifier: MIT
// Private helper of strike_fftw: where the impacts of a recording start.
#pragma once

#include <cstddef>
#include <vector>

namespace strike::detail {

/// Sample indices at which a new impact starts in the mono signal x, ascending; the first is
/// `first_onset` (the file's onset). A new impact is a 1 ms block whose peak |x| is more than
/// twice (6 dB) the largest |x| of the 25 ms before it, and above -60 dB of the file's peak.
/// Why this tells impacts from beats: the free ring of a linear body is a sum of decaying
/// sinusoids, whose envelope cannot grow faster than linearly out of a beat null, so it never
/// exceeds its own maximum over a window longer than the block by 2x (a window of 25 ms also
/// holds a half period, hence a crest, of every mode above 20 Hz). An impact adds energy
/// within the contact time (< 1 ms), a step the ring alone cannot make. The onset sample is the
/// first in the block above that 25 ms maximum.
std::vector<size_t> impactOnsets(const std::vector<double>& x, size_t first_onset, double peak, double rate_hz);

}  // namespace strike::detail
