// SPDX-License-Identifier: MIT
// Oscillator bank throughput in mode-samples per second, against a naive per-mode double biquad
// loop measured in the same run (shared machines are noisy: the ratio is the number to compare).
//   BM_Render/modes:N/block:B    one object of N undamped modes (none sleeps), render(B frames)
//   BM_RenderBanks64/objects:K   K banks (objects) of 64 modes each, all active, render(512 frames) and mix
//   BM_NaiveBiquad/modes:N/block:B  y[n] = a1 y[n-1] - a2 y[n-2] per mode, double, mode-outer loop
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "strike/synth/synth.hpp"

namespace {

using strike::ImpactDesc;
using strike::ModalObjectDesc;
using strike::OscillatorBank;
using strike::SimdLevel;
using strike::SynthSettings;

ModalObjectDesc randomObject(size_t modes, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> freq(40.0, 19000.0);
  ModalObjectDesc d;
  for (size_t i = 0; i < modes; ++i) d.eigenvalues.push_back(std::pow(2 * M_PI * freq(rng), 2));
  d.radiation_weight.assign(modes, 1e-4);
  return d;  // no damping: every mode stays awake, constant work per iteration
}

void renderBench(benchmark::State& state, SimdLevel simd, size_t objects, size_t modes_per_object, size_t block) {
  SynthSettings s;
  s.simd = simd;
  s.audibility_threshold = 0.0;
  // One bank per object, as the engine has one per voice, mixed into one output.
  std::vector<OscillatorBank> banks;
  std::vector<double> g(modes_per_object, 1e-3);
  for (size_t o = 0; o < objects; ++o) {
    banks.emplace_back(s, randomObject(modes_per_object, static_cast<uint32_t>(o + 1)));
    banks.back().addImpact(ImpactDesc{0.0, 1e-4, g.data()});
  }
  std::vector<float> out(block), mix(block);
  size_t active = 0;
  for (OscillatorBank& bank : banks) {
    bank.render(out.data(), block);  // wake everything, outside the timing
    active += bank.stats().active_modes;
  }
  for (auto _ : state) {
    std::fill(mix.begin(), mix.end(), 0.0f);
    for (OscillatorBank& bank : banks) {
      bank.render(out.data(), block);
      for (size_t n = 0; n < block; ++n) mix[n] += out[n];
    }
    benchmark::DoNotOptimize(mix.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * block * active));
  state.counters["active_modes"] = static_cast<double>(active);
  state.SetLabel(banks.front().simdName());
}

void BM_Render(benchmark::State& state) {
  renderBench(state, SimdLevel::Auto, 1, static_cast<size_t>(state.range(0)), static_cast<size_t>(state.range(1)));
}
BENCHMARK(BM_Render)->ArgNames({"modes", "block"})->ArgsProduct({{64, 256, 1024, 4096}, {64, 512}});

void BM_RenderBanks64(benchmark::State& state) {
  renderBench(state, SimdLevel::Auto, static_cast<size_t>(state.range(0)), 64, 512);
}
BENCHMARK(BM_RenderBanks64)->ArgNames({"objects"})->Arg(16)->Arg(64);

void BM_RenderAvx2(benchmark::State& state) { renderBench(state, SimdLevel::Avx2, 1, 1024, 512); }
BENCHMARK(BM_RenderAvx2);
void BM_RenderScalar(benchmark::State& state) { renderBench(state, SimdLevel::Scalar, 1, 1024, 512); }
BENCHMARK(BM_RenderScalar);

void BM_RenderDouble(benchmark::State& state) {
  SynthSettings s;
  s.double_precision = true;
  s.audibility_threshold = 0.0;
  std::vector<double> g(1024, 1e-3);
  OscillatorBank bank(s, randomObject(1024, 1));
  bank.addImpact(ImpactDesc{0.0, 0.0, g.data()});
  std::vector<float> out(512);
  for (auto _ : state) {
    bank.render(out.data(), out.size());
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * 512 * 1024));
}
BENCHMARK(BM_RenderDouble);

// The textbook loop: per mode, a double two-pole resonator y = a1 y1 - a2 y2 summed into the output.
void BM_NaiveBiquad(benchmark::State& state) {
  const size_t modes = static_cast<size_t>(state.range(0)), block = static_cast<size_t>(state.range(1));
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> freq(40.0, 19000.0);
  std::vector<double> a1(modes), a2(modes), y1(modes), y2(modes);
  for (size_t i = 0; i < modes; ++i) {
    const double r = 0.99999, w = 2 * M_PI * freq(rng) / 48000.0;
    a1[i] = 2 * r * std::cos(w), a2[i] = r * r, y1[i] = 1e-3, y2[i] = 0.0;
  }
  std::vector<double> out(block);
  for (auto _ : state) {
    std::fill(out.begin(), out.end(), 0.0);
    for (size_t i = 0; i < modes; ++i) {
      double p1 = y1[i], p2 = y2[i];
      for (size_t n = 0; n < block; ++n) {
        const double y = a1[i] * p1 - a2[i] * p2;
        out[n] += y;
        p2 = p1, p1 = y;
      }
      y1[i] = p1, y2[i] = p2;
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * block * modes));
}
BENCHMARK(BM_NaiveBiquad)->ArgNames({"modes", "block"})->ArgsProduct({{64, 256, 1024, 4096}, {64, 512}});

// Console output plus a summary: mode-samples/s per configuration and the ratio to the biquad.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) {
      auto it = r.counters.find("items_per_second");
      if (it != r.counters.end()) rates_[r.benchmark_name()] = it->second.value;
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf("\n%-40s %14s %10s\n", "configuration", "G mode-smp/s", "x biquad");
    for (const auto& [name, rate] : rates_) {
      if (name.rfind("BM_NaiveBiquad", 0) == 0) continue;
      std::string base = "BM_NaiveBiquad/modes:1024/block:512";
      if (name.rfind("BM_Render/", 0) == 0) base = "BM_NaiveBiquad/" + name.substr(10);
      auto b = rates_.find(base);
      const double ratio = b != rates_.end() && b->second > 0 ? rate / b->second : 0.0;
      std::printf("%-40s %14.2f %10.1f\n", name.c_str(), rate * 1e-9, ratio);
    }
    for (const auto& [name, rate] : rates_)
      if (name.rfind("BM_NaiveBiquad", 0) == 0) std::printf("%-40s %14.2f %10s\n", name.c_str(), rate * 1e-9, "1.0");
  }

 private:
  std::map<std::string, double> rates_;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
