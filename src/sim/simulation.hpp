// SPDX-License-Identifier: MIT
// What the parts of the simulation share (private to src/sim): the Bullet world, each body's
// state, and the Simulation that steps them. The parts: checks.cpp (input checks), shapes.cpp
// (collision shapes, Simulation::buildBody), impact_timing.cpp (when an impact's surfaces met),
// contact_events.cpp (the events of a substep) and sim.cpp (the world and the run). The frames
// are explained in sim.cpp.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "strike/core/result.hpp"
#include "strike/sim/sim.hpp"

#include <BulletCollision/CollisionDispatch/btConvexConvexAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btConvexPlaneCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btSimulationIslandManager.h>
#include <BulletCollision/CollisionDispatch/btSphereBoxCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <LinearMath/btConvexHullComputer.h>
#include <btBulletDynamicsCommon.h>

namespace strike::detail {

using Vec3 = std::array<double, 3>;

/// Hulls up to this many vertices get SAT + clipping contacts (see buildBody).
constexpr int kMaxPolyhedralVertices = 128;
/// BodyState::still_since_step of a body whose pose clock has not started.
constexpr uint64_t kNotStill = ~uint64_t(0);

inline btVector3 toBt(const Vec3& v) { return btVector3(v[0], v[1], v[2]); }
inline Vec3 fromBt(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

/// Bullet's rolling and spinning friction coefficients (lengths, m) for a contact point
/// (contact_state.cpp): see docs/contact.md.
struct RollingFriction {
  double rolling_m = 0.0, spinning_m = 0.0;
};
/// radius_a/b: each body's rolling radius (a sphere's radius; a moving exact mesh's the sphere of
/// its volume; 0 for any other shape); patch_radius_m: the Hertz patch under the point's load.
RollingFriction rollingFriction(double rolling_resistance, double friction, double radius_a_m, double radius_b_m,
                                double patch_radius_m);

/// A number for a message, "%.9g" (checks.cpp).
std::string fmt(double value);
/// "body INDEX \"NAME\"", how messages name a body (checks.cpp).
std::string bodyLabel(const SimBodyDesc& body, size_t index);

/// The settings' ranges (checks.cpp).
Status checkSettings(const SimSettings& settings);
/// Checks one body; writes the normalized orientation (checks.cpp).
Status checkBody(const SimBodyDesc& body, size_t index, btQuaternion& orientation);

/// Acceleration of a body between contacts: gravity when it moves, none when static
/// (impact_timing.cpp).
btVector3 freeAcceleration(const btCollisionObject* object);
/// Velocity of an object's material point at `world` (zero for static objects; impact_timing.cpp).
btVector3 velocityAt(const btCollisionObject* object, const btVector3& world);
/// When, from the start of the substep, a contact point's surfaces meet; negative when they met
/// in the previous substep, NaN when they never do (impact_timing.cpp).
double meetingOffset(double gap_m, double closing_m_s, double closing_accel_m_s2, double step_s);

/// Everything Bullet needs for one body; addresses must stay fixed (Bullet keeps pointers).
struct BodyState {
  btTransform mesh_from_body;  // fixed
  btTransform body_from_mesh;
  btVector3 principal_inertia{0, 0, 0};  // kg m^2, body frame
  double mass_kg = 0.0;
  double size_m = 0.0;        // largest extent of the body-frame bounding box
  double min_extent_m = 0.0;  // smallest extent
  double margin_m = 0.0;
  double sphere_radius_m = 0.0;    // a sphere shape's radius (about the centre of mass); 0: not a sphere
  double contact_radius_m = 0.0;   // for the Hertz patch (SimBodyDesc::contact_radius_m); 0: flat
  double compliance_per_pa = 0.0;  // (1 - nu^2) / E of its material
  SimBodyDesc::Shape shape_used = SimBodyDesc::Shape::ConvexHull;
  bool is_static = false;
  bool driven = false;  // follows SimBodyDesc::path (Simulation::drive)
  // Storage for concave shapes (btTriangleIndexVertexArray points into these).
  std::vector<btScalar> body_xyz;
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> mesh_interface;
  std::vector<std::unique_ptr<btConvexHullShape>> pieces;  // children of a compound shape
  std::vector<std::vector<double>> pieces_mesh;            // their points, mesh frame
  bool pieces_computed = false;
  double pieces_seconds = 0.0;
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btBoxShape> box_twin;  // a box hull's twin for sphere contacts (buildBody)
  std::unique_ptr<btRigidBody> rigid;
  // Saved at the start of each substep (pre-tick callback).
  btTransform pre_transform;
  btVector3 pre_linear{0, 0, 0}, pre_angular{0, 0, 0};
  // The pose still-clock (Simulation::hastenSleep): the pose when it started, and the substep.
  btTransform still_anchor = btTransform::getIdentity();
  uint64_t still_since_step = kNotStill;
  double sleep_start_s = NAN;  // when it fell asleep; NaN while awake
  // Bullet's contact breaking threshold of its shape (btCollisionShape::getContactBreakingThreshold),
  // for StrikeDispatcher; the rigid body's user pointer is this state.
  double breaking_threshold_m = 0.0;
};

/// Bullet's dispatcher, whose narrow phase skips pairs that hold no contact point and are too far
/// apart to make one (sim.cpp).
class StrikeDispatcher : public btCollisionDispatcher {
 public:
  explicit StrikeDispatcher(btCollisionConfiguration* config) : btCollisionDispatcher(config) {
    setNearCallback(&StrikeDispatcher::nearCallback);
  }

 private:
  static void nearCallback(btBroadphasePair& pair, btCollisionDispatcher& dispatcher, const btDispatcherInfo& info);
  bool apartWithoutPoints(const btBroadphasePair& pair);
  btManifoldArray manifolds_;  // scratch, kept to stay allocation-free
};

/// btDiscreteDynamicsWorld keeps its CCD predictive manifolds protected; their points sit at the
/// body's centre of mass (a swept sphere), so the event extraction must recognise them.
class StrikeWorld : public btDiscreteDynamicsWorld {
 public:
  using btDiscreteDynamicsWorld::btDiscreteDynamicsWorld;
  bool isPredictive(const btPersistentManifold* manifold) const {
    for (int k = 0; k < m_predictiveManifolds.size(); ++k) {
      if (m_predictiveManifolds[k] == manifold) return true;
    }
    return false;
  }
  /// Called after the narrow phase and before the solver of every substep.
  std::function<void()> before_solve;

 protected:
  void solveConstraints(btContactSolverInfo& info) override {
    if (before_solve) before_solve();
    btDiscreteDynamicsWorld::solveConstraints(info);
  }
  /// Islands of bodies linked by contact points (sim.cpp).
  void calculateSimulationIslands() override;
};

/// A sphere against a hull that is a box: Bullet's exact sphere-box test run on the hull's box
/// twin (BodyState::box_twin), the same solid. The test is the closest point of the box to the
/// sphere's centre (a clamp to the half extents), or the nearest face when the centre is inside
/// [Bullet btSphereBoxCollisionAlgorithm::getSphereDistance]; one point, as GJK found on the hull.
class SphereOnBoxHull : public btSphereBoxCollisionAlgorithm {
 public:
  SphereOnBoxHull(const btBoxShape* twin, const btCollisionAlgorithmConstructionInfo& info,
                  const btCollisionObjectWrapper* a, const btCollisionObjectWrapper* b, bool swapped)
      : btSphereBoxCollisionAlgorithm(nullptr, info, a, b, swapped), twin_(twin), swapped_(swapped) {}
  void processCollision(const btCollisionObjectWrapper* a, const btCollisionObjectWrapper* b,
                        const btDispatcherInfo& info, btManifoldResult* result) override {
    const btCollisionObjectWrapper* hull = swapped_ ? a : b;
    const btCollisionObjectWrapper box(hull->m_parent, twin_, hull->getCollisionObject(), hull->getWorldTransform(),
                                       hull->m_partId, hull->m_index);
    btSphereBoxCollisionAlgorithm::processCollision(swapped_ ? &box : a, swapped_ ? b : &box, info, result);
  }

 private:
  const btBoxShape* twin_;
  bool swapped_;  // the hull is body 0
};
// Bullet's algorithm pool holds elements of its largest algorithm's size (allocateCollisionAlgorithm).
static_assert(sizeof(SphereOnBoxHull) <= sizeof(btConvexConvexAlgorithm));

/// Convex-convex contacts without Bullet's multipoint perturbation when the shape it would turn
/// is a sphere (see Simulation::build); otherwise as Bullet's default. A sphere against a hull
/// with a box twin takes SphereOnBoxHull.
class SphereAwareConvexConvex : public btConvexConvexAlgorithm::CreateFunc {
 public:
  SphereAwareConvexConvex(btConvexPenetrationDepthSolver* solver, int iterations, int min_points)
      : btConvexConvexAlgorithm::CreateFunc(solver) {
    m_numPerturbationIterations = iterations;
    m_minimumPointsPerturbationThreshold = min_points;
  }
  btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& info,
                                                 const btCollisionObjectWrapper* a,
                                                 const btCollisionObjectWrapper* b) override {
    // btConvexConvexAlgorithm::processCollision turns A if its angular motion disc is the smaller,
    // else B.
    const btCollisionShape* shape_a = a->getCollisionShape();
    const btCollisionShape* shape_b = b->getCollisionShape();
    const btCollisionShape* turned =
        shape_a->getAngularMotionDisc() < shape_b->getAngularMotionDisc() ? shape_a : shape_b;
    const bool sphere_a = shape_a->getShapeType() == SPHERE_SHAPE_PROXYTYPE;
    const auto twin = box_twins.find(sphere_a ? shape_b : shape_a);
    if ((sphere_a || shape_b->getShapeType() == SPHERE_SHAPE_PROXYTYPE) && twin != box_twins.end()) {
      void* memory = info.m_dispatcher1->allocateCollisionAlgorithm(sizeof(SphereOnBoxHull));
      return new (memory) SphereOnBoxHull(twin->second, info, a, b, !sphere_a);
    }
    const int iterations = turned->getShapeType() == SPHERE_SHAPE_PROXYTYPE ? 0 : m_numPerturbationIterations;
    void* memory = info.m_dispatcher1->allocateCollisionAlgorithm(sizeof(btConvexConvexAlgorithm));
    return new (memory) btConvexConvexAlgorithm(info.m_manifold, info, a, b, m_pdSolver, iterations,
                                                m_minimumPointsPerturbationThreshold);
  }
  /// Hulls that are boxes, and their twins (Simulation::buildBody).
  std::map<const btCollisionShape*, const btBoxShape*> box_twins;
};

/// A contact point that strikes within the current substep (see Simulation::timeImpacts).
struct ImpactPoint {
  const btManifoldPoint* point = nullptr;
  double offset_s = 0.0;  ///< when the surfaces met, from the start of the substep, in [-step, step]
  bool retimed = false;   ///< solved as touching at offset_s (Simulation::moveImpactsToTheirTime)
};

/// A body's loaded contacts in the current substep (see Simulation::moveImpactsToTheirTime).
struct StruckBody {
  double impulse_n_s = 0.0;           ///< normal impulse of its retimed impacts
  double impulse_times_offset = 0.0;  ///< their sum of impulse x offset, N s^2
  bool other_contact = false;         ///< a loaded contact that is not a retimed impact
};

struct RecentContact {
  uint64_t step = 0;
  btVector3 world, a_mesh, b_mesh;
};

class Simulation {
 public:
  Simulation(const std::vector<SimBodyDesc>& bodies, const SimSettings& settings)
      : descs_(bodies), settings_(settings) {}
  ~Simulation() {
    if (world_) {
      for (auto& b : bodies_) {
        if (b->rigid) world_->removeRigidBody(b->rigid.get());
      }
      if (ground_) world_->removeRigidBody(ground_.get());
    }
  }
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  Status build(const std::vector<btQuaternion>& orientations);
  Result<SimResult> run();

 private:
  Status buildBody(size_t index, const btQuaternion& orientation);
  /// The body's principal frame (centre of mass, principal axes and moments), its surface in
  /// that frame, its size, contact radius and default margin (buildBody).
  Status bodyFrame(size_t index, BodyState& state);
  /// A convex hull, or a sphere when the hull is one, or a box's polyhedral hull with its box twin.
  Status buildHullShape(size_t index, BodyState& state, const std::shared_ptr<const SimHull>& hull);
  /// Convex pieces of a concave moving body, each a polyhedral hull.
  Status buildPiecesShape(size_t index, BodyState& state);
  /// The exact triangle mesh: a BVH when static, GImpact when it moves.
  void buildMeshShape(size_t index, BodyState& state);
  /// The rigid body at its start pose and velocity, with its CCD, sleep and drive settings, in the world.
  void addRigidBody(size_t index, const btQuaternion& orientation, std::unique_ptr<BodyState> state);
  /// The convex hull of body-frame points shrunk by shrink_m, through SimSettings::hull_memo or
  /// else computed once per distinct point set in the run (shapes.cpp).
  std::shared_ptr<const SimHull> bodyHull(const std::vector<double>& xyz, double shrink_m, double shrink_clamp);
  void preTick();
  void drive(size_t index);
  void timeImpacts();
  void moveImpactsToTheirTime();
  void postTick();
  /// One loaded contact point of a manifold as a ContactEvent in step_events_ (postTick).
  void recordPoint(const btCollisionObject* const objects[2], const int manifold_index[2], const btManifoldPoint& pt,
                   bool predictive, double time_s);
  /// An impact's time and place: when and where its surfaces met (recordPoint).
  void stampImpact(ContactEvent& ev, const btCollisionObject* const objects[2], const btManifoldPoint& pt,
                   double predictive_gap_m, const btVector3 point_velocity[2], const btVector3& point_world,
                   double time_s) const;
  /// The substep's events in their deterministic order, flagged new_contact, into events_ in
  /// time order (postTick).
  void appendStepEvents();
  /// Forgets the contacts older than the lookback and remembers the substep's (postTick).
  void rememberStepContacts();
  double energy(std::vector<double>* kinetic) const;
  void hastenSleep();
  /// True when every moving body is asleep (Bullet's ISLAND_SLEEPING).
  bool allAsleep() const;
  /// The substeps after step_ once every moving body is asleep (see sim.cpp).
  void fillAsleep(uint64_t substeps, SimResult& result);
  void recordStates(std::vector<SimBodyState>& states) const;
  ContactCoefficients coefficients(int index_a, int index_b) const;
  void setRollingResistance(btPersistentManifold& manifold, const ContactCoefficients& pair) const;
  void contactState(ContactEvent& ev, const int index[2], const btVector3& point_world, const btVector3& normal) const;
  static void preTickThunk(btDynamicsWorld* world, btScalar) {
    static_cast<Simulation*>(world->getWorldUserInfo())->preTick();
  }
  static void postTickThunk(btDynamicsWorld* world, btScalar) {
    static_cast<Simulation*>(world->getWorldUserInfo())->postTick();
  }

  const std::vector<SimBodyDesc>& descs_;
  const SimSettings& settings_;
  std::vector<std::unique_ptr<BodyState>> bodies_;
  std::unique_ptr<btDefaultCollisionConfiguration> config_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  // Sphere contacts without multipoint perturbation (build).
  std::unique_ptr<btGjkEpaPenetrationDepthSolver> sphere_depth_solver_;
  std::unique_ptr<SphereAwareConvexConvex> sphere_hull_;
  std::unique_ptr<btConvexPlaneCollisionAlgorithm::CreateFunc> sphere_plane_, plane_sphere_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver_;
  std::unique_ptr<StrikeWorld> world_;
  std::unique_ptr<btCollisionShape> ground_shape_;
  std::unique_ptr<btRigidBody> ground_;
  bool gimpact_registered_ = false;
  std::map<uint64_t, std::vector<std::vector<double>>> pieces_by_surface_;  // by content hash
  struct RunHull {
    std::vector<double> points_xyz;
    double shrink_m, shrink_clamp;
    std::shared_ptr<const SimHull> hull;
  };
  std::vector<RunHull> run_hulls_;  // bodyHull()

  uint64_t step_ = 0;
  std::vector<ContactEvent> events_;
  std::vector<ContactEvent> step_events_;
  std::vector<size_t> step_order_;  // the substep's events in their deterministic order (postTick)
  std::vector<RecentContact> step_recent_;
  std::vector<int> step_lifetimes_;
  std::vector<ImpactPoint> step_impacts_;
  std::vector<StruckBody> step_struck_;
  std::map<std::pair<uint32_t, uint32_t>, std::vector<RecentContact>> recent_;
};

}  // namespace strike::detail
