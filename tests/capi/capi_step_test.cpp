// SPDX-License-Identifier: MIT
// libstrike 0.3 through its C API: physics steps (strike_step), the listener model as a game hears
// it, strike_context_reset, growing output structs (struct_size), the bank's physical data and
// the logged refusals of strike_context_create. The engine-level versions of the step scenarios
// are tests/unit/synth/engine_test.cpp (ContactScheduler.*, Listener.*); these feed the same
// physics through the public ABI, as a game would.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "strike/bank/bank.hpp"
#include "strike/strike.h"
#include "test_bank.hpp"

namespace {

constexpr double kRate = 48000.0;
constexpr double kSpeedOfSound = 343.0;  // m/s, dry air at 20 C (strike.h: distance / 343 m/s)

/// The bottom of a 10 cm square steel box as a 3x3 grid, centre of mass 5 cm above it: shapes
/// differ from corner to corner, so moving the load between corners changes the modal force
/// (what a physics engine's flickering contact points do). rayleigh_mass 10/s: 60 dB in 1.4 s.
strike::ModeBank boxBank(double rayleigh_mass = 10.0) {
  strike::ModeBank b;
  b.material.name = "steel";
  b.material.youngs_pa = 2.0e11;
  b.material.poisson = 0.3;
  b.material.density_kg_m3 = 7850.0;
  b.material.rayleigh_stiffness = 1e-8;
  b.material.rayleigh_mass = rayleigh_mass;
  b.mesh_source = "test:box-bottom";
  b.tool_version = "strike capi step test";
  b.mass_kg = 1.0;
  b.volume_m3 = 1.0 / 7850.0;
  b.centre_m = {0.0, 0.0, 0.05};
  // A 10 cm cube of 1 kg: m a^2 / 6 about each axis through its centre.
  b.inertia_kg_m2 = {1.0 * 0.01 / 6, 0, 0, 0, 1.0 * 0.01 / 6, 0, 0, 0, 1.0 * 0.01 / 6};
  for (double f : {523.0, 1187.0, 2450.0, 4100.0}) b.eigenvalues.push_back(std::pow(2.0 * M_PI * f, 2));
  const double h = 0.05;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      b.surface_positions.insert(b.surface_positions.end(), {(i - 1) * h, (j - 1) * h, 0.0});
      b.surface_normals.insert(b.surface_normals.end(), {0.0f, 0.0f, -1.0f});
      b.surface_node_index.push_back(static_cast<uint32_t>(3 * j + i));
    }
  for (uint32_t j = 0; j < 2; ++j)
    for (uint32_t i = 0; i < 2; ++i) {
      const uint32_t a = 3 * j + i;
      b.surface_triangles.insert(b.surface_triangles.end(), {a, a + 4, a + 1, a, a + 3, a + 4});
    }
  for (size_t m = 0; m < b.eigenvalues.size(); ++m)
    for (size_t v = 0; v < 9; ++v)
      b.shapes.insert(b.shapes.end(), {0.1f * float(m), 0.0f, float(std::cos(0.7 * double(m + 1) * double(v)))});
  return b;
}

strike_stats statsOf(strike_context ctx) {
  strike_stats s;
  std::memset(&s, 0, sizeof s);
  s.struct_size = sizeof s;
  EXPECT_EQ(strike_context_get_stats(ctx, &s), STRIKE_OK);
  return s;
}

/// A mono context with one bank loaded; renders into a growing buffer.
struct Game {
  strike_context ctx = nullptr;
  strike_bank bank = nullptr;
  std::vector<float> out;
  size_t rendered = 0;

  explicit Game(const strike::ModeBank& b, strike_context_config cfg = monoConfig()) {
    EXPECT_EQ(strike_context_create(&cfg, &ctx), STRIKE_OK);
    const std::vector<uint8_t> bytes = strike::encodeBank(b);
    EXPECT_EQ(strike_bank_load_memory(ctx, bytes.data(), bytes.size(), &bank), STRIKE_OK)
        << strike_context_last_error(ctx);
  }
  ~Game() {
    strike_bank_destroy(bank);
    strike_context_destroy(ctx);
  }
  static strike_context_config monoConfig() {
    strike_context_config c = strike_context_config_default();
    c.sample_rate_hz = kRate;
    c.channels = 1;
    c.max_block_frames = 256;
    return c;
  }
  strike_object_id add(const std::array<double, 3>& position = {0, 0, 0}, int32_t radiation = STRIKE_RADIATION_UNIT,
                       int32_t is_static = 0) {
    strike_object_config oc = strike_object_config_default();
    oc.bank = bank;
    for (int k = 0; k < 3; ++k) oc.position[k] = position[k];
    oc.radiation = radiation;
    oc.is_static = is_static;
    strike_object_id id{0, 0};
    EXPECT_EQ(strike_object_add(ctx, &oc, &id), STRIKE_OK) << strike_context_last_error(ctx);
    return id;
  }
  /// Renders whole 256-frame blocks up to `frames` in all (the audio lags the physics).
  void renderTo(size_t frames) {
    if (out.size() < frames) out.resize(frames, 0.0f);
    while (rendered + 256 <= frames) {
      float* ch[1] = {out.data() + rendered};
      ASSERT_EQ(strike_render(ctx, ch, 1, 256), STRIKE_OK);
      rendered += 256;
    }
  }
  void renderAll(size_t frames) {
    renderTo(frames);
    while (rendered < frames) {
      const uint32_t n = static_cast<uint32_t>(std::min<size_t>(256, frames - rendered));
      float* ch[1] = {out.data() + rendered};
      ASSERT_EQ(strike_render(ctx, ch, 1, n), STRIKE_OK);
      rendered += n;
    }
  }
  double peak(double from_s, double to_s) const {
    double p = 0.0;
    for (size_t n = static_cast<size_t>(from_s * kRate); n < std::min(out.size(), static_cast<size_t>(to_s * kRate));
         ++n)
      p = std::max(p, std::fabs(double(out[n])));
    return p;
  }
  double rms(double from_s, double to_s) const {
    const size_t a = static_cast<size_t>(from_s * kRate), b = static_cast<size_t>(to_s * kRate);
    double sum = 0.0;
    for (size_t n = a; n < b; ++n) sum += double(out[n]) * out[n];
    return std::sqrt(sum / double(b - a));
  }
};

// ---- the box: dropped, resting, pushed, asleep --------------------------------------

struct BoxScenario {
  double frame_s = 1.0 / 60.0;
  double duration_s = 10.0;
  bool push = false;    // from 4 s: shoved sideways, 5 N at once, then friction alternating 5 / 5.5 N
  double sleep_s = -1;  // from then on asleep (no contacts)
  double wake_s = -1;   // from then on awake again, with no contacts (lifted)
};

struct BoxResult {
  std::vector<float> out;
  strike_stats stats{};
  uint64_t contacts_sent = 0, resting_sent = 0, steps_sent = 0, push_frames = 0, asleep_frames = 0;
  double impact_peak = 0.0;
};

/// A 1 kg box dropped at 0.5 s (one impact, 3 m/s) then resting on the ground, reported through
/// strike_step every frame: its state (pose, asleep) and its resting contacts, m g per frame
/// spread over 2 to 4 points that change every frame and always balance about the centre of
/// mass (a diagonal pair; the centre and the other diagonal at half the share; all four corners).
BoxResult boxOnTheGround(const BoxScenario& sc) {
  Game game(boxBank());
  // Radiated pressure at the default output scale (1.0 = 20 Pa): levels are SPL, and the
  // context's audibility threshold (1e-6 = 20 uPa) is the threshold of hearing.
  const strike_object_id box = game.add({0, 0, 0}, STRIKE_RADIATION_PRESSURE);
  const double listener[3] = {0.0, -1.0, 0.3}, identity[4] = {1, 0, 0, 0};
  EXPECT_EQ(strike_listener_set_pose(game.ctx, listener, identity), STRIKE_OK);
  BoxResult r;
  const double m = 1.0, g = 9.81;
  const std::array<std::array<double, 3>, 4> corners = {
      {{-0.05, -0.05, 0}, {0.05, -0.05, 0}, {-0.05, 0.05, 0}, {0.05, 0.05, 0}}};
  const size_t total = static_cast<size_t>(sc.duration_s * kRate);
  int frame = 0;
  for (double t = sc.frame_s; t <= sc.duration_s + 1e-9; t += sc.frame_s, ++frame) {
    const double start = t - sc.frame_s;
    const bool asleep = sc.sleep_s >= 0 && t > sc.sleep_s && !(sc.wake_s >= 0 && t > sc.wake_s);
    const bool lifted = sc.wake_s >= 0 && t > sc.wake_s;
    strike_body_state state{};
    state.object = box;
    state.orientation[0] = 1.0;
    state.asleep = asleep ? 1 : 0;
    r.asleep_frames += asleep ? 1 : 0;
    std::vector<strike_contact> contacts;
    if (start >= 0.5 && start < 0.5 + sc.frame_s) {
      strike_contact hit = strike_contact_default();
      hit.object = box;
      hit.point[0] = corners[0][0], hit.point[1] = corners[0][1];
      hit.impulse[2] = 3.0;  // dropped from ~0.45 m: m (1 + e) v
      hit.normal_speed_m_s = 3.0;
      hit.time_s = 0.5;
      contacts.push_back(hit);
    } else if (start > 0.5 && !asleep && !lifted) {
      std::array<std::pair<std::array<double, 3>, double>, 4> shares;
      size_t count = 0;
      auto add = [&](const std::array<double, 3>& p, double fraction) { shares[count++] = {p, fraction}; };
      if (frame % 3 == 0) {
        add(corners[frame % 2 ? 0 : 1], 0.5);
        add(corners[frame % 2 ? 3 : 2], 0.5);
      } else if (frame % 3 == 1) {
        add({0, 0, 0}, 0.5);
        add(corners[1], 0.25);
        add(corners[2], 0.25);
      } else {
        for (const auto& corner : corners) add(corner, 0.25);
      }
      const bool pushing = sc.push && start > 4.0;
      r.push_frames += pushing ? 1 : 0;
      const double push = pushing ? 5.0 + 0.5 * (frame % 2) : 0.0;  // N
      for (size_t k = 0; k < count; ++k) {
        strike_contact rest = strike_contact_default();
        rest.object = box;
        for (int i = 0; i < 3; ++i) rest.point[i] = shares[k].first[i];
        rest.impulse[0] = push * shares[k].second * sc.frame_s;
        rest.impulse[2] = m * g * shares[k].second * sc.frame_s;
        rest.normal_speed_m_s = 0.0;
        contacts.push_back(rest);
        ++r.resting_sent;
      }
    }
    strike_step_desc step = strike_step_desc_default();
    step.end_time_s = t;
    step.duration_s = sc.frame_s;
    step.states = &state;
    step.state_count = 1;
    step.contacts = contacts.data();
    step.contact_count = static_cast<uint32_t>(contacts.size());
    EXPECT_EQ(strike_step(game.ctx, &step), STRIKE_OK);
    r.contacts_sent += contacts.size();
    ++r.steps_sent;
    // Audio one step behind the physics: every contact is placed at its own time.
    game.renderTo(std::min(total, static_cast<size_t>(std::floor(start * kRate))));
  }
  game.renderAll(total);
  r.stats = statsOf(game.ctx);
  r.out = game.out;
  r.impact_peak = game.peak(0.5, 1.0);
  return r;
}

double peakIn(const std::vector<float>& x, double from_s, double to_s) {
  double p = 0.0;
  for (size_t n = static_cast<size_t>(from_s * kRate); n < std::min(x.size(), static_cast<size_t>(to_s * kRate)); ++n)
    p = std::max(p, std::fabs(double(x[n])));
  return p;
}

TEST(CApiStep, ABoxRestingTenSecondsAtSixtyFramesStays60dBBelowTheImpactThatPutItThere) {
  const BoxResult r = boxOnTheGround(BoxScenario{});
  ASSERT_GT(r.impact_peak, 0.0);
  // From one ring-out after the impact (sigma >= 5/s: 60 dB in < 1.4 s, so 2.5 s is ample) to
  // the end: the steady load is silent however its points flicker.
  const double resting = peakIn(r.out, 3.0, 10.0);
  EXPECT_LT(resting, r.impact_peak * 1e-3)
      << "resting " << 20 * std::log10(resting / r.impact_peak) << " dB re the impact";
  // And inaudible: below the threshold of hearing (audibility_threshold, 20 uPa at 1.0 = 20 Pa).
  // A scheduler that sounded the flicker would be heard like the pushed box (next test).
  EXPECT_LT(resting, strike_context_config_default().audibility_threshold);
  std::printf("impact peak %.4g (%.1f dB SPL), resting peak (3-10 s) %.3g (%.1f dB re the impact)\n", r.impact_peak,
              20 * std::log10(r.impact_peak * 20.0 / 20e-6), resting,
              20 * std::log10(std::max(resting, 1e-300) / r.impact_peak));
  // Everything reported arrived and was classified: one impact, the rest sustained.
  EXPECT_EQ(r.stats.steps, r.steps_sent);
  EXPECT_EQ(r.stats.contacts_queued, r.contacts_sent);
  EXPECT_EQ(r.stats.contacts_dropped_queue_full, 0u);
  EXPECT_EQ(r.stats.sustained_contacts, r.resting_sent);
  EXPECT_EQ(r.stats.impacts_scheduled, 1u);
  // The load came on once (the first resting frame) and never changed.
  EXPECT_EQ(r.stats.load_changes, 1u);
}

TEST(CApiStep, ABoxPushedAlongTheGroundIsHeard) {
  BoxScenario pushed;
  pushed.push = true;
  const BoxResult quiet = boxOnTheGround(BoxScenario{}), loud = boxOnTheGround(pushed);
  // Every frame of the push changes the load: the friction alternates by 0.5 N, 5.1% of the
  // 9.81 N load, over the steady tolerance (2%), so each push frame is one change of load, on top
  // of the load coming on once.
  EXPECT_EQ(loud.stats.load_changes, 1u + loud.push_frames);
  // Heard: the output is radiated pressure over 20 Pa, so the context's audibility_threshold
  // (1e-6 = 20 uPa, 0 dB SPL, where modes go to sleep) is the threshold of hearing. From 6 s on
  // the drop's ring has decayed by more than 5.5 s x 5/s x 8.7 dB = 239 dB: the resting box is
  // below the threshold (its modes sleep: exact silence) and the pushed one above it.
  const double threshold = strike_context_config_default().audibility_threshold;
  const double resting = peakIn(quiet.out, 6.0, 10.0), pushing = peakIn(loud.out, 6.0, 10.0);
  EXPECT_LT(resting, threshold);
  EXPECT_EQ(resting, 0.0) << "a resting box's modes sleep";
  EXPECT_GT(pushing, threshold) << "pushing peak " << pushing;
  std::printf("pushing peak %.3g = %.1f dB SPL (%.1f dB re the impact); resting peak %.3g\n", pushing,
              20 * std::log10(pushing * 20.0 / 20e-6), 20 * std::log10(pushing / loud.impact_peak), resting);
}

TEST(CApiStep, ASleepingObjectKeepsItsLoadAndWakingWithoutContactsReleasesIt) {
  BoxScenario asleep;
  asleep.sleep_s = 6.0;
  const BoxResult r = boxOnTheGround(asleep);
  // Asleep (no contacts from 6 s on): its load is kept, silent, one hold per asleep frame.
  EXPECT_LT(peakIn(r.out, 5.9, 10.0), r.impact_peak * 1e-3);
  EXPECT_EQ(r.stats.load_holds, r.asleep_frames);
  EXPECT_EQ(r.stats.load_changes, 1u);
  // Woken at 8 s with no contacts (lifted): the load is released, a change of load, heard.
  BoxScenario lifted = asleep;
  lifted.wake_s = 8.0;
  const BoxResult w = boxOnTheGround(lifted);
  EXPECT_EQ(w.stats.load_changes, 2u) << "on, then off";
  EXPECT_LT(peakIn(w.out, 5.9, 7.95), w.impact_peak * 1e-3);
  // The asleep run is exactly silent there (the drop's ring has put its modes to sleep long
  // before); the released load rings.
  EXPECT_EQ(peakIn(r.out, 7.95, 10.0), 0.0);
  const double released = peakIn(w.out, 7.95, 10.0);
  EXPECT_GT(released, 0.0);
  std::printf("asleep: %llu holds; released peak %.3g\n", static_cast<unsigned long long>(r.stats.load_holds),
              released);
}

// ---- the listener: a ball bouncing away -----------------------------------------------------

TEST(CApiStep, EachBounceIsHeardWithTheDelayAndLevelOfItsDistance) {
  // A body struck five times identically through strike_step while it moves away from the
  // listener along x (its pose in each step's body states): the k-th strike at distance d_k
  // (point to listener) is heard at t_k + d_k / 343 m/s, with a level reference / D_k, D_k the
  // distance of its centre of mass.
  Game game(boxBank(40.0));  // sigma >= 20/s: a strike decays by 87 dB before the next
  const strike_object_id ball = game.add();
  const std::vector<double> times = {0.1, 0.6, 1.1, 1.6, 2.1};
  const std::vector<double> distances = {1.0, 3.0, 7.0, 15.0, 31.0};  // of the centre of mass
  const double step_s = 1e-3;
  const size_t total = static_cast<size_t>(2.5 * kRate);
  size_t next = 0;
  for (int n = 1; n * step_s <= 2.5 + 1e-9; ++n) {
    const double t = n * step_s;
    size_t k = 0;
    while (k + 1 < times.size() && t - step_s > times[k + 1] - 0.25) ++k;  // it moves between strikes
    strike_body_state state{};
    state.object = ball;
    state.position[0] = distances[k];
    state.position[2] = -0.05;  // centre of mass (5 cm above the mesh origin) at (d_k, 0, 0)
    state.orientation[0] = 1.0;
    strike_contact hit = strike_contact_default();
    hit.object = ball;
    hit.impulse[2] = 0.01;  // at the mesh origin, 5 cm below the centre
    hit.normal_speed_m_s = 1.0;
    strike_step_desc step = strike_step_desc_default();
    step.end_time_s = t;
    step.duration_s = step_s;
    step.states = &state;
    step.state_count = 1;
    if (next < times.size() && times[next] >= t - step_s && times[next] < t) {
      hit.time_s = times[next++];
      step.contacts = &hit;
      step.contact_count = 1;
    }
    ASSERT_EQ(strike_step(game.ctx, &step), STRIKE_OK);
    game.renderTo(std::min(total, static_cast<size_t>(std::floor((t - step_s) * kRate))));
  }
  game.renderAll(total);
  ASSERT_EQ(next, times.size());
  const double first_peak = game.peak(0.0, 0.5);
  ASSERT_GT(first_peak, 0.0);
  double first_level = 0.0;
  for (size_t k = 0; k < times.size(); ++k) {
    const double point_distance = std::hypot(distances[k], 0.05);
    const double arrival = times[k] + point_distance / kSpeedOfSound;
    // Onset: the first sample above 1e-3 of this strike's expected peak (the previous strike has
    // decayed far below that).
    const double expected_peak = first_peak * distances[0] / distances[k];
    size_t onset = static_cast<size_t>(times[k] * kRate);
    while (onset < game.out.size() && std::fabs(game.out[onset]) < 1e-3 * expected_peak) ++onset;
    EXPECT_NEAR(onset / kRate, arrival, 1.5 / kRate) << "bounce " << k << " at " << distances[k] << " m";
    // 1/d: the rms of its first 20 ms after the arrival relative to the first bounce's.
    const double level = game.rms(arrival + 1e-3, arrival + 21e-3);
    if (k == 0) first_level = level;
    const double db = 20 * std::log10(level / first_level), expected_db = 20 * std::log10(distances[0] / distances[k]);
    EXPECT_NEAR(db, expected_db, 0.05) << "bounce " << k;
    std::printf("bounce %zu at %4.0f m: onset %+.2f samples re d/c, level %+.3f dB re 1/d\n", k, distances[k],
                (onset / kRate - arrival) * kRate, db - expected_db);
  }
}

// ---- strike_step: threads, a full queue, bad input, stale ids --------------------------------

strike_contact restingContact(strike_object_id id, double fz) {
  strike_contact c = strike_contact_default();
  c.object = id;
  c.impulse[2] = fz;
  return c;
}

// Steps from a second thread while the audio thread renders (run under TSan: preset tsan):
// every contact is queued or counted as dropped, and every step that returned OK is rendered.
TEST(CApi, StepsFromASecondThreadWhileTheAudioThreadRenders) {
  strike_context_config cfg = Game::monoConfig();
  cfg.contact_queue_capacity = 64;
  Game game(boxBank(), cfg);
  const strike_object_id a = game.add(), b = game.add({0.5, 0, 0});
  std::atomic<bool> stop{false};
  std::thread audio([&] {
    std::vector<float> buf(256);
    float* ch[1] = {buf.data()};
    while (!stop.load(std::memory_order_acquire)) EXPECT_EQ(strike_render(game.ctx, ch, 1, 256), STRIKE_OK);
  });
  uint64_t ok = 0, full = 0, contacts = 0, ok_contacts = 0;
  std::thread physics([&] {
    for (int k = 0; k < 20000; ++k) {
      strike_body_state states[2] = {};
      states[0].object = a, states[1].object = b;
      states[0].orientation[0] = states[1].orientation[0] = 1.0;
      states[1].asleep = k % 2;
      strike_contact c[3] = {restingContact(a, 0.16), restingContact(b, 0.16), restingContact(a, 0.01)};
      c[2].normal_speed_m_s = 1.0;  // an impact now and then
      strike_step_desc step = strike_step_desc_default();
      step.end_time_s = k / 60.0;
      step.states = states;
      step.state_count = 2;
      step.contacts = c;
      step.contact_count = k % 50 == 0 ? 3 : 2;
      contacts += step.contact_count;
      const strike_status s = strike_step(game.ctx, &step);
      if (s == STRIKE_OK)
        ++ok, ok_contacts += step.contact_count;
      else if (s == STRIKE_ERR_QUEUE_FULL)
        ++full;
      else
        ADD_FAILURE() << "status " << s;
      if (k % 64 == 0) std::this_thread::yield();
    }
  });
  physics.join();
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  stop.store(true, std::memory_order_release);
  audio.join();
  float buf[256];
  float* ch[1] = {buf};
  ASSERT_EQ(strike_render(game.ctx, ch, 1, 256), STRIKE_OK);  // drains what is left
  const strike_stats s = statsOf(game.ctx);
  EXPECT_EQ(ok + full, 20000u);
  EXPECT_GT(ok, 0u);
  EXPECT_EQ(s.steps, ok) << "a step is rendered exactly when strike_step returned OK";
  EXPECT_GE(s.contacts_queued, ok_contacts);
  EXPECT_LE(s.contacts_queued, contacts);
  EXPECT_EQ(s.contacts_dropped_stale, 0u);
  std::printf("steps: %llu ok, %llu full; contacts queued %llu, dropped (full) %llu\n",
              static_cast<unsigned long long>(ok), static_cast<unsigned long long>(full),
              static_cast<unsigned long long>(s.contacts_queued),
              static_cast<unsigned long long>(s.contacts_dropped_queue_full));
}

TEST(CApiStep, AFullQueueDropsTheRestOfTheStepAndCountsExactly) {
  // contact_queue_capacity 16 (the minimum, a power of two): a step of n contacts takes n + 2
  // records (its start and end), so two steps of 5 fit (14), the third gets its start and one
  // contact in (16) and drops 4, the fourth drops all 5; with 2 body states each, the same.
  strike_context_config cfg = Game::monoConfig();
  cfg.contact_queue_capacity = 16;
  Game game(boxBank(), cfg);
  const strike_object_id id = game.add();
  std::vector<strike_contact> c(5, restingContact(id, 0.16));
  strike_step_desc step = strike_step_desc_default();
  step.contacts = c.data();
  step.contact_count = 5;
  std::vector<strike_status> got;
  for (int k = 1; k <= 4; ++k) {
    step.end_time_s = k / 60.0;
    got.push_back(strike_step(game.ctx, &step));
  }
  EXPECT_EQ(got, (std::vector<strike_status>{STRIKE_OK, STRIKE_OK, STRIKE_ERR_QUEUE_FULL, STRIKE_ERR_QUEUE_FULL}));
  strike_stats s = statsOf(game.ctx);
  EXPECT_EQ(s.contacts_queued, 11u);
  EXPECT_EQ(s.contacts_dropped_queue_full, 4u + 5u);
  game.renderAll(256);
  s = statsOf(game.ctx);
  EXPECT_EQ(s.steps, 2u);
  EXPECT_EQ(s.sustained_contacts, 11u);
  step.end_time_s = 5 / 60.0;
  EXPECT_EQ(strike_step(game.ctx, &step), STRIKE_OK) << "the queue drained";
  // Body states count as dropped records too: 2 states + 7 contacts = 11 records of 16.
  strike_body_state states[2] = {};
  states[0].object = states[1].object = id;
  states[0].orientation[0] = states[1].orientation[0] = 1.0;
  game.renderAll(512);
  const uint64_t dropped_before = statsOf(game.ctx).contacts_dropped_queue_full;
  std::vector<strike_contact> seven(7, restingContact(id, 0.16));
  step.states = states;
  step.state_count = 2;
  step.contacts = seven.data();
  step.contact_count = 7;
  EXPECT_EQ(strike_step(game.ctx, &step), STRIKE_OK);              // 11 records
  EXPECT_EQ(strike_step(game.ctx, &step), STRIKE_ERR_QUEUE_FULL);  // start, 2 states, 2 contacts in; 5 dropped
  EXPECT_EQ(statsOf(game.ctx).contacts_dropped_queue_full - dropped_before, 5u);
}

TEST(CApiStep, InvalidStepsAreRefusedAndNothingIsQueued) {
  Game game(boxBank());
  const strike_object_id id = game.add();
  strike_contact c = restingContact(id, 0.16);
  strike_body_state state{};
  state.object = id;
  state.orientation[0] = 1.0;
  auto valid = [&] {
    strike_step_desc d = strike_step_desc_default();
    d.end_time_s = 1.0 / 60.0;
    d.states = &state;
    d.state_count = 1;
    d.contacts = &c;
    d.contact_count = 1;
    return d;
  };
  strike_step_desc d = valid();
  EXPECT_EQ(strike_step(nullptr, &d), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_step(game.ctx, nullptr), STRIKE_ERR_INVALID_ARG);
  auto refused = [&](const char* what, auto&& edit) {
    strike_step_desc bad = valid();
    strike_contact saved_c = c;
    strike_body_state saved_s = state;
    edit(bad);
    EXPECT_EQ(strike_step(game.ctx, &bad), STRIKE_ERR_INVALID_ARG) << what;
    c = saved_c, state = saved_s;
  };
  refused("struct_size too small",
          [](strike_step_desc& s) { s.struct_size = offsetof(strike_step_desc, contact_size); });
  refused("struct_size 0", [](strike_step_desc& s) { s.struct_size = 0; });
  refused("state_size too small", [](strike_step_desc& s) { s.state_size = sizeof(strike_body_state) - 8; });
  refused("contact_size too small", [](strike_step_desc& s) { s.contact_size = sizeof(strike_contact) - 8; });
  refused("contact_size below 0.3's",
          [](strike_step_desc& s) { s.contact_size = offsetof(strike_contact, normal_force_n) - 8; });
  refused("normal force < 0", [&](strike_step_desc&) { c.normal_force_n = -1.0; });
  refused("slip NaN", [&](strike_step_desc&) { c.slip_velocity_m_s[1] = NAN; });
  refused("rolling inf", [&](strike_step_desc&) { c.rolling_velocity_m_s[0] = INFINITY; });
  refused("partner roughness < 0", [&](strike_step_desc&) { c.partner_roughness_rms_m = -1e-6; });
  refused("contacts NULL", [](strike_step_desc& s) { s.contacts = nullptr; });
  refused("states NULL", [](strike_step_desc& s) { s.states = nullptr; });
  refused("end_time_s NaN", [](strike_step_desc& s) { s.end_time_s = NAN; });
  refused("end_time_s inf", [](strike_step_desc& s) { s.end_time_s = INFINITY; });
  refused("duration_s 0", [](strike_step_desc& s) { s.duration_s = 0.0; });
  refused("duration_s NaN", [](strike_step_desc& s) { s.duration_s = NAN; });
  refused("point NaN", [&](strike_step_desc&) { c.point[1] = NAN; });
  refused("impulse inf", [&](strike_step_desc&) { c.impulse[2] = INFINITY; });
  refused("normal speed NaN", [&](strike_step_desc&) { c.normal_speed_m_s = NAN; });
  refused("time NaN", [&](strike_step_desc&) { c.time_s = NAN; });
  refused("frame 7", [&](strike_step_desc&) { c.frame = 7; });
  refused("partner E inf", [&](strike_step_desc&) { c.partner_youngs_pa = INFINITY; });
  refused("partner mass NaN", [&](strike_step_desc&) { c.partner_mass_kg = NAN; });
  refused("position NaN", [&](strike_step_desc&) { state.position[0] = NAN; });
  refused("orientation inf", [&](strike_step_desc&) { state.orientation[3] = INFINITY; });
  refused("orientation w NaN", [&](strike_step_desc&) { state.orientation[0] = NAN; });
  game.renderAll(256);
  strike_stats s = statsOf(game.ctx);
  EXPECT_EQ(s.contacts_queued, 0u);
  EXPECT_EQ(s.contacts_dropped_queue_full, 0u);
  EXPECT_EQ(s.steps, 0u) << "nothing was queued";
  EXPECT_EQ(s.sustained_contacts, 0u);
  // The valid step goes through, and empty steps (no states, no contacts) are valid too.
  d = valid();
  EXPECT_EQ(strike_step(game.ctx, &d), STRIKE_OK);
  strike_step_desc empty = strike_step_desc_default();
  empty.end_time_s = 2.0 / 60.0;
  EXPECT_EQ(strike_step(game.ctx, &empty), STRIKE_OK);
  game.renderAll(512);
  s = statsOf(game.ctx);
  EXPECT_EQ(s.steps, 2u);
  EXPECT_EQ(s.contacts_queued, 1u);
}

// A 1 kg steel box sliding at 0.3 m/s on a steel floor for 2 s, reported every 1/60 s with a
// steady load on its four corners: rough surfaces sound the whole time it slides when the 0.4
// continuous-contact fields are given; a 0.3-sized element (read without them) and a normal
// force of 0 give the steady load's silence, byte for byte the same.
std::vector<float> slidingBox(size_t contact_size, double normal_force_scale, strike_stats* stats = nullptr) {
  Game game(boxBank());
  strike_object_config oc = strike_object_config_default();
  oc.bank = game.bank;
  oc.roughness_rms_m = 4e-7;  // ground steel (assets/materials.json)
  oc.roughness_correlation_m = 1e-5;
  oc.roughness_seed = 7;
  oc.restitution = 0.6;
  strike_object_id box{0, 0};
  EXPECT_EQ(strike_object_add(game.ctx, &oc, &box), STRIKE_OK) << strike_context_last_error(game.ctx);
  const double listener[3] = {0.0, -1.0, 0.3}, identity[4] = {1, 0, 0, 0};
  EXPECT_EQ(strike_listener_set_pose(game.ctx, listener, identity), STRIKE_OK);
  const double frame_s = 1.0 / 60.0, speed = 0.3, m = 1.0, g = 9.81, duration = 2.0;
  const std::array<std::array<double, 3>, 4> corners = {
      {{-0.05, -0.05, 0}, {0.05, -0.05, 0}, {-0.05, 0.05, 0}, {0.05, 0.05, 0}}};
  std::vector<unsigned char> bytes(4 * contact_size);
  for (double t = frame_s; t <= duration + 1e-9; t += frame_s) {
    strike_body_state state{};
    state.object = box;
    state.position[0] = speed * t;
    state.orientation[0] = 1.0;
    for (size_t k = 0; k < 4; ++k) {
      strike_contact c = strike_contact_default();
      c.object = box;
      for (int i = 0; i < 3; ++i) c.point[i] = corners[k][i];
      c.impulse[0] = -0.4 * m * g * 0.25 * frame_s;  // kinetic friction against the motion
      c.impulse[2] = m * g * 0.25 * frame_s;
      c.normal_force_n = normal_force_scale * m * g * 0.25;
      c.slip_velocity_m_s[0] = speed;  // the box's surface over the floor; the point moves with the box
      for (int i = 0; i < 3; ++i) c.partner_point[i] = corners[k][i] + state.position[i];
      c.partner_roughness_rms_m = 4e-7;
      c.partner_roughness_correlation_m = 1e-5;
      c.partner_roughness_seed = 11;
      c.partner_restitution = 0.6;
      std::memcpy(bytes.data() + k * contact_size, &c, contact_size);
    }
    strike_step_desc step = strike_step_desc_default();
    step.end_time_s = t;
    step.duration_s = frame_s;
    step.states = &state;
    step.state_count = 1;
    step.contacts = reinterpret_cast<const strike_contact*>(bytes.data());
    step.contact_count = 4;
    step.contact_size = static_cast<uint32_t>(contact_size);
    EXPECT_EQ(strike_step(game.ctx, &step), STRIKE_OK);
    game.renderTo(static_cast<size_t>(std::floor((t - frame_s) * kRate)));
  }
  game.renderAll(static_cast<size_t>(duration * kRate));
  if (stats) *stats = statsOf(game.ctx);
  return game.out;
}

TEST(CApiStep, ABoxSlidingOnARoughFloorIsHeardOnlyWithTheContinuousContactFields) {
  const size_t size03 = offsetof(strike_contact, normal_force_n);
  strike_stats with_fields{}, without_fields{};
  const std::vector<float> sliding = slidingBox(sizeof(strike_contact), 1.0, &with_fields);
  const std::vector<float> old_layout = slidingBox(size03, 1.0, &without_fields);
  const std::vector<float> no_force = slidingBox(sizeof(strike_contact), 0.0);
  auto rms = [](const std::vector<float>& x, double a, double b) {
    double sum = 0.0;
    const size_t n0 = static_cast<size_t>(a * kRate), n1 = static_cast<size_t>(b * kRate);
    for (size_t n = n0; n < n1; ++n) sum += double(x[n]) * x[n];
    return std::sqrt(sum / double(n1 - n0));
  };
  const double heard = rms(sliding, 0.5, 1.9), silent = rms(no_force, 0.5, 1.9);
  // Output 1.0 = 20 Pa = 120 dB SPL.
  std::printf("sliding box: %.1f dB SPL with the 0.4 fields, %.1f dB SPL without\n",
              120 + 20 * std::log10(std::max(heard, 1e-30)), 120 + 20 * std::log10(std::max(silent, 1e-30)));
  EXPECT_GT(heard, 1e-5);             // above 20 dB SPL
  EXPECT_GT(heard, 1000.0 * silent);  // 60 dB over the steady load's silence
  EXPECT_EQ(old_layout, no_force);    // a 0.3 element is read without the new fields
  // The four corners slide over one partner surface (the floor's seed): one contact source.
  EXPECT_EQ(with_fields.continuous_contacts, 1u);
  EXPECT_EQ(with_fields.continuous_dropped, 0u);
  EXPECT_EQ(without_fields.continuous_contacts, 0u);
}

TEST(CApiStep, ContactsOnStaleObjectsAreCountedWhenRendered) {
  strike_context_config cfg = Game::monoConfig();
  cfg.max_objects = 4;
  Game game(boxBank(), cfg);
  const strike_object_id a = game.add(), b = game.add();
  ASSERT_EQ(strike_object_remove(game.ctx, a), STRIKE_OK);
  const strike_object_id never{3, 7};
  std::vector<strike_contact> c = {restingContact(a, 0.16), restingContact(b, 0.16), restingContact(a, 0.16),
                                   restingContact(never, 0.16), restingContact({99, 1}, 0.16)};
  strike_step_desc step = strike_step_desc_default();
  step.end_time_s = 1.0 / 60.0;
  step.contacts = c.data();
  step.contact_count = static_cast<uint32_t>(c.size());
  EXPECT_EQ(strike_step(game.ctx, &step), STRIKE_OK) << "validity is checked on the audio thread";
  game.renderAll(256);
  const strike_stats s = statsOf(game.ctx);
  EXPECT_EQ(s.contacts_queued, 5u);
  EXPECT_EQ(s.contacts_dropped_stale, 4u);
  EXPECT_EQ(s.sustained_contacts, 1u) << "only b's";
  EXPECT_EQ(s.impacts_dropped_stale, 0u) << "contacts are not impacts";
}

// ---- struct_size: a newer library never writes past an older caller's struct -----------------

template <typename T>
struct Guarded {
  static constexpr size_t kGuard = 64;
  alignas(T) unsigned char bytes[sizeof(T) + kGuard];
  Guarded() { std::memset(bytes, 0xAB, sizeof bytes); }
  T* get() { return reinterpret_cast<T*>(bytes); }
  void setSize(uint32_t size) { std::memcpy(bytes, &size, sizeof size); }
  /// Index of the first byte at or past `from` that was written (not 0xAB), or -1.
  long firstWrittenFrom(size_t from) const {
    for (size_t k = from; k < sizeof bytes; ++k)
      if (bytes[k] != 0xAB) return static_cast<long>(k);
    return -1;
  }
};

TEST(CApiStep, StatsWriteExactlyStructSizeBytes) {
  Game game(boxBank());
  const strike_object_id id = game.add();
  strike_impact_desc d = strike_impact_desc_default();
  d.object = id;
  d.impulse[2] = 0.01;
  ASSERT_EQ(strike_impact(game.ctx, &d), STRIKE_OK);
  game.renderAll(256);
  const strike_stats full = statsOf(game.ctx);
  // An older (smaller) layout: the 0.2 fields only, ending at `objects`; and a few odd sizes.
  for (size_t size : {offsetof(strike_stats, steps), offsetof(strike_stats, objects) + sizeof(uint32_t),
                      offsetof(strike_stats, impacts_queued), offsetof(strike_stats, impacts_dropped_queue_full) + 3,
                      offsetof(strike_stats, clock_frames), offsetof(strike_stats, continuous_contacts),
                      sizeof(strike_stats)}) {
    Guarded<strike_stats> g;
    g.setSize(static_cast<uint32_t>(size));
    ASSERT_EQ(strike_context_get_stats(game.ctx, g.get()), STRIKE_OK) << size;
    EXPECT_EQ(g.firstWrittenFrom(size), -1) << "wrote past struct_size " << size;
    EXPECT_EQ(g.get()->struct_size, size) << "echoes what it wrote";
    if (size >= offsetof(strike_stats, impacts_queued) + sizeof(uint64_t)) {
      EXPECT_EQ(g.get()->impacts_queued, 1u);
    }
    if (size >= offsetof(strike_stats, frames_rendered) + sizeof(uint64_t)) {
      EXPECT_EQ(g.get()->frames_rendered, 256u);
    }
  }
  // A newer caller's larger struct: only this library's bytes are written, and it says how many.
  Guarded<strike_stats> big;
  big.setSize(sizeof(strike_stats) + 32);
  ASSERT_EQ(strike_context_get_stats(game.ctx, big.get()), STRIKE_OK);
  EXPECT_EQ(big.get()->struct_size, sizeof(strike_stats));
  EXPECT_EQ(big.firstWrittenFrom(sizeof(strike_stats)), -1);
  EXPECT_EQ(big.get()->clock_frames, full.clock_frames);
  EXPECT_EQ(big.get()->clock_frames, 256u);
  // Too small to hold anything: refused, nothing written.
  for (uint32_t size : {0u, 4u, static_cast<uint32_t>(offsetof(strike_stats, impacts_queued) - 1)}) {
    Guarded<strike_stats> g;
    g.setSize(size);
    EXPECT_EQ(strike_context_get_stats(game.ctx, g.get()), STRIKE_ERR_INVALID_ARG) << size;
    EXPECT_EQ(g.firstWrittenFrom(sizeof(uint32_t)), -1) << size;
  }
}

TEST(CApiStep, BankInfoWritesExactlyStructSizeBytesAndItsPhysicalData) {
  const strike::ModeBank b = boxBank();
  Game game(b);
  for (size_t size : {offsetof(strike_bank_info, volume_m3), offsetof(strike_bank_info, mode_count),
                      offsetof(strike_bank_info, material_name) + 5, sizeof(strike_bank_info)}) {
    Guarded<strike_bank_info> g;
    g.setSize(static_cast<uint32_t>(size));
    ASSERT_EQ(strike_bank_get_info(game.bank, g.get()), STRIKE_OK) << size;
    EXPECT_EQ(g.firstWrittenFrom(size), -1) << "wrote past struct_size " << size;
    EXPECT_EQ(g.get()->struct_size, size);
  }
  Guarded<strike_bank_info> tiny;
  tiny.setSize(2);
  EXPECT_EQ(strike_bank_get_info(game.bank, tiny.get()), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(tiny.firstWrittenFrom(sizeof(uint32_t)), -1);
  // The physical data, against the bank this test built and closed forms.
  strike_bank_info info;
  std::memset(&info, 0, sizeof info);
  info.struct_size = sizeof info;
  ASSERT_EQ(strike_bank_get_info(game.bank, &info), STRIKE_OK);
  EXPECT_EQ(info.mode_count, 4u);
  EXPECT_EQ(info.surface_vertex_count, 9u);
  EXPECT_EQ(info.surface_triangle_count, 8u);
  EXPECT_NEAR(info.lowest_frequency_hz, 523.0, 1e-9);
  EXPECT_EQ(info.mass_kg, 1.0);
  EXPECT_DOUBLE_EQ(info.volume_m3, 1.0 / 7850.0);
  EXPECT_DOUBLE_EQ(info.density_kg_m3 * info.volume_m3, info.mass_kg) << "rho V = m";
  for (int k = 0; k < 3; ++k) EXPECT_EQ(info.centre_of_mass_m[k], b.centre_m[k]);
  for (int k = 0; k < 9; ++k) EXPECT_EQ(info.inertia_kg_m2[k], b.inertia_kg_m2[k]);
  // The surface is a 10 cm square in z = 0: bounds +-5 cm, area (2 h)^2 = 0.01 m^2.
  EXPECT_DOUBLE_EQ(info.bounds_min_m[0], -0.05);
  EXPECT_DOUBLE_EQ(info.bounds_max_m[1], 0.05);
  EXPECT_EQ(info.bounds_min_m[2], 0.0);
  EXPECT_NEAR(info.surface_area_m2, 0.1 * 0.1, 1e-15);
  // Equal-volume radius: (4/3) pi r^3 = V.
  const double r = std::cbrt(3.0 * (1.0 / 7850.0) / (4.0 * M_PI));
  EXPECT_NEAR(info.equal_volume_radius_m, r, 1e-15);
  EXPECT_NEAR(4.0 / 3.0 * M_PI * std::pow(info.equal_volume_radius_m, 3), info.volume_m3, 1e-15);
  EXPECT_STREQ(info.material_name, "steel");
  EXPECT_EQ(info.youngs_pa, 2.0e11);
  EXPECT_EQ(info.poisson, 0.3);
  EXPECT_EQ(info.rayleigh_stiffness_s, 1e-8);
  EXPECT_EQ(info.rayleigh_mass_per_s, 10.0);
  // A long material name is truncated and NUL-terminated.
  strike::ModeBank long_name = b;
  long_name.material.name = std::string(100, 'x');
  Game other(long_name);
  ASSERT_EQ(strike_bank_get_info(other.bank, &info), STRIKE_OK);
  EXPECT_EQ(std::strlen(info.material_name), sizeof info.material_name - 1);
}

// ---- strike_context_reset ---------------------------------------------------------------------

TEST(CApiStep, ResetSilencesRestartsTheClockAndObjectsStillStrike) {
  // A fresh context struck once: the reference. The same strike after a reset must give the same
  // samples (same clock, same listener, same delay), so the reset left nothing behind.
  auto strikeAndRender = [](Game& game, strike_object_id id, std::vector<float>& out) {
    strike_impact_desc d = strike_impact_desc_default();
    d.object = id;
    d.surface_vertex = 4;
    d.impulse[2] = 0.01;
    d.sample_offset = 10;
    ASSERT_EQ(strike_impact(game.ctx, &d), STRIKE_OK);
    out.assign(2048, 0.0f);
    for (size_t n = 0; n < out.size(); n += 256) {
      float* ch[1] = {out.data() + n};
      ASSERT_EQ(strike_render(game.ctx, ch, 1, 256), STRIKE_OK);
    }
  };
  Game fresh(boxBank());
  const strike_object_id f = fresh.add({0, 1, 0});
  std::vector<float> reference;
  strikeAndRender(fresh, f, reference);
  Game game(boxBank());
  const strike_object_id id = game.add({0, 1, 0});
  std::vector<float> before;
  strikeAndRender(game, id, before);
  EXPECT_EQ(before, reference);
  // A resting load and an impact are in flight when the reset comes.
  strike_contact rest = restingContact(id, 0.16);
  strike_step_desc step = strike_step_desc_default();
  step.end_time_s = 0.1;
  step.contacts = &rest;
  step.contact_count = 1;
  ASSERT_EQ(strike_step(game.ctx, &step), STRIKE_OK);
  game.renderAll(256);
  EXPECT_GT(statsOf(game.ctx).clock_frames, 2048u);
  ASSERT_EQ(strike_context_reset(game.ctx), STRIKE_OK);
  std::vector<float> after(1024, 1.0f);
  for (size_t n = 0; n < after.size(); n += 256) {
    float* ch[1] = {after.data() + n};
    ASSERT_EQ(strike_render(game.ctx, ch, 1, 256), STRIKE_OK);
  }
  for (size_t n = 0; n < after.size(); ++n) ASSERT_EQ(after[n], 0.0f) << "silent after the reset, sample " << n;
  EXPECT_EQ(statsOf(game.ctx).clock_frames, 1024u) << "the clock restarted at 0";
  EXPECT_EQ(statsOf(game.ctx).active_modes, 0u);
  // Objects, banks and the listener stay: strike again after a second reset (clock at 0).
  ASSERT_EQ(strike_context_reset(game.ctx), STRIKE_OK);
  float scratch[1];
  float* ch[1] = {scratch};
  ASSERT_EQ(strike_render(game.ctx, ch, 1, 0), STRIKE_OK);  // applies the reset
  EXPECT_EQ(statsOf(game.ctx).clock_frames, 0u);
  std::vector<float> again;
  strikeAndRender(game, id, again);
  EXPECT_EQ(again, reference) << "the same strike on the reset context sounds as on a fresh one";
}

TEST(CApiStep, WhatIsReportedAfterAResetIsKept) {
  // strike_context_reset() empties the queues of what came before it; a game that reloads a
  // level resets, then reports the new level's first step and strikes at once.
  Game game(boxBank());
  const strike_object_id id = game.add({0, 1, 0});
  strike_impact_desc d = strike_impact_desc_default();
  d.object = id;
  d.surface_vertex = 4;
  d.impulse[2] = 0.01;
  ASSERT_EQ(strike_impact(game.ctx, &d), STRIKE_OK);  // before: dropped
  ASSERT_EQ(strike_context_reset(game.ctx), STRIKE_OK);
  ASSERT_EQ(strike_impact(game.ctx, &d), STRIKE_OK);  // after: kept
  strike_contact rest = restingContact(id, 0.16);
  strike_step_desc step = strike_step_desc_default();
  step.end_time_s = 1.0 / 60.0;
  step.contacts = &rest;
  step.contact_count = 1;
  ASSERT_EQ(strike_step(game.ctx, &step), STRIKE_OK);
  game.renderAll(1024);
  const strike_stats s = statsOf(game.ctx);
  EXPECT_EQ(s.impacts_scheduled, 1u) << "the impact after the reset is heard, the one before is not";
  EXPECT_EQ(s.steps, 1u);
  EXPECT_EQ(s.sustained_contacts, 1u);
  EXPECT_GT(game.peak(0.0, 1024 / kRate), 0.0);
}

// ---- strike_context_create names the field and value it refuses -------------------------------

TEST(CApiStep, CreateLogsTheRejectedFieldAndValue) {
  struct Log {
    std::vector<std::string> messages;
    std::vector<int32_t> levels;
  } log;
  auto sink = [](void* user, int32_t level, const char* message) {
    static_cast<Log*>(user)->messages.emplace_back(message);
    static_cast<Log*>(user)->levels.push_back(level);
  };
  struct Case {
    const char* expected;
    void (*edit)(strike_context_config&);
  };
  const Case cases[] = {
      {"sample_rate_hz = 100", [](strike_context_config& c) { c.sample_rate_hz = 100; }},
      {"sample_rate_hz = nan", [](strike_context_config& c) { c.sample_rate_hz = NAN; }},
      {"max_block_frames = 0", [](strike_context_config& c) { c.max_block_frames = 0; }},
      {"max_block_frames = 16385", [](strike_context_config& c) { c.max_block_frames = 16385; }},
      {"channels = 3", [](strike_context_config& c) { c.channels = 3; }},
      {"max_objects = 0", [](strike_context_config& c) { c.max_objects = 0; }},
      {"max_objects = 65537", [](strike_context_config& c) { c.max_objects = 65537; }},
      {"impact_queue_capacity = 1", [](strike_context_config& c) { c.impact_queue_capacity = 1; }},
      {"contact_queue_capacity = 15", [](strike_context_config& c) { c.contact_queue_capacity = 15; }},
      {"contact_queue_capacity = 1048577", [](strike_context_config& c) { c.contact_queue_capacity = (1u << 20) + 1; }},
      {"max_pending_impacts_per_object = 0", [](strike_context_config& c) { c.max_pending_impacts_per_object = 0; }},
      {"max_contact_duration_s = 2", [](strike_context_config& c) { c.max_contact_duration_s = 2; }},
      {"min_freq_hz = -1", [](strike_context_config& c) { c.min_freq_hz = -1; }},
      {"max_freq_hz = 10", [](strike_context_config& c) { c.max_freq_hz = 10; }},
      {"audibility_threshold = inf", [](strike_context_config& c) { c.audibility_threshold = INFINITY; }},
      {"reference_distance_m = -1", [](strike_context_config& c) { c.reference_distance_m = -1; }},
      {"min_distance_m = 0", [](strike_context_config& c) { c.min_distance_m = 0; }},
      {"output_full_scale_pa = 0", [](strike_context_config& c) { c.output_full_scale_pa = 0; }},
      {"contact_damping_per_s = -0.5", [](strike_context_config& c) { c.contact_damping_per_s = -0.5; }},
      {"alloc is set but free is NULL",
       [](strike_context_config& c) { c.alloc = [](void*, size_t, size_t) -> void* { return nullptr; }; }},
      {"api_version = 0.2.0", [](strike_context_config& c) { c.api_version = (0u << 16) | (2u << 8); }},
  };
  for (const Case& k : cases) {
    strike_context_config c = strike_context_config_default();
    c.log = sink;
    c.user = &log;
    k.edit(c);
    log.messages.clear();
    log.levels.clear();
    strike_context ctx = nullptr;
    EXPECT_NE(strike_context_create(&c, &ctx), STRIKE_OK) << k.expected;
    EXPECT_EQ(ctx, nullptr);
    ASSERT_EQ(log.messages.size(), 1u) << k.expected;
    EXPECT_NE(log.messages[0].find(std::string("strike_context_create: ") + k.expected), std::string::npos)
        << "logged: " << log.messages[0] << "\nexpected: " << k.expected;
    EXPECT_EQ(log.levels[0], STRIKE_LOG_ERROR);
  }
  // A valid config logs nothing.
  strike_context_config c = strike_context_config_default();
  c.log = sink;
  c.user = &log;
  log.messages.clear();
  strike_context ctx = nullptr;
  ASSERT_EQ(strike_context_create(&c, &ctx), STRIKE_OK);
  EXPECT_TRUE(log.messages.empty());
  strike_context_destroy(ctx);
}

}  // namespace
