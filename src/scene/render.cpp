// SPDX-License-Identifier: MIT
// The two-phase render. Follow renderScene() from top to bottom: bodies, simulation, banks for
// what was heard, impacts into the oscillator bank, audio.
#include "strike/render.hpp"
#include "strike/sofa_hrtf.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "cache_lock.hpp"
#include "hull_cache.hpp"
#include "pieces_cache.hpp"
#include "playback.hpp"
#include "side_by_side.hpp"
#include "strike/atomic_file.hpp"
#include "strike/bank.hpp"
#include "strike/bank_cache.hpp"
#include "strike/contact_noise.hpp"
#include "strike/element_order.hpp"
#include "strike/materials.hpp"
#include "strike/normalized_problem.hpp"
#include "strike/precompute.hpp"
#include "strike/render_session.hpp"
#include "strike/scene_checks.hpp"
#include "strike/synth.hpp"
#include "surfaces.hpp"

namespace strike {
namespace {

/// What a bank cost to solve, as it records it: the whole precompute (meshing, assembly, the
/// eigen-solve and the acoustic transfer), what a cache read saves; older banks that recorded no
/// total, the eigen-solve and the transfer.
double solveSeconds(const ModeBank& bank) {
  return std::max(bank.total_seconds, bank.factorize_seconds + bank.lanczos_seconds + bank.transfer_seconds);
}

// A velocity change below 1 micrometre per second cannot be heard from any object of audible
// size; objects struck only that softly get no eigen-solve (a conservative audibility bound).
constexpr double kInaudibleVelocityChange_m_s = 1e-6;
// Hertz pulses are capped at this length (a rubber ball's is ~1 ms): no physical pulse is cut.
constexpr double kMaxContactDuration_s = 0.05;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// One object on its way through the render.
struct Body {
  const SceneObject* object = nullptr;
  PrecomputeSettings precompute;
  uint64_t cache_key = 0;
  uint64_t mesh_hash = 0;
  /// Full bank, or mass and surface only until phase 2. Shared, never copied: with its bank file
  /// (a plate's transfer is 2 MB), with identical objects and with the voice.
  std::shared_ptr<const ModeBank> bank = std::make_shared<const ModeBank>();
  ModeBank similar_bank;  ///< with similar_reuse, phase 2: the scaled bank until its transfer is attached
  bool has_modes = false;
  std::optional<BankFile> file;    ///< a cached or given bank: its shapes are read in phase 2
                                   ///< at the vertices the contacts touch
  bool from_cache = false;         ///< counted in report.banks_cached
  std::optional<LoadedMesh> mesh;  ///< kept when the modes may still need computing
  double max_velocity_change_m_s = 0.0;
  bool sounded = false;           ///< struck audibly: gets a bank and an oscillator
  bool silent = false;            ///< ...but no mode in the synthesized band
  std::optional<ShapeRows> rows;  ///< shapes read at the struck vertices only (readStruckShapes)
  std::shared_ptr<const SurfaceLocator> locator;  ///< built for `bank` by readStruckShapes, for its voice
  LocatedPoints located;  ///< the contact points readStruckShapes located with `locator`, for its voice
  /// With a RenderSession: the session's copy of `bank` (the same header) that `locator` points
  /// into, for the voice (a locator projects only for the bank object it was built for).
  std::shared_ptr<const ModeBank> located_bank;
  double contact_radius_m = 0.0;  ///< radius of the sphere of equal volume, for Hertz
  // With RenderSettings::similar_reuse: cache_key, file, from_cache and mesh are the normalized
  // solve's, and bank its scaled copy (geometry only until phase 2).
  NormalizedProblem normal;   ///< the solve the bank is scaled from (normalized_problem.hpp)
  uint64_t identity_key = 0;  ///< of the object itself: equal for identical objects
  uint64_t normal_mesh_hash = 0;
  ModeBank normal_bank;  ///< the normalized solve: mass and surface, header, or whole once read
  uint64_t transfer_key = 0;  ///< with the transfer too: its unit transfer's (unitTransferCacheKey)
};

std::string hex(uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

Result<uint64_t> meshHash(const std::string& spec) {
  if (isPrimitiveSpec(spec)) return fnv1a64(spec.data(), spec.size());
  Result<std::string> bytes = readWholeFile(spec, uint64_t(1) << 31);
  if (!bytes) return bytes.error();
  return fnv1a64(bytes->data(), bytes->size());
}

std::string cachePath(const std::string& cache_dir, uint64_t key, const char* extension) {
  return cache_dir + "/" + hex(key) + extension;
}

/// The body's bank from the cache, if there and of the same mesh; counted in the report.
bool openCached(const std::string& cache_dir, Body& body, RenderReport& report) {
  const std::string path = cachePath(cache_dir, body.cache_key, ".modes");
  if (!std::filesystem::is_regular_file(path)) return false;
  Result<BankFile> cached = BankFile::open(path);
  // A damaged cache entry is recomputed, not trusted (damaged shapes are found in phase 2).
  if (!cached || cached->bank().mesh_hash != body.mesh_hash) return false;
  touchCacheEntry(path);  // read by this render: the size cap removes it last (least recently used)
  body.bank = cached->sharedBank();
  body.file = std::move(*cached);
  body.has_modes = true;
  body.from_cache = true;
  ++report.banks_cached;
  report.precompute_saved_seconds += solveSeconds(*body.bank);
  return true;
}

// ---- RenderSettings::similar_reuse: every bank a normalized solve, scaled ---------------------

/// The body's normalized solve from the cache (header now, shapes in phase 2), if there and of
/// the same mesh; counted in the report.
bool openCachedSolve(const std::string& cache_dir, Body& body, RenderReport& report) {
  const std::string path = cachePath(cache_dir, body.cache_key, ".modes");
  if (!std::filesystem::is_regular_file(path)) return false;
  Result<BankFile> cached = BankFile::open(path);
  // A damaged cache entry is recomputed, not trusted (damaged shapes are found in phase 2).
  if (!cached || cached->bank().mesh_hash != body.normal_mesh_hash) return false;
  touchCacheEntry(path);  // as openCached()
  body.normal_bank = cached->bank();
  body.file = std::move(*cached);
  body.has_modes = true;
  body.from_cache = true;
  ++report.banks_cached;
  report.precompute_saved_seconds += solveSeconds(body.normal_bank);
  return true;
}

/// The body's mass and surface for the simulator: its normalized solve's, scaled, so they are
/// the very numbers of the bank phase 2 scales, whether the solve was cached or not.
Status scaleGeometry(Body& body) {
  ModeBank geometry = body.normal_bank;
  geometry.eigenvalues.clear();
  geometry.shapes.clear();
  geometry.radiation_m2.clear();
  geometry.frequency_error_estimate.clear();
  Result<ModeBank> scaled = scaleNormalizedBank(geometry, body.normal, body.precompute, body.mesh_hash);
  if (!scaled) return badInput("objects \"" + body.object->name + "\": " + scaled.error().message);
  body.bank = std::make_shared<const ModeBank>(std::move(*scaled));
  return {};
}

/// Loads the normalized mesh (to solve, and for mass and surface until then).
Status loadNormalMesh(Body& body) {
  Result<LoadedMesh> loaded = loadMeshFor(body.normal.settings);
  if (!loaded) return badInput("objects \"" + body.object->name + "\": " + loaded.error().message);
  body.mesh = std::move(*loaded);
  return {};
}

/// Phase 1 for one object with similar_reuse: keys, and the scaled mass and surface.
Status prepareSimilarBody(const RenderSettings& settings, uint64_t mesh_hash, Body& body,
                          std::map<uint64_t, const Body*>& loaded_by_key, RenderReport& report) {
  body.mesh_hash = mesh_hash;
  body.identity_key = bankCacheKey(mesh_hash, body.precompute);
  body.normal = normalizeProblem(body.precompute);
  const std::string& normal_spec = body.normal.settings.mesh_spec;
  body.normal_mesh_hash = isPrimitiveSpec(normal_spec) ? fnv1a64(normal_spec.data(), normal_spec.size()) : mesh_hash;
  body.cache_key = normalizedBankCacheKey(body.normal_mesh_hash, body.normal);
  if (auto same = loaded_by_key.find(body.cache_key); same != loaded_by_key.end()) {
    body.normal_bank = same->second->normal_bank;  // an object of the same shape was read or meshed already
    body.file = same->second->file;
    body.has_modes = same->second->has_modes;
    if (!body.has_modes) body.mesh = same->second->mesh;
    return scaleGeometry(body);
  }
  if (!settings.cache_dir.empty() && openCachedSolve(settings.cache_dir, body, report)) return scaleGeometry(body);
  if (Status loaded = loadNormalMesh(body); !loaded) return loaded;
  body.normal_bank = massAndSurfaceBank(*body.mesh, body.normal.settings);
  return scaleGeometry(body);
}

/// Reads the whole cached normalized solve (a scaled bank needs every shape: its radiation is
/// recomputed from them). False when the entry is damaged.
bool readCachedSolve(Body& body, RenderReport& report) {
  Result<ModeBank> all = body.file->readAll();
  if (!all) return false;
  body.normal_bank = std::move(*all);
  body.file.reset();
  report.shape_vertices_read += body.normal_bank.surfaceVertexCount();
  report.shape_vertices_total += body.normal_bank.surfaceVertexCount();
  return true;
}

/// Undoes openCachedSolve() for an entry found damaged: it is solved again.
void forgetCachedSolve(Body& body, RenderReport& report) {
  body.file.reset();
  body.has_modes = false;
  if (body.from_cache) {
    --report.banks_cached;
    report.precompute_saved_seconds -= solveSeconds(body.normal_bank);
  }
  body.from_cache = false;
}

/// The body's bank from its whole normalized solve, which it then holds for the others.
Status scaleSolve(Body& body, size_t index, std::map<uint64_t, size_t>& solved_by_key) {
  Result<ModeBank> scaled = scaleNormalizedBank(body.normal_bank, body.normal, body.precompute, body.mesh_hash);
  if (!scaled) return badInput("objects \"" + body.object->name + "\": " + scaled.error().message);
  body.similar_bank = std::move(*scaled);
  body.has_modes = true;
  body.mesh.reset();
  solved_by_key[body.cache_key] = index;
  return {};
}

/// Phase 2 for one sounding body with similar_reuse: its shape's solve (shared with an earlier
/// body, read from the cache, or solved now and cached), scaled to it.
template <class Warn>
Status similarModes(std::vector<Body>& bodies, size_t i, const RenderSettings& settings,
                    std::map<uint64_t, size_t>& solved_by_key, RenderReport& report, Warn& warn) {
  Body& body = bodies[i];
  if (auto shared = solved_by_key.find(body.cache_key); shared != solved_by_key.end()) {
    const Body& holder = bodies[shared->second];
    ++(holder.identity_key == body.identity_key ? report.banks_shared : report.banks_scaled);
    Result<ModeBank> scaled = scaleNormalizedBank(holder.normal_bank, body.normal, body.precompute, body.mesh_hash);
    if (!scaled) return badInput("objects \"" + body.object->name + "\": " + scaled.error().message);
    body.similar_bank = std::move(*scaled);
    body.file.reset();
    body.mesh.reset();
    return {};
  }
  if (body.file) {
    if (readCachedSolve(body, report)) return scaleSolve(body, i, solved_by_key);
    forgetCachedSolve(body, report);  // damaged shapes are recomputed, not trusted
  }
  // Held until the solve is in the cache: a render elsewhere that needs it waits, then reads it.
  CacheEntryLock lock;
  if (!settings.cache_dir.empty()) {
    lock = CacheEntryLock(cachePath(settings.cache_dir, body.cache_key, ".lock"));
    // Solved by whoever held the lock while this render simulated or waited.
    if (lock.held() && openCachedSolve(settings.cache_dir, body, report)) {
      if (readCachedSolve(body, report)) return scaleSolve(body, i, solved_by_key);
      forgetCachedSolve(body, report);
    }
  }
  if (!body.mesh)
    if (Status loaded = loadNormalMesh(body); !loaded) return loaded;
  if (settings.progress) settings.progress("modes " + body.object->name, -1.0);
  Result<PrecomputeResult> computed = computeModeBankForMesh(*body.mesh, body.normal.settings);
  if (!computed) return badInput("objects \"" + body.object->name + "\": " + computed.error().message);
  for (const MeshWarning& w : computed->report.warnings) warn("objects \"" + body.object->name + "\": " + w.message);
  body.normal_bank = std::move(computed->bank);
  ++report.banks_computed;
  if (!settings.cache_dir.empty()) {
    // A failed cache write costs the next render time, never this one its result.
    (void)writeBank(cachePath(settings.cache_dir, body.cache_key, ".modes"), body.normal_bank);
  }
  return scaleSolve(body, i, solved_by_key);
}

/// The unit transfer `key` from the cache, if there and the one of these modes (a damaged,
/// foreign or stale entry is solved again, not trusted); marked as used.
std::optional<ModeBank> readCachedTransfer(const std::string& cache_dir, uint64_t key, const ModeBank& normal,
                                           const PrecomputeSettings& actual, size_t kept_modes) {
  const std::string path = cachePath(cache_dir, key, ".transfer");
  if (!std::filesystem::is_regular_file(path)) return std::nullopt;
  Result<ModeBank> cached = readBank(path);
  if (!cached || !isUnitTransferOf(*cached, normal, actual, kept_modes)) return std::nullopt;
  touchCacheEntry(path);
  return std::move(*cached);
}

/// With similar_reuse and the transfer: the body's (already scaled) bank gets its unit transfer,
/// scaled (normalized_problem.hpp): shared with an earlier body of the same shape, wave speed and
/// modes kept, read from the cache, or solved now on the normalized solve and cached. Which one
/// changes no bit of the body's transfer.
Status similarTransfer(std::vector<Body>& bodies, size_t i, const RenderSettings& settings,
                       const std::map<uint64_t, size_t>& solved_by_key, std::map<uint64_t, ModeBank>& unit_by_key,
                       RenderReport& report) {
  Body& body = bodies[i];
  const ModeBank& normal = bodies[solved_by_key.at(body.cache_key)].normal_bank;  // whole: shapes loaded
  const size_t kept = modesAtOrBelow(body.similar_bank, body.precompute.transfer_max_freq_hz);  // the heard modes
  body.transfer_key = unitTransferCacheKey(body.cache_key, body.precompute, kept);
  auto attach = [&](const ModeBank& unit) -> Status {
    Status attached = attachUnitTransfer(body.similar_bank, unit, body.normal, body.precompute);
    if (!attached) return badInput("objects \"" + body.object->name + "\": " + attached.error().message);
    return {};
  };
  if (auto shared = unit_by_key.find(body.transfer_key); shared != unit_by_key.end()) {
    ++report.transfers_shared;
    return attach(shared->second);
  }
  std::optional<ModeBank> unit;
  // Held until the transfer is in the cache: a render elsewhere that needs it waits, then reads it.
  CacheEntryLock lock;
  if (!settings.cache_dir.empty()) {
    unit = readCachedTransfer(settings.cache_dir, body.transfer_key, normal, body.precompute, kept);
    if (!unit) {
      lock = CacheEntryLock(cachePath(settings.cache_dir, body.transfer_key, ".lock"));
      // Solved by whoever held the lock while this render waited.
      if (lock.held()) unit = readCachedTransfer(settings.cache_dir, body.transfer_key, normal, body.precompute, kept);
    }
  }
  if (unit) {
    ++report.transfers_cached;
    report.transfer_saved_seconds += unit->transfer_seconds;
  } else {
    if (settings.progress) settings.progress("transfer " + body.object->name, -1.0);
    Result<ModeBank> solved = solveUnitTransfer(normal, body.precompute, kept);
    if (!solved) return badInput("objects \"" + body.object->name + "\": " + solved.error().message);
    ++report.transfers_solved;
    // A failed cache write costs the next render time, never this one its result.
    if (!settings.cache_dir.empty())
      (void)writeBank(cachePath(settings.cache_dir, body.transfer_key, ".transfer"), *solved);
    unit = std::move(*solved);
  }
  Status attached = attach(*unit);
  unit_by_key.emplace(body.transfer_key, std::move(*unit));
  return attached;
}

/// Phase 2 for one sounding body with similar_reuse: its bank, and with the transfer its transfer.
template <class Warn>
Status similarPhase2(std::vector<Body>& bodies, size_t i, const RenderSettings& settings,
                     std::map<uint64_t, size_t>& solved_by_key, std::map<uint64_t, ModeBank>& unit_by_key,
                     RenderReport& report, Warn& warn) {
  Body& body = bodies[i];
  if (Status made = similarModes(bodies, i, settings, solved_by_key, report, warn); !made) return made;
  if (settings.acoustic_transfer)
    if (Status made = similarTransfer(bodies, i, settings, solved_by_key, unit_by_key, report); !made) return made;
  body.bank = std::make_shared<const ModeBank>(std::move(body.similar_bank));
  body.similar_bank = ModeBank();
  return {};
}

/// Phase 1 for one object: a bank with at least mass properties and surface. Its modes up to
/// `max_freq_hz`; the acoustic transfer of those up to `heard_hz`, the band the engine plays.
Status prepareBody(const Scene& scene, const RenderSettings& settings, double max_freq_hz, double heard_hz, Body& body,
                   std::map<uint64_t, const Body*>& loaded_by_key, RenderReport& report) {
  const SceneObject& object = *body.object;
  if (!object.bank.empty()) {
    Result<BankFile> file = BankFile::open(object.bank);
    if (!file) return file.error();
    body.bank = file->sharedBank();
    body.file = std::move(*file);
    body.has_modes = true;
    ++report.banks_given;
    return {};
  }
  body.precompute.mesh_spec = object.mesh;
  body.precompute.material = object.material;
  body.precompute.order = object.order;
  body.precompute.target_edge_m = object.size_m;
  body.precompute.mesh_scale = object.mesh_scale;
  body.precompute.max_freq_hz = max_freq_hz;
  body.precompute.max_modes = scene.max_modes;
  body.precompute.max_tets = settings.max_tets;
  body.precompute.max_memory_bytes = settings.max_memory_bytes;
  body.precompute.progress = settings.progress;
  body.precompute.acoustic_transfer = settings.acoustic_transfer;
  body.precompute.transfer_max_freq_hz = heard_hz;
  Result<uint64_t> hash = meshHash(object.mesh);
  if (!hash) return hash.error();
  if (settings.similar_reuse) return prepareSimilarBody(settings, *hash, body, loaded_by_key, report);
  body.cache_key = bankCacheKey(*hash, body.precompute);
  body.mesh_hash = *hash;
  if (auto same = loaded_by_key.find(body.cache_key); same != loaded_by_key.end()) {
    body.bank = same->second->bank;  // an identical object was read or meshed already
    body.file = same->second->file;
    body.has_modes = same->second->has_modes;
    if (!body.has_modes) body.mesh = same->second->mesh;
    return {};
  }
  if (!settings.cache_dir.empty() && openCached(settings.cache_dir, body, report)) return {};
  Result<LoadedMesh> loaded = loadMeshFor(body.precompute);
  if (!loaded) return badInput("objects \"" + object.name + "\": " + loaded.error().message);
  body.bank = std::make_shared<const ModeBank>(massAndSurfaceBank(*loaded, body.precompute));
  body.mesh = std::move(*loaded);
  return {};
}

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
  return settings.acoustic_transfer && body.object->bank.empty() &&
         (t.offset.empty() || t.modeCount() < modesAtOrBelow(*body.bank, body.precompute.transfer_max_freq_hz));
}

/// A cached bank that lacks the transfer of modes this render plays: read whole, those modes'
/// transfer solved and appended (the bits of a cold solve), and the cache entry written again
/// with it, so that the next render at this rate finds them. An identical object takes the bank
/// extended for the first (`extended`, by cache key).
Status extendCachedTransfer(Body& body, const RenderSettings& settings,
                            std::map<uint64_t, std::shared_ptr<const ModeBank>>& extended, RenderReport& report) {
  if (auto done = extended.find(body.cache_key); done != extended.end()) {
    body.bank = done->second;
    body.file.reset();
    return {};
  }
  Result<ModeBank> all = body.file->readAll();
  if (!all) return all.error();
  report.shape_vertices_read += all->surfaceVertexCount();
  report.shape_vertices_total += all->surfaceVertexCount();
  if (settings.progress) settings.progress("transfer " + body.object->name, -1.0);
  const size_t heard = modesAtOrBelow(*all, body.precompute.transfer_max_freq_hz);
  if (Status solved = extendTransfer(*all, heard, body.precompute.transfer, settings.progress); !solved)
    return badInput("objects \"" + body.object->name + "\": " + solved.error().message);
  ++report.transfers_extended;
  body.bank = std::make_shared<const ModeBank>(std::move(*all));
  body.file.reset();
  extended[body.cache_key] = body.bank;
  // A failed cache write costs the next render time, never this one its result.
  (void)writeBank(cachePath(settings.cache_dir, body.cache_key, ".modes"), *body.bank);
  return {};
}

/// A bank opened from a file keeps its shapes there until the simulation has said where the
/// body was struck: read them only at the vertices of those points' nearest triangles (the
/// projector's locator finds the same vertices again when it projects). A render of 20 plates
/// reads ~2% of their 340 MB of shapes this way.
Status readStruckShapes(Body& body, uint32_t index, const std::vector<ContactEvent>& events, bool whole,
                        RenderSession* session, RenderReport& report) {
  body.rows.reset();
  body.locator.reset();
  body.located = {};
  body.located_bank.reset();
  const ModeBank& bank = *body.bank;
  const bool has_radiation = bank.radiation_m2.size() == bank.modeCount();
  // With a session, the locator of this file's content built by an earlier render (and the bank
  // object it points into, that render's file's): the same grid, so the same vertices and bytes.
  RenderSession::BankSurface surface;
  if (session) surface = session->bankSurface(*body.file);
  std::shared_ptr<const SurfaceLocator> shared_locator =
      session ? surface.locator : std::make_shared<const SurfaceLocator>(bank);
  const SurfaceLocator& locator = *shared_locator;
  if (!has_radiation || !locator.hasTriangles() || whole) {
    // Radiation strengths computed from every shape (banks written before the RADI chunk), no
    // triangles to locate on, or a library that loads whole bank files: the whole bank.
    Result<ModeBank> all = body.file->readAll();
    if (!all) return all.error();
    body.bank = std::make_shared<const ModeBank>(std::move(*all));
    body.file.reset();
    report.shape_vertices_read += body.bank->surfaceVertexCount();
    report.shape_vertices_total += body.bank->surfaceVertexCount();
    return {};
  }
  // The points where the body was struck; a bank with no mode in the band (a marble) needs no
  // shape anywhere, so none.
  std::vector<std::array<double, 3>> points;
  if (bank.modeCount() > 0)
    for (const ContactEvent& event : events) {
      if (event.body_a == index) points.push_back(event.point_a_mesh);
      if (event.body_b == index) points.push_back(event.point_b_mesh);
    }
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  std::vector<uint32_t> vertices;
  LocatedPoints located;
  located.vertices.resize(points.size());
  located.weights.resize(points.size());
  for (size_t p = 0; p < points.size(); ++p) {
    locator.nearest(points[p].data(), located.vertices[p].data(), located.weights[p].data());
    vertices.insert(vertices.end(), located.vertices[p].begin(), located.vertices[p].end());
  }
  located.points = std::move(points);
  Result<ShapeRows> rows = body.file->readShapeRows(std::move(vertices));
  if (!rows) return rows.error();
  report.shape_vertices_read += rows->vertices.size();
  report.shape_vertices_total += bank.surfaceVertexCount();
  body.rows = std::move(*rows);
  body.locator = std::move(shared_locator);  // the voice projects with it (the same bank object)
  body.located = std::move(located);         // and looks these points up instead of locating them again
  body.located_bank = std::move(surface.bank);
  return {};
}

SimBodyDesc simBody(const Body& body) {
  const SceneObject& object = *body.object;
  SimBodyDesc desc;
  desc.name = object.name;
  desc.is_static = object.is_static;
  desc.surface_positions = body.bank->surface_positions;
  desc.surface_triangles = body.bank->surface_triangles;
  desc.mass_kg = body.bank->mass_kg;
  desc.centre_m = body.bank->centre_m;
  desc.inertia_kg_m2 = body.bank->inertia_kg_m2;
  desc.position_m = object.position_m;
  desc.orientation_wxyz = object.orientation_wxyz;
  desc.path = object.path;
  if (!object.path.empty()) {  // a driven body starts on its path (for the checks and the voice)
    const PathPose start = pathPose(object.path, 0.0);
    desc.position_m = start.position_m;
    desc.orientation_wxyz = start.orientation_wxyz;
  }
  desc.velocity_m_s = object.velocity_m_s;
  desc.angular_velocity_rad_s = object.angular_velocity_rad_s;
  const SurfaceProperties surface = objectSurface(object, body.bank->material);
  desc.restitution = surface.restitution;
  desc.friction = surface.friction;
  desc.rolling_resistance = surface.rolling_resistance;
  desc.compliance_per_pa = surface.compliance_per_pa;
  desc.contact_radius_m = body.contact_radius_m;
  desc.shape = object.shape == "convex"    ? SimBodyDesc::Shape::ConvexHull
               : object.shape == "concave" ? SimBodyDesc::Shape::Concave
               : object.shape == "pieces"  ? SimBodyDesc::Shape::ConvexPieces
                                           : SimBodyDesc::Shape::Auto;
  return desc;
}

double dot(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
double norm(const std::array<double, 3>& a) { return std::sqrt(dot(a, a)); }

/// Whether a struck body can be heard at all: some mode in the band the oscillator bank
/// synthesizes (the band test of OscillatorBank::addObject). The error says why not.
Status hasAudibleMode(const ModeBank& bank, const SynthSettings& synth, double rate) {
  const double low = synth.min_freq_hz, high = synthesizedTopHz(synth.max_freq_hz, rate);
  for (size_t i = 0; i < bank.modeCount(); ++i) {
    const double f = bank.frequencyHz(i);
    if (f >= low && f <= high) return {};
  }
  char why[256];
  if (bank.modeCount() == 0)
    std::snprintf(why, sizeof why,
                  "its bank has no elastic mode below its cut-off of %.0f Hz: too small or too stiff to ring",
                  bank.max_freq_hz);
  else
    std::snprintf(why, sizeof why, "its %zu modes lie at %.1f to %.1f Hz, outside the synthesized band %.0f to %.0f Hz",
                  bank.modeCount(), bank.frequencyHz(0), bank.frequencyHz(bank.modeCount() - 1), low, high);
  return badInput(std::string("silent: no mode in the audible band (") + why + ")");
}

}  // namespace

EngineSettings renderEngineSettings(const Scene& scene, const RenderSettings& settings, double rate_hz,
                                    double max_freq_hz) {
  EngineSettings engine;
  engine.synth.sample_rate_hz = rate_hz;
  engine.synth.max_freq_hz = std::min(20000.0, max_freq_hz);
  engine.synth.simd = settings.simd;
  if (settings.leave_nothing_out) {
    engine.synth.max_freq_hz = max_freq_hz;
    engine.synth.audibility_threshold = 0.0;
  }
  engine.output = settings.output_format;
  engine.air_absorption = scene.air_absorption;
  engine.air = scene.air;
  engine.channels = outputChannels(settings.output_format);
  engine.max_voices = static_cast<uint32_t>(scene.objects.size());
  engine.max_block_frames = kRenderBlockFrames;
  engine.max_active_modes = 0;  // a render keeps every audible mode
  engine.max_contact_duration_s = kMaxContactDuration_s;
  engine.contact_damping_per_s = scene.contact_damping_per_s;
  engine.realtime = false;
  engine.ground.enabled = scene.has_ground && scene.ground_reflects;
  engine.ground.normal = {0, 0, 1};  // the simulation's ground plane (sim.cpp)
  engine.ground.height_m = scene.ground_height_m;
  engine.ground.reflection = std::isnan(scene.ground_reflection) ? groundReflectionCoefficient(scene.ground_material)
                                                                 : scene.ground_reflection;
  return engine;
}

std::string defaultCacheDir() {
  if (const char* dir = std::getenv("STRIKE_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::string(xdg) + "/strike";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/strike";
  return {};
}

namespace {

/// One render on its way through the pipeline: what each phase reads, and leaves for the next.
struct RenderRun {
  RenderRun(const Scene& scene_, const RenderSettings& settings_) : scene(scene_), settings(settings_) {}
  const Scene& scene;
  const RenderSettings& settings;
  double rate = 0.0, duration = 0.0, substep = 0.0;
  double max_freq_hz = 0.0;  ///< no mode above the audible band or what the rate can carry is computed
  double heard_hz = 0.0;     ///< ...and only the modes the engine plays get an acoustic transfer
  EngineSettings engine_settings;
  RenderResult result;
  std::vector<Body> bodies;
  std::vector<SimBodyDesc> sim_bodies;
  SimResult simulated;  ///< its events moved to result.events
  SurfaceProperties ground_surface;
  std::vector<bool> has_voice;

  RenderReport& report() { return result.report; }
  void warn(std::string text) {
    if (settings.on_warning) settings.on_warning(text);
    result.report.warnings.push_back(std::move(text));
  }
};

// ---- Phase 1: bodies ------------------------------------------------------------------------

/// Each object's bank (given, cached) or mesh, with mass and surface for the simulation.
Status prepareBodies(RenderRun& run) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<Body>& bodies = run.bodies;
  bodies.resize(run.scene.objects.size());
  std::map<uint64_t, const Body*> loaded_by_key;  // identical objects are read or meshed once
  for (size_t i = 0; i < bodies.size(); ++i) {
    bodies[i].object = &run.scene.objects[i];
    Status prepared =
        prepareBody(run.scene, run.settings, run.max_freq_hz, run.heard_hz, bodies[i], loaded_by_key, run.report());
    if (!prepared) return prepared;
    if (bodies[i].object->bank.empty()) loaded_by_key.emplace(bodies[i].cache_key, &bodies[i]);
    bodies[i].contact_radius_m = std::cbrt(3.0 * bodies[i].bank->volume_m3 / (4.0 * M_PI));
    run.result.body_names.push_back(run.scene.objects[i].name);
  }
  if (!run.settings.cache_dir.empty()) {
    std::error_code ignored;
    std::filesystem::create_directories(run.settings.cache_dir, ignored);
  }
  run.report().load_seconds = secondsSince(start);
  return {};
}

// ---- Phase 2: the simulation --------------------------------------------------------------

/// The starting placement's warnings, and one for a given bank without a transfer.
void warnBeforeSimulating(RenderRun& run) {
  for (std::string& text : checkStartingPlacement(run.scene, run.sim_bodies)) run.warn(std::move(text));
  // A bank given in the scene is used as it is: one without a transfer (older formats, or solved
  // with --no-transfer) is heard with the direction-averaged model (radiation.cpp). Say so once.
  if (run.settings.acoustic_transfer)
    for (const Body& body : run.bodies)
      if (!body.object->bank.empty() && body.bank->transfer.empty() && body.bank->modeCount() > 0)
        run.warn("objects \"" + body.object->name + "\": bank " + body.object->bank +
                 " has no acoustic transfer: heard at each mode's direction-averaged level, with no direction "
                 "(solve it again with `strike modes` for the transfer; docs/listener.md)");
}

/// Convex pieces of concave moving bodies from the cache (computed ones are written after); the
/// surface hash of each body looked up (0: none).
std::vector<uint64_t> readCachedPieces(RenderRun& run) {
  std::vector<uint64_t> surface_hashes(run.bodies.size(), 0);
  for (size_t i = 0; i < run.bodies.size(); ++i) {
    const SceneObject& object = *run.bodies[i].object;
    if (run.settings.cache_dir.empty() || object.is_static) continue;
    // A primitive (box, sphere, cylinder) is convex: its surface fills its hull, so "auto" makes
    // it a hull and it never needs pieces; hashing its surface (~0.2 ms) would buy nothing.
    if (object.bank.empty() && isPrimitiveSpec(object.mesh) && (object.shape == "auto" || object.shape == "convex"))
      continue;
    SimBodyDesc& sim_body = run.sim_bodies[i];
    surface_hashes[i] = surfaceHash(sim_body.surface_positions, sim_body.surface_triangles);
    Result<ConvexPiecePoints> cached =
        readPieces(piecesPath(run.settings.cache_dir, surface_hashes[i]), surface_hashes[i]);
    if (cached) sim_body.convex_pieces_m = std::move(*cached);
  }
  return surface_hashes;
}

/// The simulation's settings: the scene's world, the ground's surface, the engine's impact rule.
SimSettings simSettings(RenderRun& run) {
  const Scene& scene = run.scene;
  SimSettings sim;
  sim.duration_s = run.duration;
  sim.gravity_m_s2 = scene.gravity_m_s2;
  sim.substep_s = run.substep;
  sim.max_events = run.settings.max_events;
  sim.record_states = true;  // the sound engine follows each body as it moves
  // The engine's impact rule: the simulation times impacts within the step by it (ContactEvent::time_s).
  sim.impact_speed_m_s = run.engine_settings.impact_speed_m_s;
  sim.ground = scene.has_ground;
  sim.ground_height_m = scene.ground_height_m;
  sim.ground_restitution = run.ground_surface.restitution;
  sim.ground_friction = run.ground_surface.friction;
  sim.ground_rolling_resistance = run.ground_surface.rolling_resistance;
  sim.ground_compliance_per_pa = run.ground_surface.compliance_per_pa;
  for (const ContactPairSpec& pair : scene.contact_pairs) {
    // An object's name first; "ground" is the ground unless an object has that name.
    auto indexOf = [&](const std::string& name) {
      for (size_t i = 0; i < scene.objects.size(); ++i)
        if (scene.objects[i].name == name) return uint32_t(i);
      return kGroundBody;
    };
    sim.contact_pairs.push_back(
        {indexOf(pair.object_a), indexOf(pair.object_b), pair.restitution, pair.friction, pair.rolling_resistance});
  }
  sim.progress = run.settings.progress;
  if (run.settings.session) sim.hull_memo = run.settings.session->hullMemo();
  if (!run.settings.cache_dir.empty()) sim.hull_memo = cachedHullMemo(run.settings.cache_dir, sim.hull_memo);
  return sim;
}

/// How each concave moving body collided (pieces computed and cached, or the exact mesh).
void noteCollisionShapes(RenderRun& run, const std::vector<uint64_t>& surface_hashes) {
  RenderReport& report = run.report();
  const SimResult& simulated = run.simulated;
  for (size_t i = 0; i < run.bodies.size(); ++i) {
    const std::string& name = run.scene.objects[i].name;
    const SimBodyDesc::Shape used = simulated.shape_used[i];
    if (used == SimBodyDesc::Shape::ConvexPieces) {
      char note[160];
      if (simulated.pieces_computed[i]) {
        report.pieces_seconds += simulated.pieces_seconds[i];
        const bool cached = surface_hashes[i] != 0 && writePieces(piecesPath(run.settings.cache_dir, surface_hashes[i]),
                                                                  surface_hashes[i], simulated.convex_pieces_m[i]);
        std::snprintf(note, sizeof note, "%s: %zu convex pieces (computed in %.2f s%s)", name.c_str(),
                      simulated.collision_pieces[i], simulated.pieces_seconds[i], cached ? ", cached" : "");
      } else {
        std::snprintf(note, sizeof note, "%s: %zu convex pieces (from the cache)", name.c_str(),
                      simulated.collision_pieces[i]);
      }
      report.collision_notes.push_back(note);
    } else if (used == SimBodyDesc::Shape::Concave && !run.scene.objects[i].is_static) {
      report.collision_notes.push_back(
          name + ": exact mesh (GImpact, " + std::to_string(run.sim_bodies[i].surface_triangles.size() / 3) +
          " triangles): slow to simulate; \"shape\": \"pieces\" (the default) is ~5-20x faster");
    }
  }
}

/// The Bullet world (hulls, bodies) built and stepped: both count as simulation.
Status simulateBodies(RenderRun& run) {
  const auto start = std::chrono::steady_clock::now();
  for (const Body& body : run.bodies) run.sim_bodies.push_back(simBody(body));
  warnBeforeSimulating(run);
  const std::vector<uint64_t> surface_hashes = readCachedPieces(run);
  Result<SimResult> simulated = simulate(run.sim_bodies, simSettings(run));
  if (!simulated) return simulated.error();
  RenderReport& report = run.report();
  report.simulate_seconds = secondsSince(start);
  run.simulated = std::move(*simulated);
  noteCollisionShapes(run, surface_hashes);
  run.result.events = std::move(run.simulated.events);
  report.events = run.result.events.size();
  for (const ContactEvent& event : run.result.events)
    ++(run.engine_settings.isImpact(event.normal_speed_m_s) ? report.impact_events : report.sustained_events);
  return {};
}

// ---- Phase 3: banks only for objects struck hard enough to hear -----------------------------

/// Each body's largest velocity change from one contact; a moving body never struck is warned.
void findStruckBodies(RenderRun& run) {
  for (const ContactEvent& event : run.result.events) {
    const double impulse = norm(event.impulse_on_a_mesh);
    for (uint32_t index : {event.body_a, event.body_b}) {
      if (index == kGroundBody) continue;
      Body& body = run.bodies[index];
      if (body.bank->mass_kg > 0)
        body.max_velocity_change_m_s = std::max(body.max_velocity_change_m_s, impulse / body.bank->mass_kg);
    }
  }
  for (size_t i = 0; i < run.bodies.size(); ++i)
    if (run.bodies[i].max_velocity_change_m_s == 0.0 && !run.bodies[i].object->is_static)
      run.warn(neverStruckWarning(run.scene, run.sim_bodies[i], run.duration));
}

/// What phase 3 still has to do after each sounding body's bank was looked for.
struct BankPlan {
  std::vector<size_t> to_solve;                   ///< bodies whose bank is solved now
  std::vector<std::pair<size_t, size_t>> shares;  ///< (body, the identical body whose bank it takes)
  std::map<uint64_t, std::shared_ptr<const ModeBank>> extended_by_key;  ///< cached banks given more transfer
};

/// Reads a body's bank file (cached or given) at its struck points, or extends its transfer; false
/// (the error) when the file is damaged.
Status readBankFile(RenderRun& run, size_t i, BankPlan& plan) {
  Body& body = run.bodies[i];
  return lacksHeardTransfer(body, run.settings)
             ? extendCachedTransfer(body, run.settings, plan.extended_by_key, run.report())
             : readStruckShapes(body, static_cast<uint32_t>(i), run.result.events, bool(run.settings.output),
                                run.settings.session, run.report());
}

/// Undoes openCached() for an entry found damaged: its bank is solved again.
void forgetCachedBank(Body& body, RenderReport& report) {
  body.file.reset();
  body.rows.reset();
  body.has_modes = false;
  if (body.from_cache) {
    --report.banks_cached;
    report.precompute_saved_seconds -= solveSeconds(*body.bank);
  }
}

/// Which sounding body gets its bank how: scaled (similar_reuse), from its file, shared with an
/// identical body, or solved (plan.to_solve).
Status planBanks(RenderRun& run, BankPlan& plan, std::map<uint64_t, size_t>& solved_by_key,
                 std::map<uint64_t, ModeBank>& unit_by_key) {
  const RenderSettings& settings = run.settings;
  RenderReport& report = run.report();
  auto warn = [&](std::string text) { run.warn(std::move(text)); };
  std::map<uint64_t, size_t> computed_by_key;  // identical objects share one eigen-solve
  for (size_t i = 0; i < run.bodies.size(); ++i) {
    Body& body = run.bodies[i];
    if (body.max_velocity_change_m_s == 0.0 && !settings.leave_nothing_out) continue;
    if (body.max_velocity_change_m_s > 0.0) ++report.objects_struck;
    if (body.max_velocity_change_m_s < kInaudibleVelocityChange_m_s && !settings.leave_nothing_out) {
      ++report.objects_inaudible;
      continue;
    }
    body.sounded = true;
    if (settings.similar_reuse && body.object->bank.empty()) {
      if (Status made = similarPhase2(run.bodies, i, settings, solved_by_key, unit_by_key, report, warn); !made)
        return made;
      continue;
    }
    if (body.file) {
      Status read = readBankFile(run, i, plan);
      if (read) continue;
      if (!body.object->bank.empty()) return read;  // the user's bank file is damaged
      forgetCachedBank(body, report);               // a damaged cache entry is recomputed, not trusted
      Result<LoadedMesh> loaded = loadMeshFor(body.precompute);
      if (!loaded) return badInput("objects \"" + body.object->name + "\": " + loaded.error().message);
      body.mesh = std::move(*loaded);
    }
    if (body.has_modes) continue;
    if (auto shared = computed_by_key.find(body.cache_key); shared != computed_by_key.end()) {
      plan.shares.emplace_back(i, shared->second);  // its bank once that body has one
      continue;
    }
    computed_by_key[body.cache_key] = i;
    plan.to_solve.push_back(i);
  }
  return {};
}

/// The cache locks of the banks to solve, held until they are in the cache: a render elsewhere
/// that needs one waits, then reads it. Taken in the order of the keys, as every render takes
/// them, so two never wait for each other. A bank solved meanwhile by the holder is read instead.
std::map<uint64_t, CacheEntryLock> lockBanksToSolve(RenderRun& run, BankPlan& plan) {
  std::map<uint64_t, CacheEntryLock> locks;
  if (run.settings.cache_dir.empty()) return locks;
  std::vector<size_t> by_key = plan.to_solve;
  std::sort(by_key.begin(), by_key.end(),
            [&](size_t a, size_t b) { return run.bodies[a].cache_key < run.bodies[b].cache_key; });
  for (size_t i : by_key) {
    Body& body = run.bodies[i];
    CacheEntryLock lock(cachePath(run.settings.cache_dir, body.cache_key, ".lock"));
    if (lock.held() && !body.from_cache && openCached(run.settings.cache_dir, body, run.report())) {
      if (readBankFile(run, i, plan)) {  // solved by whoever held the lock while this render waited
        body.mesh.reset();
        plan.to_solve.erase(std::find(plan.to_solve.begin(), plan.to_solve.end(), i));
        continue;
      }
      forgetCachedBank(body, run.report());
      body.from_cache = false;
    }
    locks.emplace(body.cache_key, std::move(lock));
  }
  return locks;
}

/// The new banks, side by side (side_by_side.hpp): each solve's bits are a serial solve's. Each
/// is cached (and its lock released) as it is taken, in the bodies' order.
Status solveBanks(RenderRun& run, const BankPlan& plan, std::map<uint64_t, CacheEntryLock>& locks) {
  const RenderSettings& settings = run.settings;
  std::vector<std::optional<Result<PrecomputeResult>>> computed(plan.to_solve.size());
  std::mutex progress_lock;  // the caller's progress callback is called from one thread at a time
  auto progress = [&](std::string_view phase, double fraction) {
    std::lock_guard<std::mutex> hold(progress_lock);
    settings.progress(phase, fraction);
  };
  runSideBySide(
      plan.to_solve.size(),
      settings.solve_threads > 0 ? settings.solve_threads : std::max(1u, std::thread::hardware_concurrency()),
      settings.max_memory_bytes > 0 ? settings.max_memory_bytes : availableMemoryBytes(),
      [&](size_t j) { return solveForecastBytes(run.bodies[plan.to_solve[j]]); },
      [&](size_t j) {
        Body& body = run.bodies[plan.to_solve[j]];
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
  for (size_t j = 0; j < plan.to_solve.size(); ++j) {  // in the bodies' order, as a serial solve
    Body& body = run.bodies[plan.to_solve[j]];
    Result<PrecomputeResult>& bank = *computed[j];
    if (!bank) return badInput("objects \"" + body.object->name + "\": " + bank.error().message);
    for (const MeshWarning& w : bank->report.warnings) run.warn("objects \"" + body.object->name + "\": " + w.message);
    body.bank = std::make_shared<const ModeBank>(std::move(bank->bank));
    body.has_modes = true;
    body.mesh.reset();
    ++run.report().banks_computed;
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
Status shareBanks(RenderRun& run, const BankPlan& plan) {
  for (const auto& [i, holder] : plan.shares) {
    Body& body = run.bodies[i];
    body.bank = run.bodies[holder].bank;
    body.file = run.bodies[holder].file;
    body.has_modes = true;
    ++run.report().banks_shared;
    if (body.file)
      if (Status read = readStruckShapes(body, static_cast<uint32_t>(i), run.result.events, bool(run.settings.output),
                                         run.settings.session, run.report());
          !read)
        return read;
  }
  return {};
}

/// Every sounding body's bank: planned, locked, solved, shared; then the cache kept to its size.
Status provideBanks(RenderRun& run) {
  const auto start = std::chrono::steady_clock::now();
  findStruckBodies(run);
  BankPlan plan;
  std::map<uint64_t, size_t> solved_by_key;  // similar_reuse: objects of one shape share one solve
  std::map<uint64_t, ModeBank> unit_by_key;  // ...and one transfer per wave speed and modes kept
  if (Status planned = planBanks(run, plan, solved_by_key, unit_by_key); !planned) return planned;
  std::map<uint64_t, CacheEntryLock> locks = lockBanksToSolve(run, plan);
  if (Status solved = solveBanks(run, plan, locks); !solved) return solved;
  if (Status shared = shareBanks(run, plan); !shared) return shared;
  RenderReport& report = run.report();
  report.precompute_seconds = secondsSince(start);
  if (!run.settings.cache_dir.empty() && run.settings.cache_max_bytes > 0) {
    // This render's banks were just written or touched, so they are the last to go.
    Result<PruneReport> pruned =
        pruneCache(run.settings.cache_dir, run.settings.cache_max_bytes, -1.0, std::time(nullptr));
    if (pruned) report.cache_pruned = pruned->removed, report.cache_pruned_bytes = pruned->bytes_removed;
  }
  return {};
}

// ---- Phase 4: the simulation, step by step, into the sound engine ---------------------------

/// A voice for each sounding body with a mode to play (or a free body's clicks).
Status addVoices(RenderRun& run, SoundOutput& output) {
  RenderReport& report = run.report();
  run.has_voice.assign(run.bodies.size(), false);
  for (size_t index = 0; index < run.bodies.size(); ++index) {
    Body& body = run.bodies[index];
    if (!body.sounded) continue;
    if (Status audible = hasAudibleMode(*body.bank, run.engine_settings.synth, run.rate); !audible) {
      if (body.object->is_static || !(body.bank->mass_kg > 0.0)) {
        ++report.objects_silent;
        body.silent = true;
        run.warn("objects \"" + body.object->name + "\": " + audible.error().message);
        continue;
      }
      // A free body still clicks when struck: its acceleration noise (sound_paths.cpp).
      ++report.objects_clicks_only;
    }
    ++report.objects_sounded;
    VoiceDesc voice;
    voice.bank = body.located_bank ? body.located_bank : body.bank;  // the session's, equal to body.bank
    if (body.rows) voice.rows = std::move(*body.rows), voice.use_rows = true;
    voice.locator = body.locator;
    voice.located = std::move(body.located);
    voice.pressure_scale = outputPerPascal(run.settings.gain);
    voice.weights = pressureWeights(*body.bank, run.engine_settings.reference_distance_m, voice.pressure_scale);
    voice.is_static = body.object->is_static;
    voice.contact_radius_m = body.contact_radius_m;
    const SurfaceProperties surface = objectSurface(*body.object, body.bank->material);
    voice.roughness = surface.roughness;
    voice.restitution = surface.restitution;
    const SimBodyDesc& placed = run.sim_bodies[index];
    if (Status added = output.addVoice(static_cast<uint32_t>(index), voice, placed.position_m, placed.orientation_wxyz,
                                       body.object->name);
        !added)
      return added;
    run.has_voice[index] = true;
  }
  output.setListener(run.scene.listener_position_m, run.scene.listener_orientation_wxyz);
  return {};
}

/// The other bodies as the Hertz contact time needs them: a sounding body by its voice, anything
/// else by its material, size and mass.
std::vector<ContactPartner> contactPartners(const RenderRun& run) {
  std::vector<ContactPartner> partners(run.bodies.size());
  for (size_t i = 0; i < run.bodies.size(); ++i) {
    ContactPartner& partner = partners[i];
    if (run.has_voice[i]) {
      partner.voice = static_cast<uint32_t>(i);  // its material from its bank; its sleep keeps a static body's load
      continue;
    }
    const Body& body = run.bodies[i];
    partner.youngs_pa = body.bank->material.youngs_pa;
    partner.poisson = body.bank->material.poisson;
    partner.radius_m = body.contact_radius_m;
    partner.mass_kg = body.object->is_static ? 0.0 : body.bank->mass_kg;
    const SurfaceProperties surface = objectSurface(*body.object, body.bank->material);
    partner.roughness = surface.roughness;
    partner.restitution = surface.restitution;
  }
  return partners;
}

/// ...and the ground by its material and surface.
ContactPartner groundPartner(const RenderRun& run) {
  ContactPartner ground;
  ground.youngs_pa = run.scene.ground_material.youngs_pa;
  ground.poisson = run.scene.ground_material.poisson;
  ground.roughness = run.ground_surface.roughness;
  ground.restitution = run.ground_surface.restitution;
  return ground;
}

/// The engine's counts, the output's warnings, the peak and clipping, into the report.
void reportPlayback(RenderRun& run, const SoundOutput& output) {
  RenderReport& report = run.report();
  const EngineStats engine_stats = output.stats();
  report.impacts = engine_stats.impacts + engine_stats.impacts_inaudible;
  report.sustained_contacts = engine_stats.sustained_contacts;
  report.load_changes = engine_stats.load_changes;
  report.load_holds = engine_stats.load_holds;
  report.continuous_contacts = engine_stats.continuous_contacts;
  report.continuous_dropped = engine_stats.continuous_dropped;
  report.continuous_lost_samples = engine_stats.continuous_lost_samples;
  report.continuous_last_force_s = engine_stats.continuous_last_force_s;
  for (std::string& text : output.warnings()) run.warn(std::move(text));
  for (float s : run.result.audio.samples) {
    report.peak = std::max(report.peak, static_cast<double>(std::fabs(s)));
    if (std::fabs(s) >= 1.0f) ++report.clipped_samples;
  }
  report.modes_total = engine_stats.modes_total;
  report.modes_out_of_band = engine_stats.modes_out_of_band;
  report.mode_samples = engine_stats.mode_samples;
  report.forced_mode_samples = engine_stats.forced_mode_samples;
  report.image_mode_samples = engine_stats.image_mode_samples;
  report.max_active_modes = engine_stats.max_active_modes;
}

/// The sound engine (or the caller's output) plays the simulation into the audio.
Status playScene(RenderRun& run) {
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<SoundOutput> output;
  if (run.settings.output) {
    Result<std::unique_ptr<SoundOutput>> made = run.settings.output(run.engine_settings);
    if (!made) return made.error();
    output = std::move(*made);
  } else {
    output = makeEngineOutput(run.engine_settings);
  }
  if (Status added = addVoices(run, *output); !added) return added;
  const std::vector<ContactPartner> partners = contactPartners(run);
  AudioBuffer& audio = run.result.audio;
  audio.sample_rate_hz = run.rate;
  audio.channels = static_cast<int>(outputChannels(run.settings.output_format));
  audio.samples.assign(
      static_cast<size_t>(std::llround(run.duration * run.rate)) * outputChannels(run.settings.output_format), 0.0f);
  const Playback playback{run.result.events, run.simulated.states, run.simulated.substeps, run.substep, run.has_voice,
                          partners,          groundPartner(run)};
  if (Status played = play(playback, *output, audio, run.settings.progress); !played) return played;
  reportPlayback(run, *output);
  run.report().synthesize_seconds = secondsSince(start);
  for (const Body& body : run.bodies)
    run.result.banks.push_back(
        {body.object->bank.empty() ? body.cache_key : 0, body.object->bank, body.sounded, body.transfer_key});
  return {};
}

}  // namespace

// The render as a pipeline: prepare bodies -> simulate -> provide banks -> play.
Result<RenderResult> renderScene(const Scene& scene, const RenderSettings& settings) {
  const auto start = std::chrono::steady_clock::now();
  RenderRun run(scene, settings);
  run.rate = settings.sample_rate_hz > 0 ? settings.sample_rate_hz : scene.sample_rate_hz;
  run.duration = settings.duration_s > 0 ? settings.duration_s : scene.duration_s;
  run.substep = settings.substep_s;  // simulate() refuses steps outside (0, 1 ms]
  run.max_freq_hz = synthesizedTopHz(scene.max_freq_hz, run.rate);
  run.engine_settings = renderEngineSettings(scene, settings, run.rate, run.max_freq_hz);
  if (settings.output_format == OutputFormat::Binaural) {  // before any solve: a bad file fails at once
    Result<std::shared_ptr<const HrtfSet>> hrtf =
        loadSofaHrtf(settings.hrtf_file.empty() ? kDefaultHrtfFile : settings.hrtf_file, run.rate);
    if (!hrtf) return hrtf.error();
    run.engine_settings.hrtf = std::move(*hrtf);
  }
  run.heard_hz = synthesizedTopHz(run.engine_settings.synth.max_freq_hz, run.rate);
  run.ground_surface = groundSurface(scene);  // for the simulation and the sound
  run.report().objects = scene.objects.size();
  if (Status prepared = prepareBodies(run); !prepared) return prepared.error();
  if (Status simulated = simulateBodies(run); !simulated) return simulated.error();
  if (Status provided = provideBanks(run); !provided) return provided.error();
  if (Status played = playScene(run); !played) return played.error();
  run.report().total_seconds = secondsSince(start);
  return std::move(run.result);
}

// The events CSV's marker of continuous contact (docs/cli.md): whether the surfaces roll and/or
// slide over each other, by the speed below which a rough contact is still
// (RoughContact::kStillSpeed_m_s); "rest" otherwise, impacts included.
const char* contactMotion(const ContactEvent& e) {
  const double still = RoughContact::kStillSpeed_m_s;
  const double slip =
      std::sqrt(e.slip_velocity_m_s[0] * e.slip_velocity_m_s[0] + e.slip_velocity_m_s[1] * e.slip_velocity_m_s[1] +
                e.slip_velocity_m_s[2] * e.slip_velocity_m_s[2]);
  const bool rolling = e.rolling_speed_m_s >= still, sliding = slip >= still;
  return rolling && sliding ? "rolling+sliding" : rolling ? "rolling" : sliding ? "sliding" : "rest";
}

Status writeEventsCsv(const std::string& path, const RenderResult& result) {
  std::string csv =
      "time_s,body_a,body_b,new_contact,normal_speed_m_s,normal_impulse_n_s,friction_impulse_n_s,"
      "point_x_m,point_y_m,point_z_m,normal_x,normal_y,normal_z,"
      "point_a_mesh_x,point_a_mesh_y,point_a_mesh_z,point_b_mesh_x,point_b_mesh_y,point_b_mesh_z,step_time_s,"
      "normal_force_n,slip_x_m_s,slip_y_m_s,slip_z_m_s,rolling_speed_m_s,track_speed_a_m_s,track_speed_b_m_s,"
      "patch_radius_m,motion\n";
  auto name = [&](uint32_t index) { return index == kGroundBody ? std::string("ground") : result.body_names[index]; };
  char line[1024];
  for (const ContactEvent& e : result.events) {
    std::snprintf(line, sizeof line,
                  ",%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g"
                  ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%s\n",
                  e.new_contact ? 1 : 0, e.normal_speed_m_s, e.normal_impulse_n_s, e.friction_impulse_n_s,
                  e.point_world[0], e.point_world[1], e.point_world[2], e.normal_world[0], e.normal_world[1],
                  e.normal_world[2], e.point_a_mesh[0], e.point_a_mesh[1], e.point_a_mesh[2], e.point_b_mesh[0],
                  e.point_b_mesh[1], e.point_b_mesh[2], e.step_time_s, e.normal_force_n, e.slip_velocity_m_s[0],
                  e.slip_velocity_m_s[1], e.slip_velocity_m_s[2], e.rolling_speed_m_s, e.track_speed_a_m_s,
                  e.track_speed_b_m_s, e.patch_radius_m, contactMotion(e));
    char time[64];
    std::snprintf(time, sizeof time, "%.9g,", e.time_s);
    csv += time + name(e.body_a) + "," + name(e.body_b) + line;
  }
  return writeFileAtomically(path, csv.data(), csv.size());
}

}  // namespace strike
