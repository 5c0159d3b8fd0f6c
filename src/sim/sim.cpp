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
#include "strike/sim.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <new>
#include <utility>

#include "convex_pieces.hpp"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <LinearMath/btConvexHullComputer.h>
#include <btBulletDynamicsCommon.h>

namespace strike {
namespace {

using Vec3 = std::array<double, 3>;

/// Hulls up to this many vertices get SAT + clipping contacts (see buildBody).
constexpr int kMaxPolyhedralVertices = 128;
/// BodyState::still_since_step of a body whose pose clock has not started.
constexpr uint64_t kNotStill = ~uint64_t(0);

btVector3 toBt(const Vec3& v) { return btVector3(v[0], v[1], v[2]); }
Vec3 fromBt(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

std::string fmt(double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", value);
  return buf;
}

/// FNV-1a, 64 bit [Fowler, Noll & Vo]: a content key for identical surfaces.
uint64_t fnv1a(const void* data, size_t size, uint64_t hash = 0xcbf29ce484222325ull) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 0x100000001b3ull;
  return hash;
}

std::string bodyLabel(const SimBodyDesc& body, size_t index) {
  return "body " + std::to_string(index) + " \"" + body.name + "\"";
}

// ---------------------------------------------------------------------------------------------
// Input checks
// ---------------------------------------------------------------------------------------------

template <size_t N>
Status checkFinite(const std::array<double, N>& values, const SimBodyDesc& body, size_t index,
                   const char* field) {
  for (size_t k = 0; k < N; ++k) {
    if (!std::isfinite(values[k])) {
      return badInput(bodyLabel(body, index) + ": " + field + "[" + std::to_string(k) +
                      "] = " + fmt(values[k]) + " (must be finite)");
    }
  }
  return {};
}

Status checkSettings(const SimSettings& settings) {
  // The contact-event times and the synth's pulse model assume sub-millisecond resolution.
  if (!std::isfinite(settings.substep_s) || settings.substep_s <= 0.0 || settings.substep_s > 1e-3) {
    return badInput("sim settings: substep_s = " + fmt(settings.substep_s) + " (must be in (0, 0.001] s)");
  }
  if (!std::isfinite(settings.duration_s) || settings.duration_s <= 0.0) {
    return badInput("sim settings: duration_s = " + fmt(settings.duration_s) + " (must be > 0)");
  }
  if (settings.duration_s / settings.substep_s > 1e9) {
    return badInput("sim settings: duration_s / substep_s = " + fmt(settings.duration_s / settings.substep_s) +
                    " substeps (at most 1e9)");
  }
  for (size_t k = 0; k < 3; ++k) {
    if (!std::isfinite(settings.gravity_m_s2[k])) {
      return badInput("sim settings: gravity_m_s2[" + std::to_string(k) + "] = " + fmt(settings.gravity_m_s2[k]) +
                      " (must be finite)");
    }
  }
  const std::pair<const char*, double> scalars[] = {{"ground_height_m", settings.ground_height_m},
                                                    {"ground_restitution", settings.ground_restitution},
                                                    {"ground_friction", settings.ground_friction},
                                                    {"min_impulse_n_s", settings.min_impulse_n_s},
                                                    {"impact_speed_m_s", settings.impact_speed_m_s}};
  for (const auto& [name, value] : scalars) {
    if (!std::isfinite(value) || (value < 0.0 && std::string(name) != "ground_height_m")) {
      return badInput(std::string("sim settings: ") + name + " = " + fmt(value) + " (must be finite and >= 0)");
    }
  }
  if (!(settings.sleep_after_still_s >= 0.0 && settings.sleep_after_still_s <= 2.0)) {
    return badInput("sim settings: sleep_after_still_s = " + fmt(settings.sleep_after_still_s) +
                    " (must be in [0, 2] s)");
  }
  for (size_t k = 0; k < settings.contact_pairs.size(); ++k) {
    const SimSettings::ContactPair& pair = settings.contact_pairs[k];
    const std::string where = "sim settings: contact_pairs[" + std::to_string(k) + "]";
    if (!std::isnan(pair.restitution) && !(pair.restitution >= 0.0 && pair.restitution <= 1.0))
      return badInput(where + ".restitution = " + fmt(pair.restitution) + " (must be in [0, 1])");
    if (!std::isnan(pair.friction) && !(pair.friction >= 0.0 && std::isfinite(pair.friction)))
      return badInput(where + ".friction = " + fmt(pair.friction) + " (must be finite and >= 0)");
  }
  if (!(settings.ground_compliance_per_pa >= 0.0 && std::isfinite(settings.ground_compliance_per_pa)))
    return badInput("sim settings: ground_compliance_per_pa = " + fmt(settings.ground_compliance_per_pa) +
                    " (must be finite and >= 0)");
  if (settings.solver_iterations < 1 || settings.solver_iterations > 10000) {
    return badInput("sim settings: solver_iterations = " + std::to_string(settings.solver_iterations) +
                    " (must be in [1, 10000])");
  }
  return {};
}

/// Checks one body; writes the normalized orientation.
Status checkBody(const SimBodyDesc& body, size_t index, btQuaternion& orientation) {
  const std::string label = bodyLabel(body, index);
  if (body.surface_positions.empty() || body.surface_triangles.empty()) {
    return badInput(label + ": empty geometry (" + std::to_string(body.surface_positions.size() / 3) +
                    " vertices, " + std::to_string(body.surface_triangles.size() / 3) + " triangles)");
  }
  if (body.surface_positions.size() % 3 != 0 || body.surface_triangles.size() % 3 != 0) {
    return badInput(label + ": surface_positions has " + std::to_string(body.surface_positions.size()) +
                    " values and surface_triangles " + std::to_string(body.surface_triangles.size()) +
                    " (both must be multiples of 3)");
  }
  const size_t vertex_count = body.surface_positions.size() / 3;
  if (vertex_count > 0x7fffffffu) return badInput(label + ": too many vertices for Bullet (int indices)");
  for (size_t k = 0; k < body.surface_positions.size(); ++k) {
    if (!std::isfinite(body.surface_positions[k])) {
      return badInput(label + ": surface_positions[" + std::to_string(k) + "] (vertex " + std::to_string(k / 3) +
                      ") = " + fmt(body.surface_positions[k]) + " (must be finite)");
    }
  }
  for (size_t k = 0; k < body.surface_triangles.size(); ++k) {
    if (body.surface_triangles[k] >= vertex_count) {
      return badInput(label + ": triangle " + std::to_string(k / 3) + " references vertex " +
                      std::to_string(body.surface_triangles[k]) + ", mesh has " + std::to_string(vertex_count) +
                      " vertices");
    }
  }
  if (Status s = checkFinite(body.position_m, body, index, "position_m"); !s) return s;
  if (Status s = checkFinite(body.orientation_wxyz, body, index, "orientation_wxyz"); !s) return s;
  if (Status s = checkFinite(body.velocity_m_s, body, index, "velocity_m_s"); !s) return s;
  if (Status s = checkFinite(body.angular_velocity_rad_s, body, index, "angular_velocity_rad_s"); !s) return s;
  const auto& q = body.orientation_wxyz;
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  // Rounded quaternions from a scene file are accepted; anything further off is a mistake.
  if (std::abs(norm - 1.0) > 1e-3) {
    return badInput(label + ": orientation_wxyz = [" + fmt(q[0]) + ", " + fmt(q[1]) + ", " + fmt(q[2]) + ", " +
                    fmt(q[3]) + "] has norm " + fmt(norm) + " (must be a unit quaternion within 1e-3)");
  }
  orientation = btQuaternion(q[1] / norm, q[2] / norm, q[3] / norm, q[0] / norm);  // Bullet is (x, y, z, w)
  for (const auto& [name, value] : {std::pair<const char*, double>{"restitution", body.restitution},
                                    std::pair<const char*, double>{"friction", body.friction},
                                    std::pair<const char*, double>{"compliance_per_pa", body.compliance_per_pa}}) {
    if (!std::isfinite(value) || value < 0.0) {
      return badInput(label + ": " + name + " = " + fmt(value) + " (must be finite and >= 0)");
    }
  }
  if (body.is_static) return {};
  if (!std::isfinite(body.mass_kg) || body.mass_kg <= 0.0) {
    return badInput(label + ": mass_kg = " + fmt(body.mass_kg) + " (a dynamic body needs a mass > 0)");
  }
  if (Status s = checkFinite(body.centre_m, body, index, "centre_m"); !s) return s;
  if (Status s = checkFinite(body.inertia_kg_m2, body, index, "inertia_kg_m2"); !s) return s;
  const auto& inertia = body.inertia_kg_m2;
  const double trace = inertia[0] + inertia[4] + inertia[8];
  const double asymmetry = std::max({std::abs(inertia[1] - inertia[3]), std::abs(inertia[2] - inertia[6]),
                                     std::abs(inertia[5] - inertia[7])});
  if (!(trace > 0.0) || asymmetry > 1e-6 * trace) {
    return badInput(label + ": inertia_kg_m2 = [" + fmt(inertia[0]) + ", " + fmt(inertia[1]) + ", " +
                    fmt(inertia[2]) + "; " + fmt(inertia[3]) + ", " + fmt(inertia[4]) + ", " + fmt(inertia[5]) +
                    "; " + fmt(inertia[6]) + ", " + fmt(inertia[7]) + ", " + fmt(inertia[8]) +
                    "] (must be symmetric with a positive trace)");
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// Geometry
// ---------------------------------------------------------------------------------------------

/// Volume enclosed by a closed triangle mesh, by the divergence theorem: the sum of the signed
/// volumes of the tetrahedra (origin, a, b, c) [Zhang & Chen 2001, "Efficient feature extraction
/// for 2D/3D objects in mesh representation"].
double meshVolume(const std::vector<double>& xyz, const std::vector<uint32_t>& tris) {
  double six_v = 0.0;
  for (size_t t = 0; t + 2 < tris.size(); t += 3) {
    const double* a = &xyz[3 * size_t(tris[t])];
    const double* b = &xyz[3 * size_t(tris[t + 1])];
    const double* c = &xyz[3 * size_t(tris[t + 2])];
    six_v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
             a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return six_v / 6.0;
}

/// Volume of a convex hull from btConvexHullComputer: fan-triangulate each planar face and apply
/// the divergence theorem as above (faces are counter-clockwise seen from outside).
double hullVolume(const btConvexHullComputer& hull) {
  double six_v = 0.0;
  for (int f = 0; f < hull.faces.size(); ++f) {
    const btConvexHullComputer::Edge* first = &hull.edges[hull.faces[f]];
    const btVector3& a = hull.vertices[first->getSourceVertex()];
    const btConvexHullComputer::Edge* e = first->getNextEdgeOfFace();
    while (e->getTargetVertex() != first->getSourceVertex()) {
      const btVector3& b = hull.vertices[e->getSourceVertex()];
      const btVector3& c = hull.vertices[e->getTargetVertex()];
      six_v += a.dot(b.cross(c));
      e = e->getNextEdgeOfFace();
    }
  }
  return std::abs(six_v) / 6.0;
}

/// Everything Bullet needs for one body; addresses must stay fixed (Bullet keeps pointers).
struct BodyState {
  btTransform mesh_from_body;       // fixed
  btTransform body_from_mesh;
  btVector3 principal_inertia{0, 0, 0};  // kg m^2, body frame
  double mass_kg = 0.0;
  double size_m = 0.0;              // largest extent of the body-frame bounding box
  double min_extent_m = 0.0;        // smallest extent
  double margin_m = 0.0;
  SimBodyDesc::Shape shape_used = SimBodyDesc::Shape::ConvexHull;
  bool is_static = false;
  // Storage for concave shapes (btTriangleIndexVertexArray points into these).
  std::vector<btScalar> body_xyz;
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> mesh_interface;
  std::vector<std::unique_ptr<btConvexHullShape>> pieces;  // children of a compound shape
  std::vector<std::vector<double>> pieces_mesh;             // their points, mesh frame
  bool pieces_computed = false;
  double pieces_seconds = 0.0;
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btRigidBody> rigid;
  // Saved at the start of each substep (pre-tick callback).
  btTransform pre_transform;
  btVector3 pre_linear{0, 0, 0}, pre_angular{0, 0, 0};
  // The pose still-clock (Simulation::hastenSleep): the pose when it started, and the substep.
  btTransform still_anchor = btTransform::getIdentity();
  uint64_t still_since_step = kNotStill;
  double sleep_start_s = NAN;  // when it fell asleep; NaN while awake
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
  void preTick();
  void timeImpacts();
  void moveImpactsToTheirTime();
  void postTick();
  double energy(std::vector<double>* kinetic) const;
  void hastenSleep();
  void recordStates(std::vector<SimBodyState>& states) const;
  ContactCoefficients coefficients(int index_a, int index_b) const;
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
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver_;
  std::unique_ptr<StrikeWorld> world_;
  std::unique_ptr<btCollisionShape> ground_shape_;
  std::unique_ptr<btRigidBody> ground_;
  bool gimpact_registered_ = false;
  std::map<uint64_t, std::vector<std::vector<double>>> pieces_by_surface_;  // by content hash

  uint64_t step_ = 0;
  std::vector<ContactEvent> events_;
  std::vector<ContactEvent> step_events_;
  std::vector<RecentContact> step_recent_;
  std::vector<int> step_lifetimes_;
  std::vector<ImpactPoint> step_impacts_;
  std::vector<StruckBody> step_struck_;
  std::map<std::pair<uint32_t, uint32_t>, std::vector<RecentContact>> recent_;
};

Status Simulation::buildBody(size_t index, const btQuaternion& orientation) {
  const SimBodyDesc& desc = descs_[index];
  auto state = std::make_unique<BodyState>();
  state->is_static = desc.is_static;
  const size_t vertex_count = desc.surface_positions.size() / 3;

  // Principal frame. Bullet's btRigidBody takes a diagonal inertia about the body origin, so the
  // body frame is the centre of mass with the principal axes (Jacobi diagonalization:
  // I_mesh = R diag(I) R^T, the columns of R are the principal axes in the mesh frame).
  btMatrix3x3 principal_axes = btMatrix3x3::getIdentity();
  btVector3 centre(0, 0, 0);
  if (!desc.is_static) {
    const auto& in = desc.inertia_kg_m2;
    btMatrix3x3 inertia(in[0], 0.5 * (in[1] + in[3]), 0.5 * (in[2] + in[6]),  //
                        0.5 * (in[1] + in[3]), in[4], 0.5 * (in[5] + in[7]),  //
                        0.5 * (in[2] + in[6]), 0.5 * (in[5] + in[7]), in[8]);
    inertia.diagonalize(principal_axes, 1e-15, 100);
    state->principal_inertia = btVector3(inertia[0][0], inertia[1][1], inertia[2][2]);
    const double i_max = std::max({inertia[0][0], inertia[1][1], inertia[2][2]});
    for (int k = 0; k < 3; ++k) {
      // A real body satisfies the triangle inequality I_a <= I_b + I_c; only a positive
      // definite tensor is required here, with a little slack for thin rods and plates.
      if (!(state->principal_inertia[k] > 1e-12 * i_max)) {
        return badInput(bodyLabel(desc, index) + ": inertia_kg_m2 has principal moment " +
                        fmt(state->principal_inertia[k]) + " (must be positive definite)");
      }
    }
    if (principal_axes.determinant() < 0) principal_axes.setValue(  // keep a proper rotation
        -principal_axes[0][0], principal_axes[0][1], principal_axes[0][2], -principal_axes[1][0],
        principal_axes[1][1], principal_axes[1][2], -principal_axes[2][0], principal_axes[2][1],
        principal_axes[2][2]);
    centre = toBt(desc.centre_m);
    state->mass_kg = desc.mass_kg;
  }
  state->mesh_from_body = btTransform(principal_axes, centre);
  state->body_from_mesh = state->mesh_from_body.inverse();

  // Surface in the body frame, and its bounding box for the size-dependent tolerances.
  state->body_xyz.resize(3 * vertex_count);
  btVector3 lo(SIMD_INFINITY, SIMD_INFINITY, SIMD_INFINITY), hi = -lo;
  for (size_t v = 0; v < vertex_count; ++v) {
    const btVector3 p = state->body_from_mesh(btVector3(desc.surface_positions[3 * v], desc.surface_positions[3 * v + 1],
                                                        desc.surface_positions[3 * v + 2]));
    for (int k = 0; k < 3; ++k) state->body_xyz[3 * v + size_t(k)] = p[k];
    lo.setMin(p);
    hi.setMax(p);
  }
  const btVector3 extent = hi - lo;
  state->size_m = std::max({extent.x(), extent.y(), extent.z()});
  state->min_extent_m = std::min({extent.x(), extent.y(), extent.z()});
  if (!(state->size_m > 0.0)) {
    return badInput(bodyLabel(desc, index) + ": all " + std::to_string(vertex_count) +
                    " surface vertices coincide (zero size)");
  }
  // Collision margin: Bullet's default 4 cm would swallow a 2 cm object. Default 2% of the
  // thinnest extent, refined per shape kind below.
  state->margin_m = std::clamp(0.02 * state->min_extent_m, 1e-5, 0.01);
  if (state->min_extent_m <= 0.0) state->margin_m = std::clamp(0.002 * state->size_m, 1e-5, 0.01);

  // Shape choice.
  btConvexHullComputer hull;
  const double hull_volume =
      hull.compute(state->body_xyz.data(), int(3 * sizeof(btScalar)), int(vertex_count), 0.0, 0.0) < 0
          ? 0.0
          : hullVolume(hull);
  SimBodyDesc::Shape shape = desc.shape;
  if (shape == SimBodyDesc::Shape::Auto) {
    const double volume = std::abs(meshVolume(state->body_xyz, desc.surface_triangles));
    // A static concave body keeps its exact mesh (a BVH, cheap when it never moves); a moving one
    // becomes convex pieces: GImpact meshes cost ~100x more per substep (a mug on a table: 6.3 s
    // of simulation for 2.5 s, 0.05 s as a hull) and never rest still (see hastenSleep).
    shape = (hull_volume > 0.0 && volume >= 0.9 * hull_volume) ? SimBodyDesc::Shape::ConvexHull
            : desc.is_static                                   ? SimBodyDesc::Shape::Concave
                                                               : SimBodyDesc::Shape::ConvexPieces;
  }
  state->shape_used = shape;

  if (shape == SimBodyDesc::Shape::ConvexHull) {
    if (hull.vertices.size() == 0) {
      return badInput(bodyLabel(desc, index) + ": cannot build a convex hull of " + std::to_string(vertex_count) +
                      " vertices");
    }
    // A hull whose points all lie on one sphere about the centre of mass is a sphere: Bullet's
    // sphere shape is exact and costs O(1) per support query instead of O(points), which is what
    // makes marbles rolling in a GImpact bowl affordable.
    double radius_sum = 0.0, radius_min = INFINITY, radius_max = 0.0;
    for (int v = 0; v < hull.vertices.size(); ++v) {
      const double r = hull.vertices[v].length();
      radius_sum += r;
      radius_min = std::min(radius_min, r);
      radius_max = std::max(radius_max, r);
    }
    const double radius_mean = hull.vertices.size() > 0 ? radius_sum / hull.vertices.size() : 0.0;
    // All points on one sphere is not enough (a box's corners are too): the hull must also fill
    // the sphere.
    const double sphere_volume = 4.0 / 3.0 * M_PI * radius_mean * radius_mean * radius_mean;
    if (hull.vertices.size() >= 12 && radius_max - radius_min <= 0.02 * radius_mean &&
        hull_volume >= 0.9 * sphere_volume) {
      // Volume-equivalent radius, so the sphere neither floats above nor sinks into the ground.
      const double radius = std::cbrt(3.0 * std::abs(meshVolume(state->body_xyz, desc.surface_triangles)) / (4.0 * M_PI));
      state->shape = std::make_unique<btSphereShape>(radius > 0 ? radius : radius_mean);
      state->margin_m = state->shape->getMargin();
    } else {
    auto convex = std::make_unique<btConvexHullShape>();
    if (hull.vertices.size() <= kMaxPolyhedralVertices) {
      // Polyhedral features make hull-hull contacts use face clipping, which yields the whole
      // contact patch (up to 4 points) in the first substep; plain GJK/EPA adds one point per
      // substep, so a box landing flat on another first touches at one corner, tips and slides
      // [Bullet btPolyhedralContactClipping]. The clipping works on the bare points (no margin)
      // while GJK paths (ground, triangles) add the margin, so the points are the hull itself
      // and the margin is tiny: 0.1% of the thinnest extent, the most a body can float.
      // Edge-edge clipping costs O(edges^2) per pair, hence only for modest hulls.
      state->margin_m = std::clamp(0.001 * state->min_extent_m, 1e-6, 1e-3);
      for (int v = 0; v < hull.vertices.size(); ++v) convex->addPoint(hull.vertices[v], false);
      convex->recalcLocalAabb();
      convex->setMargin(state->margin_m);
      convex->initializePolyhedralFeatures();
    } else {
      // Large hull, GJK/EPA only: those need a real margin for robust penetration depths, and
      // btConvexHullShape puts it outside the points. Shrink the hull by the margin first
      // (btConvexHullComputer moves each face inwards) so the collision surface is the mesh's
      // hull with edges rounded by the margin; the shrink is clamped to a quarter of the inner
      // radius for thin bodies.
      btConvexHullComputer shrunk;
      const double shrink = shrunk.compute(state->body_xyz.data(), int(3 * sizeof(btScalar)), int(vertex_count),
                                           state->margin_m, 0.25);
      const btConvexHullComputer& used = shrink > 0.0 && shrunk.vertices.size() > 0 ? shrunk : hull;
      for (int v = 0; v < used.vertices.size(); ++v) convex->addPoint(used.vertices[v], false);
      convex->recalcLocalAabb();
      if (shrink > 0.0) state->margin_m = shrink;  // the clamp may have made it smaller
      convex->setMargin(state->margin_m);
    }
    state->shape = std::move(convex);
    }
  } else if (shape == SimBodyDesc::Shape::ConvexPieces) {
    // Convex pieces of the surface, each a polyhedral hull as above (SAT + clipping contacts,
    // persistent manifolds per piece), within 1% of the body's size of its hollows.
    if (!desc.convex_pieces_m.empty()) {
      state->pieces_mesh = desc.convex_pieces_m;
    } else {
      // Computed once per surface in a run (identical objects share it), in the mesh frame,
      // whose axes are usually the shape's (a turned glass's floor lies in an axis plane there,
      // and the cuts are axis-aligned); then moved to the body frame.
      uint64_t key = fnv1a(desc.surface_positions.data(), desc.surface_positions.size() * sizeof(double));
      key = fnv1a(desc.surface_triangles.data(), desc.surface_triangles.size() * sizeof(uint32_t), key);
      auto known = pieces_by_surface_.find(key);
      if (known == pieces_by_surface_.end()) {
        const auto start = std::chrono::steady_clock::now();
        ConvexPiecesSettings piece_settings;
        piece_settings.max_concavity_m = ConvexPiecesRecipe::concavity_of_size * state->size_m;
        piece_settings.max_edge_m = ConvexPiecesRecipe::max_edge_of_size * state->size_m;
        piece_settings.max_pieces = ConvexPiecesRecipe::max_pieces;
        ConvexPieces pieces = convexPieces(desc.surface_positions, desc.surface_triangles, piece_settings);
        state->pieces_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        known = pieces_by_surface_.emplace(key, std::move(pieces.hull_points)).first;
      }
      state->pieces_mesh = known->second;
      state->pieces_computed = true;
    }
    if (state->pieces_mesh.empty()) {
      return badInput(bodyLabel(desc, index) + ": cannot split " + std::to_string(vertex_count) +
                      " vertices into convex pieces");
    }
    state->margin_m = std::clamp(0.001 * state->min_extent_m, 1e-6, 1e-3);
    auto compound = std::make_unique<btCompoundShape>(true, int(state->pieces_mesh.size()));
    for (const std::vector<double>& points : state->pieces_mesh) {
      auto piece = std::make_unique<btConvexHullShape>();
      for (size_t k = 0; k + 2 < points.size(); k += 3)
        piece->addPoint(state->body_from_mesh(btVector3(points[k], points[k + 1], points[k + 2])), false);
      piece->recalcLocalAabb();
      piece->setMargin(state->margin_m);
      if (piece->getNumPoints() <= kMaxPolyhedralVertices) piece->initializePolyhedralFeatures();
      compound->addChildShape(btTransform::getIdentity(), piece.get());
      state->pieces.push_back(std::move(piece));
    }
    state->shape = std::move(compound);
  } else {
    state->indices.assign(desc.surface_triangles.begin(), desc.surface_triangles.end());
    state->mesh_interface = std::make_unique<btTriangleIndexVertexArray>(
        int(state->indices.size() / 3), state->indices.data(), int(3 * sizeof(int)), int(vertex_count),
        state->body_xyz.data(), int(3 * sizeof(btScalar)));
    // Triangles carry their margin on both sides: keep it thinner than for hulls.
    // (They also add to the surface, unlike the shrunk hull: a tray placed on the ground starts
    // that far inside it, so keep the margin small: 0.2% of the thinnest extent, at most 1 mm.)
    state->margin_m = std::clamp(0.002 * state->min_extent_m, 1e-5, 1e-3);
    if (desc.is_static) {
      auto bvh = std::make_unique<btBvhTriangleMeshShape>(state->mesh_interface.get(), true);
      bvh->setMargin(state->margin_m);
      state->shape = std::move(bvh);
    } else {
      // A moving concave body needs GImpact (btBvhTriangleMeshShape is static only).
      auto gimpact = std::make_unique<btGImpactMeshShape>(state->mesh_interface.get());
      gimpact->setMargin(state->margin_m);
      gimpact->updateBound();
      state->shape = std::move(gimpact);
      if (!gimpact_registered_) {
        btGImpactCollisionAlgorithm::registerAlgorithm(dispatcher_.get());
        gimpact_registered_ = true;
      }
    }
  }

  const btTransform world_from_mesh(orientation, toBt(desc.position_m));
  const btTransform world_from_body = world_from_mesh * state->mesh_from_body;
  btRigidBody::btRigidBodyConstructionInfo info(desc.is_static ? 0.0 : desc.mass_kg, nullptr, state->shape.get(),
                                                desc.is_static ? btVector3(0, 0, 0) : state->principal_inertia);
  info.m_startWorldTransform = world_from_body;
  info.m_restitution = desc.restitution;
  info.m_friction = desc.friction;
  info.m_linearDamping = 0.0;
  info.m_angularDamping = 0.0;
  // Still means still for a small object: Bullet's defaults (0.8 m/s, 1 rad/s) would freeze a
  // rolling marble.
  info.m_linearSleepingThreshold = 0.01;
  info.m_angularSleepingThreshold = 0.05;
  state->rigid = std::make_unique<btRigidBody>(info);
  state->rigid->setUserIndex(int(index));
  if (!desc.is_static) {
    // Bullet's integrator (symplectic Euler: v += g dt, then x += v dt) moves a body exactly along
    // the parabola of free fall when the stored velocity is the one half a step earlier; started
    // from v0 itself it falls g dt t / 2 too far by time t (0.7 mm, half a step early, at 0.14 s).
    // So the stored velocity is v(t - dt/2) throughout, as in leapfrog [Hairer, Lubich & Wanner
    // 2003, "Geometric numerical integration illustrated by the Stoermer-Verlet method"].
    state->rigid->setLinearVelocity(toBt(desc.velocity_m_s) - 0.5 * settings_.substep_s * toBt(settings_.gravity_m_s2));
    state->rigid->setAngularVelocity(toBt(desc.angular_velocity_rad_s));
    // CCD (Bullet's swept sphere + predictive contact) once a substep moves the body by more
    // than half its thinnest extent: below that the discrete narrow phase still sees the overlap
    // on the correct side of a thin wall. The sphere must fit inside the body.
    if (state->rigid->getCollisionShape()->isConvex()) {
      state->rigid->setCcdMotionThreshold(0.5 * std::max(state->min_extent_m, 1e-4));
      state->rigid->setCcdSweptSphereRadius(0.4 * state->min_extent_m);
    }
    if (!settings_.allow_sleep) state->rigid->setActivationState(DISABLE_DEACTIVATION);
  }
  world_->addRigidBody(state->rigid.get());
  // A static body is asleep for good: Bullet skips a pair only when both bodies are inactive, so
  // an awake table kept the narrow phase running for a glass asleep on it (6 s of GImpact
  // triangle tests for 1.3 s of sleep). Moving bodies still collide with it.
  if (desc.is_static) state->rigid->forceActivationState(ISLAND_SLEEPING);
  bodies_.push_back(std::move(state));
  return {};
}

Status Simulation::build(const std::vector<btQuaternion>& orientations) {
  config_ = std::make_unique<btDefaultCollisionConfiguration>();
  // A box landing flat on the ground must touch with all four corners in the same substep;
  // the default plane-convex algorithm reports one support point per substep, and the box
  // tips on it. Perturbed support queries find the rest of the face [Bullet
  // btConvexPlaneCollisionAlgorithm]. Same for convex-convex pairs without polyhedral features.
  config_->setPlaneConvexMultipointIterations(3, 3);
  config_->setConvexConvexMultipointIterations(3, 3);
  dispatcher_ = std::make_unique<btCollisionDispatcher>(config_.get());
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
    if (index < 0) return ContactSide{settings_.ground_restitution, settings_.ground_friction, settings_.ground_compliance_per_pa};
    const SimBodyDesc& d = descs_[size_t(index)];
    return ContactSide{d.restitution, d.friction, d.compliance_per_pa};
  };
  ContactCoefficients c = combineContact(side(index_a), side(index_b));
  const uint32_t a = index_a < 0 ? kGroundBody : uint32_t(index_a), b = index_b < 0 ? kGroundBody : uint32_t(index_b);
  for (const SimSettings::ContactPair& pair : settings_.contact_pairs) {  // the last one given wins
    if (!((pair.body_a == a && pair.body_b == b) || (pair.body_a == b && pair.body_b == a))) continue;
    if (!std::isnan(pair.restitution)) c.restitution = pair.restitution;
    if (!std::isnan(pair.friction)) c.friction = pair.friction;
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
  for (auto& b : bodies_) {
    b->pre_transform = b->rigid->getWorldTransform();
    b->pre_linear = b->rigid->getLinearVelocity();
    b->pre_angular = b->rigid->getAngularVelocity();
  }
}

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

void Simulation::postTick() {
  const double time_s = double(step_) * settings_.substep_s;
  moveImpactsToTheirTime();
  step_events_.clear();
  const int manifold_count = dispatcher_->getNumManifolds();
  for (int m = 0; m < manifold_count; ++m) {
    const btPersistentManifold* manifold = dispatcher_->getManifoldByIndexInternal(m);
    const btCollisionObject* objects[2] = {manifold->getBody0(), manifold->getBody1()};
    int index[2] = {objects[0]->getUserIndex(), objects[1]->getUserIndex()};
    // A sleeping island is not solved this substep: its stale impulses are not forces.
    bool any_active = false;
    for (int k = 0; k < 2; ++k) {
      if (index[k] >= 0 && !bodies_[size_t(index[k])]->is_static && objects[k]->isActive()) any_active = true;
    }
    if (!any_active) continue;
    const bool predictive = world_->isPredictive(manifold);
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      const btManifoldPoint& pt = manifold->getContactPoint(p);
      if (!(pt.m_appliedImpulse > settings_.min_impulse_n_s)) continue;
      btVector3 normal = pt.m_normalWorldOnB;  // from B to A; the impulse on A is along +normal
      btVector3 friction = pt.m_lateralFrictionDir1 * pt.m_appliedImpulseLateral1 +
                           pt.m_lateralFrictionDir2 * pt.m_appliedImpulseLateral2;
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
          *mesh_impulses[k] =
              fromBt(b.mesh_from_body.getBasis() * (b.pre_transform.getBasis().transpose() * impulse));
          point_velocity[k] = b.pre_linear + b.pre_angular.cross(point_world - b.pre_transform.getOrigin());
        }
        *mesh_points[k] = fromBt(meshes[k]);
      }
      ev.normal_speed_m_s = std::max(0.0, -(point_velocity[0] - point_velocity[1]).dot(normal));
      if (ev.normal_speed_m_s > settings_.impact_speed_m_s) {
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
          const btVector3 path_velocity_sum = point_velocity[0] + point_velocity[1] +
              0.5 * settings_.substep_s * (freeAcceleration(objects[0]) + freeAcceleration(objects[1]));
          ev.point_world = fromBt(point_world + 0.5 * offset * path_velocity_sum);
        }
      }
      step_events_.push_back(ev);
      step_recent_.push_back(RecentContact{step_, point_world, meshes[0], meshes[1]});
      step_lifetimes_.push_back(pt.m_lifeTime);
    }
  }

  // Deterministic order within the substep, independent of Bullet's manifold order.
  std::vector<size_t> order(step_events_.size());
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
  constexpr uint64_t kLookbackSteps = 3;
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
  if (events_.size() > first_new) {
    const auto earlier = [](const ContactEvent& x, const ContactEvent& y) { return x.time_s < y.time_s; };
    const auto new_begin = events_.begin() + std::ptrdiff_t(first_new);
    std::stable_sort(new_begin, events_.end(), earlier);
    std::inplace_merge(std::upper_bound(events_.begin(), new_begin, *new_begin, earlier), new_begin, events_.end(),
                       earlier);
  }
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
      return badInput("simulate: more than " + std::to_string(settings_.max_events) + " contact events by t = " +
                      std::to_string(double(step_ + 1) * dt) +
                      " s, the cap on contact events (memory); raise it with --max-events N or shorten the duration");
    result.energy_trace_j.push_back(energy(&kinetic));
    for (size_t i = 0; i < n; ++i) result.max_kinetic_energy_j[i] = std::max(result.max_kinetic_energy_j[i], kinetic[i]);
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

}  // namespace

ContactCoefficients combineContact(const ContactSide& a, const ContactSide& b) {
  const double ka = a.compliance_per_pa, kb = b.compliance_per_pa;
  const double wa = ka + kb > 0.0 ? ka / (ka + kb) : 0.5;
  const double loss = wa * (1.0 - a.restitution * a.restitution) + (1.0 - wa) * (1.0 - b.restitution * b.restitution);
  ContactCoefficients c;
  c.restitution = std::sqrt(std::clamp(1.0 - loss, 0.0, 1.0));
  c.friction = std::sqrt(a.friction * b.friction);
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
