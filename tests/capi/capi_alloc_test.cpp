// SPDX-License-Identifier: MIT
// strike_render(), strike_impact() and strike_step() must not allocate, and the allocator callback
// covers what strike.h says it covers. This program replaces every global
// operator new and (outside sanitizer builds) glibc's malloc family, counting calls made by a
// thread while its counting flag is on; 10,000 renders run while another thread sends impacts.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <map>
#include <new>
#include <thread>
#include <vector>

#include "strike/strike.h"
#include "test_bank.hpp"

namespace {
std::atomic<uint64_t> g_counted{0};
thread_local bool t_counting = false;  // initial-exec TLS in the executable: no allocation to read
inline void noteAllocation() {
  if (t_counting) g_counted.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

#if !defined(__SANITIZE_THREAD__) && !defined(__SANITIZE_ADDRESS__)
// Why __libc_*: glibc's own entry points, so the replacements need no dlsym (which allocates).
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
void __libc_free(void*);
void* malloc(size_t n) noexcept {
  noteAllocation();
  return __libc_malloc(n);
}
void* calloc(size_t a, size_t b) noexcept {
  noteAllocation();
  return __libc_calloc(a, b);
}
void* realloc(void* p, size_t n) noexcept {
  noteAllocation();
  return __libc_realloc(p, n);
}
void* aligned_alloc(size_t align, size_t n) noexcept {
  noteAllocation();
  return __libc_memalign(align, n);
}
void* memalign(size_t align, size_t n) noexcept {
  noteAllocation();
  return __libc_memalign(align, n);
}
int posix_memalign(void** out, size_t align, size_t n) noexcept {
  noteAllocation();
  void* p = __libc_memalign(align, n);
  if (!p) return 12;  // ENOMEM
  *out = p;
  return 0;
}
void free(void* p) noexcept { __libc_free(p); }
}
#define STRIKE_COUNTS_MALLOC 1
#else
#define STRIKE_COUNTS_MALLOC 0
#endif

// Why the pragma: GCC 12 cannot see that these replacements pair malloc with free.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(size_t n) {
  noteAllocation();
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](size_t n) { return ::operator new(n); }
void* operator new(size_t n, std::align_val_t a) {
  noteAllocation();
  const size_t al = static_cast<size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
  throw std::bad_alloc();
}
void* operator new[](size_t n, std::align_val_t a) { return ::operator new(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t, std::align_val_t) noexcept { std::free(p); }

namespace {

TEST(CApiRealtime, CounterSeesAllocations) {
  t_counting = true;
  const uint64_t before = g_counted.load();
  auto* v = new std::vector<int>(100);
  void* m = std::malloc(10);
  t_counting = false;
  delete v;
  std::free(m);
  EXPECT_GE(g_counted.load() - before, 1u + STRIKE_COUNTS_MALLOC);
}

TEST(CApiRealtime, TenThousandRendersWithImpactsFromAnotherThreadAllocateNothing) {
  strike_context_config c = strike_context_config_default();
  c.max_block_frames = 256;
  c.max_active_modes = 6;  // the budget culling path runs too
  strike_context ctx = nullptr;
  ASSERT_EQ(strike_context_create(&c, &ctx), STRIKE_OK);
  const std::vector<uint8_t> bytes = strike::encodeBank(strike::test::makeTestBank());
  strike_bank bank = nullptr;
  ASSERT_EQ(strike_bank_load_memory(ctx, bytes.data(), bytes.size(), &bank), STRIKE_OK);
  std::vector<strike_object_id> ids(3);
  for (size_t k = 0; k < ids.size(); ++k) {
    strike_object_config oc = strike_object_config_default();
    oc.bank = bank;
    oc.position[0] = static_cast<double>(k) - 1.0;
    oc.position[1] = 1.0;
    oc.gain = static_cast<float>(k + 1);
    ASSERT_EQ(strike_object_add(ctx, &oc, &ids[k]), STRIKE_OK);
  }
  std::atomic<bool> stop{false};
  std::atomic<uint64_t> sent{0};
  std::thread producer([&] {
    strike_impact_desc d = strike_impact_desc_default();
    d.impulse[2] = 1e-2;
    uint64_t k = 0;
    while (!stop.load(std::memory_order_acquire)) {
      d.object = ids[k % ids.size()];
      d.point[0] = 0.05 * static_cast<double>(k % 5) - 0.1;  // nearest-triangle path
      d.surface_vertex = (k % 3 == 0) ? static_cast<int32_t>(k % 9) : -1;
      d.sample_offset = static_cast<uint32_t>(k % 300);
      d.normal_speed_m_s = 0.1 + static_cast<double>(k % 10);
      d.pulse = (k % 7 == 0) ? STRIKE_PULSE_BOX : STRIKE_PULSE_HALF_SINE;
      t_counting = true;
      if (strike_impact(ctx, &d) == STRIKE_OK) sent.fetch_add(1, std::memory_order_relaxed);
      t_counting = false;
      ++k;
      if (k % 4 == 0) std::this_thread::yield();
    }
  });
  std::vector<float> l(256), r(256);
  float* out[2] = {l.data(), r.data()};
  const uint64_t before = g_counted.load();
  // At least 10,000 blocks, and on until the producer got 2,000 impacts in: on a loaded machine
  // the producer thread can be starved while the render loop runs. The deadline turns a stalled
  // producer into a failure instead of a hang.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  int renders = 0;
  for (int k = 0; k < 10000 || (sent.load() < 2000 && std::chrono::steady_clock::now() < deadline); ++k) {
    ++renders;
    t_counting = true;
    const strike_status s = strike_render(ctx, out, 2, 256);
    t_counting = false;
    ASSERT_EQ(s, STRIKE_OK);
    if (k % 16 == 0) std::this_thread::sleep_for(std::chrono::microseconds(100));  // let impacts arrive
  }
  stop.store(true, std::memory_order_release);
  producer.join();
  EXPECT_EQ(g_counted.load() - before, 0u);
  strike_stats st{};
  st.struct_size = sizeof st;
  ASSERT_EQ(strike_context_get_stats(ctx, &st), STRIKE_OK);
  EXPECT_GT(sent.load(), 1000u);
  EXPECT_GT(st.impacts_scheduled, 500u);
  EXPECT_GT(st.modes_culled, 0u);
  std::printf("%d renders x 256 frames: %llu allocations; %llu impacts sent, %llu scheduled, %llu culled modes\n",
              renders, static_cast<unsigned long long>(g_counted.load() - before),
              static_cast<unsigned long long>(sent.load()), static_cast<unsigned long long>(st.impacts_scheduled),
              static_cast<unsigned long long>(st.modes_culled));
  strike_bank_destroy(bank);
  strike_context_destroy(ctx);
}

// The allocator callback gets what strike.h says: the context and its queues, slots and engine;
// each bank handle; each object's record. Each is freed through the callback, and nothing is
// allocated by it (or by operator new / malloc) while rendering or reporting impacts and steps.
struct CountingAllocator {
  std::map<void*, size_t> live;
  uint64_t allocations = 0, frees = 0;
  static void* alloc(void* user, size_t size, size_t alignment) {
    auto* self = static_cast<CountingAllocator*>(user);
    void* p = std::aligned_alloc(alignment < alignof(std::max_align_t) ? alignof(std::max_align_t) : alignment,
                                 (size + alignment - 1) / alignment * alignment + alignment);
    const bool was = t_counting;
    t_counting = false;  // the map's node is the test's, not libstrike's
    self->live[p] = size;
    t_counting = was;
    ++self->allocations;
    return p;
  }
  static void release(void* user, void* p) {
    auto* self = static_cast<CountingAllocator*>(user);
    EXPECT_EQ(self->live.count(p), 1u) << "freed what it did not allocate";
    self->live.erase(p);
    ++self->frees;
    std::free(p);
  }
  size_t largest() const {
    size_t m = 0;
    for (const auto& kv : live) m = std::max(m, kv.second);
    return m;
  }
  size_t count(size_t at_least) const {
    size_t n = 0;
    for (const auto& kv : live) n += kv.second >= at_least ? 1 : 0;
    return n;
  }
};

TEST(CApiAlloc, TheCallbackCoversTheContextBanksAndObjectsAndNothingOnTheAudioPath) {
  CountingAllocator a;
  strike_context_config c = strike_context_config_default();
  c.alloc = CountingAllocator::alloc;
  c.free = CountingAllocator::release;
  c.user = &a;
  c.max_block_frames = 256;
  c.impact_queue_capacity = 1000;   // rounded up to 1024
  c.contact_queue_capacity = 3000;  // rounded up to 4096
  c.max_objects = 5;
  strike_context ctx = nullptr;
  ASSERT_EQ(strike_context_create(&c, &ctx), STRIKE_OK);
  // The context itself, its three queues (impacts, steps, commands), its three slot arrays and
  // the engine: 8 blocks. The queues hold at least capacity items each.
  EXPECT_EQ(a.live.size(), 8u);
  EXPECT_EQ(a.live.count(ctx), 1u) << "the context's own memory";
  EXPECT_GE(a.count(1024 * sizeof(strike_impact_desc)), 1u) << "the impact queue";
  EXPECT_GE(a.count(4096 * sizeof(strike_contact) / 2), 1u) << "the step queue (a record per state or contact)";
  const size_t after_create = a.live.size();

  const std::vector<uint8_t> bytes = strike::encodeBank(strike::test::makeTestBank());
  strike_bank bank = nullptr;
  ASSERT_EQ(strike_bank_load_memory(ctx, bytes.data(), bytes.size(), &bank), STRIKE_OK);
  EXPECT_EQ(a.live.size(), after_create + 1) << "the bank handle";
  EXPECT_EQ(a.live.count(bank), 1u);
  strike_object_config oc = strike_object_config_default();
  oc.bank = bank;
  oc.position[1] = 1.0;
  std::vector<strike_object_id> ids(3);
  for (auto& id : ids) ASSERT_EQ(strike_object_add(ctx, &oc, &id), STRIKE_OK);
  EXPECT_EQ(a.live.size(), after_create + 1 + ids.size()) << "one record per object";

  // The audio path: impacts, steps and renders allocate nothing, through the callback or not.
  std::vector<float> l(256), r(256);
  float* out[2] = {l.data(), r.data()};
  const uint64_t callback_before = a.allocations, global_before = g_counted.load();
  t_counting = true;
  for (int k = 0; k < 200; ++k) {
    strike_impact_desc d = strike_impact_desc_default();
    d.object = ids[k % 3];
    d.impulse[2] = 1e-3;
    (void)strike_impact(ctx, &d);
    strike_body_state state{};
    state.object = ids[(k + 1) % 3];
    state.orientation[0] = 1.0;
    state.position[1] = 1.0 + 0.01 * k;
    state.asleep = k % 5 == 0;
    strike_contact contacts[2] = {strike_contact_default(), strike_contact_default()};
    contacts[0].object = ids[(k + 1) % 3];
    contacts[0].impulse[2] = 0.16 + 0.01 * (k % 7);  // resting, with changes of load
    contacts[1].object = ids[(k + 2) % 3];
    contacts[1].impulse[2] = 0.02;
    contacts[1].normal_speed_m_s = 1.0;  // an impact
    strike_step_desc step = strike_step_desc_default();
    step.end_time_s = (k + 1) / 60.0;
    step.states = &state;
    step.state_count = 1;
    step.contacts = contacts;
    step.contact_count = 2;
    EXPECT_EQ(strike_step(ctx, &step), STRIKE_OK);
    ASSERT_EQ(strike_render(ctx, out, 2, 256), STRIKE_OK);
    strike_stats st{};
    st.struct_size = sizeof st;
    EXPECT_EQ(strike_context_get_stats(ctx, &st), STRIKE_OK);
  }
  t_counting = false;
  EXPECT_EQ(a.allocations - callback_before, 0u);
  EXPECT_EQ(g_counted.load() - global_before, 0u);
  strike_stats st{};
  st.struct_size = sizeof st;
  ASSERT_EQ(strike_context_get_stats(ctx, &st), STRIKE_OK);
  EXPECT_EQ(st.steps, 200u);
  EXPECT_GT(st.load_changes, 0u);
  EXPECT_GT(st.impacts_scheduled, 200u);

  // A removed object's record goes back through the callback once the audio thread let go.
  const uint64_t frees_before = a.frees;
  ASSERT_EQ(strike_object_remove(ctx, ids[0]), STRIKE_OK);
  ASSERT_EQ(strike_render(ctx, out, 2, 256), STRIKE_OK);
  ASSERT_EQ(strike_context_collect(ctx), STRIKE_OK);
  EXPECT_EQ(a.frees - frees_before, 1u);
  EXPECT_EQ(a.live.size(), after_create + 1 + ids.size() - 1);
  // strike_context_reset allocates nothing either.
  const uint64_t allocations_before_reset = a.allocations;
  ASSERT_EQ(strike_context_reset(ctx), STRIKE_OK);
  ASSERT_EQ(strike_render(ctx, out, 2, 256), STRIKE_OK);
  EXPECT_EQ(a.allocations, allocations_before_reset);
  // The bank outlives the context here: the context's blocks and records are all freed, then
  // the bank handle.
  strike_context_destroy(ctx);
  EXPECT_EQ(a.live.size(), 1u);
  EXPECT_EQ(a.live.count(bank), 1u);
  strike_bank_destroy(bank);
  EXPECT_TRUE(a.live.empty());
  EXPECT_EQ(a.allocations, a.frees);
}

}  // namespace
