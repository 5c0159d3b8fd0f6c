// SPDX-License-Identifier: MIT
#include "modes_similar.hpp"

#include <cstdio>
#include <filesystem>

#include "strike/bank/bank.hpp"
#include "strike/core/hash.hpp"
#include "strike/precompute/normalized_problem.hpp"
#include "strike/core/read_file.hpp"

namespace strike::cli {
namespace {

/// The hash a loaded mesh records (LoadedMesh::source_hash): of the spec text for a primitive,
/// of the file's bytes otherwise; as `strike render` computes it.
Result<uint64_t> specHash(const std::string& spec) {
  if (isPrimitiveSpec(spec)) return fnv1a64(spec.data(), spec.size());
  Result<std::string> bytes = readWholeFile(spec, uint64_t(1) << 31);
  if (!bytes) return bytes.error();
  return fnv1a64(bytes->data(), bytes->size());
}

/// With the transfer: `scaled` gets its unit transfer (normalized_problem.hpp) from the cache
/// entry KEY.transfer that `strike render --similar --transfer` uses, or solved and put there.
Status attachTransfer(ModeBank& scaled, const ModeBank& normalized, const NormalizedProblem& problem,
                      const PrecomputeSettings& settings, const std::string& cache_dir, uint64_t normalized_key) {
  const size_t kept = modesAtOrBelow(scaled, settings.transfer_max_freq_hz);  // the heard modes
  char name[32];
  std::snprintf(name, sizeof name, "/%016llx.transfer",
                static_cast<unsigned long long>(unitTransferCacheKey(normalized_key, settings, kept)));
  const std::string path = cache_dir + name;
  if (std::filesystem::is_regular_file(path)) {
    Result<ModeBank> cached = readBank(path);
    if (cached && isUnitTransferOf(*cached, normalized, settings, kept))  // else solved again
      return attachUnitTransfer(scaled, *cached, problem, settings);
  }
  Result<ModeBank> unit = solveUnitTransfer(normalized, settings, kept);
  if (!unit) return unit.error();
  (void)writeBank(path, *unit);  // a failed cache write costs the next run time
  return attachUnitTransfer(scaled, *unit, problem, settings);
}

}  // namespace

Result<PrecomputeResult> similarModeBank(const PrecomputeSettings& settings, const std::string& cache_dir,
                                         SimilarSource& source) {
  if (cache_dir.empty()) return computeSimilarModeBank(settings);
  Result<uint64_t> actual_hash = specHash(settings.mesh_spec);
  if (!actual_hash) return actual_hash.error();
  const NormalizedProblem problem = normalizeProblem(settings);
  Result<uint64_t> normal_hash = specHash(problem.settings.mesh_spec);
  if (!normal_hash) return normal_hash.error();
  const uint64_t normalized_key = normalizedBankCacheKey(*normal_hash, problem);
  char name[32];
  std::snprintf(name, sizeof name, "/%016llx.modes", static_cast<unsigned long long>(normalized_key));
  source.cache_entry = cache_dir + name;
  if (std::filesystem::is_regular_file(source.cache_entry)) {
    Result<ModeBank> cached = readBank(source.cache_entry);
    // A damaged or foreign entry, or one without the error estimate asked for, is solved again.
    if (cached && cached->mesh_hash == *normal_hash &&
        (!settings.error_estimate || cached->frequency_error_estimate.size() == cached->modeCount())) {
      Result<ModeBank> scaled = scaleNormalizedBank(*cached, problem, settings, *actual_hash);
      if (!scaled) return scaled.error();
      if (settings.acoustic_transfer)
        if (Status t = attachTransfer(*scaled, *cached, problem, settings, cache_dir, normalized_key); !t)
          return t.error();
      PrecomputeResult result;
      result.bank = std::move(*scaled);
      result.report.capped_by_max_modes = cached->modeCount() >= cached->max_modes;
      source.from_cache = true;
      return result;
    }
  }
  Result<PrecomputeResult> solved = computeModeBank(problem.settings);
  if (!solved) return solved.error();
  std::error_code ignored;
  std::filesystem::create_directories(cache_dir, ignored);
  (void)writeBank(source.cache_entry, solved->bank);  // a failed cache write costs the next run time
  Result<ModeBank> scaled = scaleNormalizedBank(solved->bank, problem, settings, *actual_hash);
  if (!scaled) return scaled.error();
  if (settings.acoustic_transfer)
    if (Status t = attachTransfer(*scaled, solved->bank, problem, settings, cache_dir, normalized_key); !t)
      return t.error();
  solved->bank = std::move(*scaled);
  return solved;
}

}  // namespace strike::cli
