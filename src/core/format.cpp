// SPDX-License-Identifier: MIT
#include "strike/core/format.hpp"

#include <sstream>

namespace strike {

std::string formatNumber(double value, int significant_digits) {
  std::ostringstream out;
  out.precision(significant_digits);
  out << value;
  return out.str();
}

}  // namespace strike
