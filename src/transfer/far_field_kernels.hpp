// SPDX-License-Identifier: MIT
// The far-field evaluation's instruction-set kernel (far_field_f16c.cpp), chosen at run time.
#pragma once

#include <cstddef>
#include <cstdint>

namespace strike::detail {

/// The eight partial sums S_r of evaluateFarFields (acoustic_transfer.hpp) over the first
/// `whole` coefficients (a multiple of 8) of one mode, for `directions` (1 or 2) directions:
/// out[16 d + 2 r] (real) and out[16 d + 2 r + 1] (imaginary). Needs AVX2 and F16C.
void farFieldSumsF16c(const uint16_t* halves, size_t whole, size_t directions, const float* const* weights, float* out);

/// halves[k] = floatToHalf(values[k] * up) for k < count (acoustic_transfer.hpp), up a power of
/// two that is a normal float: the same halves, eight at a time. Needs AVX2 and F16C.
void halvesF16c(const float* values, size_t count, float up, uint16_t* halves);

}  // namespace strike::detail
