// SPDX-License-Identifier: MIT
// Banks written in code (no eigen-solve: the eigenvalues and shapes are chosen, tests/capi's
// 3x3 plate) and struck once through the C API, for the runtime tests.
#pragma once

#include <cstdint>
#include <vector>

#include "capi/test_bank.hpp"
#include "check.hpp"
#include "strike/bank/bank.hpp"
#include "strike/strike.h"

namespace strike::runtime_test {

/// A bank file's bytes: modes at `freqs_hz` (eigenvalues (2 pi f)^2) with Rayleigh damping
/// C = rayleigh_mass M + rayleigh_stiffness K, i.e. decay rate sigma = (a_mass + a_stiff w^2) / 2.
inline std::vector<uint8_t> bankBytes(const std::vector<double>& freqs_hz, double rayleigh_stiffness_s,
                                      double rayleigh_mass_per_s) {
  ModeBank bank = test::makeTestBank(freqs_hz);
  bank.material.rayleigh_stiffness = rayleigh_stiffness_s;
  bank.material.rayleigh_mass = rayleigh_mass_per_s;
  return encodeBank(bank);
}

/// Loads `bank_bytes`, strikes the centre vertex (which moves in every mode) once at t = 0 and
/// renders `frames` mono samples at `sample_rate_hz`, 1 m from the listener.
inline std::vector<float> strikeOnce(const std::vector<uint8_t>& bank_bytes, double sample_rate_hz, size_t frames) {
  constexpr uint32_t kBlock = 256;
  strike_context_config config = strike_context_config_default();
  config.sample_rate_hz = sample_rate_hz;
  config.max_block_frames = kBlock;
  config.channels = 1;
  config.audibility_threshold = 0.0;  // no mode put to sleep: the whole decay is measured
  strike_context context = nullptr;
  CHECK_OK(strike_context_create(&config, &context));
  strike_bank bank = nullptr;
  CHECK_OK(strike_bank_load_memory(context, bank_bytes.data(), bank_bytes.size(), &bank));
  strike_object_config object_config = strike_object_config_default();
  object_config.bank = bank;
  object_config.position[1] = 1.0;
  object_config.radiation = STRIKE_RADIATION_UNIT;  // the modes' displacement, no radiation filter
  object_config.gain = 1e-3f;
  strike_object_id object{};
  CHECK_OK(strike_object_add(context, &object_config, &object));
  strike_impact_desc hit = strike_impact_desc_default();
  hit.object = object;
  hit.surface_vertex = 4;
  hit.impulse[2] = 1e-2;  // N s
  hit.normal_speed_m_s = 1.0;
  CHECK_OK(strike_impact(context, &hit));
  std::vector<float> samples(frames, 0.0f);
  for (size_t start = 0; start + kBlock <= frames; start += kBlock) {
    float* out[1] = {samples.data() + start};
    CHECK_OK(strike_render(context, out, 1, kBlock));
  }
  strike_bank_destroy(bank);
  strike_context_destroy(context);
  return samples;
}

}  // namespace strike::runtime_test
