// SPDX-License-Identifier: MIT
// strike_render() and strike_impact() must not allocate. This program replaces every global
// operator new and (outside sanitizer builds) glibc's malloc family, counting calls made by a
// thread while its counting flag is on; 10,000 renders run while another thread sends impacts.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
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
              renders, static_cast<unsigned long long>(g_counted.load() - before), static_cast<unsigned long long>(sent.load()),
              static_cast<unsigned long long>(st.impacts_scheduled), static_cast<unsigned long long>(st.modes_culled));
  strike_bank_destroy(bank);
  strike_context_destroy(ctx);
}

}  // namespace
