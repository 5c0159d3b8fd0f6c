// SPDX-License-Identifier: MIT
#include "strike/precompute/normalized_problem.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "strike/core/hash.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/precompute/similar_bank.hpp"

namespace strike {
namespace {

/// The lengths of a primitive spec ("box:0.3,0.02,0.02" -> kind "box", {0.3, 0.02, 0.02}).
/// Anything unusual gives no lengths: the spec is then solved as given (loadTetMesh reports it).
bool primitiveLengths(const std::string& spec, std::string& kind, std::vector<double>& lengths_m) {
  const size_t colon = spec.find(':');
  if (colon == std::string::npos) return false;
  kind = spec.substr(0, colon);
  const char* at = spec.c_str() + colon + 1;
  while (true) {
    char* end = nullptr;
    const double v = std::strtod(at, &end);
    if (end == at || !(v > 0) || !std::isfinite(v)) return false;
    lengths_m.push_back(v);
    if (*end == '\0') break;
    if (*end != ',') return false;
    at = end + 1;
  }
  return true;
}

std::string twelveDigits(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.12g", v);
  return text;
}

/// E / rho: the square of the material's wave speed (m^2/s^2), what ka depends on.
double waveSpeedSquared(const Material& material) { return material.youngs_pa / material.density_kg_m3; }

/// The unit transfer's eigenvalues: the normalized ones times (E/rho) / (E_ref/rho_ref).
std::vector<double> unitTransferEigenvalues(const ModeBank& normalized, const PrecomputeSettings& actual,
                                            size_t kept_modes) {
  const double ratio = waveSpeedSquared(actual.material) / waveSpeedSquared(normalized.material);
  std::vector<double> eigenvalues(normalized.eigenvalues.begin(),
                                  normalized.eigenvalues.begin() + std::min(kept_modes, normalized.modeCount()));
  for (double& lambda : eigenvalues) lambda *= ratio;
  return eigenvalues;
}

}  // namespace

NormalizedProblem normalizeProblem(const PrecomputeSettings& actual) {
  NormalizedProblem problem;
  PrecomputeSettings& n = problem.settings;
  n = actual;
  std::string kind;
  std::vector<double> lengths_m;
  if (isPrimitiveSpec(actual.mesh_spec) && primitiveLengths(actual.mesh_spec, kind, lengths_m)) {
    problem.scale = lengths_m[0];
    n.mesh_spec = kind + ":1";
    for (size_t i = 1; i < lengths_m.size(); ++i) n.mesh_spec += "," + twelveDigits(lengths_m[i] / problem.scale);
    n.mesh_scale = 1.0;
  } else if (!isPrimitiveSpec(actual.mesh_spec)) {
    problem.scale = actual.mesh_scale;  // the file's own units are its unit size
    n.mesh_scale = 1.0;
  }
  n.target_edge_m = actual.target_edge_m / problem.scale;  // 0 (automatic) stays 0: relative already
  n.material = Material{"normalized", kNormalizedYoungs_pa, actual.material.poisson, kNormalizedDensity_kg_m3, 0, 0};
  // No cut-off: the lowest max_modes modes. Every object of this shape keeps a prefix of them
  // (its modes below its own cut-off, at most max_modes), whatever its size and material, so
  // one solve serves them all, the same one whichever object came first.
  n.max_freq_hz = kNormalizedNoCutoffHz;
  // Rigid modes by the solver's own scale (a fraction of its shift), not by 1 Hz, which would
  // mean a different frequency in every normalized problem.
  n.rigid_freq_hz = 0.0;
  // The acoustic transfer depends on the material's wave speed (ka): the unit transfer is solved
  // apart for each (unitTransferBank), so the normalized solve (and its cache entry) has none.
  n.acoustic_transfer = false;
  return problem;
}

uint64_t normalizedBankCacheKey(uint64_t mesh_hash, const NormalizedProblem& problem) {
  static const char kTag[] = "normalized solve 1";  // never equal to a key of a direct solve
  const uint64_t key = bankCacheKey(mesh_hash, problem.settings);
  return fnv1a64(kTag, sizeof kTag - 1, key);
}

Result<ModeBank> scaleNormalizedBank(const ModeBank& normalized, const NormalizedProblem& problem,
                                     const PrecomputeSettings& actual, uint64_t mesh_hash) {
  // No transfer here: the unit transfer is solved once for every object of the shape and wave
  // speed and scaled to each (attachUnitTransfer).
  Result<ModeBank> scaled =
      similarBank(normalized, problem.scale, actual.material, actual.max_freq_hz, actual.mesh_spec, nullptr);
  if (!scaled) return scaled.error();
  // The provenance of the object asked for, as a direct solve would record it.
  scaled->mesh_hash = mesh_hash;
  scaled->target_edge_m = actual.target_edge_m;
  return scaled;
}

uint64_t unitTransferCacheKey(uint64_t normalized_key, const PrecomputeSettings& actual, size_t kept_modes) {
  static const char kTag[] = "unit transfer 1";  // never equal to a key of a bank
  uint64_t key = fnv1a64(kTag, sizeof kTag - 1, normalized_key);
  // With no mode kept only the dipole is solved, the same for every material.
  const double wave_speed_squared = kept_modes > 0 ? waveSpeedSquared(actual.material) : 0.0;
  const uint64_t kept = kept_modes;
  key = fnv1a64(&wave_speed_squared, sizeof wave_speed_squared, key);
  key = fnv1a64(&kept, sizeof kept, key);
  return transferSettingsKey(actual.transfer, key);
}

ModeBank unitTransferBank(const ModeBank& normalized, const PrecomputeSettings& actual, size_t kept_modes) {
  ModeBank unit = normalized;
  unit.eigenvalues = unitTransferEigenvalues(normalized, actual, kept_modes);
  unit.shapes.resize(unit.modeCount() * unit.surfaceVertexCount() * 3);  // [mode][vertex][xyz]: a prefix
  unit.frequency_error_estimate.clear();
  unit.radiation_m2.clear();
  unit.transfer = {};
  unit.transfer_seconds = 0.0;
  // Named by what it is, not by the object that asked first (the cache entry is shared).
  unit.material.name = "unit transfer";
  if (unit.modeCount() > 0)  // informational: E of the reference density at the object's wave speed
    unit.material.youngs_pa = waveSpeedSquared(actual.material) * normalized.material.density_kg_m3;
  unit.material.rayleigh_stiffness = unit.material.rayleigh_mass = 0.0;
  return unit;
}

Result<ModeBank> solveUnitTransfer(const ModeBank& normalized, const PrecomputeSettings& actual, size_t kept_modes) {
  ModeBank unit = unitTransferBank(normalized, actual, kept_modes);
  // Every mode of the unit bank: its eigenvalues are the kept ones already.
  if (Status solved = solveTransferInto(unit, actual.transfer, INFINITY, actual.progress); !solved)
    return solved.error();
  // What the cache keeps: the transfer with its eigenvalues (which identify it), not the surface.
  unit.shapes.clear();
  unit.surface_positions.clear();
  unit.surface_normals.clear();
  unit.surface_triangles.clear();
  unit.surface_node_index.clear();
  return unit;
}

bool isUnitTransferOf(const ModeBank& cached, const ModeBank& normalized, const PrecomputeSettings& actual,
                      size_t kept_modes) {
  return cached.mesh_hash == normalized.mesh_hash && cached.transfer.modeCount() == kept_modes &&
         cached.eigenvalues == unitTransferEigenvalues(normalized, actual, kept_modes) &&
         cached.material.density_kg_m3 == normalized.material.density_kg_m3 &&
         cached.transfer.air_density_kg_m3 == actual.transfer.air_density_kg_m3 &&
         cached.transfer.speed_of_sound_m_s == actual.transfer.speed_of_sound_m_s;
}

Status attachUnitTransfer(ModeBank& scaled, const ModeBank& unit, const NormalizedProblem& problem,
                          const PrecomputeSettings& actual) {
  if (unit.transfer.modeCount() > scaled.modeCount())
    return badInput("the unit transfer has " + std::to_string(unit.transfer.modeCount()) + " modes, the bank " +
                    std::to_string(scaled.modeCount()));
  // The shape factor of similarBank(), from the unit bank's (the reference) density.
  const double s = problem.scale;
  const double density_ratio = actual.material.density_kg_m3 / unit.material.density_kg_m3;
  const double shape_factor = 1.0 / std::sqrt(density_ratio * s * s * s);
  scaled.transfer = scaledTransfer(unit.transfer, unit.transfer.modeCount(), s, shape_factor);
  scaled.transfer_seconds = unit.transfer_seconds;  // what it cost, when it was solved
  return {};
}

Result<PrecomputeResult> computeSimilarModeBank(const PrecomputeSettings& actual) {
  // The actual material is checked here: the normalized solve has the reference one.
  if (Status valid = validateMaterial(actual.material, "material"); !valid) return valid.error();
  if (!(actual.max_freq_hz > 0))
    return badInput("--max-freq = " + std::to_string(actual.max_freq_hz) + " (must be > 0)");
  const NormalizedProblem problem = normalizeProblem(actual);
  Result<PrecomputeResult> solved = computeModeBank(problem.settings);
  if (!solved) return solved.error();
  // The actual mesh's hash: file bytes (the same file) or the actual primitive spec text.
  const uint64_t mesh_hash = isPrimitiveSpec(actual.mesh_spec)
                                 ? fnv1a64(actual.mesh_spec.data(), actual.mesh_spec.size())
                                 : solved->bank.mesh_hash;
  Result<ModeBank> scaled = scaleNormalizedBank(solved->bank, problem, actual, mesh_hash);
  if (!scaled) return scaled.error();
  if (actual.acoustic_transfer) {
    Result<ModeBank> unit =
        solveUnitTransfer(solved->bank, actual, modesAtOrBelow(*scaled, actual.transfer_max_freq_hz));
    if (!unit) return unit.error();
    if (Status attached = attachUnitTransfer(*scaled, *unit, problem, actual); !attached) return attached.error();
  }
  solved->bank = std::move(*scaled);
  return solved;
}

}  // namespace strike
