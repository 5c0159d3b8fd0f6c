// SPDX-License-Identifier: MIT
// Air absorption (air_absorption.hpp): a struck mode heard through 10 m of air loses what ISO
// 9613-1's formula says, at 1, 4, 8 and 16 kHz and three humidities.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "strike/synth/engine.hpp"

namespace strike {
namespace {

// ISO 9613-1:1993 eq. (3)-(5) and annex B, written out again here from the standard (not
// calling the library), dB per metre.
double isoAlpha(double f, double celsius, double humidity, double kpa) {
  const double t = celsius + 273.15, pa = kpa / 101.325, tr = t / 293.15;
  const double h = humidity * std::pow(10.0, -6.8346 * std::pow(273.16 / t, 1.261) + 4.6151) / pa;
  const double fro = pa * (24.0 + 4.04e4 * h * (0.02 + h) / (0.391 + h));
  const double frn = pa * std::pow(tr, -0.5) * (9.0 + 280.0 * h * std::exp(-4.170 * (std::pow(tr, -1.0 / 3.0) - 1.0)));
  return 8.686 * f * f *
         (1.84e-11 * std::pow(pa, -1.0) * std::pow(tr, 0.5) +
          std::pow(tr, -2.5) * (0.01275 * std::exp(-2239.1 / t) * std::pow(fro + f * f / fro, -1.0) +
                                0.1068 * std::exp(-3352.0 / t) * std::pow(frn + f * f / frn, -1.0)));
}

std::shared_ptr<ModeBank> oneModeBank(double f_hz) {
  auto bank = std::make_shared<ModeBank>();
  ModeBank& b = *bank;
  b.material.youngs_pa = 200e9;
  b.material.poisson = 0.3;
  b.material.density_kg_m3 = 7800;
  b.material.rayleigh_mass = 20.0;
  b.mass_kg = 0.1;
  b.eigenvalues = {std::pow(2.0 * M_PI * f_hz, 2)};
  b.surface_positions = {0, 0, 0, 0.01, 0, 0, 0, 0.01, 0};
  b.surface_normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  b.surface_triangles = {0, 1, 2};
  b.surface_node_index = {0, 1, 2};
  b.shapes = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  b.radiation_m2 = {1e-3};
  return bank;
}

/// Energy of one struck mode heard `distance_m` away.
double heardEnergy(double f_hz, double distance_m, bool air_on, const AirConditions& air) {
  EngineSettings settings;
  settings.synth.sample_rate_hz = 48000.0;
  settings.synth.audibility_threshold = 0.0;
  settings.max_voices = 1;
  settings.max_block_frames = 256;
  settings.realtime = false;
  settings.air_absorption = air_on;
  settings.air = air;
  SoundEngine engine(settings);
  const auto bank = oneModeBank(f_hz);
  VoiceDesc desc;
  desc.bank = bank;
  desc.weights = radiationWeights(*bank, settings.reference_distance_m);
  desc.pressure_scale = 1.0;
  const double at[3] = {0, distance_m, 0}, identity[4] = {1, 0, 0, 0};
  desc.pose.set(at, identity);
  Voice voice(desc, settings);
  engine.install(0, &voice);
  engine.setListener(Pose{});
  EngineImpact impact;
  impact.point = {0.003, 0.003, 0.0};
  impact.impulse = {0, 0, -0.01};
  impact.contact_duration_s = 0.0;
  impact.time_s = 0.0;
  engine.impact(impact);
  std::vector<float> out(256);
  double energy = 0.0;
  for (int block = 0; block < 60; ++block) {
    float* channel = out.data();
    engine.render(&channel, out.size());
    for (float x : out) energy += double(x) * x;
  }
  return energy;
}

TEST(AirAbsorption, DecayPerMetreMatchesTheStandardsFormula) {
  const double distance_m = 10.0;
  for (double humidity : {20.0, 50.0, 80.0}) {
    AirConditions air;
    air.relative_humidity_percent = humidity;
    for (double f : {1000.0, 4000.0, 8000.0, 16000.0}) {
      const double lost_db =
          10.0 * std::log10(heardEnergy(f, distance_m, false, air) / heardEnergy(f, distance_m, true, air));
      const double expected = isoAlpha(f, 20.0, humidity, 101.325);
      EXPECT_NEAR(lost_db / distance_m, expected, 0.01 * expected) << f << " Hz, " << humidity << "%";
      EXPECT_NEAR(airAttenuationDbPerM(f, air), expected, 1e-9 * expected);
    }
  }
  // ISO 9613-1 table 1 (20 C, 50 %, 101.325 kPa): 4.66 dB/km at 1 kHz.
  EXPECT_NEAR(airAttenuationDbPerM(1000.0, AirConditions{}) * 1000.0, 4.66, 0.01 * 4.66);
  // Colder, drier and thinner air: other relaxation frequencies, the same formula.
  AirConditions cold{-10.0, 30.0, 90.0};
  EXPECT_NEAR(airAttenuationDbPerM(4000.0, cold), isoAlpha(4000.0, -10.0, 30.0, 90.0), 1e-9);
}

}  // namespace
}  // namespace strike
