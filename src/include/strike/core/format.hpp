// SPDX-License-Identifier: MIT
// Numbers in messages.
#pragma once

#include <string>

namespace strike {

/// `value` in the stream's general format with `significant_digits` digits: 17 gives back the
/// exact double that was read (for "got VALUE" in parse errors), 6 to 9 for derived quantities.
std::string formatNumber(double value, int significant_digits);

}  // namespace strike
