// SPDX-License-Identifier: MIT
// Rigid-body simulation with Bullet (double precision) and contact event extraction.
//
// Frames. Each body has three frames:
//  - MESH frame: the frame of its surface mesh and mode bank; contact events are reported here.
//  - BODY frame: Bullet's rigid-body frame, origin at the centre of mass and axes along the
//    principal axes of inertia (Bullet's btRigidBody wants a diagonal local inertia).
//  - WORLD.
// mesh_from_body = (R_principal, centre) is fixed per body; world_from_body is Bullet's.
// Static bodies and the ground keep body frame = mesh frame.
//
// This file builds the world and runs it; the other parts are listed in simulation.hpp.
#include "strike/sim/sim.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <memory>
#include <new>
#include <string>

#include "simulation.hpp"

namespace strike {

namespace detail {

void StrikeWorld::calculateSimulationIslands() {
  // Bullet links two bodies into one island when their broadphase boxes overlap, and those are
  // loose: each box is grown by gContactBreakingThreshold (2 cm, a process global) and the
  // broadphase tree keeps its leaves 5 cm fatter still (gDbvtMargin). Twelve marbles rolling 3 cm
  // apart on a plate, none touching another, were one island: the solver iterated every marble
  // until the slowest one converged, each one's result depended on the others, and none could
  // sleep while another rolled. Here an island is what the solver needs: bodies linked by a
  // manifold that holds a contact point, or by a CCD predictive manifold or a constraint (as
  // Bullet's own btDiscreteDynamicsWorld::calculateSimulationIslands). A sleeping body is woken as
  // before, by the first contact point an awake body makes with it.
  btSimulationIslandManager& islands = *getSimulationIslandManager();
  // As btSimulationIslandManager::updateActivationState, without its union of overlapping pairs.
  int index = 0;
  for (int i = 0; i < m_collisionObjects.size(); ++i) {
    btCollisionObject* object = m_collisionObjects[i];
    if (!object->isStaticOrKinematicObject()) object->setIslandTag(index++);
    object->setCompanionId(-1);
    object->setHitFraction(1.0);
  }
  islands.initUnionFind(index);
  btUnionFind& unions = islands.getUnionFind();
  for (int m = 0; m < m_dispatcher1->getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = m_dispatcher1->getManifoldByIndexInternal(m);
    const btCollisionObject* a = manifold->getBody0();
    const btCollisionObject* b = manifold->getBody1();
    if (manifold->getNumContacts() > 0 && a->mergesSimulationIslands() && b->mergesSimulationIslands())
      unions.unite(a->getIslandTag(), b->getIslandTag());
  }
  for (int m = 0; m < m_predictiveManifolds.size(); ++m) {
    const btCollisionObject* a = m_predictiveManifolds[m]->getBody0();
    const btCollisionObject* b = m_predictiveManifolds[m]->getBody1();
    if (!a->isStaticOrKinematicObject() && !b->isStaticOrKinematicObject())
      unions.unite(a->getIslandTag(), b->getIslandTag());
  }
  for (int c = 0; c < m_constraints.size(); ++c) {
    const btTypedConstraint* constraint = m_constraints[c];
    const btRigidBody& a = constraint->getRigidBodyA();
    const btRigidBody& b = constraint->getRigidBodyB();
    if (constraint->isEnabled() && !a.isStaticOrKinematicObject() && !b.isStaticOrKinematicObject())
      unions.unite(a.getIslandTag(), b.getIslandTag());
  }
  islands.storeIslandActivationState(this);
}

void StrikeDispatcher::nearCallback(btBroadphasePair& pair, btCollisionDispatcher& dispatcher,
                                    const btDispatcherInfo& info) {
  if (static_cast<StrikeDispatcher&>(dispatcher).apartWithoutPoints(pair)) return;
  btCollisionDispatcher::defaultNearCallback(pair, dispatcher, info);
}

bool StrikeDispatcher::apartWithoutPoints(const btBroadphasePair& pair) {
  // The broadphase pairs bodies whose boxes come within 2 cm (gContactBreakingThreshold), and its
  // tree keeps them paired until they part by 5 cm more (gDbvtMargin): eight blocks 2 cm apart
  // on a plank made 22 block-block pairs, each a GJK query every substep that found nothing. The
  // narrow phase adds a point only within the pair's contact breaking threshold (btManifoldResult::
  // addContactPoint), so a pair whose boxes (margins included) are further apart than twice that
  // on some axis finds none; if it holds no point either, there is nothing to refresh, and its
  // query is skipped. A pair that holds a point is always left to Bullet.
  const auto* a = static_cast<const btCollisionObject*>(pair.m_pProxy0->m_clientObject);
  const auto* b = static_cast<const btCollisionObject*>(pair.m_pProxy1->m_clientObject);
  // The pair's threshold as btCollisionDispatcher::getNewManifold takes it: the smaller of the
  // shapes' (kept in BodyState; the ground plane's is huge, so the other body's).
  const auto* state_a = static_cast<const BodyState*>(a->getUserPointer());
  const auto* state_b = static_cast<const BodyState*>(b->getUserPointer());
  if (!state_a && !state_b) return false;
  const double threshold_m = (getDispatcherFlags() & CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD) == 0
                                 ? gContactBreakingThreshold
                             : !state_a ? state_b->breaking_threshold_m
                             : !state_b ? state_a->breaking_threshold_m
                                        : std::min(state_a->breaking_threshold_m, state_b->breaking_threshold_m);
  btVector3 min_a, max_a, min_b, max_b;
  a->getCollisionShape()->getAabb(a->getWorldTransform(), min_a, max_a);
  b->getCollisionShape()->getAabb(b->getWorldTransform(), min_b, max_b);
  bool apart = false;
  for (int k = 0; k < 3; ++k) apart = apart || std::max(min_b[k] - max_a[k], min_a[k] - max_b[k]) > 2.0 * threshold_m;
  if (!apart || !pair.m_algorithm) return apart;
  manifolds_.resize(0);
  pair.m_algorithm->getAllContactManifolds(manifolds_);
  for (int m = 0; m < manifolds_.size(); ++m)
    if (manifolds_[m]->getNumContacts() > 0) return false;
  return true;
}

Status Simulation::build(const std::vector<btQuaternion>& orientations) {
  // Bullet's default pools hold 4096 contact manifolds and 4096 collision algorithms (MBs in
  // double precision), which its allocator zeroes whenever a world is made: a few percent of a
  // small render's time. Pools sized to the scene (a manifold per touching pair, one per touching
  // piece of a compound) suffice; past them Bullet allocates from the heap, which changes where a
  // manifold lives and nothing it computes.
  btDefaultCollisionConstructionInfo pools;
  size_t parts = 1;  // the ground
  for (const SimBodyDesc& d : descs_) parts += std::max<size_t>(1, d.convex_pieces_m.size());
  pools.m_defaultMaxPersistentManifoldPoolSize = int(std::clamp<size_t>(8 * parts, 64, 4096));
  pools.m_defaultMaxCollisionAlgorithmPoolSize = pools.m_defaultMaxPersistentManifoldPoolSize;
  config_ = std::make_unique<btDefaultCollisionConfiguration>(pools);
  // A box landing flat on the ground must touch with all four corners in the same substep;
  // the default plane-convex algorithm reports one support point per substep, and the box
  // tips on it. Perturbed support queries find the rest of the face [Bullet
  // btConvexPlaneCollisionAlgorithm]. Same for convex-convex pairs without polyhedral features.
  constexpr int kPerturbations = 3, kPerturbBelowPoints = 3;
  config_->setPlaneConvexMultipointIterations(kPerturbations, kPerturbBelowPoints);
  config_->setConvexConvexMultipointIterations(kPerturbations, kPerturbBelowPoints);
  dispatcher_ = std::make_unique<StrikeDispatcher>(config_.get());
  // Except for a sphere: the perturbation turns the shape about its own origin, which for a sphere
  // is its centre, and a turned sphere is the same sphere. Against the ground it finds the same
  // lowest point again (differing in the last bits), and against a hull Bullet moves the found
  // point with the turn, off the sphere, where it is dropped or, past a deep overlap, kept as a
  // point that is not on the sphere. Three of the four collision queries of a rolling marble
  // bought nothing. (A hull smaller than the sphere is the one turned, and keeps them.)
  sphere_depth_solver_ = std::make_unique<btGjkEpaPenetrationDepthSolver>();  // as the default configuration's
  sphere_hull_ = std::make_unique<SphereAwareConvexConvex>(sphere_depth_solver_.get(), kPerturbations, kPerturbBelowPoints);
  dispatcher_->registerCollisionCreateFunc(SPHERE_SHAPE_PROXYTYPE, CONVEX_HULL_SHAPE_PROXYTYPE, sphere_hull_.get());
  dispatcher_->registerCollisionCreateFunc(CONVEX_HULL_SHAPE_PROXYTYPE, SPHERE_SHAPE_PROXYTYPE, sphere_hull_.get());
  sphere_plane_ = std::make_unique<btConvexPlaneCollisionAlgorithm::CreateFunc>();
  plane_sphere_ = std::make_unique<btConvexPlaneCollisionAlgorithm::CreateFunc>();
  plane_sphere_->m_swapped = true;
  for (btConvexPlaneCollisionAlgorithm::CreateFunc* func : {sphere_plane_.get(), plane_sphere_.get()}) {
    func->m_numPerturbationIterations = 0;
    func->m_minimumPointsPerturbationThreshold = kPerturbBelowPoints;
  }
  dispatcher_->registerCollisionCreateFunc(SPHERE_SHAPE_PROXYTYPE, STATIC_PLANE_PROXYTYPE, sphere_plane_.get());
  dispatcher_->registerCollisionCreateFunc(STATIC_PLANE_PROXYTYPE, SPHERE_SHAPE_PROXYTYPE, plane_sphere_.get());
  broadphase_ = std::make_unique<btDbvtBroadphase>();
  solver_ = std::make_unique<btSequentialImpulseConstraintSolver>();
  world_ = std::make_unique<StrikeWorld>(dispatcher_.get(), broadphase_.get(), solver_.get(), config_.get());
  world_->setGravity(toBt(settings_.gravity_m_s2));

  btContactSolverInfo& info = world_->getSolverInfo();
  info.m_numIterations = settings_.solver_iterations;
  // Stop early once converged (the squared largest impulse change per iteration, (N s)^2):
  // warm-started resting contacts converge in a few iterations; an impact through a 1000:1
  // mass-ratio chain needs hundreds.
  info.m_leastSquaresResidualThreshold = settings_.solver_residual_threshold;
  // Each island (bodies linked by contacts) is solved on its own, to that threshold. Bullet's
  // default batches islands into one solve, whose residual is the largest of them all: bodies that
  // touch nothing of each other were iterated until the slowest island converged, and each one's
  // result depended on the others.
  info.m_minimumSolverBatchSize = 1;
  // Split impulse: penetration is corrected with a separate pseudo-velocity that is thrown away
  // after the step, so position correction cannot inject kinetic energy [Catto, GDC 2006;
  // Bullet's btSequentialImpulseConstraintSolver]. Threshold 0: use it for every penetration.
  info.m_splitImpulse = 1;
  info.m_splitImpulsePenetrationThreshold = 0.0;
  // Two friction directions: isotropic Coulomb friction for resting bodies (with one, a body
  // at rest can creep along the second tangent). No random order: determinism.
  info.m_solverMode = (info.m_solverMode | SOLVER_USE_2_FRICTION_DIRECTIONS) & ~SOLVER_RANDMIZE_ORDER;
  // The CCD sweep ignores hits whose approach is under m_allowedCcdPenetration (4 cm by default,
  // larger than our objects).
  world_->getDispatchInfo().m_allowedCcdPenetration = 0.0;
  world_->getDispatchInfo().m_useContinuous = true;
  // Islands are bodies linked by contact points (StrikeWorld::calculateSimulationIslands), so a
  // pair's empty manifold may join bodies of two islands. Bullet hands each island's solve every
  // manifold of its bodies, and a solve writes back (with a step of gravity added) every body its
  // manifolds name: a block near another fell at twice gravity. With this flag Bullet passes only
  // manifolds that hold points (btSimulationIslandManager::buildIslands), and also sorts pairs and
  // manifolds by the bodies' ids.
  world_->getDispatchInfo().m_deterministicOverlappingPairs = true;

  for (size_t i = 0; i < descs_.size(); ++i) {
    if (Status s = buildBody(i, orientations[i]); !s) return s;
  }
  if (settings_.ground) {
    ground_shape_ = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), settings_.ground_height_m);
    btRigidBody::btRigidBodyConstructionInfo info_ground(0.0, nullptr, ground_shape_.get());
    info_ground.m_restitution = settings_.ground_restitution;
    info_ground.m_friction = settings_.ground_friction;
    ground_ = std::make_unique<btRigidBody>(info_ground);
    ground_->setUserIndex(-1);
    world_->addRigidBody(ground_.get());
    ground_->forceActivationState(ISLAND_SLEEPING);  // as a static body (buildBody)
  }
  world_->before_solve = [this] { timeImpacts(); };
  world_->setInternalTickCallback(&Simulation::preTickThunk, this, true);
  world_->setInternalTickCallback(&Simulation::postTickThunk, this, false);
  return {};
}

ContactCoefficients Simulation::coefficients(int index_a, int index_b) const {
  // Bullet's user index: the body, or -1 for the ground.
  auto side = [&](int index) {
    if (index < 0)
      return ContactSide{settings_.ground_restitution, settings_.ground_friction, settings_.ground_compliance_per_pa,
                         settings_.ground_rolling_resistance};
    const SimBodyDesc& d = descs_[size_t(index)];
    return ContactSide{d.restitution, d.friction, d.compliance_per_pa, d.rolling_resistance};
  };
  ContactCoefficients c = combineContact(side(index_a), side(index_b));
  const uint32_t a = index_a < 0 ? kGroundBody : uint32_t(index_a), b = index_b < 0 ? kGroundBody : uint32_t(index_b);
  for (const SimSettings::ContactPair& pair : settings_.contact_pairs) {  // the last one given wins
    if (!((pair.body_a == a && pair.body_b == b) || (pair.body_a == b && pair.body_b == a))) continue;
    if (!std::isnan(pair.restitution)) c.restitution = pair.restitution;
    if (!std::isnan(pair.friction)) c.friction = pair.friction;
    if (!std::isnan(pair.rolling_resistance)) c.rolling_resistance = pair.rolling_resistance;
  }
  return c;
}

void Simulation::recordStates(std::vector<SimBodyState>& states) const {
  for (const auto& b : bodies_) {
    const btRigidBody& rb = *b->rigid;
    const btTransform world_from_mesh = rb.getWorldTransform() * b->body_from_mesh;
    const btQuaternion q = world_from_mesh.getRotation();
    SimBodyState state;
    state.position_m = fromBt(world_from_mesh.getOrigin());
    state.orientation_wxyz = {q.w(), q.x(), q.y(), q.z()};
    state.velocity_m_s = fromBt(rb.getLinearVelocity());
    state.asleep = !b->is_static && rb.getActivationState() == ISLAND_SLEEPING;
    states.push_back(state);
  }
}

void Simulation::hastenSleep() {
  // Bullet sleeps a body still for longer than gDeactivationTime (2 s), a process global that a
  // library must not change; each body's still-time is its own, so a body still for
  // sleep_after_still_s has its clock moved past the global's limit instead. Bullet resets the
  // clock whenever the body moves, and sleeps an island only when all its bodies are still.
  //
  // Bullet's clock reads the velocity of one substep, and a body resting on a mesh (GImpact)
  // never keeps it still for long: its contact manifold is rebuilt every substep with 2 to 4 of
  // the touching triangles' points, so the solver rocks it at up to 0.05 rad/s (the angular
  // threshold) every few hundred ms while it stays where it is, and Bullet's clock restarts each
  // time (a resting glass stayed awake to the end, humming). So a second clock measures where the
  // body is, not how fast it moves: it runs while every point of the body stays within
  // kStillExcursion of the body's size from where it was when the clock started, and restarts
  // from the present pose when it does not. A body resting there for sleep_after_still_s sleeps.
  constexpr double kStillExcursion = 1e-3;  // of the body's size; solver rocking moves ~1e-4
  const double dt = settings_.substep_s;
  for (auto& b : bodies_) {
    btRigidBody& rigid = *b->rigid;
    if (b->driven) continue;  // never asleep (buildBody)
    if (b->is_static || !rigid.isActive()) {
      if (!b->is_static && rigid.getActivationState() == ISLAND_SLEEPING && std::isnan(b->sleep_start_s))
        b->sleep_start_s = double(step_ + 1) * dt;
      b->still_since_step = kNotStill;  // woken, it starts afresh
      continue;
    }
    b->sleep_start_s = NAN;
    const btScalar still_s = rigid.getDeactivationTime();
    if (still_s >= settings_.sleep_after_still_s && still_s <= gDeactivationTime)
      rigid.setDeactivationTime(gDeactivationTime + dt);
    // The pose clock. The farthest a body point moves: the origin's shift plus the rotation angle
    // times the half-size (a bound for points within size / 2 of the centre of mass).
    const btTransform& now = rigid.getWorldTransform();
    const btQuaternion turn = b->still_anchor.getRotation().inverse() * now.getRotation();
    const double excursion_m = (now.getOrigin() - b->still_anchor.getOrigin()).length() +
                               0.5 * b->size_m * std::abs(turn.getAngleShortestPath());
    if (b->still_since_step == kNotStill || excursion_m > kStillExcursion * b->size_m) {
      b->still_anchor = now;
      b->still_since_step = step_;
      continue;
    }
    if (double(step_ - b->still_since_step) * dt >= settings_.sleep_after_still_s) {
      // Asks to sleep as Bullet's own clock would (btRigidBody::wantsSleeping): the island sleeps
      // in the next substep if all its bodies agree, and Bullet zeroes the velocities then.
      rigid.setActivationState(WANTS_DEACTIVATION);
      rigid.setDeactivationTime(gDeactivationTime + dt);
    }
  }
}

double Simulation::energy(std::vector<double>* kinetic) const {
  const btVector3 gravity = toBt(settings_.gravity_m_s2);
  double total = 0.0;
  for (size_t i = 0; i < bodies_.size(); ++i) {
    const BodyState& b = *bodies_[i];
    double ke = 0.0;
    if (!b.is_static) {
      const btRigidBody& rb = *b.rigid;
      const btVector3 w_body = rb.getWorldTransform().getBasis().transpose() * rb.getAngularVelocity();
      ke = 0.5 * b.mass_kg * rb.getLinearVelocity().length2() +
           0.5 * (b.principal_inertia * w_body * w_body).dot(btVector3(1, 1, 1));
      total += ke - b.mass_kg * gravity.dot(rb.getWorldTransform().getOrigin());
    }
    if (kinetic) (*kinetic)[i] = ke;
  }
  return total;
}

void Simulation::preTick() {
  // Driven bodies first: the contact events take the velocities the substep starts with.
  for (size_t i = 0; i < bodies_.size(); ++i)
    if (bodies_[i]->driven) drive(i);
  for (auto& b : bodies_) {
    b->pre_transform = b->rigid->getWorldTransform();
    b->pre_linear = b->rigid->getLinearVelocity();
    b->pre_angular = b->rigid->getAngularVelocity();
  }
}

bool Simulation::allAsleep() const {
  for (const auto& b : bodies_)
    if (!b->is_static && b->rigid->getActivationState() != ISLAND_SLEEPING) return false;
  return true;
}

void Simulation::fillAsleep(uint64_t substeps, SimResult& result) {
  // Every moving body is asleep after substep step_, and nothing is left that could wake one: a
  // sleeping island wakes only when an active body touches it, and static bodies and the ground
  // never move. Bullet then neither integrates nor collides them (both sides of every pair are
  // inactive), postTick() records no event for a sleeping island, and the velocities were zeroed
  // when the islands fell asleep. So every later substep would record the same poses, no event
  // and the same energy: those are written here instead of stepped, the same values to the bit
  // (SimSettings::end_when_all_asleep; a test compares both ways).
  const size_t n = bodies_.size();
  const uint64_t remaining = substeps - (step_ + 1);
  if (settings_.record_states && n > 0) {
    const size_t last = result.states.size() - n;
    result.states.reserve(result.states.size() + remaining * n);
    for (uint64_t k = 0; k < remaining; ++k)
      for (size_t i = 0; i < n; ++i) result.states.push_back(result.states[last + i]);
  }
  const double energy_j = result.energy_trace_j.back();
  result.energy_trace_j.insert(result.energy_trace_j.end(), remaining, energy_j);
  step_ = substeps;
}

Result<SimResult> Simulation::run() {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto last_report = start;
  SimResult result;
  const size_t n = bodies_.size();
  result.initial_kinetic_energy_j.assign(n, 0.0);
  result.max_kinetic_energy_j.assign(n, 0.0);
  std::vector<double> kinetic(n, 0.0);
  const uint64_t substeps = uint64_t(std::ceil(settings_.duration_s / settings_.substep_s - 1e-9));
  result.energy_trace_j.reserve(substeps + 1);
  result.energy_trace_j.push_back(energy(&result.initial_kinetic_energy_j));
  result.max_kinetic_energy_j = result.initial_kinetic_energy_j;
  const double dt = settings_.substep_s;
  for (step_ = 0; step_ < substeps; ++step_) {
    // maxSubSteps = 0: exactly one internal step of dt, no accumulator and no interpolation, so
    // the step count is exact and the run is deterministic.
    world_->stepSimulation(dt, 0, dt);
    if (settings_.allow_sleep) hastenSleep();
    if (settings_.record_states) recordStates(result.states);
    if (events_.size() > settings_.max_events)
      return badInput("simulate: more than " + std::to_string(settings_.max_events) +
                      " contact events by t = " + std::to_string(double(step_ + 1) * dt) +
                      " s, the cap on contact events (memory); raise it with --max-events N or shorten the duration");
    result.energy_trace_j.push_back(energy(&kinetic));
    for (size_t i = 0; i < n; ++i)
      result.max_kinetic_energy_j[i] = std::max(result.max_kinetic_energy_j[i], kinetic[i]);
    if (settings_.end_when_all_asleep && allAsleep()) {
      fillAsleep(substeps, result);
      break;
    }
    if (settings_.progress) {
      const auto now = Clock::now();
      if (now - last_report >= std::chrono::milliseconds(100)) {
        last_report = now;
        settings_.progress("simulate", double(step_ + 1) / double(substeps));
      }
    }
  }
  if (settings_.progress) settings_.progress("simulate", 1.0);
  for (const auto& b : bodies_) {
    const btRigidBody& rb = *b->rigid;
    const btTransform world_from_mesh = rb.getWorldTransform() * b->body_from_mesh;
    result.final_position_m.push_back(fromBt(world_from_mesh.getOrigin()));
    result.final_velocity_m_s.push_back(fromBt(rb.getLinearVelocity()));
    result.final_angular_velocity_rad_s.push_back(fromBt(rb.getAngularVelocity()));
    result.shape_used.push_back(b->shape_used);
    result.collision_margin_m.push_back(b->margin_m);
    result.sleep_start_s.push_back(b->sleep_start_s);
    result.collision_pieces.push_back(b->pieces.size());
    result.convex_pieces_m.push_back(b->pieces_mesh);
    result.pieces_computed.push_back(b->pieces_computed);
    result.pieces_seconds.push_back(b->pieces_seconds);
  }
  result.events = std::move(events_);
  result.substeps = substeps;
  result.simulate_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace detail

using detail::checkBody;
using detail::checkSettings;
using detail::Simulation;

ContactCoefficients combineContact(const ContactSide& a, const ContactSide& b) {
  const double ka = a.compliance_per_pa, kb = b.compliance_per_pa;
  const double wa = ka + kb > 0.0 ? ka / (ka + kb) : 0.5;
  const double loss = wa * (1.0 - a.restitution * a.restitution) + (1.0 - wa) * (1.0 - b.restitution * b.restitution);
  ContactCoefficients c;
  c.restitution = std::sqrt(std::clamp(1.0 - loss, 0.0, 1.0));
  c.friction = std::sqrt(a.friction * b.friction);
  c.rolling_resistance = wa * a.rolling_resistance + (1.0 - wa) * b.rolling_resistance;
  return c;
}

Result<SimResult> simulate(const std::vector<SimBodyDesc>& bodies, const SimSettings& settings) {
  try {
    if (Status s = checkSettings(settings); !s) return s.error();
    std::vector<btQuaternion> orientations(bodies.size());
    for (size_t i = 0; i < bodies.size(); ++i) {
      if (Status s = checkBody(bodies[i], i, orientations[i]); !s) return s.error();
    }
    Simulation sim(bodies, settings);
    if (Status s = sim.build(orientations); !s) return s.error();
    return sim.run();
  } catch (const std::bad_alloc&) {
    return internalError("simulate: out of memory");
  } catch (const std::exception& e) {
    return internalError(std::string("simulate: ") + e.what());
  } catch (...) {
    return internalError("simulate: unknown exception");
  }
}

}  // namespace strike
