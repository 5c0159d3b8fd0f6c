// SPDX-License-Identifier: MIT
#include "strike/hash.hpp"

namespace strike {

uint64_t fnv1a64(const void* data, size_t size, uint64_t seed) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  uint64_t hash = seed;
  for (size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 0x100000001b3ull;  // the 64-bit FNV prime
  }
  return hash;
}

}  // namespace strike
