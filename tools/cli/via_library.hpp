// SPDX-License-Identifier: MIT
// `strike render --via-library`: renderScene's steps sent through libstrike's C API.
#pragma once

#include "strike/scene/render.hpp"

namespace strike::cli {

/// A SoundOutput that drives a libstrike context as a game would (via_library.cpp), with every
/// object's gain at `gain`.
SoundOutputFactory libraryOutput(double gain);

}  // namespace strike::cli
