// SPDX-License-Identifier: MIT
// Direct solves (bank_strategy.hpp): a bank per object and material, keyed by its mesh and its
// precompute settings. Phase 1 opens a cached bank (its header; shapes later) or loads the mesh;
// phase 3 reads each sounding body's shapes where it was struck, extends a cached bank that lacks
// the transfer of modes this render plays, and solves the rest side by side under their cache
// locks, each written to the cache as it is taken.
#include <algorithm>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "bank_strategy.hpp"
#include "cache_lock.hpp"
#include "side_by_side.hpp"
#include "strike/cache/bank_cache.hpp"
#include "strike/precompute/element_order.hpp"

namespace strike {
namespace {

/// What solving the body's bank may hold at its peak, bytes, for running solves side by side:
/// the eigen-solve's 30 KB per degree of freedom (the first step's forecast of `strike modes
/// --tolerance`, error_estimate.cpp: the mug's peaked at 1.42 GB for 47k DOF; the solve's exact
/// forecast needs its factor's symbolic analysis, made in the solve) plus, with the acoustic
/// transfer, the larger of its own forecast (transferMemoryForecastBytes) and what it was measured
/// to take above the eigen-solve: 0.36 GB on box:0.2,0.1,0.05 (896 triangles, 9 modes; the
/// forecast, which counts the near quadrature since solver revision 6, says 0.94 GB; before it
/// said 33 MB), nothing on assets/meshes/glass.obj (0.47 GB peak either way).
double solveForecastBytes(const Body& body) {
  constexpr double kTransferMeasuredBytes = 0.5e9;
  const double dofs = body.mesh ? 3.0 * static_cast<double>(body.mesh->mesh.nodes.rows()) : 0.0;
  const double transfer =
      body.precompute.acoustic_transfer
          ? std::max(kTransferMeasuredBytes, transferMemoryForecastBytes(*body.bank, body.precompute.transfer))
          : 0.0;
  return 30e3 * dofs + transfer;
}

/// Whether the body's cached bank lacks the transfer of modes this render plays (it was solved
/// for a lower band: another sample rate, or a bank for fewer uses).
bool lacksHeardTransfer(const Body& body, const RenderSettings& settings) {
  const AcousticTransfer& t = body.bank->transfer;
  return settings.acoustic_transfer &&
         (t.offset.empty() || t.modeCount() < modesAtOrBelow(*body.bank, body.precompute.transfer_max_freq_hz));
}

class DirectBanks final : public BankStrategy {
 public:
  explicit DirectBanks(BankContext& context) : c_(context) {}

  Status prepare(size_t i, uint64_t mesh_hash) override {
    Body& body = c_.bodies[i];
    body.cache_key = bankCacheKey(mesh_hash, body.precompute);
    body.mesh_hash = mesh_hash;
    if (auto same = loaded_by_key_.find(body.cache_key); same != loaded_by_key_.end()) {
      const Body& first = c_.bodies[same->second];  // an identical object was read or meshed already
      body.bank = first.bank;
      body.file = first.file;
      body.has_modes = first.has_modes;
      if (!body.has_modes) body.mesh = first.mesh;
      return {};
    }
    loaded_by_key_.emplace(body.cache_key, i);
    if (!c_.settings.cache_dir.empty() && openCached(body)) return {};
    Result<LoadedMesh> loaded = loadMeshFor(body.precompute);
    if (!loaded) return badInput("objects \"" + body.object->name + "\": " + loaded.error().message);
    body.bank = std::make_shared<const ModeBank>(massAndSurfaceBank(*loaded, body.precompute));
    body.mesh = std::move(*loaded);
    return {};
  }

  /// Its file read (or its transfer extended); a damaged cache entry rolled back and its mesh
  /// loaded; then shared with an identical body, or to be solved.
  Status provide(size_t i) override {
    Body& body = c_.bodies[i];
    if (body.file) {
      if (readBankFile(i)) return {};
      forgetCachedBank(body);  // a damaged cache entry is recomputed, not trusted
      Result<LoadedMesh> loaded = loadMeshFor(body.precompute);
      if (!loaded) return badInput("objects \"" + body.object->name + "\": " + loaded.error().message);
      body.mesh = std::move(*loaded);
    }
    if (body.has_modes) return {};
    if (auto shared = computed_by_key_.find(body.cache_key); shared != computed_by_key_.end()) {
      shares_.emplace_back(i, shared->second);  // its bank once that body has one
      return {};
    }
    computed_by_key_[body.cache_key] = i;
    to_solve_.push_back(i);
    return {};
  }

  Status finish() override {
    std::map<uint64_t, CacheEntryLock> locks = lockBanksToSolve();
    if (Status solved = solveBanks(locks); !solved) return solved;
    return shareBanks();
  }

 private:
  BankContext& c_;
  std::map<uint64_t, size_t> loaded_by_key_;       ///< phase 1: identical objects are read or meshed once
  std::map<uint64_t, size_t> computed_by_key_;     ///< phase 3: ...and share one eigen-solve
  std::vector<size_t> to_solve_;                   ///< bodies whose bank is solved now
  std::vector<std::pair<size_t, size_t>> shares_;  ///< (body, the identical body whose bank it takes)
  std::map<uint64_t, std::shared_ptr<const ModeBank>> extended_by_key_;  ///< cached banks given more transfer

  /// The body's bank from the cache, if there and of the same mesh; counted in the report.
  bool openCached(Body& body) {
    std::optional<BankFile> cached = openCachedBank(c_.settings.cache_dir, body.cache_key, body.mesh_hash);
    if (!cached) return false;
    body.bank = cached->sharedBank();
    body.file = std::move(*cached);
    body.has_modes = true;
    body.from_cache = true;
    ++c_.report.banks_cached;
    c_.report.precompute_saved_seconds += solveSeconds(*body.bank);
    return true;
  }

  /// Undoes openCached() for an entry found damaged: its bank is solved again.
  void forgetCachedBank(Body& body) {
    body.file.reset();
    body.rows.reset();
    body.has_modes = false;
    if (body.from_cache) {
      --c_.report.banks_cached;
      c_.report.precompute_saved_seconds -= solveSeconds(*body.bank);
    }
  }

  /// Reads a body's cached bank file at its struck points, or extends its transfer; the error
  /// when the file is damaged.
  Status readBankFile(size_t i) {
    return lacksHeardTransfer(c_.bodies[i], c_.settings) ? extendCachedTransfer(c_.bodies[i]) : readStruckShapes(c_, i);
  }

  /// A cached bank that lacks the transfer of modes this render plays: read whole, those modes'
  /// transfer solved and appended (the bits of a cold solve), and the cache entry written again
  /// with it, so that the next render at this rate finds them. An identical object takes the bank
  /// extended for the first.
  Status extendCachedTransfer(Body& body) {
    if (auto done = extended_by_key_.find(body.cache_key); done != extended_by_key_.end()) {
      body.bank = done->second;
      body.file.reset();
      return {};
    }
    Result<ModeBank> all = body.file->readAll();
    if (!all) return all.error();
    c_.report.shape_vertices_read += all->surfaceVertexCount();
    c_.report.shape_vertices_total += all->surfaceVertexCount();
    if (c_.settings.progress) c_.settings.progress("transfer " + body.object->name, -1.0);
    const size_t heard = modesAtOrBelow(*all, body.precompute.transfer_max_freq_hz);
    if (Status solved = extendTransfer(*all, heard, body.precompute.transfer, c_.settings.progress); !solved)
      return badInput("objects \"" + body.object->name + "\": " + solved.error().message);
    ++c_.report.transfers_extended;
    body.bank = std::make_shared<const ModeBank>(std::move(*all));
    body.file.reset();
    extended_by_key_[body.cache_key] = body.bank;
    // A failed cache write costs the next render time, never this one its result.
    (void)writeBank(cachePath(c_.settings.cache_dir, body.cache_key, ".modes"), *body.bank);
    return {};
  }

  /// The cache locks of the banks to solve, held until they are in the cache: a render elsewhere
  /// that needs one waits, then reads it. Taken in the order of the keys, as every render takes
  /// them, so two never wait for each other. A bank solved meanwhile by the holder is read instead.
  std::map<uint64_t, CacheEntryLock> lockBanksToSolve() {
    std::map<uint64_t, CacheEntryLock> locks;
    if (c_.settings.cache_dir.empty()) return locks;
    std::vector<size_t> by_key = to_solve_;
    std::sort(by_key.begin(), by_key.end(),
              [&](size_t a, size_t b) { return c_.bodies[a].cache_key < c_.bodies[b].cache_key; });
    for (size_t i : by_key) {
      Body& body = c_.bodies[i];
      CacheEntryLock lock(cachePath(c_.settings.cache_dir, body.cache_key, ".lock"));
      if (lock.held() && !body.from_cache && openCached(body)) {
        if (readBankFile(i)) {  // solved by whoever held the lock while this render waited
          body.mesh.reset();
          to_solve_.erase(std::find(to_solve_.begin(), to_solve_.end(), i));
          continue;
        }
        forgetCachedBank(body);
        body.from_cache = false;
      }
      locks.emplace(body.cache_key, std::move(lock));
    }
    return locks;
  }

  /// The new banks, side by side (side_by_side.hpp): each solve's bits are a serial solve's. Each
  /// is cached (and its lock released) as it is taken, in the bodies' order.
  Status solveBanks(std::map<uint64_t, CacheEntryLock>& locks) {
    const RenderSettings& settings = c_.settings;
    std::vector<std::optional<Result<PrecomputeResult>>> computed(to_solve_.size());
    std::mutex progress_lock;  // the caller's progress callback is called from one thread at a time
    auto progress = [&](std::string_view phase, double fraction) {
      std::lock_guard<std::mutex> hold(progress_lock);
      settings.progress(phase, fraction);
    };
    runSideBySide(
        to_solve_.size(),
        settings.solve_threads > 0 ? settings.solve_threads : std::max(1u, std::thread::hardware_concurrency()),
        settings.max_memory_bytes > 0 ? settings.max_memory_bytes : availableMemoryBytes(),
        [&](size_t j) { return solveForecastBytes(c_.bodies[to_solve_[j]]); },
        [&](size_t j) {
          Body& body = c_.bodies[to_solve_[j]];
          PrecomputeSettings precompute = body.precompute;
          if (settings.progress) {
            // Solves side by side interleave their phases: each names its object.
            const std::string object = "modes " + body.object->name;
            precompute.progress = [&progress, object](std::string_view phase, double fraction) {
              progress(object + ": " + std::string(phase), fraction);
            };
            progress(object, -1.0);
          }
          computed[j] = computeModeBankForMesh(*body.mesh, precompute);
        });
    for (size_t j = 0; j < to_solve_.size(); ++j) {  // in the bodies' order, as a serial solve
      Body& body = c_.bodies[to_solve_[j]];
      Result<PrecomputeResult>& bank = *computed[j];
      if (!bank) return badInput("objects \"" + body.object->name + "\": " + bank.error().message);
      for (const MeshWarning& w : bank->report.warnings) c_.warn("objects \"" + body.object->name + "\": " + w.message);
      body.bank = std::make_shared<const ModeBank>(std::move(bank->bank));
      body.has_modes = true;
      body.mesh.reset();
      ++c_.report.banks_computed;
      if (!settings.cache_dir.empty()) {
        // A failed cache write costs the next render time, never this one its result.
        (void)writeBank(cachePath(settings.cache_dir, body.cache_key, ".modes"), *body.bank);
        locks.erase(body.cache_key);
      }
    }
    return {};
  }

  /// Identical objects take the bank of the first (read from the cache meanwhile: its shapes where
  /// this one is struck).
  Status shareBanks() {
    for (const auto& [i, holder] : shares_) {
      Body& body = c_.bodies[i];
      body.bank = c_.bodies[holder].bank;
      body.file = c_.bodies[holder].file;
      body.has_modes = true;
      ++c_.report.banks_shared;
      if (body.file)
        if (Status read = readStruckShapes(c_, i); !read) return read;
    }
    return {};
  }
};

}  // namespace

std::unique_ptr<BankStrategy> makeDirectBanks(BankContext& context) { return std::make_unique<DirectBanks>(context); }

}  // namespace strike
