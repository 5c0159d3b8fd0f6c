// SPDX-License-Identifier: MIT
// Collision shapes: each body's principal frame, shape choice (sphere, convex hull, convex
// pieces, static mesh or GImpact), collision margin and Bullet rigid body (Simulation::buildBody).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "convex_pieces.hpp"
#include "simulation.hpp"

namespace strike::detail {

namespace {

/// FNV-1a, 64 bit [Fowler, Noll & Vo]: a content key for identical surfaces.
uint64_t fnv1a(const void* data, size_t size, uint64_t hash = 0xcbf29ce484222325ull) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 0x100000001b3ull;
  return hash;
}

/// Volume enclosed by a closed triangle mesh, by the divergence theorem: the sum of the signed
/// volumes of the tetrahedra (origin, a, b, c) [Zhang & Chen 2001, "Efficient feature extraction
/// for 2D/3D objects in mesh representation"].
double meshVolume(const std::vector<double>& xyz, const std::vector<uint32_t>& tris) {
  double six_v = 0.0;
  for (size_t t = 0; t + 2 < tris.size(); t += 3) {
    const double* a = &xyz[3 * size_t(tris[t])];
    const double* b = &xyz[3 * size_t(tris[t + 1])];
    const double* c = &xyz[3 * size_t(tris[t + 2])];
    six_v +=
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
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

/// The hull of a body's points shrunk by shrink_m (0: not shrunk), through the memory of hulls
/// when the settings give one.
std::shared_ptr<const SimHull> convexHull(const std::vector<double>& xyz, double shrink_m, double shrink_clamp,
                                          const SimHullMemo& memo) {
  auto compute = [&] {
    btConvexHullComputer computer;
    SimHull hull;
    hull.shrink_m =
        computer.compute(xyz.data(), int(3 * sizeof(btScalar)), int(xyz.size() / 3), shrink_m, shrink_clamp);
    hull.volume_m3 = hull.shrink_m < 0 ? 0.0 : hullVolume(computer);
    hull.vertices_xyz.reserve(3 * size_t(computer.vertices.size()));
    for (int v = 0; v < computer.vertices.size(); ++v)
      for (int k = 0; k < 3; ++k) hull.vertices_xyz.push_back(computer.vertices[v][k]);
    return hull;
  };
  return memo ? memo(xyz, shrink_m, shrink_clamp, compute) : std::make_shared<const SimHull>(compute());
}

btVector3 hullVertex(const SimHull& hull, size_t v) {
  return btVector3(hull.vertices_xyz[3 * v], hull.vertices_xyz[3 * v + 1], hull.vertices_xyz[3 * v + 2]);
}

/// True when the hull's points are the 8 corners of a box centred at the origin with edges along
/// the axes, to within tolerance_m; half_m receives its half extents.
bool boxHalfExtents(const SimHull& hull, double tolerance_m, btVector3& half_m) {
  if (hull.vertices_xyz.size() != 3 * 8) return false;
  half_m = btVector3(0, 0, 0);
  for (size_t v = 0; v < 8; ++v) half_m.setMax(hullVertex(hull, v).absolute());
  for (size_t v = 0; v < 8; ++v) {
    const btVector3 corner = hullVertex(hull, v).absolute();
    for (int k = 0; k < 3; ++k)
      if (!(half_m[k] > 0.0) || std::abs(corner[k] - half_m[k]) > tolerance_m) return false;
  }
  return true;
}

}  // namespace

std::shared_ptr<const SimHull> Simulation::bodyHull(const std::vector<double>& xyz, double shrink_m,
                                                    double shrink_clamp) {
  // Identical bodies share one hull within the run (twelve marbles: a twelfth of the time), then
  // the caller's memory (a session's, the cache folder's) is asked. The same points give the
  // same hull, to the bit.
  for (const RunHull& known : run_hulls_)
    if (known.shrink_m == shrink_m && known.shrink_clamp == shrink_clamp && known.points_xyz == xyz) return known.hull;
  run_hulls_.push_back({xyz, shrink_m, shrink_clamp, convexHull(xyz, shrink_m, shrink_clamp, settings_.hull_memo)});
  return run_hulls_.back().hull;
}

Status Simulation::buildBody(size_t index, const btQuaternion& orientation) {
  const SimBodyDesc& desc = descs_[index];
  auto state = std::make_unique<BodyState>();
  state->is_static = desc.is_static;
  if (Status framed = bodyFrame(index, *state); !framed) return framed.error();

  // Shape choice.
  const std::shared_ptr<const SimHull> hull = bodyHull(state->body_xyz, 0.0, 0.0);
  const double hull_volume = hull->volume_m3;
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

  Status built;
  if (shape == SimBodyDesc::Shape::ConvexHull)
    built = buildHullShape(index, *state, hull);
  else if (shape == SimBodyDesc::Shape::ConvexPieces)
    built = buildPiecesShape(index, *state);
  else
    buildMeshShape(index, *state);
  if (!built) return built.error();
  addRigidBody(index, orientation, std::move(state));
  return {};
}

Status Simulation::bodyFrame(size_t index, BodyState& state) {
  const SimBodyDesc& desc = descs_[index];
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
    state.principal_inertia = btVector3(inertia[0][0], inertia[1][1], inertia[2][2]);
    const double i_max = std::max({inertia[0][0], inertia[1][1], inertia[2][2]});
    for (int k = 0; k < 3; ++k) {
      // A real body satisfies the triangle inequality I_a <= I_b + I_c; only a positive
      // definite tensor is required here, with a little slack for thin rods and plates.
      if (!(state.principal_inertia[k] > 1e-12 * i_max)) {
        return badInput(bodyLabel(desc, index) + ": inertia_kg_m2 has principal moment " +
                        fmt(state.principal_inertia[k]) + " (must be positive definite)");
      }
    }
    if (principal_axes.determinant() < 0)
      principal_axes.setValue(  // keep a proper rotation
          -principal_axes[0][0], principal_axes[0][1], principal_axes[0][2], -principal_axes[1][0],
          principal_axes[1][1], principal_axes[1][2], -principal_axes[2][0], principal_axes[2][1],
          principal_axes[2][2]);
    centre = toBt(desc.centre_m);
    state.mass_kg = desc.mass_kg;
  }
  state.mesh_from_body = btTransform(principal_axes, centre);
  state.body_from_mesh = state.mesh_from_body.inverse();

  // Surface in the body frame, and its bounding box for the size-dependent tolerances.
  state.body_xyz.resize(3 * vertex_count);
  btVector3 lo(SIMD_INFINITY, SIMD_INFINITY, SIMD_INFINITY), hi = -lo;
  for (size_t v = 0; v < vertex_count; ++v) {
    const btVector3 p = state.body_from_mesh(
        btVector3(desc.surface_positions[3 * v], desc.surface_positions[3 * v + 1], desc.surface_positions[3 * v + 2]));
    for (int k = 0; k < 3; ++k) state.body_xyz[3 * v + size_t(k)] = p[k];
    lo.setMin(p);
    hi.setMax(p);
  }
  const btVector3 extent = hi - lo;
  state.size_m = std::max({extent.x(), extent.y(), extent.z()});
  state.min_extent_m = std::min({extent.x(), extent.y(), extent.z()});
  state.compliance_per_pa = desc.compliance_per_pa;
  // The Hertz patch takes each body as the sphere of its volume (as the render's contact time
  // does); a static body is flat.
  state.contact_radius_m =
      desc.is_static ? 0.0
      : desc.contact_radius_m > 0.0
          ? desc.contact_radius_m
          : std::cbrt(3.0 * std::abs(meshVolume(state.body_xyz, desc.surface_triangles)) / (4.0 * M_PI));
  if (!(state.size_m > 0.0)) {
    return badInput(bodyLabel(desc, index) + ": all " + std::to_string(vertex_count) +
                    " surface vertices coincide (zero size)");
  }
  // Collision margin: Bullet's default 4 cm would swallow a 2 cm object. Default 2% of the
  // thinnest extent, refined per shape kind below.
  state.margin_m = std::clamp(0.02 * state.min_extent_m, 1e-5, 0.01);
  if (state.min_extent_m <= 0.0) state.margin_m = std::clamp(0.002 * state.size_m, 1e-5, 0.01);
  return {};
}

Status Simulation::buildHullShape(size_t index, BodyState& state, const std::shared_ptr<const SimHull>& hull) {
  const SimBodyDesc& desc = descs_[index];
  const size_t vertex_count = desc.surface_positions.size() / 3;
  const size_t hull_vertices = hull->vertices_xyz.size() / 3;
  const double hull_volume = hull->volume_m3;
  if (hull_vertices == 0) {
    return badInput(bodyLabel(desc, index) + ": cannot build a convex hull of " + std::to_string(vertex_count) +
                    " vertices");
  }
  // A hull whose points all lie on one sphere about the centre of mass is a sphere: Bullet's
  // sphere shape is exact and costs O(1) per support query instead of O(points), which is what
  // makes marbles rolling in a GImpact bowl affordable.
  double radius_sum = 0.0, radius_min = INFINITY, radius_max = 0.0;
  for (size_t v = 0; v < hull_vertices; ++v) {
    const double r = hullVertex(*hull, v).length();
    radius_sum += r;
    radius_min = std::min(radius_min, r);
    radius_max = std::max(radius_max, r);
  }
  const double radius_mean = hull_vertices > 0 ? radius_sum / double(hull_vertices) : 0.0;
  // All points on one sphere is not enough (a box's corners are too): the hull must also fill
  // the sphere.
  const double sphere_volume = 4.0 / 3.0 * M_PI * radius_mean * radius_mean * radius_mean;
  if (hull_vertices >= 12 && radius_max - radius_min <= 0.02 * radius_mean && hull_volume >= 0.9 * sphere_volume) {
    // Volume-equivalent radius, so the sphere neither floats above nor sinks into the ground.
    const double radius = std::cbrt(3.0 * std::abs(meshVolume(state.body_xyz, desc.surface_triangles)) / (4.0 * M_PI));
    state.shape = std::make_unique<btSphereShape>(radius > 0 ? radius : radius_mean);
    state.sphere_radius_m = radius > 0 ? radius : radius_mean;
    state.margin_m = state.shape->getMargin();
  } else {
    auto convex = std::make_unique<btConvexHullShape>();
    if (hull_vertices <= kMaxPolyhedralVertices) {
      // Polyhedral features make hull-hull contacts use face clipping, which yields the whole
      // contact patch (up to 4 points) in the first substep; plain GJK/EPA adds one point per
      // substep, so a box landing flat on another first touches at one corner, tips and slides
      // [Bullet btPolyhedralContactClipping]. The clipping works on the bare points (no margin)
      // while GJK paths (ground, triangles) add the margin, so the points are the hull itself
      // and the margin is tiny: 0.1% of the thinnest extent, the most a body can float.
      // Edge-edge clipping costs O(edges^2) per pair, hence only for modest hulls.
      state.margin_m = std::clamp(0.001 * state.min_extent_m, 1e-6, 1e-3);
      for (size_t v = 0; v < hull_vertices; ++v) convex->addPoint(hullVertex(*hull, v), false);
      convex->recalcLocalAabb();
      convex->setMargin(state.margin_m);
      convex->initializePolyhedralFeatures();
      // A hull that is a box about the centre of mass along the body axes (a box primitive,
      // whose principal axes are its edges) gets a box twin for spheres: the same solid as GJK
      // sees the hull (the points' box grown by the margin, edges rounded by it), on which a
      // sphere takes the exact closest-point test instead of GJK (SphereAwareConvexConvex).
      if (btVector3 half_m; boxHalfExtents(*hull, 1e-9 * state.size_m, half_m)) {
        state.box_twin = std::make_unique<btBoxShape>(half_m + btVector3(1, 1, 1) * state.margin_m);
        state.box_twin->setMargin(state.margin_m);
        sphere_hull_->box_twins[convex.get()] = state.box_twin.get();
      }
    } else {
      // Large hull, GJK/EPA only: those need a real margin for robust penetration depths, and
      // btConvexHullShape puts it outside the points. Shrink the hull by the margin first
      // (btConvexHullComputer moves each face inwards) so the collision surface is the mesh's
      // hull with edges rounded by the margin; the shrink is clamped to a quarter of the inner
      // radius for thin bodies.
      const std::shared_ptr<const SimHull> shrunk = bodyHull(state.body_xyz, state.margin_m, 0.25);
      const double shrink = shrunk->shrink_m;
      const SimHull& used = shrink > 0.0 && !shrunk->vertices_xyz.empty() ? *shrunk : *hull;
      for (size_t v = 0; v < used.vertices_xyz.size() / 3; ++v) convex->addPoint(hullVertex(used, v), false);
      convex->recalcLocalAabb();
      if (shrink > 0.0) state.margin_m = shrink;  // the clamp may have made it smaller
      convex->setMargin(state.margin_m);
    }
    state.shape = std::move(convex);
  }
  return {};
}

Status Simulation::buildPiecesShape(size_t index, BodyState& state) {
  const SimBodyDesc& desc = descs_[index];
  const size_t vertex_count = desc.surface_positions.size() / 3;
  // Convex pieces of the surface, each a polyhedral hull as above (SAT + clipping contacts,
  // persistent manifolds per piece), within 1% of the body's size of its hollows.
  if (!desc.convex_pieces_m.empty()) {
    state.pieces_mesh = desc.convex_pieces_m;
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
      piece_settings.max_concavity_m = ConvexPiecesRecipe::concavity_of_size * state.size_m;
      piece_settings.max_edge_m = ConvexPiecesRecipe::max_edge_of_size * state.size_m;
      piece_settings.max_pieces = ConvexPiecesRecipe::max_pieces;
      ConvexPieces pieces = convexPieces(desc.surface_positions, desc.surface_triangles, piece_settings);
      state.pieces_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      known = pieces_by_surface_.emplace(key, std::move(pieces.hull_points)).first;
    }
    state.pieces_mesh = known->second;
    state.pieces_computed = true;
  }
  if (state.pieces_mesh.empty()) {
    return badInput(bodyLabel(desc, index) + ": cannot split " + std::to_string(vertex_count) +
                    " vertices into convex pieces");
  }
  state.margin_m = std::clamp(0.001 * state.min_extent_m, 1e-6, 1e-3);
  auto compound = std::make_unique<btCompoundShape>(true, int(state.pieces_mesh.size()));
  for (const std::vector<double>& points : state.pieces_mesh) {
    auto piece = std::make_unique<btConvexHullShape>();
    for (size_t k = 0; k + 2 < points.size(); k += 3)
      piece->addPoint(state.body_from_mesh(btVector3(points[k], points[k + 1], points[k + 2])), false);
    piece->recalcLocalAabb();
    piece->setMargin(state.margin_m);
    if (piece->getNumPoints() <= kMaxPolyhedralVertices) piece->initializePolyhedralFeatures();
    compound->addChildShape(btTransform::getIdentity(), piece.get());
    state.pieces.push_back(std::move(piece));
  }
  state.shape = std::move(compound);
  return {};
}

void Simulation::buildMeshShape(size_t index, BodyState& state) {
  const SimBodyDesc& desc = descs_[index];
  const size_t vertex_count = desc.surface_positions.size() / 3;
  state.indices.assign(desc.surface_triangles.begin(), desc.surface_triangles.end());
  state.mesh_interface = std::make_unique<btTriangleIndexVertexArray>(
      int(state.indices.size() / 3), state.indices.data(), int(3 * sizeof(int)), int(vertex_count),
      state.body_xyz.data(), int(3 * sizeof(btScalar)));
  // Triangles carry their margin on both sides: keep it thinner than for hulls.
  // (They also add to the surface, unlike the shrunk hull: a tray placed on the ground starts
  // that far inside it, so keep the margin small: 0.2% of the thinnest extent, at most 1 mm.)
  state.margin_m = std::clamp(0.002 * state.min_extent_m, 1e-5, 1e-3);
  if (desc.is_static) {
    auto bvh = std::make_unique<btBvhTriangleMeshShape>(state.mesh_interface.get(), true);
    bvh->setMargin(state.margin_m);
    state.shape = std::move(bvh);
  } else {
    // A moving concave body needs GImpact (btBvhTriangleMeshShape is static only).
    auto gimpact = std::make_unique<btGImpactMeshShape>(state.mesh_interface.get());
    gimpact->setMargin(state.margin_m);
    gimpact->updateBound();
    state.shape = std::move(gimpact);
    if (!gimpact_registered_) {
      btGImpactCollisionAlgorithm::registerAlgorithm(dispatcher_.get());
      gimpact_registered_ = true;
    }
  }
}

void Simulation::addRigidBody(size_t index, const btQuaternion& orientation, std::unique_ptr<BodyState> state) {
  const SimBodyDesc& desc = descs_[index];
  // A driven body starts where its path is at t = 0 (drive() moves it on from there).
  const PathPose start = pathPose(desc.path, 0.0);
  const btTransform world_from_mesh =
      desc.path.empty() ? btTransform(orientation, toBt(desc.position_m))
                        : btTransform(btQuaternion(start.orientation_wxyz[1], start.orientation_wxyz[2],
                                                   start.orientation_wxyz[3], start.orientation_wxyz[0]),
                                      toBt(start.position_m));
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
  state->rigid->setUserPointer(state.get());
  state->breaking_threshold_m = state->shape->getContactBreakingThreshold(gContactBreakingThreshold);
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
    if (!desc.path.empty()) {
      // The hand sets its velocities every substep (drive()): it must never sleep. It holds the
      // orientation, so nothing turns the body but the hand: no inverse inertia for the solver.
      // (Correcting between substeps instead is an explicit controller against a rigid contact:
      // a spoon touching down with its tip away from its centre of mass rocked up to m/s.) The
      // gyroscopic term goes with it.
      state->driven = true;
      state->rigid->setActivationState(DISABLE_DEACTIVATION);
      state->rigid->setInvInertiaDiagLocal(btVector3(0, 0, 0));
      state->rigid->updateInertiaTensor();
      state->rigid->setFlags(state->rigid->getFlags() & ~BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY);
    }
  }
  world_->addRigidBody(state->rigid.get());
  // A static body is asleep for good: Bullet skips a pair only when both bodies are inactive, so
  // an awake table kept the narrow phase running for a glass asleep on it (6 s of GImpact
  // triangle tests for 1.3 s of sleep). Moving bodies still collide with it.
  if (desc.is_static) state->rigid->forceActivationState(ISLAND_SLEEPING);
  bodies_.push_back(std::move(state));
}

}  // namespace strike::detail

namespace strike {

uint64_t simHullRecipe() { return uint64_t(BT_BULLET_VERSION) * 100 + sizeof(btScalar); }

}  // namespace strike
