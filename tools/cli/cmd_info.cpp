// SPDX-License-Identifier: MIT
// `strike info BANK.modes [--json]`: what a mode bank holds.
#include <array>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "strike/bank/bank.hpp"
#include "strike/synth/synth.hpp"

namespace strike::cli {
namespace {

/// How far a mode's level may be off for a transfer error estimate e (relative rms over
/// directions): the larger of |20 log10(1 - e)| and 20 log10(1 + e), dB (60 dB past e = 0.999).
double transferLevelDb(double e) { return e >= 0.999 ? 60.0 : -20.0 * std::log10(1.0 - e); }

CommandSpec infoSpec() {
  CommandSpec spec;
  spec.usage = "strike info BANK.modes [--json] [--vertices]";
  spec.summary =
      "Shows a mode bank: material, mesh, mass properties, and per mode the undamped frequency,\n"
      "the amplitude decay rate d = (a1 lambda + a2) / 2 and T60 = ln(1000) / d (time to fall by 60 dB).";
  spec.options = {{"--json", "", "print one JSON object on stdout (the contract in docs/cli.md)"},
                  {"--vertices", "",
                   "also list the surface vertices (index, position in m, outward unit normal): the numbers "
                   "`strike hit --vertex` takes; with --json, as surface_vertices_m and surface_normals"}};
  spec.examples =
      "  strike info bar.modes\n  strike info bar.modes --json | jq '.frequencies_hz[:5]'\n"
      "  strike info bar.modes --vertices | grep ' 1.000$'   # vertices whose normal is +z (top faces)\n";
  spec.min_positional = 1;
  spec.max_positional = 1;
  return spec;
}

// ln(1000): an amplitude decaying as exp(-d t) falls by 60 dB after ln(1000)/d seconds.
constexpr double kLn1000 = 6.907755278982137;

double t60Seconds(double decay_per_s) { return decay_per_s > 0 ? kLn1000 / decay_per_s : INFINITY; }

nlohmann::json bankJson(const ModeBank& bank) {
  nlohmann::json j;
  j["format_version"] = bank.format_version;
  j["shape_encoding"] = bank.shape_encoding == ShapeEncoding::Int16 ? "int16" : "float32";
  std::vector<double> freqs, decays, t60;
  for (size_t i = 0; i < bank.modeCount(); ++i) {
    freqs.push_back(bank.frequencyHz(i));
    decays.push_back(bank.decayPerS(i));
    const double t = t60Seconds(bank.decayPerS(i));
    t60.push_back(std::isfinite(t) ? t : -1.0);  // JSON has no infinity: -1 means "never decays"
  }
  j["modes"] = bank.modeCount();
  j["frequencies_hz"] = freqs;
  j["decay_per_s"] = decays;
  j["t60_s"] = t60;
  j["eigenvalues"] = bank.eigenvalues;
  if (!bank.frequency_error_estimate.empty()) j["frequency_error_estimate"] = bank.frequency_error_estimate;
  j["mass_kg"] = bank.mass_kg;
  j["volume_m3"] = bank.volume_m3;
  j["centre_of_mass_m"] = bank.centre_m;
  j["inertia_kg_m2"] = bank.inertia_kg_m2;
  j["material"] = {{"name", bank.material.name},
                   {"youngs_pa", bank.material.youngs_pa},
                   {"poisson", bank.material.poisson},
                   {"density_kg_m3", bank.material.density_kg_m3},
                   {"rayleigh_stiffness", bank.material.rayleigh_stiffness},
                   {"rayleigh_mass", bank.material.rayleigh_mass}};
  char hash[32];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(bank.mesh_hash));
  j["mesh"] = {{"nodes", bank.mesh_nodes},
               {"tets", bank.mesh_tets},
               {"order", bank.element_order},
               {"surface_vertices", bank.surfaceVertexCount()},
               {"surface_triangles", bank.surface_triangles.size() / 3},
               {"source", bank.mesh_source},
               {"hash", hash},
               {"target_edge_m", bank.target_edge_m}};
  j["cutoff"] = {{"max_freq_hz", bank.max_freq_hz},
                 {"max_modes", bank.max_modes},
                 {"rigid_modes_dropped", bank.rigid_modes_dropped},
                 {"above_cutoff_dropped", bank.above_cutoff_dropped}};
  j["precompute_seconds"] = {{"meshing", bank.meshing_seconds},
                             {"assembly", bank.assembly_seconds},
                             {"factorize", bank.factorize_seconds},
                             {"lanczos", bank.lanczos_seconds},
                             {"total", bank.total_seconds}};
  j["tool_version"] = bank.tool_version;
  // Format 6: the first transfer.modeCount() modes have one (those heard at the band the bank was
  // solved for); the others are heard direction-averaged until a render that plays them solves theirs.
  if (!bank.transfer.offset.empty() && bank.modeCount() > 0) {
    std::vector<uint32_t> orders(bank.transfer.order.begin(), bank.transfer.order.end());
    std::vector<double> errors(bank.transfer.relative_error.begin(), bank.transfer.relative_error.end());
    const std::vector<double> efficiency = radiationEfficiency(bank);
    const size_t with = bank.transfer.modeCount();
    j["transfer"] = {{"method", bank.transfer.method},
                     {"modes", with},
                     {"seconds", bank.transfer_seconds},
                     {"centre_m", bank.transfer.centre_m},
                     {"order", orders},
                     {"relative_error", errors},
                     {"radiation_efficiency", std::vector<double>(efficiency.begin(), efficiency.begin() + with)},
                     {"translation_dipole_m3", bank.transfer.translation_dipole_m3}};
    j["precompute_seconds"]["transfer"] = bank.transfer_seconds;
  } else {
    j["transfer"] = nullptr;  // format 1-4: direction-averaged radiation only (`strike modes` again to get it)
  }
  return j;
}

void printTable(const std::string& path, const ModeBank& bank) {
  std::printf("%s: mode bank format %u, written by %s\n", path.c_str(), bank.format_version, bank.tool_version.c_str());
  std::printf("material  %s: E %.4g Pa, nu %.4g, rho %.5g kg/m^3, Rayleigh a1 %.4g s, a2 %.4g 1/s\n",
              bank.material.name.c_str(), bank.material.youngs_pa, bank.material.poisson, bank.material.density_kg_m3,
              bank.material.rayleigh_stiffness, bank.material.rayleigh_mass);
  std::printf("mesh      %s: %u nodes, %u tets, order %u, %zu surface vertices\n", bank.mesh_source.c_str(),
              bank.mesh_nodes, bank.mesh_tets, bank.element_order, bank.surfaceVertexCount());
  std::printf("solid     mass %.6g kg, volume %.6g m^3, centre (%.4g, %.4g, %.4g) m\n", bank.mass_kg, bank.volume_m3,
              bank.centre_m[0], bank.centre_m[1], bank.centre_m[2]);
  std::printf("modes     %zu up to %.0f Hz (max %u); dropped %u rigid, %u above the cut-off; computed in %.2f s\n\n",
              bank.modeCount(), bank.max_freq_hz, bank.max_modes, bank.rigid_modes_dropped, bank.above_cutoff_dropped,
              bank.total_seconds);
  const size_t with_transfer = bank.transfer.modeCount();
  const bool has_transfer = !bank.transfer.offset.empty() && bank.modeCount() > 0;
  if (has_transfer && with_transfer == bank.modeCount())
    std::printf("sound     acoustic transfer (%s) in %.2f s\n", bank.transfer.method.c_str(), bank.transfer_seconds);
  else if (has_transfer)
    std::printf(
        "sound     acoustic transfer (%s) in %.2f s for the first %zu modes (the heard ones, to %.0f Hz); a mode "
        "without one (-) is heard direction-averaged until a render that plays it solves its own\n",
        bank.transfer.method.c_str(), bank.transfer_seconds, with_transfer,
        with_transfer > 0 ? bank.frequencyHz(with_transfer - 1) : 0.0);
  if (has_transfer)
    std::printf(
        "          transfer err: a mode's estimated far-field error, rms over directions relative to the field's\n"
        "          rms; e = 5%% is -26 dB under the field, its level within 20 log10(1 -+ e) = -0.45/+0.42 dB\n"
        "          (the column `dB`: the larger of the two)\n\n");
  else
    std::printf(
        "sound     no acoustic transfer (format %u): heard through the direction average of the older "
        "model; run `strike modes` again for directivity\n\n",
        bank.format_version);
  const bool has_error = !bank.frequency_error_estimate.empty();
  const std::vector<double> efficiency = has_transfer ? radiationEfficiency(bank) : std::vector<double>{};
  std::printf("%5s %14s %12s %10s%s%s\n", "mode", "frequency Hz", "decay 1/s", "T60 s", has_error ? "  est. error" : "",
              has_transfer ? "  order  transfer err     dB  efficiency" : "");
  for (size_t i = 0; i < bank.modeCount(); ++i) {
    const double t60 = t60Seconds(bank.decayPerS(i));
    std::printf("%5zu %14.3f %12.4g %10.4g", i, bank.frequencyHz(i), bank.decayPerS(i), t60);
    if (has_error) std::printf("  %9.3g%%", 100.0 * bank.frequency_error_estimate[i]);
    if (has_transfer && i < with_transfer)
      std::printf("  %5u %12.3g%% %6.2f %11.3g", bank.transfer.order[i], 100.0 * bank.transfer.relative_error[i],
                  transferLevelDb(bank.transfer.relative_error[i]), efficiency[i]);
    else if (has_transfer)
      std::printf("  %5s %13s %6s %11s", "-", "-", "-", "-");
    std::printf("\n");
  }
}

}  // namespace

int runInfo(const std::vector<std::string>& raw_args) {
  const CommandSpec spec = infoSpec();
  if (wantsHelp(raw_args)) {
    std::fputs(helpText(spec).c_str(), stdout);
    return 0;
  }
  Result<ParsedArgs> args = parseArgs(spec, raw_args);
  if (!args) return reportError("info", args.error());
  const std::string path = args->positional[0];
  Result<ModeBank> bank = readBank(path);
  if (!bank) return reportError("info", bank.error());
  const size_t vertices = bank->surfaceVertexCount();
  if (args->has("--json")) {
    nlohmann::json j = bankJson(*bank);
    if (args->has("--vertices")) {
      std::vector<std::array<double, 3>> positions(vertices), normals(vertices);
      for (size_t v = 0; v < vertices; ++v)
        for (size_t a = 0; a < 3; ++a) {
          positions[v][a] = bank->surface_positions[3 * v + a];
          normals[v][a] = bank->surface_normals[3 * v + a];
        }
      j["surface_vertices_m"] = positions;
      j["surface_normals"] = normals;
    }
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  printTable(path, *bank);
  if (args->has("--vertices")) {
    // Adding 0.0 prints a -0.0 as 0.
    std::printf("\n%6s %10s %10s %10s %7s %7s %7s\n", "vertex", "x m", "y m", "z m", "nx", "ny", "nz");
    for (size_t v = 0; v < vertices; ++v)
      std::printf("%6zu %10.5f %10.5f %10.5f %7.3f %7.3f %7.3f\n", v, bank->surface_positions[3 * v] + 0.0,
                  bank->surface_positions[3 * v + 1] + 0.0, bank->surface_positions[3 * v + 2] + 0.0,
                  bank->surface_normals[3 * v] + 0.0, bank->surface_normals[3 * v + 1] + 0.0,
                  bank->surface_normals[3 * v + 2] + 0.0);
  }
  return 0;
}

}  // namespace strike::cli
