// SPDX-License-Identifier: MIT
// Impact timing: Bullet solves a contact at the substep that finds it, though its surfaces met up
// to a step earlier or later. Simulation::timeImpacts finds when (meetingOffset) and gives the
// solver the rebound of that moment; Simulation::moveImpactsToTheirTime moves the struck body to
// where that rebound takes it.
#include <algorithm>
#include <cmath>
#include <vector>

#include "simulation.hpp"

namespace strike::detail {

/// Acceleration of a body between contacts: gravity when it moves, none when static.
btVector3 freeAcceleration(const btCollisionObject* object) {
  const btRigidBody* body = btRigidBody::upcast(object);
  if (!body || body->isStaticOrKinematicObject() || !body->isActive()) return btVector3(0, 0, 0);
  return body->getGravity();
}

/// Velocity of an object's material point at `world` (zero for static objects).
btVector3 velocityAt(const btCollisionObject* object, const btVector3& world) {
  const btRigidBody* body = btRigidBody::upcast(object);
  return body ? body->getVelocityInLocalPoint(world - body->getCenterOfMassPosition()) : btVector3(0, 0, 0);
}

/// When, from the start of the substep, a contact point's surfaces meet: the root of
/// gap - w t - a t^2 / 2 = 0, with the closing speed w at the start of the substep along the
/// body's path (the stored velocity is half a step old, see buildBody) and the closing
/// acceleration a. Negative when they met in the previous substep; NaN when they never do.
double meetingOffset(double gap_m, double closing_m_s, double closing_accel_m_s2, double step_s) {
  const double w = closing_m_s + 0.5 * closing_accel_m_s2 * step_s;
  const double discriminant = w * w + 2.0 * closing_accel_m_s2 * gap_m;
  if (!(w > 0.0) || discriminant < 0.0) return NAN;
  return 2.0 * gap_m / (w + std::sqrt(discriminant));  // the stable form of the root
}

void Simulation::timeImpacts() {
  // Bullet steps the world at whole substeps: a contact point found at the start of a substep is
  // solved there, though its surfaces met up to a step earlier (it is found penetrating) or will
  // meet up to a step later (it is found within the contact threshold, still apart). Bullet then
  // also bounces a point still apart by `gap` with the rebound speed less gap / dt (its
  // speculative contact: 0.6 m/s less for a 2 cm ball found 0.6 mm above the ground), and one
  // that would not even reach the surface in this step. So for each point striking faster than
  // the impact speed: when its surfaces meet (offset, in [-dt, dt]); if within a step either
  // side, the solver sees it touching (gap 0: no speculative or penetration term) with the
  // restitution that gives the rebound speed at the meeting, and moveImpactsToTheirTime() shifts
  // the body to where the rebound at that moment takes it.
  step_impacts_.clear();
  const double dt = settings_.substep_s;
  const int manifold_count = dispatcher_->getNumManifolds();
  for (int m = 0; m < manifold_count; ++m) {
    btPersistentManifold* manifold = dispatcher_->getManifoldByIndexInternal(m);
    const btCollisionObject* a = manifold->getBody0();
    const btCollisionObject* b = manifold->getBody1();
    // The pair's coefficients (combineContact or the scene's override), not Bullet's products;
    // set on every point each substep (this also undoes a previous substep's change below).
    const ContactCoefficients pair = coefficients(a->getUserIndex(), b->getUserIndex());
    const double restitution = pair.restitution;
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      manifold->getContactPoint(p).m_combinedRestitution = restitution;
      manifold->getContactPoint(p).m_combinedFriction = pair.friction;
    }
    setRollingResistance(*manifold, pair);
    // A CCD predictive point is left to Bullet: its distance is a swept sphere's, whose time of
    // impact Bullet finds only to about half a millimetre (a 2 mm plate landing at 1.5 m/s).
    if (world_->isPredictive(manifold)) continue;
    const btVector3 relative_accel = freeAcceleration(a) - freeAcceleration(b);
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      btManifoldPoint& pt = manifold->getContactPoint(p);
      const btVector3& normal = pt.m_normalWorldOnB;  // from b to a
      const double closing =
          -(velocityAt(a, pt.getPositionWorldOnA()) - velocityAt(b, pt.getPositionWorldOnB())).dot(normal);
      if (!(closing > settings_.impact_speed_m_s)) continue;
      const double accel = -relative_accel.dot(normal);
      const double offset = meetingOffset(pt.getDistance(), closing, accel, dt);
      if (std::isnan(offset)) continue;
      if (offset > dt) {
        pt.m_combinedRestitution = 0.0;  // meets in a later substep: no early bounce
        continue;
      }
      ImpactPoint impact{&pt, std::max(offset, -dt), false};
      if (offset >= -dt) {
        // Bullet bounces to restitution x (closing speed before gravity), and stores velocities
        // half a step old: after a bounce at the offset, e v_meet - a (dt/2 - offset).
        const double at_meeting = closing + accel * (0.5 * dt + offset);
        const double stored_after = restitution * at_meeting - accel * (0.5 * dt - offset);
        pt.m_combinedRestitution = std::max(0.0, stored_after / closing);
        pt.setDistance(0.0);
        impact.retimed = true;
      }
      step_impacts_.push_back(impact);
    }
  }
}

void Simulation::moveImpactsToTheirTime() {
  // The solver changed the velocities of a struck body at the start of the substep; the surfaces
  // met `offset` later (or earlier), so until then the body moved at its old velocity. Along the
  // body's path that is the step's velocity change dv applied offset later: the body ends the
  // step -dv * offset away (and turned by -dw * offset) from where Bullet put it. Only for bodies
  // whose every loaded contact in this substep is such an impact, with their impulse-weighted
  // offset: a body also resting on something keeps Bullet's step.
  std::vector<StruckBody>& struck = step_struck_;
  struck.assign(bodies_.size(), StruckBody{});
  const int manifold_count = dispatcher_->getNumManifolds();
  for (int m = 0; m < manifold_count; ++m) {
    const btPersistentManifold* manifold = dispatcher_->getManifoldByIndexInternal(m);
    // A CCD point only keeps a fast body from passing through; the discrete contacts of the same
    // impact (if found in this substep) say when it struck, so it neither moves a body nor keeps
    // it from being moved.
    if (world_->isPredictive(manifold)) continue;
    const int index[2] = {manifold->getBody0()->getUserIndex(), manifold->getBody1()->getUserIndex()};
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      const btManifoldPoint& pt = manifold->getContactPoint(p);
      if (!(pt.m_appliedImpulse > settings_.min_impulse_n_s)) continue;
      const ImpactPoint* impact = nullptr;
      for (const ImpactPoint& candidate : step_impacts_)
        if (candidate.point == &pt) impact = &candidate;
      for (int k : index) {
        if (k < 0) continue;
        StruckBody& body = struck[size_t(k)];
        if (!impact || !impact->retimed) {
          body.other_contact = true;
        } else {
          body.impulse_n_s += pt.m_appliedImpulse;
          body.impulse_times_offset += pt.m_appliedImpulse * impact->offset_s;
        }
      }
    }
  }
  for (size_t i = 0; i < bodies_.size(); ++i) {
    BodyState& b = *bodies_[i];
    if (b.is_static || struck[i].other_contact || !(struck[i].impulse_n_s > 0.0)) continue;
    btRigidBody& rigid = *b.rigid;
    const double offset = struck[i].impulse_times_offset / struck[i].impulse_n_s;
    const btVector3 dv = rigid.getLinearVelocity() - (b.pre_linear + rigid.getGravity() * settings_.substep_s);
    const btVector3 dw = rigid.getAngularVelocity() - b.pre_angular;
    btTransform moved;
    btTransformUtil::integrateTransform(rigid.getWorldTransform(), dv, dw, -offset, moved);
    rigid.proceedToTransform(moved);
  }
}

}  // namespace strike::detail
