// SPDX-License-Identifier: MIT
// The two-phase render. Follow renderScene() from top to bottom: bodies, simulation, banks for
// what was heard, impacts into the oscillator bank, audio.
#include "strike/render.hpp"

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
#include <optional>

#include "strike/atomic_file.hpp"
#include "strike/bank_cache.hpp"
#include "strike/bank.hpp"
#include "strike/materials.hpp"
#include "strike/precompute.hpp"
#include "strike/scene_checks.hpp"
#include "strike/synth.hpp"
#include "cache_lock.hpp"
#include "pieces_cache.hpp"

namespace strike {
namespace {

constexpr double kSpeedOfSoundAir_m_s = 343.0;  // dry air at 20 C
// A velocity change below 1 micrometre per second cannot be heard from any object of audible
// size; objects struck only that softly get no eigen-solve (a conservative audibility bound).
constexpr double kInaudibleVelocityChange_m_s = 1e-6;
// A contact approaching faster than this is an impact (a Hertz pulse); slower ones are sustained
// contact (a force over the step). Gravity alone adds g * step = 10 mm/s per 1 ms step to a
// resting body, five times less. Bullet may spread one impact over several substeps and flag only
// the first as new, so the approach speed, not the flag, decides.
constexpr double kImpactSpeed_m_s = 0.05;
// Sustained force changes smaller than this (relative, per step) are solver jitter, not sound.
constexpr double kSteadyForceTolerance = 1e-3;
// Sustained contacts closer in time than this belong to one contact span (contact damping).
// Sleeping bodies report no contacts, so an open span at the end of the events stays open.
constexpr double kContactGap_s = 0.02;
// Listener closer than this to a contact is treated as this far (the point-source model's 1/r
// would blow up).
constexpr double kMinListenerDistance_m = 0.05;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// One object on its way through the render.
struct Body {
  const SceneObject* object = nullptr;
  PrecomputeSettings precompute;
  uint64_t cache_key = 0;
  uint64_t mesh_hash = 0;
  ModeBank bank;                     ///< full bank, or mass and surface only until phase 2
  bool has_modes = false;
  std::optional<BankFile> file;      ///< a cached or given bank: its shapes are read in phase 2
                                     ///< at the vertices the contacts touch
  bool from_cache = false;           ///< counted in report.banks_cached
  std::optional<LoadedMesh> mesh;    ///< kept when the modes may still need computing
  double max_velocity_change_m_s = 0.0;
  bool sounded = false;              ///< struck audibly: gets a bank and an oscillator
  bool silent = false;               ///< ...but no mode in the synthesized band
  uint32_t synth_id = 0;
  std::unique_ptr<ContactProjector> projector;  ///< contact impulses onto modes
  double sustained_time_s = -1.0;           ///< substep whose sustained contacts are being summed
  double last_sustained_time_s = -1.0;      ///< the last substep with sustained contact
  std::vector<double> sustained_modal;      ///< their summed modal impulses
  std::vector<uint32_t> sustained_partners; ///< the bodies it touched in that substep
  double box_start_s = 0.0;                 ///< the open run of steady sustained force: start,
  int box_steps = 0;                        ///< length in substeps,
  std::vector<double> box_force;            ///< and modal impulse per substep
  double contact_radius_m = 0.0;     ///< radius of the sphere of equal volume, for Hertz
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
  body.bank = cached->bank();
  body.file = std::move(*cached);
  body.has_modes = true;
  body.from_cache = true;
  ++report.banks_cached;
  report.precompute_saved_seconds += body.bank.factorize_seconds + body.bank.lanczos_seconds;
  return true;
}

/// Phase 1 for one object: a bank with at least mass properties and surface.
Status prepareBody(const Scene& scene, const RenderSettings& settings, double max_freq_hz, Body& body,
                   std::map<uint64_t, const Body*>& loaded_by_key, RenderReport& report) {
  const SceneObject& object = *body.object;
  if (!object.bank.empty()) {
    Result<BankFile> file = BankFile::open(object.bank);
    if (!file) return file.error();
    body.bank = file->bank();
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
  body.precompute.progress = settings.progress;
  Result<uint64_t> hash = meshHash(object.mesh);
  if (!hash) return hash.error();
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
  Result<LoadedMesh> loaded = loadTetMesh(object.mesh, meshOptionsFor(body.precompute));
  if (!loaded) return badInput("objects \"" + object.name + "\": " + loaded.error().message);
  body.bank = massAndSurfaceBank(*loaded, body.precompute);
  body.mesh = std::move(*loaded);
  return {};
}

/// A bank opened from a file keeps its shapes there until the simulation has said where the
/// body was struck: read them only at the vertices of those points' nearest triangles (the
/// projector's locator finds the same vertices again when it projects). A render of 20 plates
/// reads ~2% of their 340 MB of shapes this way.
Status readStruckShapes(Body& body, uint32_t index, const std::vector<ContactEvent>& events, RenderReport& report) {
  body.projector = std::make_unique<ContactProjector>(body.bank);
  const bool has_radiation = body.bank.radiation_m2.size() == body.bank.modeCount();
  if (!has_radiation || !body.projector->locator().hasTriangles()) {
    // Radiation strengths computed from every shape (banks written before the RADI chunk), or
    // no triangles to locate on: the whole bank.
    Result<ModeBank> all = body.file->readAll();
    if (!all) return all.error();
    body.bank = std::move(*all);
    body.file.reset();
    body.projector = std::make_unique<ContactProjector>(body.bank);
    report.shape_vertices_read += body.bank.surfaceVertexCount();
    report.shape_vertices_total += body.bank.surfaceVertexCount();
    return {};
  }
  std::vector<std::array<double, 3>> points;
  for (const ContactEvent& event : events) {
    if (event.body_a == index) points.push_back(event.point_a_mesh);
    if (event.body_b == index) points.push_back(event.point_b_mesh);
  }
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  std::vector<uint32_t> vertices;
  for (const std::array<double, 3>& point : points) {
    uint32_t v[3];
    double w[3];
    body.projector->locator().nearest(point.data(), v, w);
    vertices.insert(vertices.end(), v, v + 3);
  }
  Result<ShapeRows> rows = body.file->readShapeRows(std::move(vertices));
  if (!rows) return rows.error();
  report.shape_vertices_read += rows->vertices.size();
  report.shape_vertices_total += body.bank.surfaceVertexCount();
  body.projector->useRows(std::move(*rows));
  return {};
}

/// (1 - nu^2) / E: how a material's restitution weighs against another's (combineContact).
double compliance(const Material& m) { return (1.0 - m.poisson * m.poisson) / m.youngs_pa; }

SimBodyDesc simBody(const Body& body) {
  const SceneObject& object = *body.object;
  const MaterialTable& table = builtinMaterials();
  SimBodyDesc desc;
  desc.name = object.name;
  desc.is_static = object.is_static;
  desc.surface_positions = body.bank.surface_positions;
  desc.surface_triangles = body.bank.surface_triangles;
  desc.mass_kg = body.bank.mass_kg;
  desc.centre_m = body.bank.centre_m;
  desc.inertia_kg_m2 = body.bank.inertia_kg_m2;
  desc.position_m = object.position_m;
  desc.orientation_wxyz = object.orientation_wxyz;
  desc.velocity_m_s = object.velocity_m_s;
  desc.angular_velocity_rad_s = object.angular_velocity_rad_s;
  const ContactProperties contact = table.contactProperties(body.bank.material.name);
  desc.restitution = std::isnan(object.restitution) ? contact.restitution : object.restitution;
  desc.friction = std::isnan(object.friction) ? contact.friction : object.friction;
  desc.compliance_per_pa = compliance(body.bank.material);
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
  const double low = synth.min_freq_hz, high = std::min(synth.max_freq_hz, 0.45 * rate);
  for (size_t i = 0; i < bank.modeCount(); ++i) {
    const double f = bank.frequencyHz(i);
    if (f >= low && f <= high) return {};
  }
  char why[256];
  if (bank.modeCount() == 0)
    std::snprintf(why, sizeof why, "its bank has no elastic mode below its cut-off of %.0f Hz: too small or too stiff to ring",
                  bank.max_freq_hz);
  else
    std::snprintf(why, sizeof why, "its %zu modes lie at %.1f to %.1f Hz, outside the synthesized band %.0f to %.0f Hz",
                  bank.modeCount(), bank.frequencyHz(0), bank.frequencyHz(bank.modeCount() - 1), low, high);
  return badInput(std::string("silent: no mode in the audible band (") + why + ")");
}

}  // namespace

std::string defaultCacheDir() {
  if (const char* dir = std::getenv("STRIKE_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::string(xdg) + "/strike";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/strike";
  return {};
}

Result<RenderResult> renderScene(const Scene& scene, const RenderSettings& settings) {
  const auto start = std::chrono::steady_clock::now();
  const double rate = settings.sample_rate_hz > 0 ? settings.sample_rate_hz : scene.sample_rate_hz;
  const double duration = settings.duration_s > 0 ? settings.duration_s : scene.duration_s;
  const double substep = settings.substep_s;  // simulate() refuses steps outside (0, 1 ms]
  // No mode above the audible band or what the sample rate can carry is ever computed.
  const double max_freq_hz = std::min(scene.max_freq_hz, 0.45 * rate);
  RenderResult result;
  RenderReport& report = result.report;
  report.objects = scene.objects.size();

  // ---- Phase 1: bodies and simulation -------------------------------------------------------
  std::vector<Body> bodies(scene.objects.size());
  std::map<uint64_t, const Body*> loaded_by_key;  // identical objects are read or meshed once
  for (size_t i = 0; i < bodies.size(); ++i) {
    bodies[i].object = &scene.objects[i];
    Status prepared = prepareBody(scene, settings, max_freq_hz, bodies[i], loaded_by_key, report);
    if (!prepared) return prepared.error();
    if (bodies[i].object->bank.empty()) loaded_by_key.emplace(bodies[i].cache_key, &bodies[i]);
    bodies[i].contact_radius_m = std::cbrt(3.0 * bodies[i].bank.volume_m3 / (4.0 * M_PI));
    result.body_names.push_back(scene.objects[i].name);
  }
  if (!settings.cache_dir.empty()) {
    std::error_code ignored;
    std::filesystem::create_directories(settings.cache_dir, ignored);
  }
  report.load_seconds = secondsSince(start);

  // Simulate: the Bullet world (hulls, bodies) is built and stepped; both count as simulation.
  const auto simulate_start = std::chrono::steady_clock::now();
  std::vector<SimBodyDesc> sim_bodies;
  for (const Body& body : bodies) sim_bodies.push_back(simBody(body));
  auto warn = [&](std::string text) {
    if (settings.on_warning) settings.on_warning(text);
    report.warnings.push_back(std::move(text));
  };
  for (std::string& text : checkStartingPlacement(scene, sim_bodies)) warn(std::move(text));
  // Convex pieces of concave moving bodies from the cache (computed ones are written after).
  std::vector<uint64_t> surface_hashes(bodies.size(), 0);
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (settings.cache_dir.empty() || bodies[i].object->is_static) continue;
    surface_hashes[i] = surfaceHash(sim_bodies[i].surface_positions, sim_bodies[i].surface_triangles);
    Result<ConvexPiecePoints> cached = readPieces(piecesPath(settings.cache_dir, surface_hashes[i]), surface_hashes[i]);
    if (cached) sim_bodies[i].convex_pieces_m = std::move(*cached);
  }
  SimSettings sim;
  sim.duration_s = duration;
  sim.gravity_m_s2 = scene.gravity_m_s2;
  sim.substep_s = substep;
  sim.max_events = settings.max_events;
  sim.impact_speed_m_s = kImpactSpeed_m_s;  // impacts are timed within the step (ContactEvent::time_s)
  sim.ground = scene.has_ground;
  sim.ground_height_m = scene.ground_height_m;
  const ContactProperties ground_contact = builtinMaterials().contactProperties(scene.ground_material.name);
  sim.ground_restitution = std::isnan(scene.ground_restitution) ? ground_contact.restitution : scene.ground_restitution;
  sim.ground_friction = std::isnan(scene.ground_friction) ? ground_contact.friction : scene.ground_friction;
  sim.ground_compliance_per_pa = compliance(scene.ground_material);
  for (const ContactPairSpec& pair : scene.contact_pairs) {
    // An object's name first; "ground" is the ground unless an object has that name.
    auto indexOf = [&](const std::string& name) {
      for (size_t i = 0; i < scene.objects.size(); ++i)
        if (scene.objects[i].name == name) return uint32_t(i);
      return kGroundBody;
    };
    sim.contact_pairs.push_back({indexOf(pair.object_a), indexOf(pair.object_b), pair.restitution, pair.friction});
  }
  sim.progress = settings.progress;
  Result<SimResult> simulated = simulate(sim_bodies, sim);
  if (!simulated) return simulated.error();
  report.simulate_seconds = secondsSince(simulate_start);
  for (size_t i = 0; i < bodies.size(); ++i) {
    const std::string& name = scene.objects[i].name;
    const SimBodyDesc::Shape used = simulated->shape_used[i];
    if (used == SimBodyDesc::Shape::ConvexPieces) {
      char note[160];
      if (simulated->pieces_computed[i]) {
        report.pieces_seconds += simulated->pieces_seconds[i];
        const bool cached = surface_hashes[i] != 0 &&
            writePieces(piecesPath(settings.cache_dir, surface_hashes[i]), surface_hashes[i], simulated->convex_pieces_m[i]);
        std::snprintf(note, sizeof note, "%s: %zu convex pieces (computed in %.2f s%s)", name.c_str(),
                      simulated->collision_pieces[i], simulated->pieces_seconds[i], cached ? ", cached" : "");
      } else {
        std::snprintf(note, sizeof note, "%s: %zu convex pieces (from the cache)", name.c_str(), simulated->collision_pieces[i]);
      }
      report.collision_notes.push_back(note);
    } else if (used == SimBodyDesc::Shape::Concave && !scene.objects[i].is_static) {
      report.collision_notes.push_back(name + ": exact mesh (GImpact, " + std::to_string(sim_bodies[i].surface_triangles.size() / 3) +
                                       " triangles): slow to simulate; \"shape\": \"pieces\" (the default) is ~5-20x faster");
    }
  }
  result.events = std::move(simulated->events);
  report.events = result.events.size();
  for (const ContactEvent& event : result.events)
    ++(event.normal_speed_m_s > kImpactSpeed_m_s ? report.impact_events : report.sustained_events);

  // ---- Phase 2: banks only for objects struck hard enough to hear ----------------------------
  for (const ContactEvent& event : result.events) {
    const double impulse = norm(event.impulse_on_a_mesh);
    for (uint32_t index : {event.body_a, event.body_b}) {
      if (index == kGroundBody) continue;
      Body& body = bodies[index];
      if (body.bank.mass_kg > 0)
        body.max_velocity_change_m_s = std::max(body.max_velocity_change_m_s, impulse / body.bank.mass_kg);
    }
  }
  for (size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].max_velocity_change_m_s == 0.0 && !bodies[i].object->is_static)
      warn(neverStruckWarning(scene, sim_bodies[i], duration));
  const auto precompute_start = std::chrono::steady_clock::now();
  std::map<uint64_t, size_t> computed_by_key;  // identical objects share one eigen-solve
  for (size_t i = 0; i < bodies.size(); ++i) {
    Body& body = bodies[i];
    if (body.max_velocity_change_m_s == 0.0 && !settings.leave_nothing_out) continue;
    if (body.max_velocity_change_m_s > 0.0) ++report.objects_struck;
    if (body.max_velocity_change_m_s < kInaudibleVelocityChange_m_s && !settings.leave_nothing_out) {
      ++report.objects_inaudible;
      continue;
    }
    body.sounded = true;
    if (body.file) {
      Status read = readStruckShapes(body, static_cast<uint32_t>(i), result.events, report);
      if (read) continue;
      if (!body.object->bank.empty()) return read.error();  // the user's bank file is damaged
      // A cache entry whose shapes are damaged is recomputed, not trusted.
      body.file.reset();
      body.projector.reset();
      body.has_modes = false;
      if (body.from_cache) {
        --report.banks_cached;
        report.precompute_saved_seconds -= body.bank.factorize_seconds + body.bank.lanczos_seconds;
      }
      Result<LoadedMesh> loaded = loadTetMesh(body.object->mesh, meshOptionsFor(body.precompute));
      if (!loaded) return badInput("objects \"" + body.object->name + "\": " + loaded.error().message);
      body.mesh = std::move(*loaded);
    }
    if (body.has_modes) continue;
    if (auto shared = computed_by_key.find(body.cache_key); shared != computed_by_key.end()) {
      body.bank = bodies[shared->second].bank;
      body.has_modes = true;
      ++report.banks_shared;
      continue;
    }
    // Held until the bank is in the cache: a render elsewhere that needs it waits, then reads it.
    CacheEntryLock lock;
    if (!settings.cache_dir.empty()) {
      lock = CacheEntryLock(cachePath(settings.cache_dir, body.cache_key, ".lock"));
      if (lock.held() && !body.from_cache && openCached(settings.cache_dir, body, report)) {
        // Solved by whoever held the lock while this render simulated or waited.
        if (readStruckShapes(body, static_cast<uint32_t>(i), result.events, report)) {
          body.mesh.reset();
          continue;
        }
        --report.banks_cached;
        report.precompute_saved_seconds -= body.bank.factorize_seconds + body.bank.lanczos_seconds;
        body.file.reset();
        body.projector.reset();
        body.has_modes = false;
        body.from_cache = false;
      }
    }
    if (settings.progress) settings.progress("modes " + body.object->name, -1.0);
    Result<PrecomputeResult> computed = computeModeBankForMesh(*body.mesh, body.precompute);
    if (!computed) return badInput("objects \"" + body.object->name + "\": " + computed.error().message);
    for (const MeshWarning& w : computed->report.warnings) warn("objects \"" + body.object->name + "\": " + w.message);
    body.bank = std::move(computed->bank);
    body.has_modes = true;
    body.mesh.reset();
    computed_by_key[body.cache_key] = i;
    ++report.banks_computed;
    if (!settings.cache_dir.empty()) {
      // A failed cache write costs the next render time, never this one its result.
      (void)writeBank(cachePath(settings.cache_dir, body.cache_key, ".modes"), body.bank);
    }
  }
  report.precompute_seconds = secondsSince(precompute_start);
  if (!settings.cache_dir.empty() && settings.cache_max_bytes > 0) {
    // This render's banks were just written or touched, so they are the last to go.
    Result<PruneReport> pruned = pruneCache(settings.cache_dir, settings.cache_max_bytes, -1.0, std::time(nullptr));
    if (pruned) report.cache_pruned = pruned->removed, report.cache_pruned_bytes = pruned->bytes_removed;
  }

  // ---- Phase 3: impacts into the oscillator bank --------------------------------------------
  const auto synth_start = std::chrono::steady_clock::now();
  SynthSettings synth_settings;
  synth_settings.sample_rate_hz = rate;
  synth_settings.max_freq_hz = std::min(20000.0, max_freq_hz);
  synth_settings.simd = settings.simd;
  if (settings.leave_nothing_out) {
    synth_settings.max_freq_hz = max_freq_hz;
    synth_settings.audibility_threshold = 0.0;
  }
  OscillatorBank synth(synth_settings);
  for (Body& body : bodies) {
    if (!body.sounded) continue;
    if (Status audible = hasAudibleMode(body.bank, synth_settings, rate); !audible) {
      ++report.objects_silent;
      body.silent = true;
      warn("objects \"" + body.object->name + "\": " + audible.error().message);
    } else {
      ++report.objects_sounded;
    }
    // The listener hears each object from where it was first struck (objects that travel far
    // while ringing are not tracked: a documented simplification).
    std::array<double, 3> where = body.object->position_m;
    const uint32_t index = static_cast<uint32_t>(&body - bodies.data());
    for (const ContactEvent& event : result.events)
      if (event.body_a == index || event.body_b == index) {
        where = event.point_world;
        break;
      }
    std::array<double, 3> offset{};
    for (int a = 0; a < 3; ++a) offset[a] = where[a] - scene.listener_position_m[a];
    const double distance = std::max(kMinListenerDistance_m, norm(offset));
    ModalObjectDesc desc;
    desc.eigenvalues = body.bank.eigenvalues;
    desc.rayleigh_stiffness = body.bank.material.rayleigh_stiffness;
    desc.rayleigh_mass = body.bank.material.rayleigh_mass;
    desc.radiation_weight = radiationWeights(body.bank, distance);
    for (double& w : desc.radiation_weight) w *= settings.gain / kFullScalePascal;
    desc.delay_s = distance / kSpeedOfSoundAir_m_s;
    body.synth_id = synth.addObject(desc);
    if (!body.projector) body.projector = std::make_unique<ContactProjector>(body.bank);
  }

  // Contact damping: while a body is in sustained contact, its modes lose energy into what it
  // touches. Contact spans are the runs of sustained-contact steps with gaps under kContactGap_s.
  if (scene.contact_damping_per_s > 0) {
    for (size_t index = 0; index < bodies.size(); ++index) {
      Body& body = bodies[index];
      if (!body.sounded) continue;
      double span_start = -1.0, last = -1.0;
      for (const ContactEvent& event : result.events) {
        if ((event.body_a != index && event.body_b != index) || event.normal_speed_m_s > kImpactSpeed_m_s) continue;
        if (span_start >= 0 && event.time_s - last > kContactGap_s) {
          synth.setExtraDamping(body.synth_id, span_start, scene.contact_damping_per_s);
          synth.setExtraDamping(body.synth_id, last + kContactGap_s, 0.0);
          span_start = -1.0;
        }
        if (span_start < 0) span_start = event.time_s;
        last = event.time_s;
      }
      // A span still open at the end lasts: the body came to rest on something.
      if (span_start >= 0) synth.setExtraDamping(body.synth_id, span_start, scene.contact_damping_per_s);
    }
  }

  // Sustained contacts of one body in one substep are one force over that step: their modal
  // impulses add (the projection is linear in J). Consecutive steps whose force stays within
  // kSteadyForceTolerance of the run's first step are one longer box (contiguous boxes of one
  // force are exactly one box), so a body resting for seconds costs a few pulses, not thousands;
  // what is dropped is solver jitter 60 dB below the resting force.
  std::vector<double> modal;
  auto emitBox = [&](Body& body) {
    if (body.box_steps == 0) return;
    for (double& g : body.box_force) g *= body.box_steps;
    ImpactDesc impact;
    impact.object = body.synth_id;
    // Ramped over one step and centred on the steps: the step forces are linearly interpolated,
    // not held, so solver jitter does not ring at the step rate (1 kHz) and its harmonics.
    impact.time_s = body.box_start_s - 0.5 * substep;
    impact.duration_s = body.box_steps * substep;
    impact.ramp_s = substep;
    impact.shape = PulseShape::Box;
    impact.modal_impulse = body.box_force.data();
    synth.addImpact(impact);
    body.box_steps = 0;
  };
  auto flushSustained = [&](Body& body) {
    if (body.sustained_time_s < 0) return;
    const bool contiguous = body.box_steps > 0 &&
        std::fabs(body.sustained_time_s - (body.box_start_s + body.box_steps * substep)) < 0.25 * substep;
    bool steady = contiguous;
    if (steady) {
      double scale = 0.0, change = 0.0;
      for (size_t i = 0; i < body.box_force.size(); ++i) {
        scale = std::max(scale, std::fabs(body.box_force[i]));
        change = std::max(change, std::fabs(body.sustained_modal[i] - body.box_force[i]));
      }
      steady = change <= kSteadyForceTolerance * scale;
    }
    if (!steady) {
      emitBox(body);
      body.box_start_s = body.sustained_time_s;
      body.box_force = body.sustained_modal;
    }
    ++body.box_steps;
    body.last_sustained_time_s = body.sustained_time_s;
    body.sustained_time_s = -1.0;
  };
  for (const ContactEvent& event : result.events) {
    for (int side = 0; side < 2; ++side) {
      const uint32_t index = side == 0 ? event.body_a : event.body_b;
      const uint32_t other = side == 0 ? event.body_b : event.body_a;
      if (index == kGroundBody || !bodies[index].sounded) continue;
      Body& body = bodies[index];
      const auto& point = side == 0 ? event.point_a_mesh : event.point_b_mesh;
      const auto& impulse = side == 0 ? event.impulse_on_a_mesh : event.impulse_on_b_mesh;
      modal.resize(body.bank.modeCount());
      body.projector->projectImpulseInto(point.data(), impulse.data(), modal.data());
      if (event.normal_speed_m_s > kImpactSpeed_m_s) {
        // An impact: a Hertz pulse, short and bright when hard and fast [Johnson 1985].
        const Material& m1 = body.bank.material;
        const bool ground = other == kGroundBody;
        const Material& m2 = ground ? scene.ground_material : bodies[other].bank.material;
        const double r2 = ground ? INFINITY : bodies[other].contact_radius_m;
        const double mass2 = ground || bodies[other].object->is_static ? INFINITY : bodies[other].bank.mass_kg;
        const double mass1 = body.object->is_static ? INFINITY : body.bank.mass_kg;
        ImpactDesc impact;
        impact.object = body.synth_id;
        impact.time_s = event.time_s;
        impact.modal_impulse = modal.data();
        impact.duration_s = hertzContactDuration(m1.youngs_pa, m1.poisson, body.contact_radius_m, mass1, m2.youngs_pa,
                                                 m2.poisson, r2, mass2, event.normal_speed_m_s);
        impact.shape = PulseShape::HalfSine;
        synth.addImpact(impact);
        if (!body.silent) ++report.impacts;
      } else {
        // Sustained contact: the step's impulse is a constant force over the step, so a
        // steady resting force is a constant and makes no sound; only its changes do.
        if (body.sustained_time_s != event.time_s) {
          flushSustained(body);
          body.sustained_time_s = event.time_s;
          body.sustained_modal.assign(modal.size(), 0.0);
          body.sustained_partners.clear();
        }
        body.sustained_partners.push_back(other);
        for (size_t i = 0; i < modal.size(); ++i) body.sustained_modal[i] += modal[i];
        if (!body.silent) ++report.sustained_contacts;
      }
    }
  }
  for (Body& body : bodies) {
    flushSustained(body);
    emitBox(body);
  }

  // A body Bullet puts to sleep reports no more contacts, but it still rests on its support: its
  // last resting force is held to the end, or its disappearance would ring the modes like a lift.
  // The same for a static body (a table) whose last sustained contacts were all with bodies that
  // fell asleep on it: the weight it carries stays.
  const std::vector<double>& asleep_since = simulated->sleep_start_s;
  auto asleepAtEnd = [&](uint32_t index) {
    return index != kGroundBody && index < asleep_since.size() && std::isfinite(asleep_since[index]);
  };
  for (size_t index = 0; index < bodies.size(); ++index) {
    Body& body = bodies[index];
    if (!body.sounded || body.last_sustained_time_s < 0) continue;
    const double hold_start = body.last_sustained_time_s + substep;
    if (hold_start >= duration) continue;
    if (body.object->is_static) {
      bool all_asleep = !body.sustained_partners.empty();
      for (uint32_t other : body.sustained_partners) all_asleep = all_asleep && asleepAtEnd(other);
      if (!all_asleep) continue;
    } else if (norm(simulated->final_velocity_m_s[index]) > kImpactSpeed_m_s) {
      continue;
    }
    bool later_impact = false;
    for (const ContactEvent& event : result.events)
      if ((event.body_a == index || event.body_b == index) && event.step_time_s > body.last_sustained_time_s) later_impact = true;
    if (later_impact) continue;
    const double hold = duration - hold_start;
    for (double& g : body.sustained_modal) g *= hold / substep;  // same force, longer box
    ImpactDesc impact;
    impact.object = body.synth_id;
    impact.time_s = hold_start - 0.5 * substep;
    impact.duration_s = hold;
    impact.ramp_s = substep;
    impact.shape = PulseShape::Box;
    impact.modal_impulse = body.sustained_modal.data();
    synth.addImpact(impact);
  }

  AudioBuffer& audio = result.audio;
  audio.sample_rate_hz = rate;
  audio.channels = 1;
  audio.samples.assign(static_cast<size_t>(std::llround(duration * rate)), 0.0f);
  const size_t chunk = 8192;
  for (size_t done = 0; done < audio.samples.size(); done += chunk) {
    synth.render(audio.samples.data() + done, std::min(chunk, audio.samples.size() - done));
    if (settings.progress) settings.progress("synthesize", static_cast<double>(done) / audio.samples.size());
  }
  for (float s : audio.samples) {
    report.peak = std::max(report.peak, static_cast<double>(std::fabs(s)));
    if (std::fabs(s) >= 1.0f) ++report.clipped_samples;
  }
  const SynthStats stats = synth.stats();
  report.modes_total = stats.modes_total;
  report.modes_out_of_band = stats.modes_out_of_band;
  report.mode_samples = stats.mode_samples;
  report.max_active_modes = stats.max_active_modes;
  report.synthesize_seconds = secondsSince(synth_start);
  for (const Body& body : bodies)
    result.banks.push_back({body.object->bank.empty() ? body.cache_key : 0, body.object->bank, body.sounded});
  report.total_seconds = secondsSince(start);
  return result;
}

Status writeEventsCsv(const std::string& path, const RenderResult& result) {
  std::string csv =
      "time_s,body_a,body_b,new_contact,normal_speed_m_s,normal_impulse_n_s,friction_impulse_n_s,"
      "point_x_m,point_y_m,point_z_m,normal_x,normal_y,normal_z,"
      "point_a_mesh_x,point_a_mesh_y,point_a_mesh_z,point_b_mesh_x,point_b_mesh_y,point_b_mesh_z,step_time_s\n";
  auto name = [&](uint32_t index) { return index == kGroundBody ? std::string("ground") : result.body_names[index]; };
  char line[512];
  for (const ContactEvent& e : result.events) {
    std::snprintf(line, sizeof line,
                  ",%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n",
                  e.new_contact ? 1 : 0, e.normal_speed_m_s, e.normal_impulse_n_s, e.friction_impulse_n_s,
                  e.point_world[0], e.point_world[1], e.point_world[2], e.normal_world[0], e.normal_world[1],
                  e.normal_world[2], e.point_a_mesh[0], e.point_a_mesh[1], e.point_a_mesh[2], e.point_b_mesh[0],
                  e.point_b_mesh[1], e.point_b_mesh[2], e.step_time_s);
    char time[64];
    std::snprintf(time, sizeof time, "%.9g,", e.time_s);
    csv += time + name(e.body_a) + "," + name(e.body_b) + line;
  }
  return writeFileAtomically(path, csv.data(), csv.size());
}

}  // namespace strike
