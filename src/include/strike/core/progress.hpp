// SPDX-License-Identifier: MIT
// Progress reporting for long steps (meshing, factorization, Lanczos, rendering).
#pragma once

#include <functional>
#include <string_view>

namespace strike {

/// Called from long-running steps. `phase` names the step ("tetrahedralize", "factorize",
/// "lanczos", ...), `fraction` is in [0, 1] when known, or negative when the step cannot say.
/// May be empty; callers must check before calling. Never called from an audio thread.
using ProgressFn = std::function<void(std::string_view phase, double fraction)>;

}  // namespace strike
