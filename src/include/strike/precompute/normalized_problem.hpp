// SPDX-License-Identifier: MIT
// Every computed bank comes from a solve of its object's normalized problem, scaled by
// similarBank(). The normalized problem keeps only what the mode shapes
// depend on: the shape at unit size, the Poisson ratio, the element order, the mesh resolution
// relative to the size, and the number of modes; its material is a fixed reference one. Objects
// that differ only by size, Young's modulus and density share it, so a dataset that draws sizes
// and materials at random solves each shape once, and the cache keys it that way.
//
// Determinism: a body's bank is ALWAYS its normalized solve scaled, whether that solve was just
// done, done for another object of this render, or read from the cache, so a render's bytes do
// not depend on what the cache holds. For the same reason the normalized solve has no cut-off: it
// holds the lowest max_modes modes of the shape, and every object of that shape keeps a prefix of
// them (those below its own cut-off), so the solve a body uses depends on that body alone, never
// on which larger or softer copy happened to be solved first. The price: max_modes modes solved
// for every shape, however few an object needs (a small stiff object may need none). A cut-off
// rounded up to a grid of half octaves was tried first: it solves fewer
// modes, but objects share a solve only within one grid cell, and on the randomized benchmark
// (examples/python/random-drops.json: 4 shapes x 3 scales 0.7, 1, 1.4 x 5 materials) the scales
// fall half an octave apart and the materials each have their own Poisson ratio: 60 solves for
// 60 objects, against 20 (4 shapes x 5 ratios) without a cut-off. Solving "only the modes beyond
// what was solved" for a larger copy would make the bank depend on the order objects came in (the
// first band's Lanczos basis seeds the rest, and eigenvector signs follow the basis), so it is
// not done.
//
// Unit size: a primitive is divided by its first length (box:LX,... by LX, sphere and cylinder by
// R), its other lengths kept to 12 significant digits, so that box:0.3,0.02,0.02 and
// box:0.6,0.04,0.04 are one problem even where the quotients differ in their last bit (the
// solved object then differs from the asked one by at most 5e-13 in its proportions). A mesh
// file is normalized to its own units (its "units" / --units scale is the size).
#pragma once

#include <cstdint>
#include <limits>

#include "strike/precompute/precompute.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// The reference material of every normalized solve: only its Poisson ratio (the object's)
/// matters. E / rho = 10^7 m^2/s^2 (a wave speed of ~3.2 km/s, like metals and glass), so a
/// unit-size object rings in the kHz range where the solver's defaults are at home.
constexpr double kNormalizedYoungs_pa = 1e10;
constexpr double kNormalizedDensity_kg_m3 = 1e3;

struct NormalizedProblem {
  PrecomputeSettings settings;  ///< the unit-size, reference-material solve (progress kept)
  double scale = 1.0;           ///< metres of the object per unit of the normalized problem
};

/// The normalized solve's cut-off: none (its lowest max_modes modes).
constexpr double kNormalizedNoCutoffHz = std::numeric_limits<double>::infinity();

/// The normalized problem of `actual` (max_freq_hz kNormalizedNoCutoffHz).
NormalizedProblem normalizeProblem(const PrecomputeSettings& actual);

/// Cache key of a normalized solve (mesh_hash: of the normalized mesh spec or file bytes).
uint64_t normalizedBankCacheKey(uint64_t mesh_hash, const NormalizedProblem& problem);

/// The actual object's bank from its normalized bank (modes or mass and surface only): frequencies,
/// shapes, mass and surface scaled, the actual material (damping) and provenance. mesh_hash is the
/// actual mesh's (file bytes or spec text).
Result<ModeBank> scaleNormalizedBank(const ModeBank& normalized, const NormalizedProblem& problem,
                                     const PrecomputeSettings& actual, uint64_t mesh_hash);

// ---- The acoustic transfer of similar banks ----------------------------------------
// The transfer depends on ka of each mode, which similarity changes only through the material:
// scaled by s from the unit size and made of E, rho, a mode's omega is the normalized one times
// sqrt((E/rho) / (E_ref/rho_ref)) / s and the body's radius s times the unit one, so ka is the
// normalized ka times the ratio of wave speeds, whatever the size. The exterior problem of the
// scaled body with data scaled by shape_factor then has the solution p'(s x) = shape_factor s
// p(x) of the unit body's (similar_bank.cpp), so F' = shape_factor s^2 F exactly. So ONE solve
// serves every object of a shape and of one E/rho, at any size and density: the UNIT TRANSFER,
// solved on the normalized solve at unit size with its eigenvalues scaled to the object's wave
// speed (unitTransferBank) and scaled to each object (attachUnitTransfer).
// Determinism: the unit transfer depends on the shape, E/rho, the modes kept and the transfer
// settings only, never on which object of a render came first or on the cache (the cache keeps its
// exact bits: floats and doubles as they are). The modes kept are part of its key: the solver's
// near-quadrature rules are chosen at the bank's largest k, so a transfer of 12 modes is not the
// prefix of one of 20. With no mode kept the transfer is the rigid translation's dipole alone,
// which does not depend on the material: one for every material.

/// Cache key of the unit transfer (the cache entry KEY.transfer) of an object of `actual`'s
/// material and transfer settings that keeps `kept_modes` modes of the normalized solve keyed
/// `normalized_key` (normalizedBankCacheKey).
uint64_t unitTransferCacheKey(uint64_t normalized_key, const PrecomputeSettings& actual, size_t kept_modes);

/// The bank the unit transfer is solved on: `normalized` (shapes loaded) at unit size, its first
/// `kept_modes` modes, eigenvalues times (E/rho) / (E_ref/rho_ref) of `actual`'s material.
ModeBank unitTransferBank(const ModeBank& normalized, const PrecomputeSettings& actual, size_t kept_modes);

/// Solves the unit transfer (actual.transfer's settings). The result is what the cache keeps: the
/// unit bank's header, eigenvalues and transfer, without surface or shapes (a few hundred kB).
Result<ModeBank> solveUnitTransfer(const ModeBank& normalized, const PrecomputeSettings& actual, size_t kept_modes);

/// Whether `cached` (a KEY.transfer entry read back) is the unit transfer of these: the same
/// normalized mesh, the same eigenvalues to the bit, a transfer of every mode in the same air.
bool isUnitTransferOf(const ModeBank& cached, const ModeBank& normalized, const PrecomputeSettings& actual,
                      size_t kept_modes);

/// Sets `scaled.transfer` (a bank from scaleNormalizedBank) to the unit transfer `unit` scaled to
/// its object: F' = shape_factor s^2 F, the dipole times s^3. The unit transfer keeps the heard
/// modes (modesAtOrBelow the object's transfer_max_freq_hz), a prefix of the bank's.
Status attachUnitTransfer(ModeBank& scaled, const ModeBank& unit, const NormalizedProblem& problem,
                          const PrecomputeSettings& actual);

/// What `strike modes` and a render compute: the normalized solve, scaled (and with
/// actual.acoustic_transfer, the unit transfer solved and scaled).
Result<PrecomputeResult> computeSimilarModeBank(const PrecomputeSettings& actual);

}  // namespace strike
