// SPDX-License-Identifier: MIT
// Contact events: after each substep, every loaded contact point becomes a ContactEvent in each
// body's mesh frame (a CCD point at its leading vertex, an impact at the moment and place its
// surfaces met), in a deterministic order, flagged new_contact or not (Simulation::postTick).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <vector>

#include "simulation.hpp"

namespace strike::detail {

namespace {

/// Substeps a contact is remembered for, to tell a new contact from a continuing one.
constexpr uint64_t kLookbackSteps = 3;

/// Where a CCD predictive point strikes. Bullet puts that point at A's centre of mass, and B's
/// point at the swept sphere's centre at its time of impact; the sphere's surface there lies on
/// B, and A's leading vertex (along -normal) lands on B's tangent plane through it.
struct LeadingPoint {
  btVector3 local_a;     ///< A's leading vertex, A's body frame
  btVector3 on_b_plane;  ///< where it lands: its projection on B's tangent plane, world
  double gap_m = 0.0;    ///< its height above that plane with A at a_pose
};
LeadingPoint ccdLeadingPoint(const btCollisionObject& a, const btCollisionObject& b, const btManifoldPoint& pt,
                             const btTransform& a_pose) {
  const btVector3& normal = pt.m_normalWorldOnB;
  const auto* convex = static_cast<const btConvexShape*>(a.getCollisionShape());
  LeadingPoint leading;
  leading.local_a = convex->localGetSupportingVertex(a_pose.getBasis().transpose() * -normal);
  const btVector3 world = a_pose(leading.local_a);
  const btVector3 on_b = pt.m_positionWorldOnB - normal * a.getCcdSweptSphereRadius();
  leading.gap_m = normal.dot(world - on_b);
  if (b.getCollisionShape()->getShapeType() == STATIC_PLANE_PROXYTYPE) {
    // The ground: exact, where the swept sphere's time of impact is good to ~0.5 mm.
    const auto* plane = static_cast<const btStaticPlaneShape*>(b.getCollisionShape());
    const btVector3 plane_normal = b.getWorldTransform().getBasis() * plane->getPlaneNormal();
    const double plane_constant = plane->getPlaneConstant() + plane_normal.dot(b.getWorldTransform().getOrigin());
    const double cosine = plane_normal.dot(normal);
    if (cosine > 0.5) leading.gap_m = (plane_normal.dot(world) - plane_constant) / cosine;
  }
  leading.on_b_plane = world - normal * leading.gap_m;
  return leading;
}

}  // namespace

void Simulation::postTick() {
  const double time_s = double(step_) * settings_.substep_s;
  moveImpactsToTheirTime();
  step_events_.clear();
  const int manifold_count = dispatcher_->getNumManifolds();
  for (int m = 0; m < manifold_count; ++m) {
    const btPersistentManifold* manifold = dispatcher_->getManifoldByIndexInternal(m);
    const btCollisionObject* objects[2] = {manifold->getBody0(), manifold->getBody1()};
    const int manifold_index[2] = {objects[0]->getUserIndex(), objects[1]->getUserIndex()};
    // A sleeping island is not solved this substep: its stale impulses are not forces.
    bool any_active = false;
    for (int k = 0; k < 2; ++k) {
      if (manifold_index[k] >= 0 && !bodies_[size_t(manifold_index[k])]->is_static && objects[k]->isActive())
        any_active = true;
    }
    if (!any_active) continue;
    const bool predictive = world_->isPredictive(manifold);
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      const btManifoldPoint& pt = manifold->getContactPoint(p);
      if (!(pt.m_appliedImpulse > settings_.min_impulse_n_s)) continue;
      recordPoint(objects, manifold_index, pt, predictive, time_s);
    }
  }
  appendStepEvents();
  rememberStepContacts();
}

void Simulation::recordPoint(const btCollisionObject* const objects[2], const int manifold_index[2],
                             const btManifoldPoint& pt, bool predictive, double time_s) {
  // Per point: the canonical order below swaps it (a copy per manifold swapped the first
  // point's pair and left the next points of a swapped manifold labelled the wrong way).
  int index[2] = {manifold_index[0], manifold_index[1]};
  btVector3 normal = pt.m_normalWorldOnB;  // from B to A; the impulse on A is along +normal
  btVector3 friction =
      pt.m_lateralFrictionDir1 * pt.m_appliedImpulseLateral1 + pt.m_lateralFrictionDir2 * pt.m_appliedImpulseLateral2;
  btVector3 impulse_on_a = normal * pt.m_appliedImpulse + friction;
  // Points in each body's Bullet frame, at the start of the substep (when the narrow phase
  // found them). A predictive (CCD) point sits at A's centre of mass: use instead the point
  // of A's shape that leads along -normal, which is where A strikes.
  const btTransform identity = btTransform::getIdentity();
  const btTransform& pre_a = index[0] >= 0 ? bodies_[size_t(index[0])]->pre_transform : identity;
  const btTransform& pre_b = index[1] >= 0 ? bodies_[size_t(index[1])]->pre_transform : identity;
  btVector3 local_a = pt.m_localPointA;
  btVector3 local_b = pt.m_localPointB;
  btVector3 point_world = 0.5 * (pre_a(local_a) + pre_b(local_b));
  double predictive_gap_m = NAN;  // a CCD point's leading point above B's surface
  if (predictive && objects[0]->getCollisionShape()->isConvex()) {
    const LeadingPoint leading = ccdLeadingPoint(*objects[0], *objects[1], pt, pre_a);
    local_a = leading.local_a;
    point_world = leading.on_b_plane;
    predictive_gap_m = leading.gap_m;
    local_b = pre_b.invXform(point_world);
  }
  // Canonical order: the ground is always b; otherwise a is the lower index.
  bool swap = index[0] < 0 || (index[1] >= 0 && index[0] > index[1]);
  if (swap) {
    std::swap(index[0], index[1]);
    std::swap(local_a, local_b);
    normal = -normal;
    impulse_on_a = -impulse_on_a;
  }
  ContactEvent ev;
  ev.time_s = time_s;
  ev.step_time_s = time_s;
  ev.body_a = uint32_t(index[0]);
  ev.body_b = index[1] < 0 ? kGroundBody : uint32_t(index[1]);
  ev.point_world = fromBt(point_world);
  ev.normal_world = fromBt(normal);
  ev.normal_impulse_n_s = pt.m_appliedImpulse;
  ev.friction_impulse_n_s = friction.length();
  btVector3 point_velocity[2] = {btVector3(0, 0, 0), btVector3(0, 0, 0)};
  const btVector3 locals[2] = {local_a, local_b};
  btVector3 meshes[2];
  std::array<double, 3>* mesh_points[2] = {&ev.point_a_mesh, &ev.point_b_mesh};
  std::array<double, 3>* mesh_impulses[2] = {&ev.impulse_on_a_mesh, &ev.impulse_on_b_mesh};
  for (int k = 0; k < 2; ++k) {
    const btVector3 impulse = k == 0 ? impulse_on_a : -impulse_on_a;
    if (index[k] < 0) {  // ground: mesh frame = world
      meshes[k] = locals[k];
      *mesh_impulses[k] = fromBt(impulse);
    } else {
      const BodyState& b = *bodies_[size_t(index[k])];
      meshes[k] = b.mesh_from_body(locals[k]);
      *mesh_impulses[k] = fromBt(b.mesh_from_body.getBasis() * (b.pre_transform.getBasis().transpose() * impulse));
      point_velocity[k] = b.pre_linear + b.pre_angular.cross(point_world - b.pre_transform.getOrigin());
    }
    *mesh_points[k] = fromBt(meshes[k]);
  }
  ev.normal_speed_m_s = std::max(0.0, -(point_velocity[0] - point_velocity[1]).dot(normal));
  contactState(ev, index, point_world, normal);
  if (ev.normal_speed_m_s > settings_.impact_speed_m_s)
    stampImpact(ev, objects, pt, predictive_gap_m, point_velocity, point_world, time_s);
  step_events_.push_back(ev);
  step_recent_.push_back(RecentContact{step_, point_world, meshes[0], meshes[1]});
  step_lifetimes_.push_back(pt.m_lifeTime);
}

void Simulation::stampImpact(ContactEvent& ev, const btCollisionObject* const objects[2], const btManifoldPoint& pt,
                             double predictive_gap_m, const btVector3 point_velocity[2], const btVector3& point_world,
                             double time_s) const {
  // An impact is stamped with the moment its surfaces met (timeImpacts; for a CCD point,
  // from its leading point's height above B's surface at the start of the substep).
  double offset = NAN;
  for (const ImpactPoint& impact : step_impacts_)
    if (impact.point == &pt) offset = impact.offset_s;
  if (std::isnan(offset) && std::isfinite(predictive_gap_m)) {
    const double closing_accel =
        -(freeAcceleration(objects[0]) - freeAcceleration(objects[1])).dot(pt.m_normalWorldOnB);
    offset = meetingOffset(predictive_gap_m, ev.normal_speed_m_s, closing_accel, settings_.substep_s);
  }
  if (std::isfinite(offset)) {
    offset = std::clamp(offset, -settings_.substep_s, settings_.substep_s);
    ev.time_s = time_s + offset;
    // And placed where they met: both points moved along their paths (see meetingOffset).
    const btVector3 path_velocity_sum =
        point_velocity[0] + point_velocity[1] +
        0.5 * settings_.substep_s * (freeAcceleration(objects[0]) + freeAcceleration(objects[1]));
    ev.point_world = fromBt(point_world + 0.5 * offset * path_velocity_sum);
  }
}

void Simulation::appendStepEvents() {
  // Deterministic order within the substep, independent of Bullet's manifold order.
  std::vector<size_t>& order = step_order_;
  order.resize(step_events_.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    const ContactEvent& ex = step_events_[x];
    const ContactEvent& ey = step_events_[y];
    if (ex.body_a != ey.body_a) return ex.body_a < ey.body_a;
    if (ex.body_b != ey.body_b) return ex.body_b < ey.body_b;
    if (ex.point_a_mesh != ey.point_a_mesh) return ex.point_a_mesh < ey.point_a_mesh;
    return x < y;
  });

  // new_contact: no event of the same pair near this point in the last few substeps, and the
  // point is young. The proximity test covers Bullet's point replacement (lifetime restarts at 0),
  // CCD predictive points (a fresh manifold every substep), GImpact (which rebuilds its manifolds
  // every substep) and rolling. The age test covers a resting face whose load the solver shifts
  // between corners: a corner can carry nothing for a while and then take load again, and that is
  // not an impact (its point stayed within the contact threshold all along).
  const size_t first_new = events_.size();
  for (size_t k : order) {
    ContactEvent& ev = step_events_[k];
    const RecentContact& here = step_recent_[k];
    const double size_a = bodies_[ev.body_a]->size_m;
    const double size_b = ev.body_b == kGroundBody ? size_a : bodies_[ev.body_b]->size_m;
    const double tolerance = std::max(1e-4, 0.2 * std::min(size_a, size_b));
    const double tolerance2 = tolerance * tolerance;
    bool seen = false;
    auto it = recent_.find({ev.body_a, ev.body_b});
    if (it != recent_.end()) {
      for (const RecentContact& r : it->second) {
        if (r.step + kLookbackSteps < step_) continue;
        if (r.world.distance2(here.world) < tolerance2 || r.a_mesh.distance2(here.a_mesh) < tolerance2 ||
            r.b_mesh.distance2(here.b_mesh) < tolerance2) {
          seen = true;
          break;
        }
      }
    }
    ev.new_contact = !seen && step_lifetimes_[k] <= int(kLookbackSteps) + 1;
    events_.push_back(ev);
  }
  // Impacts are stamped up to a step either side of their substep: keep the events in time order
  // (a stable merge, so events of one time keep the order above).
  // Most substeps have no stamped impact: their events are already in order, and both sorts would
  // leave them as they are (and allocate a buffer each), so they are skipped then.
  if (events_.size() > first_new) {
    const auto earlier = [](const ContactEvent& x, const ContactEvent& y) { return x.time_s < y.time_s; };
    const auto new_begin = events_.begin() + std::ptrdiff_t(first_new);
    if (!std::is_sorted(new_begin, events_.end(), earlier)) std::stable_sort(new_begin, events_.end(), earlier);
    if (first_new > 0 && earlier(*new_begin, *(new_begin - 1)))
      std::inplace_merge(std::upper_bound(events_.begin(), new_begin, *new_begin, earlier), new_begin, events_.end(),
                         earlier);
  }
}

void Simulation::rememberStepContacts() {
  for (auto it = recent_.begin(); it != recent_.end();) {
    auto& list = it->second;
    list.erase(std::remove_if(list.begin(), list.end(),
                              [&](const RecentContact& r) { return r.step + kLookbackSteps <= step_; }),
               list.end());
    it = list.empty() ? recent_.erase(it) : std::next(it);
  }
  for (size_t k = 0; k < step_events_.size(); ++k) {
    recent_[{step_events_[k].body_a, step_events_[k].body_b}].push_back(step_recent_[k]);
  }
  step_recent_.clear();
  step_lifetimes_.clear();
}

}  // namespace strike::detail
