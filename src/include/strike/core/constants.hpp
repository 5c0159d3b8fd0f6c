// SPDX-License-Identifier: MIT
// Mathematical constants (C++17 has no std::numbers).
#pragma once

namespace strike {

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace strike
