// SPDX-License-Identifier: MIT
// libstrike throughput and latency through the C API and its queues, at 48 kHz, 256-frame blocks.
//   BM_CapiRender/modes:N/hits:H  N/2000 objects of 2000 lightly damped modes, H impacts per block
//                           through strike_impact() (round robin), strike_render(256) stereo.
//                           Counters: active modes, real-time factor (block duration / time),
//                           and modes_realtime = active modes x real-time factor: how many modes
//                           one core renders in real time at this load.
//   BM_ImpactLatency        strike_impact() then strike_render(256) on a silent context: the wall
//                           time of the pair, and first_sample = index of the first non-zero
//                           output sample in that very block (latency in samples).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <vector>

#include "strike/strike.h"
#include "test_bank.hpp"

namespace {

constexpr double kRate = 48000.0;
constexpr uint32_t kBlock = 256;
constexpr size_t kModesPerObject = 2000;

struct Scene {
  strike_context ctx = nullptr;
  strike_bank bank = nullptr;
  std::vector<strike_object_id> ids;
  std::vector<float> l = std::vector<float>(kBlock), r = std::vector<float>(kBlock);
  float* out[2] = {l.data(), r.data()};

  explicit Scene(size_t objects, size_t modes_per_object) {
    strike_context_config c = strike_context_config_default();
    c.sample_rate_hz = kRate;
    c.max_block_frames = kBlock;
    c.max_objects = static_cast<uint32_t>(objects);
    c.max_active_modes = 0;  // measure raw throughput
    c.audibility_threshold = 1e-12;
    strike_context_create(&c, &ctx);
    std::vector<double> f(modes_per_object);
    for (size_t i = 0; i < f.size(); ++i)
      f[i] = 60.0 * std::pow(300.0, static_cast<double>(i) / static_cast<double>(f.size()));
    strike::ModeBank mb = strike::test::makeTestBank(f);
    mb.material.rayleigh_stiffness = 1e-11;  // decays slowly: modes stay awake
    mb.material.rayleigh_mass = 0.5;
    const std::vector<uint8_t> bytes = strike::encodeBank(mb);
    strike_bank_load_memory(ctx, bytes.data(), bytes.size(), &bank);
    for (size_t k = 0; k < objects; ++k) {
      strike_object_config oc = strike_object_config_default();
      oc.bank = bank;
      oc.position[0] = static_cast<double>(k % 7) - 3.0;
      oc.position[1] = 2.0;
      oc.radiation = STRIKE_RADIATION_UNIT;
      oc.gain = 1e-4f;
      strike_object_id id;
      strike_object_add(ctx, &oc, &id);
      ids.push_back(id);
    }
  }
  ~Scene() {
    strike_bank_destroy(bank);
    strike_context_destroy(ctx);
  }
  void hit(size_t k, uint32_t offset = 0) {
    strike_impact_desc d = strike_impact_desc_default();
    d.object = ids[k % ids.size()];
    d.surface_vertex = static_cast<int32_t>(k % 9);
    d.impulse[2] = 1e-2;
    d.sample_offset = offset;
    strike_impact(ctx, &d);
  }
};

void BM_CapiRender(benchmark::State& state) {
  const size_t modes = static_cast<size_t>(state.range(0));
  const size_t objects = (modes + kModesPerObject - 1) / kModesPerObject;
  Scene s(objects, kModesPerObject);
  for (size_t k = 0; k < objects; ++k) s.hit(k);
  for (int k = 0; k < 20; ++k) strike_render(s.ctx, s.out, 2, kBlock);  // warm up
  size_t k = 0;
  for (auto _ : state) {
    for (int64_t h = 0; h < state.range(1); ++h, ++k) s.hit(k, static_cast<uint32_t>(k % kBlock));
    strike_render(s.ctx, s.out, 2, kBlock);
    benchmark::DoNotOptimize(s.l.data());
    benchmark::ClobberMemory();
  }
  strike_stats st{};
  st.struct_size = sizeof st;  // 0.3: the library writes at most this many bytes
  strike_context_get_stats(s.ctx, &st);
  state.counters["active_modes"] = st.active_modes;
  state.counters["rt_factor"] = benchmark::Counter(kBlock / kRate, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["modes_realtime"] = benchmark::Counter(static_cast<double>(st.active_modes) * kBlock / kRate,
                                                        benchmark::Counter::kIsIterationInvariantRate);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * kBlock * st.active_modes);
}
BENCHMARK(BM_CapiRender)
    ->ArgNames({"modes", "hits"})
    ->ArgsProduct({{10000, 50000, 100000, 200000}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

void BM_ImpactLatency(benchmark::State& state) {
  Scene s(1, 64);
  double first_sum = 0, first_max = 0;
  int64_t n = 0;
  for (auto _ : state) {
    state.PauseTiming();
    // Silence: a fresh object each time so the previous hit does not ring into this block.
    strike_object_remove(s.ctx, s.ids[0]);
    strike_object_config oc = strike_object_config_default();
    oc.bank = s.bank;
    oc.radiation = STRIKE_RADIATION_UNIT;
    strike_object_add(s.ctx, &oc, &s.ids[0]);
    strike_render(s.ctx, s.out, 2, kBlock);
    state.ResumeTiming();
    s.hit(0);
    strike_render(s.ctx, s.out, 2, kBlock);
    state.PauseTiming();
    size_t first = kBlock;
    for (size_t i = 0; i < kBlock && first == kBlock; ++i)
      if (s.l[i] != 0.0f) first = i;
    first_sum += static_cast<double>(first);
    first_max = std::max(first_max, static_cast<double>(first));
    ++n;
    state.ResumeTiming();
  }
  state.counters["first_sample_mean"] = first_sum / static_cast<double>(n);
  state.counters["first_sample_max"] = first_max;
  state.counters["block"] = kBlock;
}
BENCHMARK(BM_ImpactLatency)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
