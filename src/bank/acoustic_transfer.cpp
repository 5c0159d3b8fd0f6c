// SPDX-License-Identifier: MIT
// AcousticTransfer's data helpers and its evaluation at a direction (acoustic_transfer.hpp).
// TODO(transfer helper): realSphericalHarmonics, evaluateFarField, rmsFarField, checkConsistency.
#include "strike/acoustic_transfer.hpp"

namespace strike {}  // namespace strike
