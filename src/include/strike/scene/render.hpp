// SPDX-License-Identifier: MIT
// `strike render`: a scene to sound, in two phases so nothing is computed that is not heard.
//   1. simulate: mass properties and surfaces (from cached or given banks, or from the meshes
//      without an eigen-solve), Bullet simulation, contact events;
//   2. sound: mode banks only for objects struck hard enough to be heard (cache, or compute),
//      contact impulses projected onto modes, oscillator bank, mix.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "strike/audio/audio.hpp"
#include "strike/cache/bank_cache.hpp"
#include "strike/synth/engine.hpp"
#include "strike/mesh/mesh.hpp"
#include "strike/core/progress.hpp"
#include "strike/scene/scene.hpp"
#include "strike/sim/sim.hpp"
#include "strike/synth/spatializer.hpp"
#include "strike/synth/synth.hpp"

namespace strike {

// The tools' output level convention, kFullScalePascal (1.0 = 20 Pa), is in strike/synth/synth.hpp:
// libstrike uses it too.

/// Where renderScene sends the simulation, step by step, exactly as a game would: the built-in
/// sound engine, or libstrike through its public C API (`strike render --via-library`, in
/// tools/cli/via_library.cpp). Calls come in this order: addVoice for every sounding body and
/// setListener; then per physics step beginStep, setPose for every body, contact for each side
/// of each contact point, endStep; and render() whenever the audio may advance.
class RenderSession;

class SoundOutput {
 public:
  virtual ~SoundOutput() = default;
  /// slot: the body's index in the scene; voice.pose is ignored: the pose is given as a position
  /// and quaternion (w, x, y, z), as a physics engine has it. Errors name the body.
  virtual Status addVoice(uint32_t slot, const VoiceDesc& voice, const std::array<double, 3>& position_m,
                          const std::array<double, 4>& orientation_wxyz, const std::string& name) = 0;
  /// The listener's pose: its position and orientation (w, x, y, z; world from listener).
  virtual void setListener(const std::array<double, 3>& position_m, const std::array<double, 4>& orientation_wxyz) = 0;
  virtual void beginStep(double step_end_s, double step_s) = 0;
  virtual void setPose(uint32_t slot, const std::array<double, 3>& position_m,
                       const std::array<double, 4>& orientation_wxyz, bool asleep) = 0;
  virtual void contact(const EngineContact& contact) = 0;
  virtual void endStep() = 0;
  /// The next `frames` (<= kRenderBlockFrames) frames of the engine settings' channels
  /// (EngineSettings::output), interleaved, full scale 1.0.
  virtual Status render(float* interleaved, size_t frames) = 0;
  virtual EngineStats stats() const = 0;
  /// Problems to report after the render (e.g. what a fixed-size queue dropped); empty if none.
  virtual std::vector<std::string> warnings() const { return {}; }
};
using SoundOutputFactory = std::function<Result<std::unique_ptr<SoundOutput>>(const EngineSettings&)>;

/// Audio comes out of the engine in blocks of this many frames, each rendered as soon as the
/// physics has passed it by one step (a game's audio callback, at a fixed latency).
constexpr size_t kRenderBlockFrames = 256;

struct RenderSettings {
  double sample_rate_hz = 0.0;  ///< 0: the scene's
  double duration_s = 0.0;      ///< 0: the scene's
  std::string cache_dir;        ///< where banks are cached by content hash; empty: no cache
  /// After the render, the cache's least recently used banks are removed until it fits in this
  /// (strike/cache/bank_cache.hpp); 0: no cap.
  uint64_t cache_max_bytes = kDefaultCacheMaxBytes;
  double gain = 1.0;                             ///< output scale on top of kFullScalePascal
  int64_t max_tets = kDefaultMaxTets;            ///< size cap of each object's tet mesh (PrecomputeSettings::max_tets)
  size_t max_events = SimSettings{}.max_events;  ///< cap on recorded contact events (SimSettings::max_events)
  /// Memory budget of each object's solve, bytes (PrecomputeSettings::max_memory_bytes); 0: none.
  double max_memory_bytes = 0.0;
  /// For `strike bench leftout` only: leave nothing out, to measure what leaving out saves. Every
  /// object gets a bank and an oscillator (struck or not, however softly); the synth keeps every
  /// mode of the banks (no 20 kHz synth cap: the banks' own cut-off, the scene's max_freq_hz
  /// capped at 0.45 x the sample rate, is the only one); and its audibility threshold drops to its
  /// floor (1e-30 full scale, -600 dB), so no mode is culled and a mode sleeps only once it has
  /// rung down below -600 dB. The eigen-solve's cut-off stays the scene's: a bank solved to
  /// another cut-off has other eigenvector signs and degenerate-pair bases, which the per-mode
  /// radiation weight (an rms over directions, without sign) does not undo, so the two renders
  /// would differ by that arbitrariness rather than by what was left out (README).
  bool leave_nothing_out = false;
  /// Exact similarity reuse (`strike render --similar`; src/include/strike/precompute/normalized_problem.hpp):
  /// every object's bank is the solve of its normalized problem (unit size, a reference material
  /// of its Poisson ratio, its lowest max_modes modes), scaled and cut at the object's cut-off; the
  /// cache keys that solve, so objects of one shape at other sizes and materials share one
  /// eigen-solve, and the output does not depend on what the cache holds. Off by default: that
  /// solve has other eigenvector signs than one to the object's own cut-off (see
  /// leave_nothing_out), so its renders differ from those without it in the polarity of some modes
  /// (the same modes, frequencies equal to 2e-12) and the committed golden renders would not match.
  bool similar_reuse = false;
  /// Banks computed by this render get an acoustic transfer (PrecomputeSettings::acoustic_transfer).
  /// `strike render` and the Python package turn it on unless told `--no-transfer`; here it is
  /// asked for, as in PrecomputeSettings. Banks given in the scene are used as they are.
  bool acoustic_transfer = false;
  /// How many of the banks this render computes are solved at once, each on a thread of its own
  /// (src/scene/side_by_side.hpp): 0, one per core, as far as the memory forecast allows; 1, one
  /// after another. The banks, and so the output, are the same bytes either way.
  unsigned solve_threads = 0;
  /// Physics step, s (at most 1 ms, what the issue allows). Contact times fall on this grid, so an
  /// impact is placed within one step (48 samples at 48 kHz); 1 ms halves the simulation cost of
  /// the 0.5 ms step used before (`strike bench render` measures both).
  double substep_s = 1e-3;
  /// The channels written (`strike render --output`; spatializer.hpp): mono by default.
  OutputFormat output_format = OutputFormat::Mono;
  /// The binaural output's head-related responses: an AES69 SOFA file (`--hrtf`); empty: the MIT
  /// KEMAR set Debian's libmysofa installs (kDefaultHrtfFile). Read at the render's sample rate.
  std::string hrtf_file;
  /// The synthesizer's kernel (SynthSettings::simd): kernels differ only in the last bits.
  SimdLevel simd = SimdLevel::Auto;
  ProgressFn progress;
  /// Null: the built-in sound engine. Else where the simulation goes instead (--via-library);
  /// the banks are then read whole (a library loads whole bank files).
  SoundOutputFactory output;
  /// Called with each warning as soon as it is found (before the simulation for the scene's
  /// placement, so a long render does not hide it until the end); also kept in report.warnings.
  std::function<void(const std::string&)> on_warning;
  /// What renders rebuild from identical inputs (hulls, bank surfaces and their locators), kept
  /// between the renders that share it (strike/scene/render_session.hpp); the same bytes with or
  /// without it. Owned by the caller, who keeps it alive through the render. Null: none.
  RenderSession* session = nullptr;
};

struct RenderReport {
  size_t objects = 0, objects_struck = 0;
  size_t objects_sounded = 0;      ///< struck audibly and with at least one mode in the synthesized band
  size_t objects_silent = 0;       ///< struck audibly, but no mode in the synthesized band (warnings say why)
  size_t objects_clicks_only = 0;  ///< sounded, but only by acceleration noise: no mode in the band
  size_t objects_inaudible = 0;    ///< struck, but too softly to hear: no eigen-solve
  size_t banks_given = 0, banks_cached = 0, banks_computed = 0, banks_shared = 0;
  /// Banks scaled from a solve of the same shape made in this render for an object of another
  /// size or material (every computed bank is a normalized solve, scaled: normalized_problem.hpp).
  size_t banks_scaled = 0;
  /// With similar_reuse and the acoustic transfer: unit transfers (one per shape, wave speed E/rho
  /// and number of modes kept; normalized_problem.hpp) solved by this render, read from the cache,
  /// and taken from an earlier object of this render; each body's is its unit transfer, scaled.
  size_t transfers_solved = 0, transfers_cached = 0, transfers_shared = 0;
  /// Cached banks whose transfer stopped short of the modes this render plays (solved for a lower
  /// band) and got the rest now, written back to the cache.
  size_t transfers_extended = 0;
  /// Surface vertices whose mode shapes were read from given or cached bank files, of all theirs
  /// (a render reads shapes only where its contacts land).
  size_t shape_vertices_read = 0, shape_vertices_total = 0;
  /// Contact points Bullet recorded (one per point per step), split by their closing speed into
  /// impacts (> 5 cm/s) and resting or sliding contact.
  size_t events = 0, impact_events = 0, sustained_events = 0;
  /// What reached the oscillators: one impact pulse, or one resting/sliding impulse, per event
  /// per sounding body (objects_sounded) it acts on. An event between two sounding bodies counts
  /// for both; one against the ground, a silent body or one that was not heard, for one or none.
  size_t impacts = 0, sustained_contacts = 0;
  /// Changes of a body's load (a force step each: landing, being pushed, lifted; a steady load is
  /// silent), and steps a sleeping body's load was kept.
  size_t load_changes = 0, load_holds = 0;
  /// Rolling, sliding and scraping (docs/contact.md): contact generators started, samples in
  /// which a rough contact lost contact, and the time the last one's force stopped (-1: none).
  size_t continuous_contacts = 0;
  size_t continuous_dropped = 0;  ///< contact points not heard: the body already sounded with kForceChannels partners
  uint64_t continuous_lost_samples = 0;
  double continuous_last_force_s = -1.0;
  /// Scenes that cannot be right, and silent results, in words with numbers (scene_checks.hpp).
  std::vector<std::string> warnings;
  uint64_t modes_total = 0, modes_out_of_band = 0, mode_samples = 0, max_active_modes = 0;
  uint64_t forced_mode_samples = 0;  ///< of mode_samples, driven by rolling and sliding contacts
  uint64_t image_mode_samples = 0;   ///< of mode_samples, the ground image's oscillators (free ones)
  double peak = 0.0;
  size_t clipped_samples = 0;
  double load_seconds = 0, simulate_seconds = 0, precompute_seconds = 0, synthesize_seconds = 0, total_seconds = 0;
  double precompute_saved_seconds =
      0;  ///< solve time (meshing, eigen-solve, transfer) the cache answered, as the banks record it
  double transfer_saved_seconds = 0;  ///< unit transfer solves the cache answered (as recorded in them)
  size_t cache_pruned = 0;            ///< banks removed from the cache by its size cap after this render
  uint64_t cache_pruned_bytes = 0;
  double pieces_seconds = 0;  ///< of simulate_seconds: computing convex pieces (cached for the next render)
  /// One line per concave moving body: its collision shape and what it cost (the summary's
  /// "collision" lines; exact meshes are named as the slow choice).
  std::vector<std::string> collision_notes;
};

/// Which bank a body's sound came from: its content address in the cache (the file name
/// KEY.modes: a hash of the mesh bytes and of every setting that changes the modes), or the
/// bank file the scene gave.
struct BodyBank {
  uint64_t cache_key = 0;  ///< 0 when the scene gave the bank file
  std::string given_path;  ///< the scene's "bank", or empty
  bool sounded = false;    ///< struck hard enough to be heard (its bank was used)
  /// With similar_reuse and the transfer: the cache address of its unit transfer (KEY.transfer),
  /// equal for bodies that share it; 0 otherwise.
  uint64_t transfer_key = 0;
};

struct RenderResult {
  AudioBuffer audio;
  std::vector<ContactEvent> events;
  std::vector<std::string> body_names;
  std::vector<BodyBank> banks;  ///< per body, in scene order
  RenderReport report;
};

Result<RenderResult> renderScene(const Scene& scene, const RenderSettings& settings);

/// The engine settings of a render at this sample rate and cut-off (both outputs use them).
EngineSettings renderEngineSettings(const Scene& scene, const RenderSettings& settings, double rate_hz,
                                    double max_freq_hz);

/// How the surfaces move at a contact: "rolling", "sliding", "rolling+sliding", or "rest" (impacts
/// included) when both speeds are below a rough contact's still speed (the events CSV's last column).
const char* contactMotion(const ContactEvent& event);

/// One row per contact event: time, bodies, points, impulses, speeds (see the header row).
Status writeEventsCsv(const std::string& path, const RenderResult& result);

/// Default cache folder: $STRIKE_CACHE_DIR, else $XDG_CACHE_HOME/strike, else ~/.cache/strike.
std::string defaultCacheDir();

}  // namespace strike
