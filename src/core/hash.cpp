// SPDX-License-Identifier: MIT
#include "strike/core/hash.hpp"

#include <cstring>

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

uint64_t hashWords64(const void* data, size_t count, uint64_t seed) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  uint64_t hash = seed ^ (count * 0x9e3779b97f4a7c15ull);  // the length counts too
  for (size_t i = 0; i < count; ++i) {
    uint64_t word;
    std::memcpy(&word, bytes + 8 * i, sizeof word);  // one unaligned load
    hash = (hash ^ word) * 0x100000001b3ull;
    hash ^= hash >> 32;
  }
  // fmix64 of MurmurHash3.
  hash ^= hash >> 33;
  hash *= 0xff51afd7ed558ccdull;
  hash ^= hash >> 33;
  hash *= 0xc4ceb9fe1a85ec53ull;
  hash ^= hash >> 33;
  return hash;
}

}  // namespace strike
