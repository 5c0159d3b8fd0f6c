// SPDX-License-Identifier: MIT
// Head-related impulse responses from an AES69 SOFA file (SimpleFreeFieldHRIR), read with
// libmysofa (target strike_sofa: the tools and the Python package, never libstrike, which is
// handed the responses through strike_output_desc).
#pragma once

#include <memory>
#include <string>

#include "strike/synth/hrtf.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// The MIT KEMAR set (normal pinna) that Debian's libmysofa package installs.
constexpr const char* kDefaultHrtfFile = "/usr/share/libmysofa/MIT_KEMAR_normal_pinna.sofa";

/// Reads `path` and resamples its responses to sample_rate_hz (libmysofa's resampler), with
/// Data.Delay applied (rounded to a sample) and prepareHrtfSet done. Bad input names the file.
Result<std::shared_ptr<const HrtfSet>> loadSofaHrtf(const std::string& path, double sample_rate_hz);

}  // namespace strike
