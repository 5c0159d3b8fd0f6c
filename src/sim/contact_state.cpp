// SPDX-License-Identifier: MIT
// Contact state: what a continuous (rolling, sliding, scraping) contact sound needs from each
// contact point (normal force, slip, rolling speed, Hertz patch; ContactEvent), and the rolling
// and spinning friction that make a rolling sphere stop as it does in reality.
#include <algorithm>
#include <cmath>

#include "simulation.hpp"

namespace strike {

double hertzPatchRadius(double force_n, double radius_a_m, double radius_b_m, double compliance_a_per_pa,
                        double compliance_b_per_pa) {
  auto curvature = [](double radius_m) { return radius_m > 0.0 && std::isfinite(radius_m) ? 1.0 / radius_m : 0.0; };
  const double curvature_per_m = curvature(radius_a_m) + curvature(radius_b_m);
  const double compliance_per_pa = compliance_a_per_pa + compliance_b_per_pa;  // 1 / E*
  if (!(curvature_per_m > 0.0) || !(compliance_per_pa > 0.0) || !(force_n > 0.0)) return 0.0;
  return std::cbrt(3.0 * force_n * compliance_per_pa / (4.0 * curvature_per_m));
}

namespace detail {

RollingFriction rollingFriction(double rolling_resistance, double friction, double radius_a_m, double radius_b_m,
                                double patch_radius_m) {
  // Bullet's rolling friction is a pure torque between the bodies about the two tangent axes whose
  // impulse per substep is at most m_combinedRollingFriction x the point's normal impulse (and at
  // most m_combinedRollingFriction itself, a cap that binds only above 1 N s of normal impulse in
  // one substep) [btSequentialImpulseConstraintSolver::convertContact and
  // solveGroupCacheFriendlyIterations, Bullet 3.24]: a length, the lever arm of the normal force.
  // The dimensionless c_rr = F / N is the resisting force at the axle of a wheel of radius R, a
  // torque c_rr N R about the contact [Engineering Toolbox, "Rolling resistance": F = c_l W / R
  // with c_l = c R], so Bullet's length is c_rr R with R the rolling radius.
  // Radii: a sphere's own; a moving exact mesh (GImpact: a fine triangle surface, touching at
  // single points of a curved surface, such as a round-bottomed bowl rocking on a table) the
  // sphere of its volume, as its Hertz patch takes it; 0 for a flat static body and the ground.
  // A polyhedral hull or piece rolls by tipping over its edges, which loses energy in impacts,
  // and a box must not rest differently (a glass wobbled on its foot's rim 1.5 s longer with a
  // rolling radius). Two curved bodies roll on each other with the radius of relative curvature
  // R1 R2 / (R1 + R2).
  const double ra = radius_a_m, rb = radius_b_m;
  const double rolling_radius_m = ra > 0.0 && rb > 0.0 ? ra * rb / (ra + rb) : std::max(ra, rb);
  if (!(rolling_radius_m > 0.0)) return {};
  RollingFriction r;
  r.rolling_m = rolling_resistance * rolling_radius_m;
  // Spinning about the normal: with Coulomb friction over a Hertz pressure p = p0 sqrt(1 - r^2/a^2),
  // the torque that makes the whole patch slip is (3 pi / 16) mu N a [Johnson 1985, Contact
  // Mechanics, sec. 7.4 (torsion of spheres in contact)], so Bullet's length is (3 pi / 16) mu a.
  // Bullet adds the spinning constraint only where the rolling one is (rolling_m > 0).
  r.spinning_m = 3.0 * M_PI / 16.0 * friction * patch_radius_m;
  return r;
}

void Simulation::setRollingResistance(btPersistentManifold& manifold, const ContactCoefficients& pair) const {
  const int index[2] = {manifold.getBody0()->getUserIndex(), manifold.getBody1()->getUserIndex()};
  double rolling_radius[2] = {0.0, 0.0}, contact_radius[2] = {0.0, 0.0};
  double compliance[2] = {settings_.ground_compliance_per_pa, settings_.ground_compliance_per_pa};
  for (int k = 0; k < 2; ++k) {
    if (index[k] < 0) continue;
    const BodyState& b = *bodies_[size_t(index[k])];
    rolling_radius[k] = b.sphere_radius_m > 0.0                       ? b.sphere_radius_m
                        : b.shape_used == SimBodyDesc::Shape::Concave ? b.contact_radius_m
                                                                      : 0.0;
    contact_radius[k] = b.contact_radius_m;
    compliance[k] = b.compliance_per_pa;
  }
  for (int p = 0; p < manifold.getNumContacts(); ++p) {
    btManifoldPoint& pt = manifold.getContactPoint(p);
    // The load is not known before the solve; the point's previous substep's (its warm start)
    // is within a substep's change of it while it rolls, and 0 on a new point (no spin torque).
    const double load_n = pt.m_appliedImpulse / settings_.substep_s;
    const double patch_m = hertzPatchRadius(load_n, contact_radius[0], contact_radius[1], compliance[0], compliance[1]);
    const RollingFriction r =
        rollingFriction(pair.rolling_resistance, pair.friction, rolling_radius[0], rolling_radius[1], patch_m);
    pt.m_combinedRollingFriction = r.rolling_m;
    pt.m_combinedSpinningFriction = r.spinning_m;
  }
}

void Simulation::contactState(ContactEvent& ev, const int index[2], const btVector3& point_world,
                              const btVector3& normal) const {
  // Velocities after the substep's solve (what the surfaces do while in contact: a ball rolling
  // without slip has no slip velocity after it), about the centres of mass at the start of the
  // substep, where the solver takes them.
  btVector3 material[2] = {btVector3(0, 0, 0), btVector3(0, 0, 0)};  // the material point at the contact
  btVector3 centre[2] = {btVector3(0, 0, 0), btVector3(0, 0, 0)};    // velocity of the centre of curvature
  double sphere_radius[2] = {0.0, 0.0}, contact_radius[2] = {0.0, 0.0};
  double compliance[2] = {settings_.ground_compliance_per_pa, settings_.ground_compliance_per_pa};
  bool moving[2] = {false, false}, driven[2] = {false, false};
  for (int k = 0; k < 2; ++k) {
    if (index[k] < 0) continue;
    const BodyState& b = *bodies_[size_t(index[k])];
    sphere_radius[k] = b.sphere_radius_m;
    contact_radius[k] = b.contact_radius_m;
    compliance[k] = b.compliance_per_pa;
    if (b.is_static) continue;
    moving[k] = true;
    driven[k] = b.driven;
    const btRigidBody& rb = *b.rigid;
    centre[k] = rb.getLinearVelocity();
    material[k] = centre[k] + rb.getAngularVelocity().cross(point_world - b.pre_transform.getOrigin());
  }
  // Where the contact point goes. Two spheres touch on the line between their centres at
  // (R_b c_a + R_a c_b) / (R_a + R_b); a sphere on any other shape (taken locally flat) keeps the
  // contact under its centre. Two non-spheres touch at a vertex, edge or face of the moving one
  // (a box sliding on a table drags its contact with it); two moving ones share it equally,
  // unless one is driven (SimBodyDesc::path): the tool a hand draws over the other drags it.
  btVector3 point_velocity;
  const double ra = sphere_radius[0], rb = sphere_radius[1];
  if (ra > 0.0 && rb > 0.0)
    point_velocity = (rb * centre[0] + ra * centre[1]) / (ra + rb);
  else if (ra > 0.0)
    point_velocity = centre[0];
  else if (rb > 0.0)
    point_velocity = centre[1];
  else if (moving[0] && moving[1] && driven[0] != driven[1])
    point_velocity = driven[0] ? material[0] : material[1];
  else if (moving[0] && moving[1])
    point_velocity = 0.5 * (material[0] + material[1]);
  else
    point_velocity = moving[0] ? material[0] : material[1];
  auto tangential = [&](const btVector3& v) { return v - normal * normal.dot(v); };
  const btVector3 slip = tangential(material[0] - material[1]);
  ev.slip_velocity_m_s = fromBt(slip);
  const btVector3 track_a = tangential(point_velocity - material[0]);
  ev.track_velocity_a_m_s = fromBt(track_a);
  ev.track_speed_a_m_s = track_a.length();
  ev.track_speed_b_m_s = tangential(point_velocity - material[1]).length();
  ev.rolling_speed_m_s = std::min(ev.track_speed_a_m_s, ev.track_speed_b_m_s);
  ev.normal_force_n = ev.normal_impulse_n_s / settings_.substep_s;
  ev.patch_radius_m =
      hertzPatchRadius(ev.normal_force_n, contact_radius[0], contact_radius[1], compliance[0], compliance[1]);
}

}  // namespace detail
}  // namespace strike
