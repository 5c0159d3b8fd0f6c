// SPDX-License-Identifier: MIT
// The integration path a game developer copies: a game steps its own Bullet world, reports
// contacts to libstrike through the C API only (strike.h), and an audio callback pulls blocks.
//
// Usage: strike_game BANK.modes OUT.wav [SECONDS]
// Four plates of the bank's object are dropped onto a ground plane and onto each other. After
// every physics substep, new contact points with a real impulse become strike_impact() calls
// (world-frame point and impulse, relative normal speed for the Hertz contact time, and a sample
// offset that places them inside the audio block). Object poses follow the bodies every frame.
//
// Threads: here everything runs on one thread so the WAV is deterministic. In a game,
// strike_impact() is called from the physics thread (it is [any-thread] and lock-free) and
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
constexpr int kSubsteps = 4;        // per 60 Hz game frame: 240 Hz physics
constexpr double kFrameDt = 1.0 / 60.0;

// Minimal 16-bit PCM stereo WAV writer (RIFF): no libsndfile needed.
bool writeWav(const char* path, const std::vector<float>& interleaved, uint32_t rate, double gain, size_t& clipped) {
  std::FILE* f = std::fopen(path, "wb");
  if (!f) return false;
  const uint32_t data_bytes = static_cast<uint32_t>(interleaved.size() * 2);
  auto u32 = [&](uint32_t v) { for (int i = 0; i < 4; ++i) std::fputc(static_cast<int>((v >> (8 * i)) & 0xff), f); };
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

  std::vector<Body> bodies(4);
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
    b.motion = std::make_unique<btDefaultMotionState>(start);
    b.body = std::make_unique<btRigidBody>(btRigidBody::btRigidBodyConstructionInfo(mass, b.motion.get(), b.shape.get(), inertia));
    b.body->setRestitution(0.4);
    b.body->setUserIndex(static_cast<int>(k));
    world.addRigidBody(b.body.get());

    strike_object_config oc = strike_object_config_default();
    oc.bank = bank;
    poseOf(*b.body, oc.position, oc.orientation);
    if (strike_object_add(ctx, &oc, &b.sound) != STRIKE_OK) {
      std::fprintf(stderr, "%s\n", strike_context_last_error(ctx));
      return 2;
    }
  }

  // --- the loop -----------------------------------------------------------------------------
  std::vector<float> wav;
  std::vector<float> left(kBlock), right(kBlock);
  float* out[2] = {left.data(), right.data()};
  double audio_time = 0.0;  // seconds rendered so far
  uint64_t impacts = 0;
  const int frames = static_cast<int>(std::ceil(seconds / kFrameDt));
  for (int frame = 0; frame < frames; ++frame) {
    const double frame_start = frame * kFrameDt;
    for (int sub = 0; sub < kSubsteps; ++sub) {
      world.stepSimulation(kFrameDt / kSubsteps, 0, kFrameDt / kSubsteps);
      const double t = frame_start + (sub + 1) * kFrameDt / kSubsteps;
      for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
        btPersistentManifold* pm = dispatcher.getManifoldByIndexInternal(m);
        const auto* a = static_cast<const btRigidBody*>(pm->getBody0());
        const auto* b = static_cast<const btRigidBody*>(pm->getBody1());
        for (int c = 0; c < pm->getNumContacts(); ++c) {
          const btManifoldPoint& cp = pm->getContactPoint(c);
          // Only the step a contact appears (lifetime 1) with a real impulse is an impact; resting
          // contact would be a stream of STRIKE_PULSE_BOX impacts, left out here.
          if (cp.getLifeTime() > 1 || cp.getAppliedImpulse() < 1e-4) continue;
          const btVector3 va = a->getVelocityInLocalPoint(cp.getPositionWorldOnA() - a->getCenterOfMassPosition());
          const btVector3 vb = b->getVelocityInLocalPoint(cp.getPositionWorldOnB() - b->getCenterOfMassPosition());
          const double speed = std::fabs((va - vb).dot(cp.m_normalWorldOnB));
          // The normal points from B to A: A receives +impulse * n, B receives -impulse * n.
          const btRigidBody* sides[2] = {a, b};
          const btVector3 points[2] = {cp.getPositionWorldOnA(), cp.getPositionWorldOnB()};
          for (int s = 0; s < 2; ++s) {
            const btRigidBody* body = sides[s];
            if (body->getInvMass() == 0.0 || body->getUserIndex() < 0) continue;
            const btVector3 j = cp.m_normalWorldOnB * (s == 0 ? cp.getAppliedImpulse() : -cp.getAppliedImpulse());
            strike_impact_desc d = strike_impact_desc_default();
            d.object = bodies[static_cast<size_t>(body->getUserIndex())].sound;
            d.frame = STRIKE_FRAME_WORLD;
            for (int i = 0; i < 3; ++i) d.point[i] = points[s][i], d.impulse[i] = j[i];
            d.normal_speed_m_s = speed > 1e-3 ? speed : 1e-3;
            d.striker_radius_m = 0.002;  // box corners and edges are sharp
            d.sample_offset = static_cast<uint32_t>(std::max(0.0, (t - audio_time) * kRate));
            if (strike_impact(ctx, &d) == STRIKE_OK) ++impacts;
          }
        }
      }
    }
    // Poses follow the bodies ([main-thread]; applied at the next render).
    for (Body& b : bodies) {
      double pos[3], quat[4];
      poseOf(*b.body, pos, quat);
      strike_object_set_pose(ctx, b.sound, pos, quat);
    }
    // The "audio callback": pull whole blocks up to the end of this game frame.
    while (audio_time + kBlock / kRate <= frame_start + kFrameDt + 1e-12) {
      if (strike_render(ctx, out, 2, kBlock) != STRIKE_OK) return 2;
      for (uint32_t n = 0; n < kBlock; ++n) wav.push_back(left[n]), wav.push_back(right[n]);
      audio_time += kBlock / kRate;
    }
  }

  strike_stats stats;
  strike_context_get_stats(ctx, &stats);
  float peak = 0.0f;
  for (float x : wav) peak = std::max(peak, std::fabs(x));
  const double gain = peak > 0 ? 0.5 / peak : 1.0;  // normalize to -6 dBFS
  size_t clipped = 0;
  if (!writeWav(argv[2], wav, static_cast<uint32_t>(kRate), gain, clipped)) {
    std::fprintf(stderr, "%s: cannot write\n", argv[2]);
    return 1;
  }
  std::printf("%s: %.2f s, %llu impacts queued, %llu scheduled, %llu dropped, peak %.3g full scale = %.3g Pa (normalized x%.3g), %zu clipped\n",
              argv[2], audio_time, static_cast<unsigned long long>(impacts),
              static_cast<unsigned long long>(stats.impacts_scheduled),
              static_cast<unsigned long long>(stats.impacts_dropped_queue_full + stats.impacts_dropped_capacity),
              static_cast<double>(peak), static_cast<double>(peak) * cfg.output_full_scale_pa, gain, clipped);
  for (Body& b : bodies) world.removeRigidBody(b.body.get());
  world.removeRigidBody(&ground);
  strike_bank_destroy(bank);
  strike_context_destroy(ctx);
  return impacts > 0 && peak > 0.0f ? 0 : 3;
}
