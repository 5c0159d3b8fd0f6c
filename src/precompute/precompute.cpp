// SPDX-License-Identifier: MIT
#include "strike/precompute/precompute.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <map>

#include "exclusive_solve.hpp"
#include "strike/precompute/element_order.hpp"
#include "strike/precompute/error_estimate.hpp"
#include "strike/fem/fem.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/bank/radiation_strength.hpp"

namespace strike {
namespace {
double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

void fillSurfaceAndShapes(const TetMesh& mesh, const Eigen::MatrixXd& shapes, ModeBank& bank) {
  // Surface vertices are the corner nodes used by boundary triangles, numbered in order of
  // first use so the bank is deterministic.
  std::map<int, uint32_t> surface_index_of_node;
  std::vector<uint32_t> node_of_surface;
  bank.surface_triangles.clear();
  for (Eigen::Index f = 0; f < mesh.surface.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int node = mesh.surface(f, c);
      auto [it, inserted] = surface_index_of_node.emplace(node, static_cast<uint32_t>(node_of_surface.size()));
      if (inserted) node_of_surface.push_back(static_cast<uint32_t>(node));
      bank.surface_triangles.push_back(it->second);
    }
  const size_t vertices = node_of_surface.size();
  bank.surface_node_index = node_of_surface;
  bank.surface_positions.resize(vertices * 3);
  for (size_t v = 0; v < vertices; ++v)
    for (int a = 0; a < 3; ++a) bank.surface_positions[v * 3 + a] = mesh.nodes(node_of_surface[v], a);

  // Area-weighted vertex normals: the cross product of two edges is twice the area times the
  // unit normal, so summing it weights each face by its area.
  std::vector<double> normals(vertices * 3, 0.0);
  for (size_t t = 0; t + 2 < bank.surface_triangles.size(); t += 3) {
    const uint32_t* tri = &bank.surface_triangles[t];
    const Eigen::Vector3d p0(&bank.surface_positions[tri[0] * 3]), p1(&bank.surface_positions[tri[1] * 3]),
        p2(&bank.surface_positions[tri[2] * 3]);
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) normals[tri[c] * 3 + a] += n[a];
  }
  bank.surface_normals.resize(vertices * 3);
  for (size_t v = 0; v < vertices; ++v) {
    const Eigen::Vector3d n(&normals[v * 3]);
    const double length = n.norm();
    for (int a = 0; a < 3; ++a) bank.surface_normals[v * 3 + a] = static_cast<float>(length > 0 ? n[a] / length : 0.0);
  }

  const Eigen::Index modes = shapes.cols();
  bank.shapes.resize(static_cast<size_t>(modes) * vertices * 3);
  for (Eigen::Index m = 0; m < modes; ++m)
    for (size_t v = 0; v < vertices; ++v)
      for (int a = 0; a < 3; ++a)
        bank.shapes[(static_cast<size_t>(m) * vertices + v) * 3 + a] =
            static_cast<float>(shapes(3 * static_cast<Eigen::Index>(node_of_surface[v]) + a, m));
}

namespace {

Status checkSettings(const PrecomputeSettings& settings) {
  Status valid = validateMaterial(settings.material, "material");
  if (!valid) return valid;
  if (settings.order != kAutoOrder && settings.order != 1 && settings.order != 2)
    return badInput("--order = " + std::to_string(settings.order) + " (must be 1 or 2)");
  if (!(settings.max_freq_hz > 0))
    return badInput("--max-freq = " + std::to_string(settings.max_freq_hz) + " (must be > 0)");
  if (settings.max_modes < 1)
    return badInput("--max-modes = " + std::to_string(settings.max_modes) + " (must be >= 1)");
  if (!(settings.target_edge_m >= 0))
    return badInput("--size = " + std::to_string(settings.target_edge_m) + " (must be > 0)");
  return {};
}

void fillProvenance(const LoadedMesh& loaded, const PrecomputeSettings& settings, const MassProperties& mass,
                    ModeBank& bank) {
  const TetMesh& mesh = loaded.mesh;
  bank.material = settings.material;
  bank.mesh_hash = loaded.source_hash;
  bank.mesh_source = settings.mesh_spec;
  bank.element_order = static_cast<uint32_t>(mesh.order);
  bank.target_edge_m = settings.target_edge_m;
  bank.mesh_nodes = static_cast<uint32_t>(mesh.nodes.rows());
  bank.mesh_tets = static_cast<uint32_t>(mesh.tets.rows());
  bank.max_freq_hz = settings.max_freq_hz;
  bank.max_modes = static_cast<uint32_t>(settings.max_modes);
  bank.mass_kg = mass.mass_kg;
  bank.volume_m3 = mass.volume_m3;
  for (int a = 0; a < 3; ++a) bank.centre_m[a] = mass.centre_m[a];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) bank.inertia_kg_m2[r * 3 + c] = mass.inertia_kg_m2(r, c);
  bank.meshing_seconds = loaded.meshing_seconds;
  bank.tool_version = "strike " STRIKE_VERSION_STRING;
}

}  // namespace

size_t modesAtOrBelow(const ModeBank& bank, double max_freq_hz) {
  size_t count = 0;
  while (count < bank.modeCount() && bank.frequencyHz(count) <= max_freq_hz) ++count;
  return count;
}

Status solveTransferInto(ModeBank& bank, const TransferSettings& settings, double max_freq_hz,
                         const ProgressFn& progress) {
  bank.transfer = AcousticTransfer{};
  bank.transfer_seconds = 0.0;
  return extendTransfer(bank, modesAtOrBelow(bank, max_freq_hz), settings, progress);
}

Status extendTransfer(ModeBank& bank, size_t modes, const TransferSettings& settings, const ProgressFn& progress) {
  const size_t first = bank.transfer.modeCount();
  const bool none = bank.transfer.offset.empty();  // not even the dipole: never solved
  if (modes > bank.modeCount()) return internalError("a transfer asked for more modes than the bank has");
  // Whole groups (modes of nearly one frequency share a solve: transferGroups): a transfer ends
  // where a group ends, so an extension starts where one starts and its modes get the bits of a
  // cold solve of them all (a group's solve depends on its own modes alone).
  const std::vector<size_t> groups = transferGroups(bank, settings);
  modes = *std::lower_bound(groups.begin(), groups.end(), modes);
  if (first >= modes && !none) return {};
  const auto start = std::chrono::steady_clock::now();
  if (progress) progress("transfer", 0.0);
  Result<AcousticTransfer> solved = internalError("no transfer solved");
  if (first == 0 && modes == bank.modeCount()) {
    solved = solveAcousticTransfer(bank, settings, progress);
  } else {
    // The solver takes a bank: this one's surface with the modes [first, modes) only. The shapes
    // are [mode][vertex][xyz], so theirs are one contiguous range.
    std::vector<float> shapes = std::move(bank.shapes);
    AcousticTransfer transfer = std::move(bank.transfer);
    ModeBank part = bank;
    bank.shapes = std::move(shapes);
    bank.transfer = std::move(transfer);
    const size_t row = bank.surfaceVertexCount() * 3;
    if (bank.shapes.size() < modes * row)
      return internalError("a transfer asked for modes whose shapes are not loaded");
    part.eigenvalues.assign(bank.eigenvalues.begin() + first, bank.eigenvalues.begin() + modes);
    part.shapes.assign(bank.shapes.begin() + first * row, bank.shapes.begin() + modes * row);
    part.radiation_m2.clear();
    part.frequency_error_estimate.clear();
    solved = solveAcousticTransfer(part, settings, progress);
  }
  if (!solved) return solved.error();
  AcousticTransfer& t = bank.transfer;
  if (none) {
    t = std::move(*solved);
  } else {
    // The new modes' coefficients after the others', about the same centre (the dipole, the air
    // and the method are the first solve's).
    if (solved->centre_m != t.centre_m) return internalError("a transfer extension about another centre");
    const uint64_t base = t.offset.back();
    for (size_t i = 0; i < solved->modeCount(); ++i) {
      t.order.push_back(solved->order[i]);
      t.relative_error.push_back(solved->relative_error[i]);
      t.offset.push_back(base + solved->offset[i + 1]);
    }
    t.coefficients.insert(t.coefficients.end(), solved->coefficients.begin(), solved->coefficients.end());
    t.solve_seconds += solved->solve_seconds;
  }
  bank.transfer_seconds += secondsSince(start);
  return {};
}

uint64_t bankCacheKey(uint64_t mesh_hash, const PrecomputeSettings& settings) {
  // Bit-exact inputs: the key changes whenever any input to the precompute changes.
  const Material& m = settings.material;
  const double numbers[] = {m.youngs_pa,          m.poisson,       m.density_kg_m3,
                            m.rayleigh_stiffness, m.rayleigh_mass, settings.target_edge_m,
                            settings.max_freq_hz};
  const uint64_t integers[] = {mesh_hash, static_cast<uint64_t>(settings.order),
                               static_cast<uint64_t>(settings.max_modes), kBankFormatVersion};
  uint64_t key = fnv1a64(numbers, sizeof numbers);
  key = fnv1a64(integers, sizeof integers, key);
  // The automatic order is the rule's answer: another rule, another bank.
  if (settings.order == kAutoOrder) {
    key = fnv1a64(&kThinWallFraction, sizeof kThinWallFraction, key);
    key = fnv1a64(&kTet10EdgeFactor, sizeof kTet10EdgeFactor, key);
  }
  // Only a scaled mesh hashes its scale, so banks cached before "units" existed keep their keys.
  if (settings.mesh_scale != 1.0) key = fnv1a64(&settings.mesh_scale, sizeof settings.mesh_scale, key);
  // A bank with an acoustic transfer is another bank than one without, and so is one solved to
  // another target or budget.
  if (settings.acoustic_transfer) key = transferSettingsKey(settings.transfer, key);
  return fnv1a64(STRIKE_VERSION_STRING, sizeof STRIKE_VERSION_STRING - 1, key);
}

uint64_t transferSettingsKey(const TransferSettings& t, uint64_t key) {
  const double transfer[] = {t.air_density_kg_m3,
                             t.speed_of_sound_m_s,
                             t.target_relative_error,
                             static_cast<double>(t.max_elements),
                             static_cast<double>(t.min_elements),
                             static_cast<double>(t.fixed_elements),
                             t.chief ? 1.0 : 0.0,
                             static_cast<double>(kTransferSolverRevision),
                             static_cast<double>(t.direct_max_elements)};
  return fnv1a64(transfer, sizeof transfer, key);
}

ModeBank massAndSurfaceBank(const LoadedMesh& loaded, const PrecomputeSettings& settings) {
  ModeBank bank;
  fillProvenance(loaded, settings, computeMassProperties(loaded.mesh, settings.material.density_kg_m3), bank);
  fillSurfaceAndShapes(loaded.mesh, Eigen::MatrixXd(3 * loaded.mesh.nodes.rows(), 0), bank);
  return bank;
}

MeshOptions meshOptionsFor(const PrecomputeSettings& settings) {
  MeshOptions options;
  options.order = settings.order;
  options.target_edge_m = settings.target_edge_m;
  options.scale = settings.mesh_scale;
  options.max_tets = settings.max_tets;
  options.progress = settings.progress;
  return options;
}

Result<PrecomputeResult> computeModeBank(const PrecomputeSettings& settings) {
  Status valid = checkSettings(settings);
  if (!valid) return valid.error();
  Result<LoadedMesh> loaded = loadMeshFor(settings);
  if (!loaded) return loaded.error();
  return computeModeBankForMesh(*loaded, settings);
}

Result<PrecomputeResult> computeModeBankForMesh(const LoadedMesh& loaded, const PrecomputeSettings& settings) {
  const auto start = std::chrono::steady_clock::now();
  Status valid = checkSettings(settings);
  if (!valid) return valid.error();
  const TetMesh& mesh = loaded.mesh;
  PrecomputeResult result;
  result.report.warnings = loaded.warnings;
  ModeBank& bank = result.bank;

  const auto assembly_start = std::chrono::steady_clock::now();
  if (settings.progress) settings.progress("assemble", -1.0);
  Eigen::SparseMatrix<double> K, M;
  assembleStiffnessAndMass(mesh, settings.material, K, M);
  const MassProperties mass = computeMassProperties(mesh, settings.material.density_kg_m3);
  bank.assembly_seconds = secondsSince(assembly_start);
  result.report.dofs = static_cast<size_t>(K.rows());

  ModalSettings modal;
  modal.max_freq_hz = settings.max_freq_hz;
  modal.max_modes = settings.max_modes;
  modal.rigid_freq_hz = settings.rigid_freq_hz;
  modal.progress = settings.progress;
  modal.max_bytes = settings.max_memory_bytes;
  Result<ModalResult> modes = solveModesExclusive(K, M, modal);
  if (!modes) return modes.error();

  fillProvenance(loaded, settings, mass, bank);
  bank.eigenvalues.assign(modes->eigenvalues.data(), modes->eigenvalues.data() + modes->eigenvalues.size());
  fillSurfaceAndShapes(mesh, modes->shapes, bank);
  bank.radiation_m2 = radiationStrengths(bank);  // once here, so no render has to
  bank.factorize_seconds = modes->factorize_seconds;
  bank.lanczos_seconds = modes->lanczos_seconds;
  bank.rigid_modes_dropped = static_cast<uint32_t>(modes->rigid_modes_dropped);
  bank.above_cutoff_dropped = static_cast<uint32_t>(modes->above_cutoff_dropped);
  result.report.capped_by_max_modes = modes->capped_by_max_modes;
  result.report.operator_applications = modes->operator_applications;
  if (settings.acoustic_transfer) {
    // The acoustic transfer: a phase of its own, part of the bank's cost (total_seconds).
    if (Status fits = checkTransferMemory(bank, settings.transfer, settings.max_memory_bytes); !fits)
      return fits.error();
    TransferSettings transfer = settings.transfer;
    if (settings.max_seconds > 0)  // what is left of the budget (at least a token: still a budget)
      transfer.max_seconds = std::max(1e-3, settings.max_seconds - loaded.meshing_seconds - secondsSince(start));
    if (Status solved = solveTransferInto(bank, transfer, settings.transfer_max_freq_hz, settings.progress); !solved)
      return solved.error();
  }
  bank.total_seconds = loaded.meshing_seconds + secondsSince(start);

  // ---- frequency error estimate (src/precompute/error_estimate.cpp); reported apart from
  // total_seconds, which stays the cost of the bank itself.
  if (settings.error_estimate) {
    Result<ErrorEstimateReport> estimated =
        estimateFrequencyErrors(loaded, settings, bank.eigenvalues, bank.frequency_error_estimate);
    if (!estimated) return estimated.error();
    result.report.error_estimate_method = estimated->method;
    result.report.error_estimate_note = estimated->note;
    result.report.error_estimate_seconds = estimated->seconds;
    result.report.error_estimate_ratio = estimated->ratio;
    result.report.error_estimate_coarse_dofs = estimated->coarse_dofs;
  }
  if (const std::string locking = lockingWarning(mesh.order, settings.material); !locking.empty())
    result.report.warnings.push_back({locking});
  // Tet4 on a thin shape locks in bending: its frequencies come out far too high (a mug 108%).
  // The automatic order picks Tet10 there; an explicit order 1 (or a Tet4 tet file) is warned.
  const OrderChoice choice = chooseElementOrder(mesh);
  if (mesh.order == 1 && choice.order == 2)
    result.report.warnings.push_back({"thin shape (" + choice.reason +
                                      "): Tet4 frequencies come out far too high (a mug with 4 mm walls: 108%); "
                                      "use order 2 (scene \"order\": 2, strike modes --order 2), or leave the "
                                      "order out (automatic)"});
  if (settings.order == kAutoOrder)
    result.report.order_reason = "Tet" + std::string(mesh.order == 2 ? "10" : "4") + " chosen: " +
                                 (canRemesh(settings.mesh_spec) ? choice.reason : "the tet file's own order");

  const std::string problem = bank.checkConsistency();
  if (!problem.empty()) return internalError("the computed mode bank is inconsistent: " + problem);
  return result;
}

}  // namespace strike
