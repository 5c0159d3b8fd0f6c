// SPDX-License-Identifier: MIT
// The bank source's two strategies for banks solved from meshes (bank_source.hpp), and what they
// share: the cache's paths, a cached bank's recorded cost, and reading a bank file's shapes only
// where its body was struck.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "bank_source.hpp"

namespace strike {

/// How the banks of bodies solved from meshes are found, solved and cached.
class BankStrategy {
 public:
  virtual ~BankStrategy() = default;
  /// Phase 1, body i solved from its mesh (`mesh_hash`: its mesh file's or primitive's): its cache
  /// keys; its bank from the cache or an identical body's, or else its mesh, with mass and surface.
  virtual Status prepare(size_t i, uint64_t mesh_hash) = 0;
  /// Phase 3, in the bodies' order, each sounding body solved from its mesh.
  virtual Status provide(size_t i) = 0;
  /// Phase 3, after every sounding body: what provide() left to do for them together.
  virtual Status finish() { return {}; }
};

/// A bank per object: from the cache, an identical object's, or solved side by side, cached, with
/// a cached bank's missing transfer extended (bank_source_direct.cpp).
std::unique_ptr<BankStrategy> makeDirectBanks(BankContext& context);
/// --similar: one solve per shape at unit size, and with the transfer one unit transfer per wave
/// speed and modes kept, each cached and scaled to every body (bank_source_similar.cpp).
std::unique_ptr<BankStrategy> makeSimilarBanks(BankContext& context);

/// The cache's file for `key`: "<cache_dir>/<16 hex digits><extension>".
std::string cachePath(const std::string& cache_dir, uint64_t key, const char* extension);

/// The cache's bank file for `key` if it is there, opens and was solved from the mesh
/// `mesh_hash`, marked as read by this render (the size cap removes it last, least recently
/// used); nothing otherwise: a damaged or foreign entry is solved again, not trusted (damaged
/// shapes are found in phase 3).
std::optional<BankFile> openCachedBank(const std::string& cache_dir, uint64_t key, uint64_t mesh_hash);

/// What a bank cost to solve, as it records it: the whole precompute (meshing, assembly, the
/// eigen-solve and the acoustic transfer), what a cache read saves; older banks that recorded no
/// total, the eigen-solve and the transfer.
double solveSeconds(const ModeBank& bank);

/// Body i's bank file (cached or given), read only at the vertices where context.events strike
/// it (or whole where it must be); the error when the file is damaged.
Status readStruckShapes(BankContext& context, size_t i);

}  // namespace strike
