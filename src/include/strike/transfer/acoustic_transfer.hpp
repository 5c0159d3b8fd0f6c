// SPDX-License-Identifier: MIT
// Acoustic transfer: what each vibration mode of a body radiates, as a function of direction.
// The data lives in a ModeBank (bank chunk ACTF, format 5); the solver is strike_transfer
// (src/transfer/), the evaluation (src/transfer/far_field.cpp, spherical_harmonics.cpp) is in
// strike_bank (C++ standard library only, so libstrike evaluates it at each impact).
//
// Conventions. Time dependence e^{-i omega t} (acoustics' usual one). For mode i with modal
// acceleration q_i''(t) = Re(Q e^{-i omega_i t}), the pressure far from the body is
//   p(r d) ~= Re( F_i(d) Q e^{i k (r - 0) - i omega_i t} ) / r,   k = omega_i / c_air,
// r measured from `centre_m` (mesh frame), d the unit direction in the mesh frame, and
//   F_i(d) = sum_{n=0}^{order_i} sum_{m=-n}^{n} c_{i,n,m} Y_nm(d)
// with Y_nm the real orthonormal spherical harmonics of realSphericalHarmonics() (index n^2+n+m).
// F is in Pa m per unit modal acceleration (m/s^2 sqrt(kg)). It is linear in the mode shape, so
// the arbitrary sign of an eigenvector, and the basis of a degenerate pair, cancel in the sum
// over modes of F_i(d) phi_i(p).J.
#pragma once

#include <array>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace strike {

struct AcousticTransfer {
  std::array<double, 3> centre_m{};               ///< expansion centre, mesh frame
  std::vector<uint32_t> order;                    ///< #modes: spherical-harmonic order n_max of each mode
  std::vector<uint64_t> offset;                   ///< #modes + 1: mode i's coefficients are [offset[i], offset[i+1])
  std::vector<std::complex<float>> coefficients;  ///< c_{i,n,m}, Pa m per unit modal acceleration
  /// #modes: estimated relative error of F_i over directions (rms of the error / rms of F_i).
  std::vector<float> relative_error;
  /// Acceleration noise (rigid translation, compact limit): a rigid acceleration a (m/s^2, mesh
  /// frame) radiates F(d) = -(i k rho_air / (4 pi)) d . M a, i.e. in time
  /// p(t) = rho_air / (4 pi c_air r) d . M da/dt. M is symmetric, m^3: the body's volume plus its
  /// added-mass tensor over rho_air (a sphere of radius a: M = 2 pi a^3 I) [Howe 1998; Chadwick,
  /// Zheng & James 2012]. Row-major.
  std::array<double, 9> translation_dipole_m3{};
  double air_density_kg_m3 = 0.0;  ///< what it was solved for
  double speed_of_sound_m_s = 0.0;
  double solve_seconds = 0.0;
  std::string method;  ///< e.g. "bem-chief, 6 elements per wavelength"

  size_t modeCount() const { return order.size(); }
  bool empty() const { return order.empty(); }
  /// Largest order over the modes (what an evaluation's scratch must hold: (n+1)^2 doubles).
  uint32_t maxOrder() const;
  /// rms over directions of |F_i|: sqrt(sum |c|^2 / (4 pi)), Pa m per unit modal acceleration.
  double rmsFarField(size_t mode) const;
  /// Empty when consistent with `modes` modes, else what is wrong.
  std::string checkConsistency(size_t modes) const;
};

/// Real orthonormal spherical harmonics Y_nm(d), n = 0..order, m = -n..n, at unit vector d
/// (normalized here; a zero vector gives the values at +z). out[n*n + n + m]; (order+1)^2 values.
/// Y_00 = 1/sqrt(4 pi); Y_1,-1 = sqrt(3/4pi) y, Y_10 = sqrt(3/4pi) z, Y_11 = sqrt(3/4pi) x.
/// No allocation (real-time safe).
void realSphericalHarmonics(uint32_t order, const double direction[3], double* out);

/// The constants of realSphericalHarmonics' recurrence up to `order` (square roots of ratios),
/// computed once so that an evaluation per impact does only multiplications and additions.
struct SphericalHarmonicsTable {
  uint32_t order = 0;
  std::vector<double> sectoral, first;  ///< per m
  std::vector<double> a, b;             ///< per (n, m), at n*n + n + m
};
SphericalHarmonicsTable sphericalHarmonicsTable(uint32_t order);
/// realSphericalHarmonics(table.order, direction, out), to the same bits. No allocation.
void realSphericalHarmonics(const SphericalHarmonicsTable& table, const double direction[3], double* out);

/// F_i(d) for every mode into out[0 .. #modes), given Y from realSphericalHarmonics() at
/// order >= maxOrder(): the plain sum, in double. The reference the fast form below is tested
/// against; the engine uses the fast form.
void evaluateFarField(const AcousticTransfer& transfer, const double* sh, std::complex<double>* out);

/// The fast evaluation's weights: Y_j (count values from realSphericalHarmonics()) rounded to
/// float, count floats. Each scales a coefficient's real and imaginary parts alike (the F16C
/// kernel puts each beside itself in its register). No allocation.
void farFieldWeights(const double* sh, size_t count, float* weights);

/// IEEE binary16 ("half precision"): 1 sign, 5 exponent and 10 fraction bits.
/// floatToHalf rounds a finite x with |x| < 65520 to the nearest half (ties to even); below the
/// smallest normal half, 2^-14, it gives zero (with x's sign): a CompactTransfer never holds a
/// subnormal half. halfToFloat is exact for zeros and normal halves.
uint16_t floatToHalf(float x);
float halfToFloat(uint16_t h);

/// The coefficients as the sound engine reads them at every evaluation: in half precision, each
/// mode scaled by a power of two that puts its largest real or imaginary part in [2^14, 2^15).
/// An evaluation is bound by reading the coefficients (a 0.4 m plate to 20 kHz: 1.1 MB here,
/// 2.2 MB as floats), so half the bytes is most of half the time. A half keeps 11 significant
/// bits: each coefficient is within 2^-11 of itself (relative), and a far field within about
/// 2^-11 / sqrt(3) = 2.8e-4 (-71 dB) of the float sum, rms over directions; parts under 2^-28
/// of the mode's largest are dropped. The bank file keeps the floats (AcousticTransfer).
struct CompactTransfer {
  std::vector<uint64_t> offset;  ///< #modes + 1, as AcousticTransfer::offset (in coefficients)
  std::vector<uint16_t> halves;  ///< 2 per coefficient: re, im (halves of c_j 2^s_i)
  std::vector<double> scale;     ///< #modes: 2^-s_i, what mode i's sum is multiplied by
  bool f16c = false;             ///< evaluate with F16C and AVX2 (the same bits as without)
  size_t modeCount() const { return scale.size(); }
  bool empty() const { return scale.empty(); }
};
/// allow_f16c = false keeps the portable loop even where the processor has F16C (tests).
CompactTransfer compactTransfer(const AcousticTransfer& transfer, bool allow_f16c = true);

/// F_i(d) for every mode at `directions` (1 or 2) directions in one pass over the coefficients:
/// out[k][0 .. #modes) from weights[k] (farFieldWeights at order >= the transfer's largest). The
/// direct path and the ground's image share one reading. No allocation (real-time safe).
///
/// Its arithmetic, the same bits on every machine (F16C with AVX2 where the processor has them,
/// else the portable loop): each half is turned into its float exactly; for each mode and direction,
/// eight partial sums S_r in single precision, S_r taking the coefficients j = r, r + 8,
/// r + 16, ... in that order (a float product q_j y_j, then a float addition: the project builds
/// without contracting them into fused multiply-adds); then
/// ((S0 + S2) + (S4 + S6)) + ((S1 + S3) + (S5 + S7)), the last addition in double, times the
/// mode's scale (exact: a power of two). Eight independent sums keep the processor busy. The
/// rounding error of the sum is below (count / 8 + 4) 2^-24 sum_j |q_j Y_j| (tested), ~1e-5 of
/// the mode's rms far field for the plates above.
void evaluateFarFields(const CompactTransfer& transfer, size_t directions, const float* const* weights,
                       std::complex<double>* const* out);

}  // namespace strike
