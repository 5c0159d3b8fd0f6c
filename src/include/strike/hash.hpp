// SPDX-License-Identifier: MIT
// FNV-1a 64 (Fowler, Noll, Vo): the one hash of bank checksums, mesh hashes and cache keys.
#pragma once

#include <cstddef>
#include <cstdint>

namespace strike {

/// FNV-1a 64-bit hash. Simple, deterministic and good enough to detect corruption and key a
/// cache; not a cryptographic hash. Chain calls by passing the previous result as `seed`.
uint64_t fnv1a64(const void* data, size_t size, uint64_t seed = 0xcbf29ce484222325ull);

}  // namespace strike
