// SPDX-License-Identifier: MIT
// libstrike through its C API: bad use (status codes, never a crash), versioning, stale ids,
// bank errors, latency and sample-accurate offsets, stereo pan, the mode budget, and the
// lock-free queue under four producers with a rendering audio thread.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <thread>
#include <vector>

#include "strike/strike.h"
#include "strike/synth/synth.hpp"
#include "test_bank.hpp"

namespace {

std::vector<uint8_t> testBankBytes() { return strike::encodeBank(strike::test::makeTestBank()); }

struct Fixture {
  strike_context ctx = nullptr;
  strike_bank bank = nullptr;
  std::vector<float> left, right;
  float* out[2] = {nullptr, nullptr};
  uint32_t block = 256;

  explicit Fixture(strike_context_config cfg = strike_context_config_default()) {
    block = cfg.max_block_frames;
    EXPECT_EQ(strike_context_create(&cfg, &ctx), STRIKE_OK);
    const std::vector<uint8_t> bytes = testBankBytes();
    EXPECT_EQ(strike_bank_load_memory(ctx, bytes.data(), bytes.size(), &bank), STRIKE_OK);
    left.assign(block, 0.0f);
    right.assign(block, 0.0f);
    out[0] = left.data();
    out[1] = right.data();
  }
  ~Fixture() {
    strike_bank_destroy(bank);
    strike_context_destroy(ctx);
  }
  strike_object_id add(double x = 0.0, double y = 1.0, float gain = 1e-3f) {
    strike_object_config oc = strike_object_config_default();
    oc.bank = bank;
    oc.position[0] = x;
    oc.position[1] = y;
    oc.gain = gain;
    oc.radiation = STRIKE_RADIATION_UNIT;
    strike_object_id id{0, 0};
    EXPECT_EQ(strike_object_add(ctx, &oc, &id), STRIKE_OK) << strike_context_last_error(ctx);
    return id;
  }
  strike_status hit(strike_object_id id, uint32_t offset = 0, double impulse = 1e-2) {
    strike_impact_desc d = strike_impact_desc_default();
    d.object = id;
    d.surface_vertex = 4;
    d.impulse[2] = impulse;
    d.sample_offset = offset;
    return strike_impact(ctx, &d);
  }
  strike_status render(uint32_t frames) { return strike_render(ctx, out, 2, frames); }
  strike_stats stats() {
    strike_stats s;
    std::memset(&s, 0, sizeof s);
    s.struct_size = sizeof s;
    EXPECT_EQ(strike_context_get_stats(ctx, &s), STRIKE_OK);
    return s;
  }
};

// Every order of destruction strike.h allows, each a whole life: create, load, add an object,
// sound it, tear down. Under ASan (CI) a read of freed memory or a leak fails the test.
TEST(CApi, EveryDocumentedDestructionOrderIsClean) {
  enum class Order { BankThenContext, ContextThenBank, ObjectRemovedBankThenContext, ContextWithLiveObjectThenBank };
  for (Order order : {Order::BankThenContext, Order::ContextThenBank, Order::ObjectRemovedBankThenContext,
                      Order::ContextWithLiveObjectThenBank}) {
    strike_context_config cfg = strike_context_config_default();
    strike_context ctx = nullptr;
    ASSERT_EQ(strike_context_create(&cfg, &ctx), STRIKE_OK);
    const std::vector<uint8_t> bytes = testBankBytes();
    strike_bank bank = nullptr;
    ASSERT_EQ(strike_bank_load_memory(ctx, bytes.data(), bytes.size(), &bank), STRIKE_OK);
    strike_object_config oc = strike_object_config_default();
    oc.bank = bank;
    oc.position[1] = 1.0;
    strike_object_id id{0, 0};
    ASSERT_EQ(strike_object_add(ctx, &oc, &id), STRIKE_OK) << strike_context_last_error(ctx);
    strike_impact_desc d = strike_impact_desc_default();
    d.object = id;
    d.surface_vertex = 4;
    d.impulse[2] = 1e-2;
    ASSERT_EQ(strike_impact(ctx, &d), STRIKE_OK);
    std::vector<float> left(cfg.max_block_frames), right(cfg.max_block_frames);
    float* out[2] = {left.data(), right.data()};
    ASSERT_EQ(strike_render(ctx, out, 2, cfg.max_block_frames), STRIKE_OK);
    switch (order) {
      case Order::BankThenContext:
        strike_bank_destroy(bank);  // the live object keeps the bank's data
        ASSERT_EQ(strike_render(ctx, out, 2, cfg.max_block_frames), STRIKE_OK);
        strike_context_destroy(ctx);
        break;
      case Order::ContextThenBank:
        strike_context_destroy(ctx);
        strike_bank_destroy(bank);  // a bank may outlive its context (strike.h)
        break;
      case Order::ObjectRemovedBankThenContext:
        ASSERT_EQ(strike_object_remove(ctx, id), STRIKE_OK);
        ASSERT_EQ(strike_render(ctx, out, 2, cfg.max_block_frames), STRIKE_OK);
        strike_bank_destroy(bank);
        strike_context_destroy(ctx);
        break;
      case Order::ContextWithLiveObjectThenBank:
        strike_context_destroy(ctx);  // frees the live object's voice
        strike_bank_destroy(bank);
        break;
    }
  }
}

TEST(CApi, VersionCheckAtCreation) {
  EXPECT_EQ(strike_get_version(), STRIKE_VERSION);
  strike_context ctx = nullptr;
  strike_context_config c = strike_context_config_default();
  c.api_version = STRIKE_VERSION + (1u << 16);  // next major
  EXPECT_EQ(strike_context_create(&c, &ctx), STRIKE_ERR_VERSION);
  c.api_version = STRIKE_VERSION + (1u << 8);  // newer minor than the library
  EXPECT_EQ(strike_context_create(&c, &ctx), STRIKE_ERR_VERSION);
  // Before 1.0 an older minor's config has another layout (0.2 added output_full_scale_pa).
  static_assert(STRIKE_VERSION_MAJOR > 0 || STRIKE_VERSION_MINOR >= 2, "this header is 0.2 or later");
  c.api_version = STRIKE_VERSION - (1u << 8);  // a 0.1 header
  EXPECT_EQ(strike_context_create(&c, &ctx), STRIKE_ERR_VERSION);
  EXPECT_EQ(ctx, nullptr) << "nothing is written to *out on failure";
  strike_context_config raw;
  std::memset(&raw, 0, sizeof raw);
  raw.api_version = STRIKE_VERSION;
  EXPECT_EQ(strike_context_create(&raw, &ctx), STRIKE_ERR_NOT_INITIALIZED);
}

TEST(CApi, InvalidConfigValues) {
  strike_context ctx = nullptr;
  auto tryCreate = [&](auto&& edit) {
    strike_context_config c = strike_context_config_default();
    edit(c);
    return strike_context_create(&c, &ctx);
  };
  EXPECT_EQ(tryCreate([](strike_context_config& c) { c.channels = 3; }), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(tryCreate([](strike_context_config& c) { c.sample_rate_hz = NAN; }), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(tryCreate([](strike_context_config& c) { c.max_block_frames = 0; }), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(tryCreate([](strike_context_config& c) { c.max_objects = 0; }), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(tryCreate([](strike_context_config& c) { c.reference_distance_m = -1; }), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(ctx, nullptr);
  EXPECT_EQ(strike_context_create(nullptr, &ctx), STRIKE_ERR_INVALID_ARG);
}

TEST(CApi, NullHandlesGiveStatusCodes) {
  strike_stats s;
  strike_bank b = nullptr;
  strike_object_id id{0, 1};
  strike_impact_desc d = strike_impact_desc_default();
  float buf[4];
  float* out[2] = {buf, buf};
  const double p[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
  EXPECT_EQ(strike_context_get_stats(nullptr, &s), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_context_collect(nullptr), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_bank_load_file(nullptr, "x", &b), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_bank_load_memory(nullptr, "x", 1, &b), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_bank_get_info(nullptr, nullptr), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_object_add(nullptr, nullptr, &id), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_object_remove(nullptr, id), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_object_is_valid(nullptr, id), 0);
  EXPECT_EQ(strike_object_set_pose(nullptr, id, p, q), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_listener_set_pose(nullptr, p, q), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_impact(nullptr, &d), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_render(nullptr, out, 2, 4), STRIKE_ERR_INVALID_ARG);
  EXPECT_NE(strike_context_last_error(nullptr), nullptr);
  strike_bank_destroy(nullptr);
  strike_context_destroy(nullptr);

  Fixture f;
  EXPECT_EQ(strike_bank_load_memory(f.ctx, nullptr, 10, &b), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_object_add(f.ctx, nullptr, &id), STRIKE_ERR_INVALID_ARG);
  strike_object_config oc = strike_object_config_default();  // bank left NULL
  EXPECT_EQ(strike_object_add(f.ctx, &oc, &id), STRIKE_ERR_INVALID_ARG);
  EXPECT_NE(std::strlen(strike_context_last_error(f.ctx)), 0u);
  oc.internal_cookie = 0;
  EXPECT_EQ(strike_object_add(f.ctx, &oc, &id), STRIKE_ERR_NOT_INITIALIZED);
  EXPECT_EQ(strike_impact(f.ctx, nullptr), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_render(f.ctx, nullptr, 2, 4), STRIKE_ERR_INVALID_ARG);
  float* half[2] = {buf, nullptr};
  EXPECT_EQ(strike_render(f.ctx, half, 2, 4), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_listener_set_pose(f.ctx, nullptr, q), STRIKE_ERR_INVALID_ARG);
  const double zero_q[4] = {0, 0, 0, 0};
  EXPECT_EQ(strike_listener_set_pose(f.ctx, p, zero_q), STRIKE_ERR_INVALID_ARG);
}

TEST(CApi, BadBanksAreRefusedWithTheRightCode) {
  Fixture f;
  std::vector<uint8_t> bytes = testBankBytes();
  strike_bank b = nullptr;
  for (size_t n : {size_t{0}, size_t{7}, size_t{31}, size_t{32}, bytes.size() / 2, bytes.size() - 1}) {
    EXPECT_EQ(strike_bank_load_memory(f.ctx, bytes.data(), n, &b), STRIKE_ERR_PARSE) << "truncated to " << n;
    EXPECT_NE(std::strlen(strike_context_last_error(f.ctx)), 0u);
  }
  std::vector<uint8_t> newer = bytes;
  newer[8] = static_cast<uint8_t>(strike::kBankFormatVersionMax + 1);
  EXPECT_EQ(strike_bank_load_memory(f.ctx, newer.data(), newer.size(), &b), STRIKE_ERR_VERSION);
  EXPECT_NE(std::strstr(strike_context_last_error(f.ctx), "newer"), nullptr) << strike_context_last_error(f.ctx);
  std::vector<uint8_t> foreign(bytes.size(), 0x5a);
  EXPECT_EQ(strike_bank_load_memory(f.ctx, foreign.data(), foreign.size(), &b), STRIKE_ERR_PARSE);
  std::vector<uint8_t> flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x40;
  EXPECT_EQ(strike_bank_load_memory(f.ctx, flipped.data(), flipped.size(), &b), STRIKE_ERR_PARSE);
  EXPECT_EQ(strike_bank_load_file(f.ctx, "/nonexistent/bank.modes", &b), STRIKE_ERR_IO);
  EXPECT_NE(std::strstr(strike_context_last_error(f.ctx), "/nonexistent/bank.modes"), nullptr);
  EXPECT_EQ(b, nullptr);
}

TEST(CApi, StaleIdsAreDetected) {
  strike_context_config c = strike_context_config_default();
  c.max_objects = 2;
  Fixture f(c);
  const strike_object_id a = f.add();
  EXPECT_EQ(f.hit(a), STRIKE_OK);
  EXPECT_EQ(strike_object_remove(f.ctx, a), STRIKE_OK);
  EXPECT_EQ(f.hit(a), STRIKE_ERR_STALE_ID);
  EXPECT_EQ(strike_object_remove(f.ctx, a), STRIKE_ERR_STALE_ID);
  EXPECT_EQ(strike_object_set_gain(f.ctx, a, 1.0f), STRIKE_ERR_STALE_ID);
  const strike_object_id b = f.add();  // reuses slot 0 with a new generation
  EXPECT_EQ(b.index, a.index);
  EXPECT_NE(b.generation, a.generation);
  EXPECT_EQ(strike_object_is_valid(f.ctx, a), 0);
  EXPECT_EQ(strike_object_is_valid(f.ctx, b), 1);
  const strike_object_id bogus{99, 1};
  EXPECT_EQ(strike_object_remove(f.ctx, bogus), STRIKE_ERR_STALE_ID);
  f.add();
  strike_object_config oc = strike_object_config_default();
  oc.bank = f.bank;
  strike_object_id id{0, 0};
  EXPECT_EQ(strike_object_add(f.ctx, &oc, &id), STRIKE_ERR_CAPACITY);
  // The impact queued on `a` before its removal is dropped as stale on the audio thread.
  EXPECT_EQ(f.render(f.block), STRIKE_OK);
  EXPECT_EQ(f.stats().impacts_dropped_stale, 1u);
  EXPECT_EQ(f.stats().objects, 2u);
}

TEST(CApi, TooManyFramesIsAnErrorNotACrash) {
  strike_context_config c = strike_context_config_default();
  c.max_block_frames = 64;
  Fixture f(c);
  std::vector<float> big(100000);
  float* out[2] = {big.data(), big.data()};
  EXPECT_EQ(strike_render(f.ctx, out, 2, 65), STRIKE_ERR_TOO_MANY_FRAMES);
  EXPECT_EQ(strike_render(f.ctx, out, 2, 100000), STRIKE_ERR_TOO_MANY_FRAMES);
  EXPECT_EQ(strike_render(f.ctx, out, 1, 64), STRIKE_ERR_INVALID_ARG);
  EXPECT_EQ(strike_render(f.ctx, out, 2, 0), STRIKE_OK);
  EXPECT_EQ(strike_render(f.ctx, out, 2, 64), STRIKE_OK);
}

TEST(CApi, ImpactSoundsInTheNextBlockAtItsSampleOffset) {
  // 0.3: an impact is heard d / 343 m/s after its sample offset, d from the contact point to the
  // listener. Vertex 4 is the plate's centre, the mesh origin, placed at (0, 1, 0); the listener
  // is at the origin: d = 1 m, 139.94 samples at 48 kHz.
  strike_context_config c = strike_context_config_default();
  c.max_block_frames = 256;
  const double delay = 1.0 / 343.0 * c.sample_rate_hz;
  // The first sample that may be non-zero, and the latest by which sound must have started
  // (sample 0 of the pulse is its zero-force start; the next ones are not).
  auto firstSound = [](const std::vector<float>& x, size_t from) {
    for (size_t n = from; n < x.size(); ++n)
      if (x[n] != 0.0f) return n;
    return x.size();
  };
  Fixture f(c);
  const strike_object_id id = f.add();
  ASSERT_EQ(f.render(256), STRIKE_OK);
  ASSERT_EQ(f.hit(id, 100), STRIKE_OK);
  ASSERT_EQ(f.render(256), STRIKE_OK);
  const size_t first = firstSound(f.left, 0);
  EXPECT_GE(static_cast<double>(first), std::floor(100 + delay)) << "nothing before the offset plus the delay";
  EXPECT_LE(static_cast<double>(first), 100 + delay + 2.0);
  float peak = 0.0f;
  for (size_t n = first; n < 256; ++n) peak = std::max(peak, std::fabs(f.left[n]));
  EXPECT_GT(peak, 0.0f);
  EXPECT_EQ(f.stats().impacts_scheduled, 1u);
  // Offset 0 on a silent context: sound starts at the delay, within the very next block
  // (latency <= one block plus the propagation delay).
  Fixture g(c);
  const strike_object_id id2 = g.add();
  ASSERT_EQ(g.hit(id2, 0), STRIKE_OK);
  ASSERT_EQ(g.render(256), STRIKE_OK);
  const size_t first0 = firstSound(g.left, 0);
  EXPECT_GE(static_cast<double>(first0), std::floor(delay));
  EXPECT_LE(static_cast<double>(first0), delay + 2.0);
  // The offset is exact: the same impact 100 samples later is the same signal 100 samples later.
  for (size_t n = first0; n + 100 < 256; ++n) ASSERT_EQ(f.left[n + 100], g.left[n]) << n;
  // Nearer listener, shorter delay: move the listener 0.5 m towards the object (d = 0.5 m).
  Fixture h(c);
  const strike_object_id id3 = h.add();
  const double p[3] = {0.0, 0.5, 0.0}, q[4] = {1, 0, 0, 0};
  ASSERT_EQ(strike_listener_set_pose(h.ctx, p, q), STRIKE_OK);
  ASSERT_EQ(h.hit(id3, 0), STRIKE_OK);
  ASSERT_EQ(h.render(256), STRIKE_OK);
  const size_t first_half = firstSound(h.left, 0);
  EXPECT_GE(static_cast<double>(first_half), std::floor(delay / 2));
  EXPECT_LE(static_cast<double>(first_half), delay / 2 + 2.0);
}

TEST(CApi, StereoPanFollowsTheListener) {
  Fixture f;
  const strike_object_id id = f.add(2.0, 0.0);  // to the right of a listener facing +y
  ASSERT_EQ(f.hit(id), STRIKE_OK);
  double el = 0, er = 0;
  for (int k = 0; k < 8; ++k) {
    ASSERT_EQ(f.render(f.block), STRIKE_OK);
    for (uint32_t n = 0; n < f.block; ++n) el += f.left[n] * f.left[n], er += f.right[n] * f.right[n];
  }
  EXPECT_GT(er, 1000.0 * el);
  // Turn the listener around (180 degrees about z): the object is now on the left.
  const double p[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1};
  ASSERT_EQ(strike_listener_set_pose(f.ctx, p, q), STRIKE_OK);
  ASSERT_EQ(f.render(f.block), STRIKE_OK);  // gain ramp
  el = er = 0;
  ASSERT_EQ(f.render(f.block), STRIKE_OK);
  for (uint32_t n = 0; n < f.block; ++n) el += f.left[n] * f.left[n], er += f.right[n] * f.right[n];
  EXPECT_GT(el, 1000.0 * er);
}

// A host that moves a ringing body hears its Doppler shift (docs/listener.md, "Moving sources"):
// a 1 kHz mode on a body passing 5 m from the listener at 20 m/s, its pose set before every
// 48-frame block, is heard at f c / (c - v_r) while it approaches, v_r from the geometry at the
// emission time t_e = t - r(t_e) / c.
TEST(CApi, AHostMovingABodyHearsItsDopplerShift) {
  strike_context_config cfg = strike_context_config_default();
  cfg.max_block_frames = 48;
  const double rate = cfg.sample_rate_hz, c = 343.0, speed = 20.0, miss = 5.0, start_x = -30.0;
  strike_context ctx = nullptr;
  ASSERT_EQ(strike_context_create(&cfg, &ctx), STRIKE_OK);
  const std::vector<uint8_t> bytes = strike::encodeBank(strike::test::makeTestBank({1000.0}));
  strike_bank bank = nullptr;
  ASSERT_EQ(strike_bank_load_memory(ctx, bytes.data(), bytes.size(), &bank), STRIKE_OK);
  strike_object_config oc = strike_object_config_default();
  oc.bank = bank;
  oc.position[0] = start_x;
  oc.position[1] = miss;
  oc.gain = 1e-3f;
  oc.radiation = STRIKE_RADIATION_UNIT;
  strike_object_id id{0, 0};
  ASSERT_EQ(strike_object_add(ctx, &oc, &id), STRIKE_OK);
  auto x = [&](double t) { return start_x + speed * t; };
  const size_t blocks = static_cast<size_t>(0.8 * rate) / 48;
  std::vector<float> heard;
  std::vector<float> left(48), right(48);
  float* out[2] = {left.data(), right.data()};
  const double q[4] = {1, 0, 0, 0};
  for (size_t b = 0; b < blocks; ++b) {
    const double p[3] = {x(static_cast<double>(b * 48) / rate), miss, 0.0};
    ASSERT_EQ(strike_object_set_pose(ctx, id, p, q), STRIKE_OK);
    if (b == 2) {  // struck once it moves
      strike_impact_desc d = strike_impact_desc_default();
      d.object = id;
      d.surface_vertex = 4;
      d.impulse[2] = 1e-2;
      ASSERT_EQ(strike_impact(ctx, &d), STRIKE_OK);
    }
    ASSERT_EQ(strike_render(ctx, out, 2, 48), STRIKE_OK);
    heard.insert(heard.end(), left.begin(), left.end());
  }
  strike_bank_destroy(bank);
  strike_context_destroy(ctx);
  // The mean frequency over 0.6-0.7 s from its upward zero crossings.
  const size_t from = static_cast<size_t>(0.6 * rate), to = static_cast<size_t>(0.7 * rate);
  double first = -1.0, last = -1.0;
  int crossings = 0;
  for (size_t n = from; n + 1 < to; ++n)
    if (heard[n] < 0.0f && heard[n + 1] >= 0.0f) {
      const double t = (static_cast<double>(n) + heard[n] / (heard[n] - heard[n + 1])) / rate;
      if (first < 0.0) first = t;
      last = t;
      ++crossings;
    }
  const double measured = (crossings - 1) / (last - first);
  double t_e = 0.65;
  for (int i = 0; i < 60; ++i) t_e = 0.65 - std::hypot(x(t_e), miss) / c;
  const double v_r = -speed * x(t_e) / std::hypot(x(t_e), miss);
  const double lambda = std::pow(2.0 * M_PI * 1000.0, 2), damping = 1e-9 * lambda + 4.0;  // the test bank's
  const double f = std::sqrt(lambda - 0.25 * damping * damping) / (2.0 * M_PI);
  EXPECT_NEAR(measured / (f * c / (c - v_r)) - 1.0, 0.0, 1e-3) << "v_r " << v_r << " m/s, measured " << measured;
}

// Binaural through the C API: the host hands the responses over. A set in which every direction
// has the same responses (left: a unit impulse; right: half of one, 3 samples later) makes the
// left ear the mono render, bit for bit, and the right ear half of it 3 samples later; and bad
// responses are refused, naming the field.
std::vector<float> renderOutput(const strike_output_desc& output, uint32_t channels, strike_status* created) {
  strike_context_config cfg = strike_context_config_default();
  strike_context ctx = nullptr;
  *created = strike_context_create_with_output(&cfg, &output, &ctx);
  if (*created != STRIKE_OK) return {};
  const std::vector<uint8_t> bytes = testBankBytes();
  strike_bank bank = nullptr;
  EXPECT_EQ(strike_bank_load_memory(ctx, bytes.data(), bytes.size(), &bank), STRIKE_OK);
  strike_object_config oc = strike_object_config_default();
  oc.bank = bank;
  oc.position[0] = -1.0;
  oc.position[1] = 1.0;
  oc.gain = 1e-3f;
  oc.radiation = STRIKE_RADIATION_UNIT;
  strike_object_id id{0, 0};
  EXPECT_EQ(strike_object_add(ctx, &oc, &id), STRIKE_OK);
  strike_impact_desc d = strike_impact_desc_default();
  d.object = id;
  d.surface_vertex = 4;
  d.impulse[2] = 1e-2;
  EXPECT_EQ(strike_impact(ctx, &d), STRIKE_OK);
  const uint32_t block = cfg.max_block_frames, blocks = 8;
  std::vector<float> planar(static_cast<size_t>(channels) * block * blocks);
  for (uint32_t b = 0; b < blocks; ++b) {
    std::vector<float> left(block), right(block);
    float* out[2] = {left.data(), right.data()};
    EXPECT_EQ(strike_render(ctx, out, channels, block), STRIKE_OK);
    std::copy(left.begin(), left.end(), planar.begin() + b * block);
    if (channels == 2) std::copy(right.begin(), right.end(), planar.begin() + (blocks + b) * block);
  }
  strike_bank_destroy(bank);
  strike_context_destroy(ctx);
  return planar;
}

TEST(CApi, BinauralRunsTheHostsResponses) {
  const uint32_t count = 6, taps = 8;
  const double directions[count * 3] = {1, 0, 0, -1, 0, 0, 0, 2, 0, 0, -2, 0, 0, 0, 1, 0, 0, -1};
  std::vector<float> left(count * taps, 0.0f), right(count * taps, 0.0f);
  for (uint32_t i = 0; i < count; ++i) left[i * taps] = 1.0f, right[i * taps + 3] = 0.5f;
  strike_status status = STRIKE_OK;
  const std::vector<float> mono = renderOutput(strike_output_desc_default(), 1, &status);
  ASSERT_EQ(status, STRIKE_OK);
  strike_output_desc output = strike_output_desc_default();
  output.format = STRIKE_OUTPUT_BINAURAL;
  output.hrtf_count = count;
  output.hrtf_length = taps;
  output.hrtf_directions = directions;
  output.hrtf_left = left.data();
  output.hrtf_right = right.data();
  const std::vector<float> ears = renderOutput(output, 2, &status);
  ASSERT_EQ(status, STRIKE_OK);
  const size_t frames = mono.size();
  double energy = 0.0;
  for (size_t n = 0; n < frames; ++n) {
    ASSERT_EQ(ears[n], mono[n]) << n;
    ASSERT_EQ(ears[frames + n], n >= 3 ? 0.5f * mono[n - 3] : 0.0f) << n;
    energy += double(mono[n]) * mono[n];
  }
  EXPECT_GT(energy, 0.0);
  // Refusals: no responses, too few directions, a struct from before the hrtf fields.
  strike_output_desc bad = output;
  bad.hrtf_left = nullptr;
  EXPECT_EQ(renderOutput(bad, 2, &status).size(), 0u);
  EXPECT_EQ(status, STRIKE_ERR_INVALID_ARG);
  bad = output;
  bad.hrtf_count = 3;
  renderOutput(bad, 2, &status);
  EXPECT_EQ(status, STRIKE_ERR_INVALID_ARG);
  bad = output;
  bad.struct_size = offsetof(strike_output_desc, hrtf_count);
  renderOutput(bad, 2, &status);
  EXPECT_EQ(status, STRIKE_ERR_INVALID_ARG);
  const double zero[count * 3] = {};
  bad = output;
  bad.hrtf_directions = zero;
  renderOutput(bad, 2, &status);
  EXPECT_EQ(status, STRIKE_ERR_INVALID_ARG);
}

TEST(CApi, WorldFrameImpactsUseThePose) {
  Fixture f;
  const strike_object_id id = f.add(5.0, 5.0);
  strike_impact_desc d = strike_impact_desc_default();
  d.object = id;
  d.frame = STRIKE_FRAME_WORLD;
  d.point[0] = 5.0, d.point[1] = 5.0, d.point[2] = 0.0;  // the plate's centre in world
  d.impulse[2] = 1e-2;
  ASSERT_EQ(strike_impact(f.ctx, &d), STRIKE_OK);
  ASSERT_EQ(f.render(f.block), STRIKE_OK);
  EXPECT_EQ(f.stats().impacts_scheduled, 1u);
  EXPECT_GT(f.stats().active_modes, 0u);
}

TEST(CApi, BudgetCullsTheQuietestObjectFirst) {
  strike_context_config c = strike_context_config_default();
  c.max_active_modes = 4;
  Fixture f(c);
  const strike_object_id loud = f.add(0.0, 1.0, 1e-3f);
  const strike_object_id quiet = f.add(0.0, 1.0, 1e-6f);
  ASSERT_EQ(f.hit(loud), STRIKE_OK);
  ASSERT_EQ(f.hit(quiet), STRIKE_OK);
  ASSERT_EQ(f.render(f.block), STRIKE_OK);
  const strike_stats s = f.stats();
  EXPECT_LE(s.active_modes, 4u);
  EXPECT_EQ(s.modes_culled, 4u);
  // What remains is the loud object alone: compare with a context that only has it.
  std::vector<float> with_budget;
  for (int k = 0; k < 4; ++k) {
    ASSERT_EQ(f.render(f.block), STRIKE_OK);
    with_budget.insert(with_budget.end(), f.left.begin(), f.left.end());
  }
  Fixture g;
  const strike_object_id only = g.add(0.0, 1.0, 1e-3f);
  ASSERT_EQ(g.hit(only), STRIKE_OK);
  ASSERT_EQ(g.render(g.block), STRIKE_OK);
  for (int k = 0; k < 4; ++k) {
    ASSERT_EQ(g.render(g.block), STRIKE_OK);
    for (uint32_t n = 0; n < g.block; ++n) ASSERT_NEAR(with_budget[k * g.block + n], g.left[n], 1e-6) << k << " " << n;
  }
}

TEST(CApi, FullQueueDropsAndCountsExactly) {
  strike_context_config c = strike_context_config_default();
  c.impact_queue_capacity = 64;
  c.max_impacts_per_render = 0;
  Fixture f(c);
  const strike_object_id id = f.add();
  int full = 0;
  for (int k = 0; k < 164; ++k)
    if (f.hit(id) == STRIKE_ERR_QUEUE_FULL) ++full;
  EXPECT_EQ(full, 100);
  EXPECT_EQ(f.stats().impacts_dropped_queue_full, 100u);
  EXPECT_EQ(f.stats().impacts_queued, 64u);
  ASSERT_EQ(f.render(f.block), STRIKE_OK);
  const strike_stats s = f.stats();
  // 64 impacts at the same instant on one object: 32 fit the per-object reserve.
  EXPECT_EQ(s.impacts_scheduled + s.impacts_inaudible + s.impacts_dropped_capacity, 64u);
  EXPECT_EQ(s.impacts_dropped_capacity, 64u - c.max_pending_impacts_per_object);
  EXPECT_EQ(f.hit(id), STRIKE_OK) << "the queue drained";
}

TEST(CApi, ImpactsBeyondThePerRenderLimitWaitForTheNextCall) {
  strike_context_config c = strike_context_config_default();
  c.max_impacts_per_render = 3;
  c.max_pending_impacts_per_object = 64;
  Fixture f(c);
  const strike_object_id id = f.add();
  for (int k = 0; k < 7; ++k) ASSERT_EQ(f.hit(id, 1000), STRIKE_OK);
  ASSERT_EQ(f.render(f.block), STRIKE_OK);
  EXPECT_EQ(f.stats().impacts_scheduled, 3u);
  ASSERT_EQ(f.render(f.block), STRIKE_OK);
  EXPECT_EQ(f.stats().impacts_scheduled, 6u);
  ASSERT_EQ(f.render(f.block), STRIKE_OK);
  EXPECT_EQ(f.stats().impacts_scheduled, 7u);
}

// Four producers flood a small queue while the audio thread renders and the main thread adds
// and removes objects: every impact is accounted for exactly once (run under TSan: preset tsan).
TEST(CApi, FourProducersWhileRendering) {
  strike_context_config c = strike_context_config_default();
  c.impact_queue_capacity = 128;
  c.max_block_frames = 128;
  c.max_objects = 8;
  Fixture f(c);
  std::vector<strike_object_id> ids;
  for (int k = 0; k < 4; ++k) ids.push_back(f.add(0.3 * k, 1.0));
  std::atomic<bool> stop{false};
  std::atomic<int> producers_done{0};
  std::atomic<uint64_t> ok{0}, full{0}, stale{0};
  std::thread audio([&] {
    std::vector<float> l(128), r(128);
    float* out[2] = {l.data(), r.data()};
    while (!stop.load(std::memory_order_acquire)) EXPECT_EQ(strike_render(f.ctx, out, 2, 128), STRIKE_OK);
  });
  std::vector<std::thread> producers;
  constexpr int kPerProducer = 20000;
  for (int p = 0; p < 4; ++p)
    producers.emplace_back([&, p] {
      strike_impact_desc d = strike_impact_desc_default();
      d.surface_vertex = p;
      d.impulse[2] = 1e-3;
      for (int k = 0; k < kPerProducer; ++k) {
        d.object = ids[static_cast<size_t>(k + p) % ids.size()];
        d.sample_offset = static_cast<uint32_t>(k % 64);
        const strike_status s = strike_impact(f.ctx, &d);
        if (s == STRIKE_OK)
          ok.fetch_add(1);
        else if (s == STRIKE_ERR_QUEUE_FULL)
          full.fetch_add(1);
        else if (s == STRIKE_ERR_STALE_ID)
          stale.fetch_add(1);
        else
          ADD_FAILURE() << "status " << s;
      }
      producers_done.fetch_add(1);
    });
  // Main thread: churn one object while impacts fly.
  strike_object_id churn = f.add(-1.0, 1.0);
  uint64_t main_full = 0;
  while (producers_done.load() < 4) {
    strike_impact_desc d = strike_impact_desc_default();
    d.object = churn;
    d.impulse[2] = 1e-3;
    if (strike_impact(f.ctx, &d) == STRIKE_ERR_QUEUE_FULL) ++main_full;  // may be stale when rendered
    EXPECT_EQ(strike_object_remove(f.ctx, churn), STRIKE_OK);
    churn = f.add(-1.0, 1.0);
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  for (auto& t : producers) t.join();
  stop.store(true, std::memory_order_release);
  audio.join();
  // Drain what is still queued: a render takes at most its per-call share of the queue, and on a
  // loaded machine the audio thread may have stopped with the queue still full (the queue's
  // capacity, 128, is drained in a bounded number of calls).
  const auto handled = [](const strike_stats& st) {
    return st.impacts_scheduled + st.impacts_inaudible + st.impacts_dropped_capacity + st.impacts_dropped_stale;
  };
  for (int call = 0; call < 1000 && handled(f.stats()) != f.stats().impacts_queued; ++call)
    ASSERT_EQ(f.render(128), STRIKE_OK);
  const strike_stats s = f.stats();
  EXPECT_EQ(ok.load() + full.load() + stale.load(), 4u * kPerProducer);
  EXPECT_EQ(stale.load(), 0u) << "producer ids stay alive";
  EXPECT_EQ(s.impacts_dropped_queue_full, full.load() + main_full);
  EXPECT_GT(ok.load(), 0u);
  EXPECT_EQ(s.impacts_scheduled + s.impacts_inaudible + s.impacts_dropped_capacity + s.impacts_dropped_stale,
            s.impacts_queued);
  std::printf(
      "producers: %llu queued, %llu dropped (queue full), %llu scheduled, %llu stale, %llu over reserve\n",
      static_cast<unsigned long long>(s.impacts_queued), static_cast<unsigned long long>(s.impacts_dropped_queue_full),
      static_cast<unsigned long long>(s.impacts_scheduled), static_cast<unsigned long long>(s.impacts_dropped_stale),
      static_cast<unsigned long long>(s.impacts_dropped_capacity));
}

// A bank whose allocation is Reserved gives the same samples as one that grows, and refuses what
// its reserve does not hold instead of growing it.
TEST(OscillatorBankRealtime, NoAllocImpactsMatchAddImpact) {
  const strike::ModeBank bank = strike::test::makeTestBank();
  strike::ModalObjectDesc desc;
  desc.eigenvalues = bank.eigenvalues;
  desc.rayleigh_stiffness = bank.material.rayleigh_stiffness;
  desc.rayleigh_mass = bank.material.rayleigh_mass;
  strike::SynthSettings realtime;
  realtime.allocation = strike::Allocation::Reserved;
  strike::OscillatorBank b{realtime, desc};
  b.reserveImpacts(4, 0.001);
  const double impulse[3] = {0, 0, 1e-2};
  std::vector<double> g(bank.modeCount());
  strike::projectImpulseAtVertexInto(bank, 4, impulse, g.data());
  EXPECT_EQ(g, strike::projectImpulseAtVertex(bank, 4, impulse));
  std::vector<float> oa(4096), ob(4096);
  // Four reserved records: the fifth pending impact is refused instead of growing the pool.
  for (int k = 0; k < 5; ++k) {
    const strike::ImpactDesc d{0.002 * k + 1e-5, 2e-4, g.data(), strike::PulseShape::HalfSine};
    EXPECT_EQ(b.addImpact(d), k < 4 ? strike::ImpactResult::Scheduled : strike::ImpactResult::NoCapacity) << k;
  }
  // Too long a pulse for the reserve is refused, not grown.
  const strike::ImpactDesc long_pulse{0.0, 0.01, g.data(), strike::PulseShape::HalfSine};
  EXPECT_EQ(b.addImpact(long_pulse), strike::ImpactResult::NoCapacity);
  strike::OscillatorBank c{strike::SynthSettings{}, desc}, d2{realtime, desc};
  d2.reserveImpacts(8, 0.001);
  for (int k = 0; k < 6; ++k) {
    const strike::ImpactDesc d{0.002 * k + 1e-5, 2e-4, g.data(), strike::PulseShape::HalfSine};
    c.addImpact(d);
    ASSERT_EQ(d2.addImpact(d), strike::ImpactResult::Scheduled);
  }
  c.render(oa.data(), oa.size());
  d2.render(ob.data(), ob.size());
  EXPECT_EQ(oa, ob);
  EXPECT_FALSE(d2.idle());
}

}  // namespace
