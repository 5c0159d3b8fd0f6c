// SPDX-License-Identifier: MIT
// Driven bodies (SimBodyDesc::path): a hand moves the body along its keyframes. Bullet's
// kinematic bodies were the first idea, but a kinematic body has infinite mass: pressed onto a
// plate that lies on the ground, the plate's load is not determined by rigid bodies (Bullet's split
// impulse gives 0 N and nothing is heard; a path that presses a little deeper each step gives
// whatever the solver's 1000 iterations add up to), and a kinematic body is not collided with
// static bodies at all. So a driven body is a dynamic body of its own mass whose velocities are
// set at the start of every substep: the hand, stiff in everything but pressing down, and its
// weight rests on what it meets. Its orientation is the hand's alone: the solver sees no inverse
// inertia (buildBody), so a contact away from its centre of mass cannot turn it.
#include <algorithm>
#include <cmath>

#include "simulation.hpp"

namespace strike::detail {

namespace {

/// A body above its path by more than this is held up by something its path goes into, m: far
/// below any contact's geometry, far above the rounding of a body that follows its path.
constexpr double kHeldUpTolerance_m = 1e-6;

/// The body frame's pose in the world when the mesh frame is at `pose`.
btTransform bodyPose(const PathPose& pose, const BodyState& b) {
  const std::array<double, 4>& q = pose.orientation_wxyz;
  const btTransform world_from_mesh(btQuaternion(q[1], q[2], q[3], q[0]), toBt(pose.position_m));
  return world_from_mesh * b.mesh_from_body;
}

/// The angular velocity that turns `from` into `to` in dt (Bullet integrates a constant angular
/// velocity exactly: btTransformUtil::integrateTransform).
btVector3 turnRate(const btQuaternion& from, const btQuaternion& to, double dt) {
  btQuaternion turn = to * from.inverse();
  if (turn.w() < 0.0) turn = -turn;  // the shorter way
  const btVector3 axis(turn.x(), turn.y(), turn.z());
  const double sine = axis.length();  // sin(angle / 2)
  if (sine < 1e-12) return axis * (2.0 / dt);  // small angle: angle ~ 2 sin(angle / 2)
  const double angle = 2.0 * std::atan2(sine, turn.w());
  return axis * (angle / (sine * dt));
}

}  // namespace

void Simulation::drive(size_t index) {
  BodyState& b = *bodies_[index];
  const std::vector<PathKey>& path = descs_[index].path;
  btRigidBody& rigid = *b.rigid;
  const double dt = settings_.substep_s;
  const btTransform& now = rigid.getWorldTransform();
  // Where the path is at the end of this substep, and where it is now.
  const btTransform target = bodyPose(pathPose(path, double(step_ + 1) * dt), b);
  const btTransform here = bodyPose(pathPose(path, double(step_) * dt), b);
  btVector3 velocity = (target.getOrigin() - now.getOrigin()) / dt;
  const btVector3 gravity = rigid.getGravity();
  if (gravity.length2() > 0.0) {
    // Upward the hand only holds: Bullet adds g dt to the velocity before the solve, so tracking
    // the path means starting that much faster upward; but a body that something holds above its
    // path keeps its own vertical velocity and rests its weight there.
    const btVector3 up = -gravity.normalized();
    const bool held_up = up.dot(now.getOrigin() - here.getOrigin()) > kHeldUpTolerance_m;
    const double tracking = up.dot(velocity) + gravity.length() * dt;
    const double own = up.dot(rigid.getLinearVelocity());
    velocity += up * ((held_up ? own : tracking) - up.dot(velocity));
  }
  rigid.setLinearVelocity(velocity);
  rigid.setAngularVelocity(turnRate(now.getRotation(), target.getRotation(), dt));
}

}  // namespace strike::detail
