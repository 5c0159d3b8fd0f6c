// SPDX-License-Identifier: MIT
// The integration path a game developer copies: a game steps its own Bullet world, reports
// contacts to libstrike through the C API only (strike.h), and an audio callback pulls blocks.
//
// Usage: strike_game BANK.modes OUT.wav [SECONDS]
// Four plates of the bank's object are dropped onto a ground plane and onto each other, and a
// steel ball rolls across a fifth plate lying on the ground (rolling sound). After
// every physics substep the game reports the step through strike_step(): every body's pose and
// sleep state, and every contact point of Bullet's manifolds, resting ones included (both bodies'
// sides, world-frame point, normal + friction impulse, approach speed from the bodies' relative
// velocity). libstrike's contact scheduler decides what is an impact, a steady load or a change.
// Each point also carries what rolling and sliding need (docs/contact.md): its normal force, the
// slip and rolling velocities, and where it is on the partner's surface; the objects carry their
// surface roughness. The ball is not an object (a 2.4 cm steel ball rings far above hearing):
// the plate's contact with it names it by its material, radius, mass and roughness.
//
// Threads: here everything runs on one thread so the WAV is deterministic. In a game,
// strike_step() is called from the physics thread (it is [any-thread] and lock-free) and
// audioCallback() is the audio device's callback, which only calls strike_render().
#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include "strike/strike.h"

namespace {

constexpr double kRate = 48000.0;
constexpr uint32_t kBlock = 256;
constexpr int kSubsteps = 4;  // per 60 Hz game frame: 240 Hz physics
constexpr double kFrameDt = 1.0 / 60.0;

// Minimal 16-bit PCM stereo WAV writer (RIFF): no libsndfile needed.
bool writeWav(const char* path, const std::vector<float>& interleaved, uint32_t rate, double gain, size_t& clipped) {
  std::FILE* f = std::fopen(path, "wb");
  if (!f) return false;
  const uint32_t data_bytes = static_cast<uint32_t>(interleaved.size() * 2);
  auto u32 = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) std::fputc(static_cast<int>((v >> (8 * i)) & 0xff), f);
  };
  auto u16 = [&](uint16_t v) { std::fputc(v & 0xff, f), std::fputc(v >> 8, f); };
  std::fwrite("RIFF", 1, 4, f), u32(36 + data_bytes), std::fwrite("WAVEfmt ", 1, 8, f);
  u32(16), u16(1), u16(2), u32(rate), u32(rate * 4), u16(4), u16(16);
  std::fwrite("data", 1, 4, f), u32(data_bytes);
  clipped = 0;
  for (float x : interleaved) {
    double v = std::round(static_cast<double>(x) * gain * 32767.0);
    if (v > 32767.0 || v < -32768.0) ++clipped, v = v > 0 ? 32767.0 : -32768.0;
    u16(static_cast<uint16_t>(static_cast<int16_t>(v)));
  }
  return std::fclose(f) == 0;
}

struct Body {
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btDefaultMotionState> motion;
  std::unique_ptr<btRigidBody> body;
  strike_object_id sound{0, 0};
};

// Bullet user indices of the bodies that are not objects (objects: their index in `bodies`).
constexpr int kGround = -1, kBall = -2;

// Surfaces, from assets/materials.json: R_q and correlation length of the roughness, m.
constexpr double kSteelRoughness_m = 4e-7, kSteelCorrelation_m = 1e-5, kSteelRestitution = 0.6;
constexpr double kConcreteRoughness_m = 3e-5, kConcreteCorrelation_m = 3e-4, kConcreteRestitution = 0.4;
constexpr double kBallRadius_m = 0.012, kSteelDensity_kg_m3 = 7850.0;

btVector3 tangential(const btVector3& v, const btVector3& normal) { return v - normal * normal.dot(v); }

void poseOf(const btRigidBody& b, double pos[3], double quat[4]) {
  const btTransform& t = b.getWorldTransform();
  const btQuaternion q = t.getRotation();
  pos[0] = t.getOrigin().x(), pos[1] = t.getOrigin().y(), pos[2] = t.getOrigin().z();
  quat[0] = q.w(), quat[1] = q.x(), quat[2] = q.y(), quat[3] = q.z();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s BANK.modes OUT.wav [SECONDS]\n", argv[0]);
    return 1;
  }
  const double seconds = argc > 3 ? std::atof(argv[3]) : 3.0;

  // --- audio: one context, one bank, one sounding object per body --------------------------
  strike_context_config cfg = strike_context_config_default();
  cfg.sample_rate_hz = kRate;
  cfg.max_block_frames = kBlock;
  cfg.channels = 2;
  strike_context ctx = nullptr;
  strike_status st = strike_context_create(&cfg, &ctx);
  if (st != STRIKE_OK) {
    std::fprintf(stderr, "strike_context_create: %s\n", strike_status_string(st));
    return 2;
  }
  strike_bank bank = nullptr;
  if (strike_bank_load_file(ctx, argv[1], &bank) != STRIKE_OK) {
    std::fprintf(stderr, "%s\n", strike_context_last_error(ctx));
    strike_context_destroy(ctx);
    return 1;
  }
  strike_bank_info info;
  std::memset(&info, 0, sizeof info);
  info.struct_size = sizeof info;
  strike_bank_get_info(bank, &info);
  const double half[3] = {0.5 * (info.bounds_max_m[0] - info.bounds_min_m[0]),
                          0.5 * (info.bounds_max_m[1] - info.bounds_min_m[1]),
                          std::max(0.005, 0.5 * (info.bounds_max_m[2] - info.bounds_min_m[2]))};
  const double listener[3] = {0.0, -1.5, 0.5}, facing_plus_y[4] = {1, 0, 0, 0};
  strike_listener_set_pose(ctx, listener, facing_plus_y);

  // --- physics: the game's own Bullet world -------------------------------------------------
  btDefaultCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher(&collision_config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &collision_config);
  world.setGravity(btVector3(0, 0, -9.81));
  btStaticPlaneShape ground_shape(btVector3(0, 0, 1), 0);
  btRigidBody ground(btRigidBody::btRigidBodyConstructionInfo(0, nullptr, &ground_shape));
  ground.setRestitution(0.3);
  world.addRigidBody(&ground);

  // Plates 0-3 fall; plate 4 lies on the ground for the ball to roll across.
  std::vector<Body> bodies(5);
  const size_t kRollPlate = 4;
  for (size_t k = 0; k < bodies.size(); ++k) {
    Body& b = bodies[k];
    const double mass = info.mass_kg > 0 ? info.mass_kg : 1.0;
    b.shape = std::make_unique<btBoxShape>(btVector3(half[0], half[1], half[2]));
    btVector3 inertia;
    b.shape->calculateLocalInertia(mass, inertia);
    btTransform start;
    start.setIdentity();
    start.setOrigin(btVector3(0.15 * static_cast<double>(k) - 0.2, 0.05 * static_cast<double>(k), 0.3 + 0.25 * k));
    start.setRotation(btQuaternion(btVector3(1, 0.3 * k, 0).normalized(), 0.2 + 0.3 * k));
    if (k == kRollPlate) start = btTransform(btQuaternion::getIdentity(), btVector3(0.9, 0.0, half[2]));
    b.motion = std::make_unique<btDefaultMotionState>(start);
    b.body = std::make_unique<btRigidBody>(
        btRigidBody::btRigidBodyConstructionInfo(mass, b.motion.get(), b.shape.get(), inertia));
    b.body->setRestitution(0.4);
    b.body->setUserIndex(static_cast<int>(k));
    world.addRigidBody(b.body.get());

    strike_object_config oc = strike_object_config_default();
    oc.bank = bank;
    poseOf(*b.body, oc.position, oc.orientation);
    oc.roughness_rms_m = kSteelRoughness_m;  // the test bank is a steel plate
    oc.roughness_correlation_m = kSteelCorrelation_m;
    oc.roughness_seed = 100 + k;  // each plate its own surface
    oc.restitution = kSteelRestitution;
    if (strike_object_add(ctx, &oc, &b.sound) != STRIKE_OK) {
      std::fprintf(stderr, "%s\n", strike_context_last_error(ctx));
      return 2;
    }
  }

  // The ball starts on plate 4's near edge, rolling without slip at 0.25 m/s along +x (spin
  // v / r about +y), so it crosses the 0.2 m plate in ~0.7 s and rolls off onto the ground.
  const double ball_mass_kg = kSteelDensity_kg_m3 * 4.0 / 3.0 * M_PI * std::pow(kBallRadius_m, 3);
  const double ball_speed_m_s = 0.25;
  btSphereShape ball_shape(kBallRadius_m);
  btVector3 ball_inertia;
  ball_shape.calculateLocalInertia(ball_mass_kg, ball_inertia);
  btDefaultMotionState ball_motion(
      btTransform(btQuaternion::getIdentity(), btVector3(0.82, 0.0, 2.0 * half[2] + kBallRadius_m)));
  btRigidBody ball(btRigidBody::btRigidBodyConstructionInfo(ball_mass_kg, &ball_motion, &ball_shape, ball_inertia));
  ball.setRestitution(kSteelRestitution);
  ball.setUserIndex(kBall);
  ball.setLinearVelocity(btVector3(ball_speed_m_s, 0, 0));
  ball.setAngularVelocity(btVector3(0, ball_speed_m_s / kBallRadius_m, 0));
  world.addRigidBody(&ball);
  ground.setUserIndex(kGround);

  // --- the loop -----------------------------------------------------------------------------
  std::vector<float> wav;
  std::vector<float> left(kBlock), right(kBlock);
  float* out[2] = {left.data(), right.data()};
  double audio_time = 0.0;  // seconds rendered so far
  uint64_t reported_steps = 0, reported_contacts = 0, reported_states = 0;
  std::vector<strike_contact> contacts;
  std::vector<strike_body_state> states(bodies.size());
  const int frames = static_cast<int>(std::ceil(seconds / kFrameDt));
  for (int frame = 0; frame < frames; ++frame) {
    const double frame_start = frame * kFrameDt;
    for (int sub = 0; sub < kSubsteps; ++sub) {
      const double dt = kFrameDt / kSubsteps;
      world.stepSimulation(dt, 0, dt);
      const double t = frame_start + (sub + 1) * dt;
      // One strike_step per physics step: where every body is (asleep = Bullet deactivated it),
      // and every contact point Bullet solved, resting ones included. libstrike's contact
      // scheduler decides what is an impact, a steady load (silent) or a change of load.
      contacts.clear();
      // The velocity of a body's material at a world point (0 for the ground).
      auto materialVelocity = [](const btRigidBody* body, const btVector3& p) {
        return body->getVelocityInLocalPoint(p - body->getCenterOfMassPosition());
      };
      for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
        btPersistentManifold* pm = dispatcher.getManifoldByIndexInternal(m);
        const auto* a = static_cast<const btRigidBody*>(pm->getBody0());
        const auto* b = static_cast<const btRigidBody*>(pm->getBody1());
        for (int c = 0; c < pm->getNumContacts(); ++c) {
          const btManifoldPoint& cp = pm->getContactPoint(c);
          if (cp.getAppliedImpulse() <= 0.0) continue;  // touching, but no force this step
          // Approach speed along the normal (B to A): > 5 cm/s is an impact, else part of a load.
          const btVector3 va = a->getVelocityInLocalPoint(cp.getPositionWorldOnA() - a->getCenterOfMassPosition());
          const btVector3 vb = b->getVelocityInLocalPoint(cp.getPositionWorldOnB() - b->getCenterOfMassPosition());
          const double approach = -(va - vb).dot(cp.m_normalWorldOnB);
          // The impulse on A over the step: normal plus the two friction directions; B gets -it.
          const btVector3 j = cp.m_normalWorldOnB * cp.getAppliedImpulse() +
                              cp.m_lateralFrictionDir1 * cp.m_appliedImpulseLateral1 +
                              cp.m_lateralFrictionDir2 * cp.m_appliedImpulseLateral2;
          const btRigidBody* sides[2] = {a, b};
          const btVector3 points[2] = {cp.getPositionWorldOnA(), cp.getPositionWorldOnB()};
          for (int side = 0; side < 2; ++side) {
            const btRigidBody* body = sides[side];
            const btRigidBody* other = sides[1 - side];
            if (body->getUserIndex() < 0) continue;  // the ground and the ball are not heard
            strike_contact k = strike_contact_default();
            k.object = bodies[static_cast<size_t>(body->getUserIndex())].sound;
            if (other->getUserIndex() >= 0) k.partner = bodies[static_cast<size_t>(other->getUserIndex())].sound;
            k.frame = STRIKE_FRAME_WORLD;
            const btVector3 on_body = side == 0 ? j : -j;
            for (int i = 0; i < 3; ++i) k.point[i] = points[side][i], k.impulse[i] = on_body[i];
            k.normal_speed_m_s = approach > 0.0 ? approach : 0.0;
            k.partner_radius_m = other->getUserIndex() == kGround ? 0.0 : 0.002;  // the ground is flat; corners sharp
            // Continuous contact. The slip: this body's surface relative to the partner's. The
            // contact point rides under the ball's centre when one side is the ball, so it travels
            // over this body's surface at (centre - material); between plates it stays with this
            // plate's material (they slide, nothing rolls).
            const btVector3& normal = cp.m_normalWorldOnB;
            const btVector3 here = materialVelocity(body, points[side]);
            const btVector3 there = materialVelocity(other, points[side]);
            const btVector3 slip = tangential(here - there, normal);
            const btVector3 rolling =
                other->getUserIndex() == kBall ? tangential(other->getLinearVelocity() - here, normal) : btVector3(0, 0, 0);
            k.normal_force_n = cp.getAppliedImpulse() / dt;
            for (int i = 0; i < 3; ++i) k.slip_velocity_m_s[i] = slip[i], k.rolling_velocity_m_s[i] = rolling[i];
            // Where the point is on the partner's surface, in a frame fixed to that surface, so
            // the same spot always has the same roughness (for an object: its mesh frame).
            const btVector3 on_partner = other->getWorldTransform().invXform(points[side]);
            for (int i = 0; i < 3; ++i) k.partner_point[i] = on_partner[i];
            if (other->getUserIndex() == kBall) {
              k.partner_youngs_pa = 2.0e11, k.partner_poisson = 0.29;
              k.partner_radius_m = kBallRadius_m, k.partner_mass_kg = ball_mass_kg;
              k.partner_roughness_rms_m = kSteelRoughness_m, k.partner_roughness_correlation_m = kSteelCorrelation_m;
              k.partner_roughness_seed = 1, k.partner_restitution = kSteelRestitution;
            } else if (other->getUserIndex() == kGround) {
              k.partner_youngs_pa = 3.0e10, k.partner_poisson = 0.2;
              k.partner_roughness_rms_m = kConcreteRoughness_m, k.partner_roughness_correlation_m = kConcreteCorrelation_m;
              k.partner_roughness_seed = 2, k.partner_restitution = kConcreteRestitution;
            }
            contacts.push_back(k);
          }
        }
      }
      for (size_t k = 0; k < bodies.size(); ++k) {
        states[k] = strike_body_state{};
        states[k].object = bodies[k].sound;
        poseOf(*bodies[k].body, states[k].position, states[k].orientation);
        states[k].asleep = bodies[k].body->isActive() ? 0 : 1;
      }
      strike_step_desc step = strike_step_desc_default();
      step.end_time_s = t;
      step.duration_s = dt;
      step.states = states.data();
      step.state_count = static_cast<uint32_t>(states.size());
      step.contacts = contacts.data();
      step.contact_count = static_cast<uint32_t>(contacts.size());
      if (strike_step(ctx, &step) != STRIKE_OK) {
        std::fprintf(stderr, "strike_step failed (queue full?)\n");
        return 2;
      }
      ++reported_steps;
      reported_contacts += contacts.size();
      reported_states += states.size();
    }
    // The "audio callback": pull whole blocks up to the end of this game frame.
    while (audio_time + kBlock / kRate <= frame_start + kFrameDt + 1e-12) {
      if (strike_render(ctx, out, 2, kBlock) != STRIKE_OK) return 2;
      for (uint32_t n = 0; n < kBlock; ++n) wav.push_back(left[n]), wav.push_back(right[n]);
      audio_time += kBlock / kRate;
    }
  }

  strike_stats stats;
  std::memset(&stats, 0, sizeof stats);
  stats.struct_size = sizeof stats;
  strike_context_get_stats(ctx, &stats);
  float peak = 0.0f, tail = 0.0f;
  const size_t tail_from =
      wav.size() > static_cast<size_t>(2 * 0.25 * kRate) ? wav.size() - static_cast<size_t>(2 * 0.25 * kRate) : 0;
  for (size_t n = 0; n < wav.size(); ++n) {
    peak = std::max(peak, std::fabs(wav[n]));
    if (n >= tail_from) tail = std::max(tail, std::fabs(wav[n]));
  }
  const double gain = peak > 0 ? 0.5 / peak : 1.0;  // normalize to -6 dBFS
  size_t clipped = 0;
  if (!writeWav(argv[2], wav, static_cast<uint32_t>(kRate), gain, clipped)) {
    std::fprintf(stderr, "%s: cannot write\n", argv[2]);
    return 1;
  }
  std::printf(
      "%s: %.2f s, %llu steps, %llu contacts reported (%llu queued): %llu impacts, %llu sustained, %llu load "
      "changes, %llu load holds; peak %.3g full scale = %.3g Pa (normalized x%.3g), %zu clipped; last 0.25 s "
      "%.1f dB re the peak\n",
      argv[2], audio_time, static_cast<unsigned long long>(stats.steps),
      static_cast<unsigned long long>(reported_contacts), static_cast<unsigned long long>(stats.contacts_queued),
      static_cast<unsigned long long>(stats.impacts_scheduled),
      static_cast<unsigned long long>(stats.sustained_contacts), static_cast<unsigned long long>(stats.load_changes),
      static_cast<unsigned long long>(stats.load_holds), static_cast<double>(peak),
      static_cast<double>(peak) * cfg.output_full_scale_pa, gain, clipped,
      20.0 * std::log10(std::max(static_cast<double>(tail), 1e-30) / std::max(static_cast<double>(peak), 1e-30)));
  std::printf("rolling and sliding: %llu contact sources started, %llu dropped\n",
              static_cast<unsigned long long>(stats.continuous_contacts),
              static_cast<unsigned long long>(stats.continuous_dropped));
  world.removeRigidBody(&ball);
  for (Body& b : bodies) world.removeRigidBody(b.body.get());
  world.removeRigidBody(&ground);
  strike_bank_destroy(bank);
  strike_context_destroy(ctx);
  // What the test checks: every step and contact arrived (none dropped), the drops struck,
  // the resting plates were reported as sustained contact, the ball's rolling drove a plate,
  // and there was sound.
  const bool ok = stats.steps == reported_steps && stats.contacts_queued == reported_contacts &&
                  stats.contacts_dropped_queue_full == 0 && stats.contacts_dropped_stale == 0 &&
                  stats.impacts_scheduled > 0 && stats.sustained_contacts > 0 && stats.continuous_contacts > 0 &&
                  peak > 0.0f && reported_states > 0;
  return ok ? 0 : 3;
}
