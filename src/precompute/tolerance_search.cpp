// SPDX-License-Identifier: MIT
// The tolerance-driven mesh choice (strike modes --tolerance): Tet10 meshes refined step by step,
// each forecast against the time and memory budget, until every mode's estimated frequency error
// (error_estimate.cpp) is below the tolerance. See error_estimate.hpp.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>

#include "mesh_sizing.hpp"
#include "strike/precompute/error_estimate.hpp"

namespace strike {

using detail::meanEdge;
using detail::meshWithTetRatio;
using detail::secondsSince;
using detail::SizedMesh;

Result<ToleranceResult> computeModeBankToTolerance(const PrecomputeSettings& settings, double tolerance) {
  ToleranceOptions options;
  options.tolerance = tolerance;
  return computeModeBankToTolerance(settings, options);
}

namespace {

/// Peak resident memory of this process so far, bytes (Linux reports ru_maxrss in KiB).
double peakResidentBytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return 1024.0 * static_cast<double>(usage.ru_maxrss);
}

std::string gigabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f GB", bytes / 1e9);
  return text;
}

}  // namespace

namespace {

/// A step's forecast: the last step's time and peak memory scaled by the DOF ratio.
struct StepForecast {
  double seconds = 0.0;  ///< 0: unknown (the first step)
  double bytes = 0.0;
};

/// Forecast: the last step's time and peak memory scaled by the DOF ratio, as t ~ n^1.5 and
/// memory ~ n^1.2 (measured on the mug, Tet10: 47k -> 118k DOF took 2.9x the time and 2.4x
/// the memory). Before any step: 30 KB per DOF (the mug's first step with its finer-mesh
/// estimate peaked at 1.42 GB for 47k DOF; without it 11.6 KB per DOF), time unknown.
StepForecast forecastStep(const std::vector<ToleranceTrial>& trials, size_t dofs) {
  double forecast_s = 0.0, forecast_bytes = 30e3 * static_cast<double>(dofs);
  if (!trials.empty()) {
    const ToleranceTrial& last = trials.back();
    const double growth = static_cast<double>(dofs) / static_cast<double>(last.dofs);
    forecast_s = last.seconds * std::pow(growth, 1.5);
    forecast_bytes = last.peak_bytes * std::pow(growth, 1.2);
  }
  return {forecast_s, forecast_bytes};
}

/// "step N: Tet10, D DOF (T tets), forecast ...": what a step is about to cost.
std::string announceStep(int step, size_t dofs, long long tets, const StepForecast& forecast) {
  const double forecast_s = forecast.seconds, forecast_bytes = forecast.bytes;
  char line[256];
  std::snprintf(line, sizeof line, "step %d: Tet10, %zu DOF (%lld tets), forecast %s%s", step + 1, dofs, tets,
                forecast_s > 0 ? "" : "time unknown, ", gigabytes(forecast_bytes).c_str());
  std::string announce = line;
  if (forecast_s > 0) {
    std::snprintf(line, sizeof line, "step %d: Tet10, %zu DOF (%lld tets), forecast %.0f s, %s", step + 1, dofs, tets,
                  forecast_s, gigabytes(forecast_bytes).c_str());
    announce = line;
  }
  return announce;
}

/// Why a step's forecast does not fit --max-memory or --max-seconds; empty when it fits.
std::string overBudget(const ToleranceOptions& options, const StepForecast& forecast, double elapsed) {
  const double forecast_s = forecast.seconds, forecast_bytes = forecast.bytes;
  char line[256];
  std::string over;
  if (options.max_bytes > 0 && forecast_bytes > options.max_bytes)
    over = "its forecast memory " + gigabytes(forecast_bytes) + " exceeds --max-memory " + gigabytes(options.max_bytes);
  else if (options.max_seconds > 0 && forecast_s > 0 && elapsed + forecast_s > options.max_seconds) {
    std::snprintf(line, sizeof line, "%.1f s spent + %.1f s forecast exceeds --max-seconds %g", elapsed, forecast_s,
                  options.max_seconds);
    over = line;
  }
  return over;
}

/// What a step cost and estimated, and whether it met the tolerance.
ToleranceTrial trialOf(const PrecomputeResult& trial, const LoadedMesh& loaded, double edge,
                       const StepForecast& forecast, double tolerance) {
  const double forecast_s = forecast.seconds, forecast_bytes = forecast.bytes;
  ToleranceTrial t;
  t.order = 2;
  t.target_edge_m = edge > 0 ? edge : meanEdge(loaded.mesh);
  t.dofs = trial.report.dofs;
  t.seconds = trial.bank.total_seconds + trial.report.error_estimate_seconds;
  t.peak_bytes = peakResidentBytes();
  t.forecast_seconds = forecast_s;
  t.forecast_bytes = forecast_bytes;
  t.method = trial.report.error_estimate_method;
  const std::vector<double>& e = trial.bank.frequency_error_estimate;
  t.max_estimate = e.empty() ? INFINITY : *std::max_element(e.begin(), e.end());
  t.met = !e.empty() && t.max_estimate <= tolerance;
  if (trial.bank.modeCount() == 0) {  // nothing in the band to be wrong: refining cannot help
    t.met = true;
    t.max_estimate = 0.0;
  }
  return t;
}

/// The next step's mesh: the DOF growth for the error to fall to tolerance / 1.3.
Result<SizedMesh> nextMesh(const PrecomputeSettings& settings, const ToleranceTrial& t, const LoadedMesh& loaded,
                           double tolerance, bool exact_geometry) {
  const double p = t.method == "richardson" && exact_geometry ? 4.0 : 2.0;
  const double wanted = std::isfinite(t.max_estimate) ? std::pow(1.3 * t.max_estimate / tolerance, 3.0 / p) : 3.0;
  const double want = std::clamp(wanted, 1.5, kMaxDofGrowthPerStep);
  const double edge_now = t.target_edge_m;
  return meshWithTetRatio(settings.mesh_spec, settings.mesh_scale, 2, settings.max_tets,
                          static_cast<double>(loaded.mesh.tets.rows()), edge_now / std::cbrt(want), 1.3,
                          kMaxDofGrowthPerStep, want);
}

}  // namespace

Result<ToleranceResult> computeModeBankToTolerance(const PrecomputeSettings& settings,
                                                   const ToleranceOptions& options) {
  const double tolerance = options.tolerance;
  if (!(tolerance > 0 && tolerance < 1))
    return badInput("--tolerance = " + std::to_string(tolerance) + " (must be between 0 and 100%)");
  if (!canRemesh(settings.mesh_spec))
    return badInput("--tolerance needs a mesh that can be remeshed (a primitive or a surface .obj/.stl/.ply), got " +
                    settings.mesh_spec);
  const auto start = std::chrono::steady_clock::now();
  auto say = [&](const std::string& line) {
    if (options.log) options.log(line);
  };
  // Tet10 throughout: its error falls as h^4 where Tet4's falls as h^2 and locks in bending (the
  // plate of the README: Tet4 23% off at 11.5k DOF, Tet10 0.5% at 14k). The first step is the
  // automatic mesh; each next one is finer by the ratio the last estimate asks for (error ~ h^p,
  // DOF ~ h^-3, with a 1.3 margin), but never more than 3x the DOF (the old search jumped from
  // 66k to 1.41M DOF on a mug: 826 s, 22 GB) and at least 1.5x.
  const bool exact_geometry = settings.mesh_spec.rfind("box:", 0) == 0;
  ToleranceResult out;
  double edge = 0.0;  // 0: automatic
  std::optional<LoadedMesh> next_mesh;
  for (int step = 0; step < kMaxToleranceSteps; ++step) {
    PrecomputeSettings trial_settings = settings;
    trial_settings.order = 2;
    trial_settings.error_estimate = true;
    trial_settings.acoustic_transfer = false;  // solved once, on the bank chosen
    LoadedMesh loaded;
    if (step == 0) {
      MeshOptions mesh_options;
      mesh_options.scale = settings.mesh_scale;
      mesh_options.order = 2;
      mesh_options.max_tets = settings.max_tets;
      Result<LoadedMesh> first = loadTetMesh(settings.mesh_spec, mesh_options);
      if (!first) return first.error();
      loaded = std::move(*first);
    } else {
      loaded = std::move(*next_mesh);
    }
    trial_settings.target_edge_m = edge;
    const size_t dofs = 3 * static_cast<size_t>(loaded.mesh.nodes.rows());
    const StepForecast forecast = forecastStep(out.trials, dofs);
    const double elapsed = secondsSince(start);
    const std::string announce = announceStep(step, dofs, static_cast<long long>(loaded.mesh.tets.rows()), forecast);
    const std::string over = overBudget(options, forecast, elapsed);
    if (!over.empty()) {
      if (out.trials.empty())
        return badInput("--tolerance: the first step (" + std::to_string(dofs) +
                        " DOF) does not fit the budget: " + over);
      out.stopped_by_budget = true;
      out.stop_reason =
          "stopped before step " + std::to_string(step + 1) + " (" + std::to_string(dofs) + " DOF): " + over;
      say(out.stop_reason);
      break;
    }
    say(announce);
    Result<PrecomputeResult> trial = computeModeBankForMesh(loaded, trial_settings);
    // A later step whose own solve forecasts more than the budget ends the refinement as the
    // step's forecast above would have (the finest result kept).
    if (!trial && trial.error().kind == ErrorKind::BadInput && !out.trials.empty() && options.max_bytes > 0) {
      out.stopped_by_budget = true;
      out.stop_reason = "stopped in step " + std::to_string(step + 1) + ": " + trial.error().message;
      say(out.stop_reason);
      break;
    }
    if (!trial) return trial.error();
    ToleranceTrial t = trialOf(*trial, loaded, edge, forecast, tolerance);
    if (trial->bank.modeCount() == 0)
      say("step " + std::to_string(step + 1) + ": no modes in the band, nothing to refine");
    char line[256];
    std::snprintf(line, sizeof line, "step %d: %.1f s, peak %s, max est. error %.3g%% (%s)%s", step + 1, t.seconds,
                  gigabytes(t.peak_bytes).c_str(), 100.0 * t.max_estimate, t.method.c_str(), t.met ? ": met" : "");
    say(line);
    out.trials.push_back(t);
    out.chosen = std::move(*trial);
    if (t.met) {
      out.met = true;
      break;
    }
    if (step + 1 == kMaxToleranceSteps) break;
    Result<SizedMesh> finer = nextMesh(settings, t, loaded, tolerance, exact_geometry);
    if (!finer) {
      out.stop_reason = "stopped after step " + std::to_string(step + 1) + ": " + finer.error().message;
      say(out.stop_reason);
      break;
    }
    edge = finer->target_edge_m;
    next_mesh = std::move(finer->loaded);
  }
  if (settings.acoustic_transfer && !out.trials.empty()) {
    TransferSettings transfer = settings.transfer;
    if (options.max_seconds > 0) transfer.max_seconds = std::max(1e-3, options.max_seconds - secondsSince(start));
    if (Status solved = solveTransferInto(out.chosen.bank, transfer, settings.transfer_max_freq_hz, settings.progress);
        !solved)
      return solved.error();
    out.chosen.bank.total_seconds += out.chosen.bank.transfer_seconds;
  }
  out.total_seconds = secondsSince(start);
  return out;
}

}  // namespace strike
