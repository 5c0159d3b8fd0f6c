// SPDX-License-Identifier: MIT
// The acoustic transfer solver: for every mode of a bank, the far field that its
// surface acceleration radiates with the body as an acoustic obstacle, as spherical-harmonic
// coefficients (acoustic_transfer.hpp for the conventions). Target strike_precompute (Eigen).
//
// Method (docs/acoustic-transfer.md): the exterior Neumann Helmholtz problem
//   (Delta + k^2) p = 0 outside the body,  dp/dn = -rho_air a_n on its surface,  outgoing,
// solved by a collocation boundary-element method on the bank's own surface triangles:
// the conventional boundary integral equation (Kirkup 2007, "The boundary element method in
// acoustics", ch. 3)
//   1/2 p(x) - int_S p dG/dn_y dS = - int_S G dp/dn dS,   G = e^{ikr} / (4 pi r),
// with the pressure piecewise constant on CLUSTERS of triangles (a bounding-volume tree cut at
// the size the wavelength asks for: elements per wavelength from the target error, within an
// element budget) and the integrals over the exact triangles (far cells by their moments, near
// ones subdivided adaptively, the singular one by a Duffy transform), so a coarse solve keeps
// the geometry and the fine boundary data. Fictitious interior resonances (Schenck 1968, CHIEF)
// are suppressed by interior points in least squares once k reaches the body's interior
// resonance range. The far field is projected onto spherical harmonics from the surface
// integral with the plane wave's expansion; the order is cut where the tail's energy is small.
// Error estimate per mode: the far field of the same system with clusters merged pairwise
// (about half the unknowns), against the full one, plus the truncated tail.
// Cost (docs/acoustic-transfer.md): a row is summed over the cut's pieces in vectorized passes;
// the near triangles' quadrature is built once per cut (rules at the group's k rounded up to a
// quarter octave) and only its exponentials are evaluated per mode; modes of one frequency share the system and
// its LU or least-squares QR (single precision, refined in double); the far field is summed at
// the directions of a Gauss-Legendre x uniform rule and projected on the harmonics. The rows
// and the directions are each done in two fixed halves, the second on a helper thread (same
// bits on one thread), as are the fine solve and the error estimate's coarse one.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "strike/transfer/acoustic_transfer.hpp"
#include "strike/bank/bank.hpp"
#include "strike/core/air.hpp"
#include "strike/core/progress.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// One decision of a time budget (TransferSettings::max_seconds): whether to make a solve of
/// `elements` unknowns for the group of modes [first_mode, first_mode + modes), from its
/// forecast (the rates measured on the solve before it, scaled to its unknowns).
struct TransferBudgetStep {
  enum class Kind {
    Refinement,  ///< not made: the group keeps the solve it has
    FirstSolve,  ///< the group's first solve; not made: tried again with the fewest unknowns
    Fewest,      ///< the group's first solve with the fewest unknowns; not made: the transfer
                 ///< ends before this group (it and the groups above keep none)
  };
  Kind kind = Kind::Refinement;
  size_t first_mode = 0, modes = 0;
  size_t elements = 0;     ///< the unknowns of the solve forecast
  double elapsed_s = 0.0;  ///< since the solve started
  double forecast_s = 0.0;
  double budget_s = 0.0;
  bool made = false;
};

struct TransferSettings {
  double air_density_kg_m3 = kAirDensity_kg_m3;
  double speed_of_sound_m_s = kSpeedOfSoundAir_m_s;
  /// Target relative error of each mode's far field (rms over directions); picks the resolution
  /// (elements per wavelength ~ 1/sqrt(target)). 0.05 is -26 dB.
  double target_relative_error = 0.05;
  /// Element budget: at most this many unknowns per mode's solve (dense complex LU / QR,
  /// cost ~ N^3). Above it the solve is coarser than the target asks and says so in its error.
  uint32_t max_elements = 700;
  /// At least this many unknowns (or every triangle of a smaller surface): the mode's pattern
  /// needs them even where the wavelength does not.
  uint32_t min_elements = 160;
  /// Force this many unknowns for every mode (0: automatic). For studies of error against cost.
  uint32_t fixed_elements = 0;
  /// Square systems (no interior points) with more unknowns than this are solved by restarted
  /// GMRES (a relative residual of min(1e-5, target / 100)), the others by a dense LU: with an
  /// element budget above it, thin walls get more unknowns at ~N^2 instead of N^3.
  uint32_t direct_max_elements = 700;
  /// Those iterative systems as hierarchical matrices: well-separated blocks compressed by
  /// adaptive cross approximation, memory and products ~ N log N (false: dense, N^2; a study).
  bool hierarchical = true;
  /// Interior (CHIEF) points once k reaches the interior resonances (false: never; a study).
  bool chief = true;
  /// 2: the system's rows are assembled, and the far field summed at its directions, in two
  /// fixed halves, the second on a helper thread when the machine has two cores (as the
  /// eigen-solve's block stage). The bits do not depend on it.
  int threads = 2;
  /// Time budget of the solve, seconds from its start (0: none; not part of a bank cache key).
  /// Before each refinement step and each group's first solve the step's time is forecast from
  /// the rates measured on the solve before it; a step forecast to end past the budget is not
  /// made: a refinement leaves the group its coarser solve (with that solve's estimate), a first
  /// solve is tried with the fewest unknowns (min_elements), and when even that does not fit the
  /// transfer ends there: it holds the groups below (a prefix of the modes; a render that plays
  /// the others solves theirs). The first solve of all is always made (it measures the rates),
  /// and so is the rigid translation's dipole. What is decided depends on the machine's speed:
  /// the bank does too (docs/cli.md).
  double max_seconds = 0.0;
  /// Told each decision of the time budget (optional).
  std::function<void(const TransferBudgetStep&)> on_budget_step;
};

/// The solver's revision, in the bank cache's key of banks with a transfer: raised whenever the
/// same inputs give other numbers (2: the faster assembly, far field and single-precision LU of
/// 2026-11; 3: modes share a solve while the gap costs a tenth of the target, the far field is
/// first projected to a lower order, a group goes straight to the budget when a lower frequency
/// missed the target there; 4: least-squares (interior-point) systems by a single-precision QR
/// refined in double, which changes the last bits of a few coefficients; 5: a group's near
/// quadrature rules chosen at its own wavenumber (rounded up to a quarter octave) instead of the
/// bank's largest, and no group starting at the budget because a lower one missed the target
/// there: a group's transfer depends on its own modes and the settings alone; 6: square systems
/// above direct_max_elements as hierarchical matrices with adaptive cross approximation, which
/// changes the solutions of budgets above 700 within the approximation's tolerance; the default
/// budget's are the same bits; 7: triangles larger than k d = 2.5 integrated by collapsed Gauss
/// products of their k d instead of split for the oscillation, near and far, which moves
/// entries by the rules' errors, 2.5e-5 near and 1e-3 far of area / r), so cached transfers are solved again rather than mixed with the
/// new solver's.
constexpr uint32_t kTransferSolverRevision = 7;

/// What one mode's solve cost and found (for studies and reports).
struct TransferModeStats {
  double ka = 0.0;              ///< k times the surface's radius about the centre
  uint32_t elements = 0;        ///< unknowns of the solve
  uint32_t chief_points = 0;    ///< interior points used (0: square system)
  uint32_t order = 0;           ///< spherical-harmonic order kept
  double relative_error = 0.0;  ///< the estimate stored in the transfer
  double seconds = 0.0;
  double assembly_seconds = 0.0;   ///< of `seconds`: the system's matrix and right-hand side
  double factor_seconds = 0.0;     ///< of `seconds`: LU / QR and the coarse solve
  double far_field_seconds = 0.0;  ///< of `seconds`: the spherical-harmonic projection
  uint32_t solves = 0;             ///< systems solved (refinement steps)
  uint32_t iterations = 0;         ///< GMRES iterations of the kept solve (0: a direct solve)
  /// What its group's solves held at most, counted by the solver: the fine system's matrix
  /// (dense, or the hierarchical matrix's blocks) and the near quadrature caches.
  uint64_t matrix_bytes = 0, near_cache_bytes = 0;
};

/// The memory of the largest system of a solve with `elements` unknowns, forecast before it is
/// allocated. Dense (at most direct_max_elements unknowns, or without the hierarchical matrix):
/// the matrix in double and its single-precision copy (LU), and the error estimate's coarse
/// system beside it (about half the unknowns), 24 bytes per entry; the interior points' rows (at
/// most a tenth more) included. Hierarchical (src/transfer/hmatrix.hpp): 16 bytes per value,
/// n min(n, 40 sqrt(n)) values (measured on the 4 mm bench plate: 1400 a row at 1473 unknowns,
/// 2000-2200 at 2931, against 38 sqrt(n) and 40 sqrt(n)), the coarse system's restriction half
/// that, and GMRES's two bases of 61 vectors.
inline double transferSystemBytes(uint64_t elements, uint32_t direct_max_elements = 700, bool hierarchical = true) {
  const double n = static_cast<double>(elements);
  if (!hierarchical || elements <= direct_max_elements) {
    const double rows = 1.1 * n, coarse = 0.5 * n + 0.1 * n;
    return 24.0 * (rows * n + coarse * 0.5 * n);
  }
  const double per_row = std::min(n, 40.0 * std::sqrt(n));
  return 16.0 * (1.5 * n * per_row + 2.0 * 61.0 * n);
}

/// The groups of modes that share one solve (modes of nearly one frequency: a degenerate pair
/// split by the mesh's asymmetry): group g is modes [starts[g], starts[g + 1]), the last entry
/// is the mode count. Each group's transfer (coefficients, order, estimate) depends on its own
/// modes' eigenvalues and shapes, the surface and the settings alone: solving a bank whose modes
/// are some of these groups gives those groups the same bits (so a bank may be extended by the
/// groups above the ones it has, as a cold solve of them all would give). A group starts where a
/// mode is farther from the group's first mode than the target allows, so the groups of the
/// modes from a group start on do not depend on the modes below it.
std::vector<size_t> transferGroups(const ModeBank& bank, const TransferSettings& settings);

/// Solves the transfer of every mode of `bank` (its eigenvalues, shapes on surface vertices,
/// surface triangles CCW from outside) and the rigid translation's dipole tensor. `progress`
/// (optional) is called with phase "transfer" and the fraction of modes done. `stats`
/// (optional) receives one entry per mode.
Result<AcousticTransfer> solveAcousticTransfer(const ModeBank& bank, const TransferSettings& settings = {},
                                               const ProgressFn& progress = {},
                                               std::vector<TransferModeStats>* stats = nullptr);

}  // namespace strike
