// SPDX-License-Identifier: MIT
// Where a render's banks come from (render.cpp's phases 1 and 3). The bank source owns looking a
// bank up (given in the scene, in the cache, or an identical object's), locking the cache entry
// it solves, solving, writing it back, and rolling back a cache entry found damaged. Banks
// solved from meshes follow one of two strategies (bank_strategy.hpp): direct solves, one bank
// per object and material (bank_source_direct.cpp), or similar ones, one solve per shape at unit
// size scaled to every size and material (--similar, bank_source_similar.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "strike/bank/bank.hpp"
#include "strike/precompute/normalized_problem.hpp"
#include "strike/precompute/precompute.hpp"
#include "strike/scene/render.hpp"
#include "strike/sim/sim.hpp"
#include "strike/synth/synth.hpp"

namespace strike {

/// One object on its way through the render.
struct Body {
  const SceneObject* object = nullptr;
  PrecomputeSettings precompute;
  uint64_t cache_key = 0;
  uint64_t mesh_hash = 0;
  /// Full bank, or mass and surface only until phase 3. Shared, never copied: with its bank file
  /// (a plate's transfer is 2 MB), with identical objects and with the voice.
  std::shared_ptr<const ModeBank> bank = std::make_shared<const ModeBank>();
  ModeBank similar_bank;  ///< with similar_reuse, phase 3: the scaled bank until its transfer is attached
  bool has_modes = false;
  std::optional<BankFile> file;    ///< a cached or given bank: its shapes are read in phase 3
                                   ///< at the vertices the contacts touch
  bool from_cache = false;         ///< counted in report.banks_cached
  std::optional<LoadedMesh> mesh;  ///< kept when the modes may still need computing
  double max_velocity_change_m_s = 0.0;
  bool sounded = false;                           ///< struck audibly: gets a bank and an oscillator
  bool silent = false;                            ///< ...but no mode in the synthesized band
  std::optional<ShapeRows> rows;                  ///< shapes read at the struck vertices only (readStruckShapes)
  std::shared_ptr<const SurfaceLocator> locator;  ///< built for `bank` by readStruckShapes, for its voice
  /// With a RenderSession: the session's copy of `bank` (the same header) that `locator` points
  /// into, for the voice (a locator projects only for the bank object it was built for).
  std::shared_ptr<const ModeBank> located_bank;
  double contact_radius_m = 0.0;  ///< radius of the sphere of equal volume, for Hertz
  // With RenderSettings::similar_reuse: cache_key, file, from_cache and mesh are the normalized
  // solve's, and bank its scaled copy (geometry only until phase 3).
  NormalizedProblem normal;   ///< the solve the bank is scaled from (normalized_problem.hpp)
  uint64_t identity_key = 0;  ///< of the object itself: equal for identical objects
  uint64_t normal_mesh_hash = 0;
  ModeBank normal_bank;       ///< the normalized solve: mass and surface, header, or whole once read
  uint64_t transfer_key = 0;  ///< with the transfer too: its unit transfer's (unitTransferCacheKey)
};

/// What the bank source and its strategies read and write: the render's bodies, its settings,
/// its report and its warnings.
struct BankContext {
  const RenderSettings& settings;
  std::vector<Body>& bodies;
  RenderReport& report;
  std::function<void(std::string)> warn;
  const std::vector<ContactEvent>* events = nullptr;  ///< phase 3: where each body was struck
};

class BankStrategy;

/// The banks of one render. prepare() in phase 1, provide() in phase 3, then pruneCache().
class BankSource {
 public:
  /// settings.similar_reuse chooses the strategy for banks solved from meshes.
  BankSource(const RenderSettings& settings, std::vector<Body>& bodies, RenderReport& report,
             std::function<void(std::string)> warn);
  ~BankSource();
  BankSource(const BankSource&) = delete;
  BankSource& operator=(const BankSource&) = delete;

  /// Phase 1, every body (object and, for a mesh, precompute settings filled in): its bank given
  /// in the scene, from the cache or an identical body's; otherwise its mesh, with the mass and
  /// surface the simulation needs.
  Status prepare();
  /// Phase 3: a bank for every body marked `sounded`, its shapes read where `events` strike it:
  /// from its file, shared, scaled, or solved (side by side), written to the cache.
  Status provide(const std::vector<ContactEvent>& events);
  /// After phase 3: the cache's least recently used entries removed until it fits its size cap
  /// (this render's banks were just written or touched, so they are the last to go).
  void pruneCache();

 private:
  BankContext context_;
  std::unique_ptr<BankStrategy> strategy_;
};

}  // namespace strike
