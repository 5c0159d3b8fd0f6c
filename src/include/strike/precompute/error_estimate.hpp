// SPDX-License-Identifier: MIT
// Estimated frequency error per mode of a mode bank, and the cheapest-mesh search behind
// `strike modes --tolerance`.
//
// Method (Richardson 1911; Roache, "Verification and Validation in Computational Science and
// Engineering", 1998, ch. 5): the same problem is solved again on a mesh about twice as coarse
// (h_c / h_f = r, measured as the cube root of the tet-count ratio, so the extra solve has ~1/8
// of the unknowns), the modes are paired in ascending order (within a degenerate group any
// pairing gives the same frequencies; sorted pairing minimizes the largest difference over all
// pairings), and the fine mesh's relative error is estimated as
//     e_i = Fs |f_c,i - f_f,i| / ((r^p - 1) f_f,i),
// with the asymptotic order of the frequency error p = 2 for Tet4 and p = 4 for Tet10 (eigenvalue
// error O(h^{2k}) for degree-k elements: Strang & Fix, "An Analysis of the Finite Element
// Method", 1973, ch. 6) -- but p = 2 for Tet10 on re-faceted curved primitives (sphere,
// cylinder), whose straight-edged boundary error is O(h^2) -- and the safety factor Fs of
// Roache's grid convergence index.
// When the mesh can be regenerated but not coarser (thin walls: the automatic mesh is as coarse
// as the walls allow), a Tet10 bank is compared with a finer mesh instead (1.7-4x the tets):
//     e_i = Fs |f_ff,i - f_f,i| r^2 / ((r^2 - 1) f_f,i),   method "richardson-finer",
// p = 2 because re-entrant edges (a cup's rim and foot) keep Tet10 below h^4 (observed 1.3 on
// a mug); within 1.8-3.6x of the truth on the mug and a small cup (tests/unit/extreme).
// When the mesh cannot be regenerated coarser (a tet file), a Tet10 bank is compared with Tet4
// on its corner nodes instead: e_i = |f_4,i - f_10,i| / f_10,i, an upper bound in practice
// (the Tet4 error dominates) but pessimistic by one to two orders of magnitude.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "strike/precompute/precompute.hpp"

namespace strike {

struct ErrorEstimateReport {
  std::string method;    ///< "richardson", "richardson-finer" or "tet4-corner" (empty when not estimated)
  std::string note;      ///< why not estimated, or a caveat
  double seconds = 0.0;  ///< extra run time (meshing + assembly + solve of the coarse problem)
  double ratio = 0.0;    ///< h_coarse / h_fine (richardson)
  size_t coarse_dofs = 0;
  size_t unmatched = 0;  ///< fine modes with no coarse partner (their estimate is 1.0 = 100%)
};

/// Grid-convergence safety factor Fs: Roache recommends 3 for a two-mesh study (1.25 needs three
/// meshes and an observed order). With 1.25 the default Tet4 bar was under-estimated (13% for 16%); the
/// validation tests in tests/unit/extreme/accuracy_test.cpp state how often it holds.
constexpr double kRichardsonSafety = 3.0;

/// The coarse problem must have at least this many unknowns per mode (counting the 6 rigid
/// ones) for mode i to get an estimate: coarse DOF >= 20 (i + 7). Below that, 1.0 ("unknown").
constexpr size_t kMinCoarseDofsPerMode = 20;

/// Thin walls (no coarser mesh): the finer mesh solved for the estimate may have at most this
/// many unknowns; past it the Tet10 estimate falls back to the Tet4-corner bound.
constexpr size_t kMaxFinerEstimateDofs = 500000;

/// True when `mesh_spec` can be meshed again at another resolution (a primitive or a surface).
bool canRemesh(const std::string& mesh_spec);

/// Fills `estimate` (one relative error per fine eigenvalue) for the bank computed from `loaded`
/// with `settings`. On an error the estimate is left empty.
Result<ErrorEstimateReport> estimateFrequencyErrors(const LoadedMesh& loaded, const PrecomputeSettings& settings,
                                                    const std::vector<double>& fine_eigenvalues,
                                                    std::vector<double>& estimate);

/// Non-empty for Tet4 with a nearly incompressible material (nu > 0.45): linear tets lock
/// volumetrically there (Hughes, "The Finite Element Method", 2000, sec. 4.1) and ring too high;
/// measured on a rubber bar (tests/unit/extreme/extreme_test.cpp) Tet4/Tet10 = 1.49 at nu 0.49
/// and 1.72 at nu 0.4999.
std::string lockingWarning(int order, const Material& material);

/// One step of computeModeBankToTolerance.
struct ToleranceTrial {
  int order = 2;
  double target_edge_m = 0.0;  ///< the requested edge, or the automatic mesh's mean edge
  size_t dofs = 0;
  double seconds = 0.0;       ///< its precompute + error estimate
  double max_estimate = 0.0;  ///< largest estimated relative error over kept modes
  bool met = false;
  std::string method;           ///< of its error estimate
  double forecast_seconds = 0;  ///< forecast before the step (0: none yet)
  double forecast_bytes = 0;
  double peak_bytes = 0;  ///< the process's peak resident memory after it
};

struct ToleranceResult {
  PrecomputeResult chosen;             ///< the last (finest) step's bank
  std::vector<ToleranceTrial> trials;  ///< in the order tried (coarsest first)
  double total_seconds = 0.0;
  bool met = false;                ///< false: the finest step is returned, tolerance missed
  bool stopped_by_budget = false;  ///< the next step's forecast exceeded max_bytes or max_seconds
  std::string stop_reason;         ///< why it stopped unmet (budget, no finer mesh), empty when met
};

/// The DOF of one refinement step are at most this many times the last step's.
constexpr double kMaxDofGrowthPerStep = 3.0;
constexpr int kMaxToleranceSteps = 8;

struct ToleranceOptions {
  double tolerance = 0.005;  ///< relative, e.g. 0.005 for 0.5%
  double max_bytes = 0.0;    ///< memory budget; a step whose forecast exceeds it is not run (0: none)
  double max_seconds = 0.0;  ///< time budget for all steps (0: none)
  std::function<void(const std::string&)> log;  ///< one line before (forecast) and after each step
};

/// Refines a Tet10 mesh from the automatic one until every kept mode's estimated error meets
/// `tolerance`: each step's DOF grow by what the last estimate asks for, 1.5x to 3x; before each
/// step its time and memory are forecast from the last one, and a step that would exceed the
/// budget is not run (the finest result so far is returned, stopped_by_budget says so).
/// Needs a remeshable spec (primitive or surface file).
Result<ToleranceResult> computeModeBankToTolerance(const PrecomputeSettings& settings, const ToleranceOptions& options);
Result<ToleranceResult> computeModeBankToTolerance(const PrecomputeSettings& settings, double tolerance);

}  // namespace strike
