// SPDX-License-Identifier: MIT
// The render as a pipeline. Follow renderScene() from the bottom of the file: prepare bodies ->
// simulate -> provide banks (bank_source.hpp: only for what was heard) -> play (playback.cpp).
#include "strike/scene/render.hpp"
#include "strike/audio/sofa_hrtf.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "bank_source.hpp"
#include "hrtf_cache.hpp"
#include "hull_cache.hpp"
#include "pieces_cache.hpp"
#include "playback.hpp"
#include "strike/core/atomic_file.hpp"
#include "strike/bank/bank.hpp"
#include "strike/cache/bank_cache.hpp"
#include "strike/synth/contact_noise.hpp"
#include "strike/precompute/element_order.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/core/read_file.hpp"
#include "strike/scene/render_session.hpp"
#include "strike/scene/scene_checks.hpp"
#include "strike/synth/synth.hpp"
#include "surfaces.hpp"

namespace strike {
namespace {

// A velocity change below 1 micrometre per second cannot be heard from any object of audible
// size; objects struck only that softly get no eigen-solve (a conservative audibility bound).
constexpr double kInaudibleVelocityChange_m_s = 1e-6;
// Hertz pulses are capped at this length (a rubber ball's is ~1 ms): no physical pulse is cut.
constexpr double kMaxContactDuration_s = 0.05;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// What the precompute of an object solved from its mesh is asked: its modes up to `max_freq_hz`,
/// the acoustic transfer of those up to `heard_hz`, the band the engine plays.
PrecomputeSettings precomputeSettings(const SceneObject& object, const Scene& scene, const RenderSettings& settings,
                                      double max_freq_hz, double heard_hz) {
  PrecomputeSettings precompute;
  precompute.mesh_spec = object.mesh;
  precompute.material = object.material;
  precompute.order = object.order;
  precompute.target_edge_m = object.size_m;
  precompute.mesh_scale = object.mesh_scale;
  precompute.max_freq_hz = max_freq_hz;
  precompute.max_modes = scene.max_modes;
  precompute.max_tets = settings.max_tets;
  precompute.max_memory_bytes = settings.max_memory_bytes;
  precompute.progress = settings.progress;
  precompute.acoustic_transfer = settings.acoustic_transfer;
  precompute.transfer_max_freq_hz = heard_hz;
  return precompute;
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
  RenderRun(const Scene& scene_, const RenderSettings& settings_)
      : scene(scene_),
        settings(settings_),
        banks(settings_, bodies, result.report, [this](std::string text) { warn(std::move(text)); }) {}
  RenderRun(const RenderRun&) = delete;
  RenderRun& operator=(const RenderRun&) = delete;
  const Scene& scene;
  const RenderSettings& settings;
  double rate = 0.0, duration = 0.0, substep = 0.0;
  double max_freq_hz = 0.0;  ///< no mode above the audible band or what the rate can carry is computed
  double heard_hz = 0.0;     ///< ...and only the modes the engine plays get an acoustic transfer
  EngineSettings engine_settings;
  RenderResult result;
  std::vector<Body> bodies;
  BankSource banks;  ///< where the bodies' banks come from (phase 1 and 3)
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
  for (size_t i = 0; i < bodies.size(); ++i) {
    const SceneObject& object = run.scene.objects[i];
    bodies[i].object = &object;
    if (object.bank.empty())
      bodies[i].precompute = precomputeSettings(object, run.scene, run.settings, run.max_freq_hz, run.heard_hz);
  }
  if (Status prepared = run.banks.prepare(); !prepared) return prepared;
  for (size_t i = 0; i < bodies.size(); ++i) {
    bodies[i].contact_radius_m = std::cbrt(3.0 * bodies[i].bank->volume_m3 / (4.0 * M_PI));
    run.result.body_names.push_back(run.scene.objects[i].name);
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

/// Which struck bodies sound: those a contact changed the velocity of audibly (every body when
/// leaving nothing out).
void markSoundingBodies(RenderRun& run) {
  RenderReport& report = run.report();
  const bool all = run.settings.leave_nothing_out;
  for (Body& body : run.bodies) {
    if (body.max_velocity_change_m_s == 0.0 && !all) continue;
    if (body.max_velocity_change_m_s > 0.0) ++report.objects_struck;
    if (body.max_velocity_change_m_s < kInaudibleVelocityChange_m_s && !all) {
      ++report.objects_inaudible;
      continue;
    }
    body.sounded = true;
  }
}

/// Every sounding body's bank (bank_source.hpp); then the cache kept to its size.
Status provideBanks(RenderRun& run) {
  const auto start = std::chrono::steady_clock::now();
  findStruckBodies(run);
  markSoundingBodies(run);
  if (Status provided = run.banks.provide(run.result.events); !provided) return provided;
  run.report().precompute_seconds = secondsSince(start);
  run.banks.pruneCache();
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

// The binaural output's responses at the render's rate: from the cache when it holds this SOFA
// file's at this rate (hrtf_cache.hpp), else read and resampled by libmysofa and written there.
Result<std::shared_ptr<const HrtfSet>> headRelatedResponses(const RenderSettings& settings, double rate) {
  const std::string& file = settings.hrtf_file.empty() ? kDefaultHrtfFile : settings.hrtf_file;
  if (settings.cache_dir.empty()) return loadSofaHrtf(file, rate);
  Result<std::string> bytes = readWholeFile(file, uint64_t(1) << 28);
  if (!bytes) return loadSofaHrtf(file, rate);  // which names what is wrong with it
  const uint64_t key = hrtfKey(*bytes, rate);
  const std::string path = hrtfPath(settings.cache_dir, key);
  if (Result<HrtfSet> cached = readHrtf(path, key)) {
    auto set = std::make_shared<HrtfSet>(std::move(*cached));
    if (prepareHrtfSet(*set).empty() && set->sample_rate_hz == rate) {
      touchCacheEntry(path);
      return std::shared_ptr<const HrtfSet>(std::move(set));
    }
  }
  Result<std::shared_ptr<const HrtfSet>> loaded = loadSofaHrtf(file, rate);
  if (loaded) (void)writeHrtf(path, key, **loaded);  // a failed cache write costs the next render time only
  return loaded;
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
    Result<std::shared_ptr<const HrtfSet>> hrtf = headRelatedResponses(settings, run.rate);
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
