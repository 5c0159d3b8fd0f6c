// SPDX-License-Identifier: MIT
#include "strike/normalized_problem.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "strike/hash.hpp"
#include "strike/materials.hpp"
#include "strike/similar_bank.hpp"

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
  // The acoustic transfer depends on the actual frequencies (ka): similarBank() solves it on the
  // scaled bank, so the normalized solve (and its cache entry) has none.
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
  Result<ModeBank> scaled = similarBank(normalized, problem.scale, actual.material, actual.max_freq_hz,
                                        actual.mesh_spec, actual.acoustic_transfer ? &actual.transfer : nullptr);
  if (!scaled) return scaled.error();
  // The provenance of the object asked for, as a direct solve would record it.
  scaled->mesh_hash = mesh_hash;
  scaled->target_edge_m = actual.target_edge_m;
  return scaled;
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
  solved->bank = std::move(*scaled);
  return solved;
}

}  // namespace strike
