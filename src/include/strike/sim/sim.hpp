// SPDX-License-Identifier: MIT
// Rigid-body simulation with Bullet (double precision) and contact event extraction.
// Target strike_bullet. Phase 1 of a render: rigid motion does not depend on the sound, so the
// whole scene is simulated first and its contacts recorded; sound comes after.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "strike/sim/path.hpp"
#include "strike/core/progress.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// A body for the simulator. Geometry and mass properties are in the body's MESH frame (the
/// frame of its mode bank); the pose places the mesh frame in the world.
struct SimBodyDesc {
  std::string name;
  bool is_static = false;                              ///< a table or tray: never moves, still sounds when struck
  std::vector<double> surface_positions;               ///< #V * 3, metres, mesh frame
  std::vector<uint32_t> surface_triangles;             ///< #F * 3, CCW from outside
  double mass_kg = 0.0;                                ///< from the tet mesh (ignored when static)
  std::array<double, 3> centre_m{};                    ///< centre of mass, mesh frame
  std::array<double, 9> inertia_kg_m2{};               ///< about centre_m, mesh frame, row-major
  std::array<double, 3> position_m{};                  ///< world position of the mesh-frame origin
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};  ///< unit quaternion, mesh frame -> world
  std::array<double, 3> velocity_m_s{};                ///< of the centre of mass, world
  std::array<double, 3> angular_velocity_rad_s{};      ///< world
  double restitution = 0.5;                            ///< the body's own (its material on itself); see combineContact
  double friction = 0.5;
  /// Coefficient of rolling resistance c_rr = F_resist / N (dimensionless) of its material on
  /// itself; see combineContact. Acts where a sphere-shaped body or a moving exact mesh (Shape::
  /// Concave: a round-bottomed bowl rocking) touches (docs/contact.md).
  /// 0: none, and a sphere rolls for ever (a render takes it from the material table).
  double rolling_resistance = 0.0;
  /// Radius of the sphere of equal volume, m, for the Hertz contact patch (ContactEvent::
  /// patch_radius_m). 0: computed from the surface mesh. Ignored for a static body (flat).
  double contact_radius_m = 0.0;
  /// (1 - nu^2) / E of its material, 1/Pa: weights its restitution when two bodies meet
  /// (combineContact). 0: unknown (both bodies weigh the same).
  double compliance_per_pa = 0.0;
  /// Collision shape: "auto" picks a convex hull when the mesh fills >= 90% of its hull's volume;
  /// else, so things can fall inside (a bowl, a mug), convex pieces for a moving body (a
  /// decomposition within 1% of its size, see convex_pieces.hpp) and the exact triangle mesh for
  /// a static one. Concave: the exact mesh, moving or not (GImpact: ~100x slower than pieces).
  enum class Shape { Auto, ConvexHull, Concave, ConvexPieces } shape = Shape::Auto;
  /// A ConvexPieces shape's pieces, if known (from a previous run, SimResult::convex_pieces_m):
  /// per piece its hull points (x, y, z, ...), mesh frame. Empty: computed (~0.1-1 s a body).
  std::vector<std::vector<double>> convex_pieces_m;
  /// A driven body (scene key "path"): not empty, it follows these keyframes of its mesh frame's
  /// pose as a hand would move it, and position_m, orientation_wxyz and the velocities are not
  /// used (it starts on its path). Each substep its velocities are set so that it ends the substep
  /// where its path is then: exactly in free air, and against friction too (a lag is made up in the
  /// next substep). Upward (against gravity) the hand only holds it: where its path goes into
  /// something it rests on that under its own weight, above its path, and it is lifted again when
  /// its path rises above it. Nothing but the hand turns it (no inverse inertia in the solver).
  /// Never asleep. See docs/scene-format.md.
  std::vector<PathKey> path;
};

/// A convex hull as the simulator computes it (Bullet's btConvexHullComputer) from a body's
/// surface points in its body frame, shrunk by a margin or not.
struct SimHull {
  std::vector<double> vertices_xyz;  ///< #hull vertices * 3, m
  double volume_m3 = 0.0;            ///< 0 when the hull could not be built
  double shrink_m = 0.0;             ///< what btConvexHullComputer::compute returned (< 0: failed)
};
/// Hulls remembered between simulations (a RenderSession's, strike/scene/render_session.hpp): returns
/// the hull of `points_xyz` shrunk by `shrink_m` (clamped to `shrink_clamp` of the inner radius),
/// calling `compute` only for points it has not seen, byte for byte. The same points give the same
/// hull, so a memory changes no result: it saves the hull's computation (~1 ms a body).
using SimHullMemo =
    std::function<std::shared_ptr<const SimHull>(const std::vector<double>& points_xyz, double shrink_m,
                                                 double shrink_clamp, const std::function<SimHull()>& compute)>;
/// What a hull depends on besides its points and shrink: Bullet's version (BT_BULLET_VERSION)
/// and the size of its scalar, for the keys of hulls kept on disk.
uint64_t simHullRecipe();

struct SimSettings {
  double duration_s = 3.0;
  std::array<double, 3> gravity_m_s2{0, 0, -9.81};
  double substep_s = 1.0 / 1000.0;  ///< fixed physics step, <= 1 ms
  bool ground = true;               ///< a static plane z = ground_height_m (silent)
  double ground_height_m = 0.0;
  double ground_restitution = 0.5, ground_friction = 0.6;
  double ground_rolling_resistance = 0.0;  ///< as SimBodyDesc::rolling_resistance
  double ground_compliance_per_pa = 0.0;   ///< as SimBodyDesc::compliance_per_pa
  /// Contact coefficients for particular pairs of bodies (body_b may be kGroundBody), overriding
  /// combineContact; a NaN coefficient is not overridden.
  struct ContactPair {
    uint32_t body_a = 0, body_b = 0;
    double restitution = NAN, friction = NAN, rolling_resistance = NAN;
  };
  std::vector<ContactPair> contact_pairs;
  /// Contacts whose normal impulse is below this are not recorded, N s.
  double min_impulse_n_s = 1e-9;
  /// A contact point closing faster than this is an impact. Its surfaces meet anywhere within a
  /// step either side of the substep that finds it; Bullet still solves it at that substep, but
  /// with the restitution that gives the rebound speed at the meeting and no speculative or
  /// penetration term, and a body whose only loaded contacts are such impacts is then moved to
  /// where that rebound takes it. The event is stamped with the meeting (ContactEvent::time_s).
  /// A CCD predictive contact is left to Bullet; only its event time is estimated. m/s. The sound
  /// engine owns this rule (EngineSettings::impact_speed_m_s) and the render hands it over.
  double impact_speed_m_s = 0.05;
  /// Maximum sequential-impulse iterations per substep. An impact through a 1000:1 mass ratio
  /// needs ~1000 (with 100 a heavy box squeezes a light one out from under it); the solver stops
  /// early once the largest squared impulse change per iteration is below the threshold, (N s)^2.
  int solver_iterations = 1000;
  double solver_residual_threshold = 1e-12;
  /// Let Bullet put bodies to sleep once they have been still (below 1 cm/s and 0.05 rad/s, or
  /// every point within 0.1% of the body's size of where it was) for sleep_after_still_s. A sleeping body reports no contacts (no impulse is applied to it), which
  /// is what makes resting objects quiet and cheap; it wakes when something strikes it.
  bool allow_sleep = true;
  /// Seconds of stillness before sleep, at most Bullet's own 2 s. A still body's contacts are a
  /// steady force, which the render turns into silence, so simulating them longer buys nothing:
  /// 20 plates resting from 0.25 s cost 2 s of solver steps each at Bullet's 2 s.
  double sleep_after_still_s = 0.5;
  /// Stop stepping once every moving body is asleep, and write the remaining substeps' states
  /// and energy as they would be (a sleeping world records no event and does not move: see
  /// Simulation::fillAsleep in sim.cpp). The same result either way, to the bit; false steps to
  /// the end (for the test that says so).
  bool end_when_all_asleep = true;
  /// Memory cap: a run that records more contact events than this stops with an error naming
  /// the cap (`strike render --max-events`). ~100 bytes each: the default is ~2 GB.
  size_t max_events = 20'000'000;
  /// Record every body's pose after every substep (SimResult::states): what a game engine hands
  /// the sound engine each frame. ~80 bytes per body and substep.
  bool record_states = false;
  ProgressFn progress;  ///< phase "simulate", fraction of simulated time; every ~100 ms of wall time
  SimHullMemo hull_memo;  ///< empty: each distinct body's hull is computed once in the run
};

constexpr uint32_t kGroundBody = 0xffffffffu;

/// How a ConvexPieces shape is made (src/sim/convex_pieces.hpp): no surface point deeper inside
/// its piece's hull than concavity_of_size x the body's size, triangle edges refined to at most
/// max_edge_of_size x the size, at most max_pieces. Cached pieces are keyed by these too.
struct ConvexPiecesRecipe {
  static constexpr int version = 1;
  static constexpr double concavity_of_size = 0.02;
  static constexpr double max_edge_of_size = 0.125;
  static constexpr int max_pieces = 64;
};

/// One body's side of a contact: its own coefficients and compliance (SimBodyDesc's).
struct ContactSide {
  double restitution = 0.5, friction = 0.5, compliance_per_pa = 0.0, rolling_resistance = 0.0;
};
struct ContactCoefficients {
  double restitution = 0.0, friction = 0.0, rolling_resistance = 0.0;
};

/// The coefficients of two bodies in contact. A material's own restitution and friction are
/// those of the material on itself, and a pair of one material gets exactly those (Bullet's
/// product gave glass on glass 0.49 for 0.7).
///  - Restitution: in a Hertz contact each body takes a share of the approach, and so of the
///    stored elastic energy, proportional to its compliance k = (1 - nu^2) / E [Johnson 1985,
///    Contact Mechanics, sec. 4.2, eqs. 4.22-4.23]; each is taken to lose the fraction 1 - e^2 of
///    its share that it loses against itself, so 1 - e^2 = (k1 (1 - e1^2) + k2 (1 - e2^2)) / (k1 + k2).
///    The softer body decides: rubber (0.8) on concrete gives 0.80, steel (0.6) on glass (0.7)
///    0.68 (the product: 0.32 and 0.42). Unknown compliances (0) weigh the same.
///  - Friction: the geometric mean sqrt(mu1 mu2), Box2D's mixing law [Catto, Box2D
///    b2MixFriction]: a slippery surface makes the pair slippery (the product: steel 0.4 on
///    steel 0.4 gave 0.16).
///  - Rolling resistance: the compliance-weighted mean c = (k1 c1 + k2 c2) / (k1 + k2). Rolling
///    resistance on smooth solids is hysteresis in the material the contact deforms [Tabor 1955,
///    Proc. R. Soc. A 229, 198-220; Johnson 1985, ch. 9], and each body takes the share
///    k / (k1 + k2) of the deformation (as for restitution): a steel ball on rubber rolls as on
///    rubber, and one material on itself keeps its own value.
ContactCoefficients combineContact(const ContactSide& a, const ContactSide& b);

/// One contact point during one substep.
struct ContactEvent {
  /// When the contact happened, s. An impact (normal_speed_m_s > SimSettings::impact_speed_m_s):
  /// the moment its surfaces met, estimated within a step either side of step_time_s from the gap
  /// and the closing speed at the start of the substep. Any other contact: step_time_s.
  double time_s = 0.0;
  double step_time_s = 0.0;                              ///< start of the substep in which the impulse was applied
  uint32_t body_a = 0, body_b = 0;                       ///< indices into the body list; body_b may be kGroundBody
  std::array<double, 3> point_a_mesh{}, point_b_mesh{};  ///< contact point in each body's mesh frame
  std::array<double, 3> impulse_on_a_mesh{},
      impulse_on_b_mesh{};  ///< total impulse (normal + friction), N s, in each body's mesh frame
  std::array<double, 3> point_world{}, normal_world{};  ///< at time_s; normal points from b to a
  double normal_impulse_n_s = 0.0;
  double friction_impulse_n_s = 0.0;  ///< magnitude of the tangential impulse
  double normal_speed_m_s = 0.0;      ///< approach speed along the normal before the substep (>= 0)
  /// First substep with an impulse at this contact point (an impact, not resting): no event of the
  /// same two bodies lay near this point in the previous 3 substeps (in the world or in either
  /// mesh frame), and Bullet's point is at most 4 substeps old. Proximity alone would flag a
  /// resting corner that the solver left unloaded for a while; m_lifeTime alone restarts at 0 when
  /// a manifold replaces a point, when a CCD predictive contact hands over, for GImpact and rolling.
  /// Reported for users' analysis only: the new_contact column of `strike render --events`
  /// (docs/cli.md) and of the Python events table. The renderer does not read it; it tells an
  /// impact from sustained contact by normal_speed_m_s against SimSettings::impact_speed_m_s.
  bool new_contact = false;
  // Contact state, for continuous (rolling, sliding, scraping) contact sounds (docs/contact.md).
  // The path a contact point travels over a surface is the sequence of point_a_mesh (or
  // point_b_mesh) of the pair's successive events: the same spot of a surface has the same
  // mesh-frame coordinates whenever it is touched.
  double normal_force_n = 0.0;  ///< normal_impulse_n_s / substep: the mean normal force over the substep, N
  /// Relative velocity of a's surface to b's at the contact point, in the tangent plane, world,
  /// m/s, after the substep's solve: 0 while the surfaces stick (rolling without slip, resting).
  std::array<double, 3> slip_velocity_m_s{};
  /// How fast the contact point travels over each body's surface, m/s: a ball rolling at speed v
  /// on the ground, v over both; a block sliding at v, 0 over the block and v over the ground.
  double track_speed_a_m_s = 0.0, track_speed_b_m_s = 0.0;
  /// The velocity whose length is track_speed_a_m_s: the point's travel over a's surface, in the
  /// tangent plane, world, m/s. It travels over b's at this + slip_velocity_m_s (the sound
  /// engine's and strike_contact's rolling_velocity_m_s of a's side).
  std::array<double, 3> track_velocity_a_m_s{};
  /// The rolling speed: the part of the contact point's travel common to both surfaces,
  /// min(track_speed_a, track_speed_b), m/s. A ball rolling without slip: v; sliding: 0.
  double rolling_speed_m_s = 0.0;
  /// Radius of the Hertz contact patch under normal_force_n, m (hertzPatchRadius); 0 when the
  /// materials' stiffness is unknown (compliance 0).
  double patch_radius_m = 0.0;
};

/// The radius of the Hertz contact circle of two elastic bodies pressed together by force_n:
/// a = (3 F R* / (4 E*))^(1/3), 1/R* = 1/R1 + 1/R2, 1/E* = k1 + k2 with k = (1 - nu^2) / E
/// [Johnson 1985, Contact Mechanics, eqs. 4.22-4.23]. A radius of 0 or infinity is flat. 0 when
/// both are flat, the force is not positive, or k1 + k2 is 0 (unknown).
double hertzPatchRadius(double force_n, double radius_a_m, double radius_b_m, double compliance_a_per_pa,
                        double compliance_b_per_pa);

/// A body after a substep, as a game engine reports it every frame.
struct SimBodyState {
  std::array<double, 3> position_m{};                  ///< mesh-frame origin, world
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};  ///< mesh frame -> world
  std::array<double, 3> velocity_m_s{};                ///< of the centre of mass, world
  bool asleep = false;  ///< Bullet deactivated it: it reports no contacts, yet still rests on its support
};

struct SimResult {
  std::vector<ContactEvent> events;  ///< in order of time_s
  /// With SimSettings::record_states: states[k * bodies + i] is body i after substep k (at time
  /// (k + 1) * substep_s). Static bodies too (never asleep).
  std::vector<SimBodyState> states;
  /// Total mechanical energy (kinetic + gravitational potential) of the dynamic bodies, J,
  /// sampled every substep; and each body's kinetic energy maximum over the run.
  /// energy_trace_j[0] is the initial energy, then one value after each substep (substeps + 1).
  std::vector<double> energy_trace_j;
  std::vector<double> max_kinetic_energy_j;
  std::vector<double> initial_kinetic_energy_j;
  std::vector<std::array<double, 3>> final_position_m;  ///< mesh-frame origin, world
  /// Of the centre of mass, world; Bullet's stored velocity, which is half a step old (sim.cpp,
  /// buildBody): under gravity alone it differs from the velocity at the end by g dt / 2.
  std::vector<std::array<double, 3>> final_velocity_m_s;
  std::vector<std::array<double, 3>> final_angular_velocity_rad_s;  ///< world
  /// Per body: the collision shape actually used (Auto resolved) and its collision margin, m.
  std::vector<SimBodyDesc::Shape> shape_used;
  std::vector<double> collision_margin_m;
  std::vector<size_t> collision_pieces;  ///< per body: convex pieces of a ConvexPieces shape, else 0
  /// Per body: a ConvexPieces shape's pieces (as SimBodyDesc::convex_pieces_m), to reuse; and
  /// whether they were computed in this run (not given), and the seconds that took (identical
  /// bodies share one decomposition: the first has the time, the rest 0).
  std::vector<std::vector<std::vector<double>>> convex_pieces_m;
  std::vector<bool> pieces_computed;
  std::vector<double> pieces_seconds;
  /// Per body: when it fell asleep and stayed so to the end, s; NaN if awake at the end (or static).
  std::vector<double> sleep_start_s;
  double simulate_seconds = 0.0;  ///< wall time
  uint64_t substeps = 0;
};

/// Simulates the bodies; errors name the body and the bad value (NaN pose, zero mass...).
Result<SimResult> simulate(const std::vector<SimBodyDesc>& bodies, const SimSettings& settings);

}  // namespace strike
