// SPDX-License-Identifier: MIT
// ISO 9613-1:1993, sec. 6 and annex B: the relaxation frequencies of oxygen and nitrogen from
// the molar concentration of water vapour, then the classical and rotational absorption plus the
// two vibrational relaxations.
#include "strike/synth/air_absorption.hpp"

#include <cmath>

namespace strike {

double airAttenuationDbPerM(double f_hz, const AirConditions& air) {
  constexpr double kReferencePressure_kpa = 101.325;
  constexpr double kReferenceTemperature_k = 293.15;
  constexpr double kTriplePoint_k = 273.16;
  const double t = air.temperature_c + 273.15;
  const double pa = air.pressure_kpa / kReferencePressure_kpa;
  const double tr = t / kReferenceTemperature_k;
  // Annex B, eq. (B.1)-(B.3): saturation vapour pressure over the reference, then h in percent.
  const double c = -6.8346 * std::pow(kTriplePoint_k / t, 1.261) + 4.6151;
  const double h = air.relative_humidity_percent * std::pow(10.0, c) / pa;
  // Eq. (3) and (4): relaxation frequencies, Hz.
  const double fr_o = pa * (24.0 + 4.04e4 * h * (0.02 + h) / (0.391 + h));
  const double fr_n = pa / std::sqrt(tr) * (9.0 + 280.0 * h * std::exp(-4.170 * (std::cbrt(1.0 / tr) - 1.0)));
  const double f2 = f_hz * f_hz;
  // Eq. (5).
  return 8.686 * f2 *
         (1.84e-11 / pa * std::sqrt(tr) + std::pow(tr, -2.5) * (0.01275 * std::exp(-2239.1 / t) / (fr_o + f2 / fr_o) +
                                                                0.1068 * std::exp(-3352.0 / t) / (fr_n + f2 / fr_n)));
}

}  // namespace strike
