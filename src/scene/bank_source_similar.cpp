// SPDX-License-Identifier: MIT
// Similar solves (--similar, bank_strategy.hpp): every bank is a normalized solve of its shape at
// unit size (normalized_problem.hpp), scaled to the body's size and material. Phase 1 opens the
// shape's cached solve (its header) or loads its normalized mesh, and scales mass and surface;
// phase 3 reads, shares or solves (under its cache lock) each shape's solve once and scales it,
// and with the transfer does the same for each unit transfer (one per shape, wave speed and
// number of modes kept).
#include <filesystem>
#include <map>
#include <optional>
#include <utility>

#include "bank_strategy.hpp"
#include "cache_lock.hpp"
#include "strike/cache/bank_cache.hpp"
#include "strike/precompute/element_order.hpp"

namespace strike {
namespace {

class SimilarBanks final : public BankStrategy {
 public:
  explicit SimilarBanks(BankContext& context) : c_(context) {}

  /// Keys, and the scaled mass and surface of the shape's solve (cached, or from its mesh).
  Status prepare(size_t i, uint64_t mesh_hash) override {
    Body& body = c_.bodies[i];
    body.mesh_hash = mesh_hash;
    body.identity_key = bankCacheKey(mesh_hash, body.precompute);
    body.normal = normalizeProblem(body.precompute);
    const std::string& normal_spec = body.normal.settings.mesh_spec;
    body.normal_mesh_hash = isPrimitiveSpec(normal_spec) ? fnv1a64(normal_spec.data(), normal_spec.size()) : mesh_hash;
    body.cache_key = normalizedBankCacheKey(body.normal_mesh_hash, body.normal);
    if (auto same = loaded_by_key_.find(body.cache_key); same != loaded_by_key_.end()) {
      const Body& first = c_.bodies[same->second];  // an object of the same shape was read or meshed already
      body.normal_bank = first.normal_bank;
      body.file = first.file;
      body.has_modes = first.has_modes;
      if (!body.has_modes) body.mesh = first.mesh;
      return scaleGeometry(body);
    }
    loaded_by_key_.emplace(body.cache_key, i);
    if (!c_.settings.cache_dir.empty() && openCachedSolve(body)) return scaleGeometry(body);
    if (Status loaded = loadNormalMesh(body); !loaded) return loaded;
    body.normal_bank = massAndSurfaceBank(*body.mesh, body.normal.settings);
    return scaleGeometry(body);
  }

  /// Its bank, and with the transfer its transfer.
  Status provide(size_t i) override {
    Body& body = c_.bodies[i];
    if (Status made = provideModes(i); !made) return made;
    if (c_.settings.acoustic_transfer)
      if (Status made = provideTransfer(i); !made) return made;
    body.bank = std::make_shared<const ModeBank>(std::move(body.similar_bank));
    body.similar_bank = ModeBank();
    return {};
  }

 private:
  BankContext& c_;
  std::map<uint64_t, size_t> loaded_by_key_;  ///< phase 1: each shape is read or meshed once
  std::map<uint64_t, size_t> solved_by_key_;  ///< phase 3: ...solved once, held by this body
  std::map<uint64_t, ModeBank> unit_by_key_;  ///< ...and one transfer per wave speed and modes kept

  Status objectError(const Body& body, const Error& error) const {
    return badInput("objects \"" + body.object->name + "\": " + error.message);
  }

  /// The body's normalized solve from the cache (header now, shapes in phase 3), if there and of
  /// the same mesh; counted in the report.
  bool openCachedSolve(Body& body) {
    std::optional<BankFile> cached = openCachedBank(c_.settings.cache_dir, body.cache_key, body.normal_mesh_hash);
    if (!cached) return false;
    body.normal_bank = cached->bank();
    body.file = std::move(*cached);
    body.has_modes = true;
    body.from_cache = true;
    ++c_.report.banks_cached;
    c_.report.precompute_saved_seconds += solveSeconds(body.normal_bank);
    return true;
  }

  /// Reads the whole cached normalized solve (a scaled bank needs every shape: its radiation is
  /// recomputed from them). False when the entry is damaged.
  bool readCachedSolve(Body& body) {
    Result<ModeBank> all = body.file->readAll();
    if (!all) return false;
    body.normal_bank = std::move(*all);
    body.file.reset();
    c_.report.shape_vertices_read += body.normal_bank.surfaceVertexCount();
    c_.report.shape_vertices_total += body.normal_bank.surfaceVertexCount();
    return true;
  }

  /// Undoes openCachedSolve() for an entry found damaged: it is solved again.
  void forgetCachedSolve(Body& body) {
    body.file.reset();
    body.has_modes = false;
    if (body.from_cache) {
      --c_.report.banks_cached;
      c_.report.precompute_saved_seconds -= solveSeconds(body.normal_bank);
    }
    body.from_cache = false;
  }

  /// The body's mass and surface for the simulator: its normalized solve's, scaled, so they are
  /// the very numbers of the bank phase 3 scales, whether the solve was cached or not.
  Status scaleGeometry(Body& body) {
    ModeBank geometry = body.normal_bank;
    geometry.eigenvalues.clear();
    geometry.shapes.clear();
    geometry.radiation_m2.clear();
    geometry.frequency_error_estimate.clear();
    Result<ModeBank> scaled = scaleNormalizedBank(geometry, body.normal, body.precompute, body.mesh_hash);
    if (!scaled) return objectError(body, scaled.error());
    body.bank = std::make_shared<const ModeBank>(std::move(*scaled));
    return {};
  }

  /// Loads the normalized mesh (to solve, and for mass and surface until then).
  Status loadNormalMesh(Body& body) {
    Result<LoadedMesh> loaded = loadMeshFor(body.normal.settings);
    if (!loaded) return objectError(body, loaded.error());
    body.mesh = std::move(*loaded);
    return {};
  }

  /// The body's bank from its whole normalized solve, which it then holds for the others.
  Status scaleSolve(size_t i) {
    Body& body = c_.bodies[i];
    Result<ModeBank> scaled = scaleNormalizedBank(body.normal_bank, body.normal, body.precompute, body.mesh_hash);
    if (!scaled) return objectError(body, scaled.error());
    body.similar_bank = std::move(*scaled);
    body.has_modes = true;
    body.mesh.reset();
    solved_by_key_[body.cache_key] = i;
    return {};
  }

  /// The body's shape's solve (shared with an earlier body, read from the cache, or solved now
  /// and cached), scaled to it.
  Status provideModes(size_t i) {
    Body& body = c_.bodies[i];
    if (auto shared = solved_by_key_.find(body.cache_key); shared != solved_by_key_.end()) {
      const Body& holder = c_.bodies[shared->second];
      ++(holder.identity_key == body.identity_key ? c_.report.banks_shared : c_.report.banks_scaled);
      Result<ModeBank> scaled = scaleNormalizedBank(holder.normal_bank, body.normal, body.precompute, body.mesh_hash);
      if (!scaled) return objectError(body, scaled.error());
      body.similar_bank = std::move(*scaled);
      body.file.reset();
      body.mesh.reset();
      return {};
    }
    if (body.file) {
      if (readCachedSolve(body)) return scaleSolve(i);
      forgetCachedSolve(body);  // damaged shapes are recomputed, not trusted
    }
    // Held until the solve is in the cache: a render elsewhere that needs it waits, then reads it.
    CacheEntryLock lock;
    if (!c_.settings.cache_dir.empty()) {
      lock = CacheEntryLock(cachePath(c_.settings.cache_dir, body.cache_key, ".lock"));
      // Solved by whoever held the lock while this render simulated or waited.
      if (lock.held() && openCachedSolve(body)) {
        if (readCachedSolve(body)) return scaleSolve(i);
        forgetCachedSolve(body);
      }
    }
    if (!body.mesh)
      if (Status loaded = loadNormalMesh(body); !loaded) return loaded;
    if (c_.settings.progress) c_.settings.progress("modes " + body.object->name, -1.0);
    Result<PrecomputeResult> computed = computeModeBankForMesh(*body.mesh, body.normal.settings);
    if (!computed) return objectError(body, computed.error());
    for (const MeshWarning& w : computed->report.warnings)
      c_.warn("objects \"" + body.object->name + "\": " + w.message);
    body.normal_bank = std::move(computed->bank);
    ++c_.report.banks_computed;
    if (!c_.settings.cache_dir.empty()) {
      // A failed cache write costs the next render time, never this one its result.
      (void)writeBank(cachePath(c_.settings.cache_dir, body.cache_key, ".modes"), body.normal_bank);
    }
    return scaleSolve(i);
  }

  /// The unit transfer `key` from the cache, if there and the one of these modes (a damaged,
  /// foreign or stale entry is solved again, not trusted); marked as used.
  std::optional<ModeBank> readCachedTransfer(uint64_t key, const ModeBank& normal, const PrecomputeSettings& actual,
                                             size_t kept_modes) const {
    const std::string path = cachePath(c_.settings.cache_dir, key, ".transfer");
    if (!std::filesystem::is_regular_file(path)) return std::nullopt;
    Result<ModeBank> cached = readBank(path);
    if (!cached || !isUnitTransferOf(*cached, normal, actual, kept_modes)) return std::nullopt;
    touchCacheEntry(path);
    return std::move(*cached);
  }

  /// The body's (already scaled) bank gets its unit transfer, scaled (normalized_problem.hpp):
  /// shared with an earlier body of the same shape, wave speed and modes kept, read from the
  /// cache, or solved now on the normalized solve and cached. Which one changes no bit of the
  /// body's transfer.
  Status provideTransfer(size_t i) {
    Body& body = c_.bodies[i];
    const ModeBank& normal = c_.bodies[solved_by_key_.at(body.cache_key)].normal_bank;  // whole: shapes loaded
    const size_t kept = modesAtOrBelow(body.similar_bank, body.precompute.transfer_max_freq_hz);  // the heard modes
    body.transfer_key = unitTransferCacheKey(body.cache_key, body.precompute, kept);
    auto attach = [&](const ModeBank& unit) -> Status {
      Status attached = attachUnitTransfer(body.similar_bank, unit, body.normal, body.precompute);
      if (!attached) return objectError(body, attached.error());
      return {};
    };
    if (auto shared = unit_by_key_.find(body.transfer_key); shared != unit_by_key_.end()) {
      ++c_.report.transfers_shared;
      return attach(shared->second);
    }
    std::optional<ModeBank> unit;
    // Held until the transfer is in the cache: a render elsewhere that needs it waits, then reads it.
    CacheEntryLock lock;
    if (!c_.settings.cache_dir.empty()) {
      unit = readCachedTransfer(body.transfer_key, normal, body.precompute, kept);
      if (!unit) {
        lock = CacheEntryLock(cachePath(c_.settings.cache_dir, body.transfer_key, ".lock"));
        // Solved by whoever held the lock while this render waited.
        if (lock.held()) unit = readCachedTransfer(body.transfer_key, normal, body.precompute, kept);
      }
    }
    if (unit) {
      ++c_.report.transfers_cached;
      c_.report.transfer_saved_seconds += unit->transfer_seconds;
    } else {
      if (c_.settings.progress) c_.settings.progress("transfer " + body.object->name, -1.0);
      Result<ModeBank> solved = solveUnitTransfer(normal, body.precompute, kept);
      if (!solved) return objectError(body, solved.error());
      ++c_.report.transfers_solved;
      // A failed cache write costs the next render time, never this one its result.
      if (!c_.settings.cache_dir.empty())
        (void)writeBank(cachePath(c_.settings.cache_dir, body.transfer_key, ".transfer"), *solved);
      unit = std::move(*solved);
    }
    Status attached = attach(*unit);
    unit_by_key_.emplace(body.transfer_key, std::move(*unit));
    return attached;
  }
};

}  // namespace

std::unique_ptr<BankStrategy> makeSimilarBanks(BankContext& context) { return std::make_unique<SimilarBanks>(context); }

}  // namespace strike
