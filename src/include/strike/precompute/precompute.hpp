// SPDX-License-Identifier: MIT
// Mesh -> FEM -> eigen-solve -> ModeBank: the whole precompute of `strike modes`, also used by
// the scene renderer for objects without a cached bank.
#pragma once

#include <string>
#include <vector>

#include "strike/bank/bank.hpp"
#include "strike/core/material.hpp"
#include "strike/mesh/mesh.hpp"
#include "strike/modal/modal.hpp"
#include "strike/core/band.hpp"
#include "strike/transfer/transfer_solver.hpp"

namespace strike {

struct PrecomputeSettings {
  std::string mesh_spec;  ///< file path or primitive ("box:0.3,0.02,0.02")
  Material material;
  /// 1 Tet4, 2 Tet10, or kAutoOrder (0): chosen from the shape by chooseElementOrder
  /// (src/precompute/element_order.cpp). Every front-end asks for kAutoOrder unless told an
  /// order: `strike modes` without --order, a scene object without "order", Python's order=None.
  int order = 1;
  double target_edge_m = 0;  ///< 0: automatic
  double mesh_scale = 1.0;   ///< metres per unit of a mesh file (MeshOptions::scale); primitives ignore it
  double max_freq_hz = 20000.0;
  int max_modes = 200;
  /// Modes below this are rigid-body modes (ModalSettings::rigid_freq_hz). Normalized solves
  /// use 0: the solver's own scale decides (src/include/strike/precompute/normalized_problem.hpp).
  double rigid_freq_hz = 1.0;
  int64_t max_tets = kDefaultMaxTets;  ///< size cap of the tet mesh (--max-tets), see MeshOptions
  ProgressFn progress;                 ///< optional
  /// Estimate each mode's frequency error (src/precompute/error_estimate.cpp) at extra cost;
  /// does not change the modes, so it is not part of the cache key.
  bool error_estimate = false;
  /// Solve each mode's acoustic transfer (bank.transfer, its own phase "transfer").
  /// The tools turn it on (`strike modes`, `strike render` and the Python package solve it unless
  /// told `--no-transfer` / transfer=False); here, as error_estimate, it is asked for. Without it
  /// the sound depends on the eigen-solver's signs and degenerate bases and has no direction. It costs 0.8x to 1.8x the eigen-solve on the order-2 examples, more on coarse
  /// linear-tet plates and blocks (docs/acoustic-transfer.md, "On the examples' banks").
  /// Off for solves whose frequencies are not the object's (the normalized problem, the
  /// --tolerance trials, which solve it once on the bank they choose). Part of the cache key.
  bool acoustic_transfer = false;
  TransferSettings transfer;  ///< air and resolution of the transfer solve
  /// The transfer is solved only for the modes at or below this: those a render can play,
  /// synthesizedTopHz(its max_freq, its sample rate); by default a render's at 48 kHz, 20 kHz.
  /// The modes above are kept without one (for other uses, at no cost), and a render that plays
  /// more solves theirs then (extendTransfer). Not part of the cache key: the bank records which
  /// modes have a transfer (a prefix, AcousticTransfer::modeCount()).
  double transfer_max_freq_hz = synthesizedTopHz(kDefaultMaxFreqHz, kDefaultSampleRateHz);
  /// Memory budget of each solve, bytes; 0: none (`--max-memory`, default the memory available).
  /// The eigen-solve (ModalSettings::max_bytes) and the acoustic transfer
  /// (transferMemoryForecastBytes) forecast what they will hold before they take it, and one
  /// whose forecast is over the budget is refused with the forecast (bad input). Not part of the
  /// cache key: it changes whether a bank is computed, never its numbers.
  double max_memory_bytes = 0.0;
  /// Time budget, seconds from the start of the precompute (`--max-seconds`); 0: none. The
  /// acoustic transfer keeps within what is left of it (TransferSettings::max_seconds), so the
  /// bank then depends on the machine's speed. Not part of the cache key.
  double max_seconds = 0.0;
};

struct PrecomputeReport {
  std::vector<MeshWarning> warnings;
  size_t dofs = 0;
  bool capped_by_max_modes = false;
  int operator_applications = 0;
  // The frequency error estimate (settings.error_estimate): method, extra time, caveats.
  std::string error_estimate_method;  ///< "richardson", "richardson-finer", "tet4-corner" or empty (none)
  std::string error_estimate_note;
  double error_estimate_seconds = 0.0;
  double error_estimate_ratio = 0.0;  ///< h_coarse / h_fine of the Richardson pair
  size_t error_estimate_coarse_dofs = 0;
  std::string order_reason;  ///< with kAutoOrder: why this order (one line for the summary)
};

struct PrecomputeResult {
  ModeBank bank;
  PrecomputeReport report;
};

/// The meshing options these settings ask for (order, size, cap, progress). loadMeshFor() is the
/// mesh a precompute solves on (it resolves kAutoOrder).
MeshOptions meshOptionsFor(const PrecomputeSettings& settings);

/// Runs the precompute on loadMeshFor(settings). Errors name the mesh, the material field or the solver failure.
Result<PrecomputeResult> computeModeBank(const PrecomputeSettings& settings);
/// The same from a mesh already loaded (settings.mesh_spec is recorded, not read again).
Result<PrecomputeResult> computeModeBankForMesh(const LoadedMesh& loaded, const PrecomputeSettings& settings);

/// A bank with no modes yet: mass properties and surface of the mesh, for the simulator, so a
/// scene can be simulated before deciding which objects need an eigen-solve.
ModeBank massAndSurfaceBank(const LoadedMesh& loaded, const PrecomputeSettings& settings);

/// The acoustic transfer's own memory forecast for this bank (its surface and modes), bytes:
/// what solveTransferInto will hold at its peak besides the bank (memory_forecast.cpp).
double transferMemoryForecastBytes(const ModeBank& bank, const TransferSettings& settings);

/// Refuses a transfer whose forecast is over `max_bytes` (0: no budget): bad input that says the
/// forecast and the option to change.
Status checkTransferMemory(const ModeBank& bank, const TransferSettings& settings, double max_bytes);

/// How many of the bank's modes lie at or below `max_freq_hz`: its heard modes, a prefix (the
/// modes are ascending), the ones a render whose band ends there plays.
size_t modesAtOrBelow(const ModeBank& bank, double max_freq_hz);

/// Solves bank.transfer for the modes at or below `max_freq_hz` (modesAtOrBelow) from the bank's
/// modes and surface and sets bank.transfer_seconds (not total_seconds: callers that time a whole
/// precompute include it there themselves). The modes above keep no transfer.
Status solveTransferInto(ModeBank& bank, const TransferSettings& settings, double max_freq_hz,
                         const ProgressFn& progress = {});

/// Makes bank.transfer cover its first `modes` modes: solves the modes it lacks, [its modeCount(),
/// modes), on their own and appends them (a first solve, from none, also solves the rigid
/// translation's dipole); adds their time to transfer_seconds. A mode's transfer depends on its
/// own data only, so the extended bank holds the bits of a bank solved to `modes` at once. Nothing
/// to do when it covers them already. The bank's shapes must be loaded.
Status extendTransfer(ModeBank& bank, size_t modes, const TransferSettings& settings, const ProgressFn& progress = {});

/// Cache key of the bank that `settings` would compute from a mesh whose source hashes to
/// mesh_hash: every input that changes the result goes in.
uint64_t bankCacheKey(uint64_t mesh_hash, const PrecomputeSettings& settings);
/// `key` hashed on with every transfer setting that changes the result and kTransferSolverRevision
/// (part of bankCacheKey with acoustic_transfer, and of the unit transfer's key).
uint64_t transferSettingsKey(const TransferSettings& transfer, uint64_t key);

/// Restricts a full mode-shape matrix (3N by #modes) to the surface of `mesh` and fills the
/// bank's surface (positions, area-weighted outward normals, triangles, node index) and shapes.
void fillSurfaceAndShapes(const TetMesh& mesh, const Eigen::MatrixXd& shapes, ModeBank& bank);

}  // namespace strike
