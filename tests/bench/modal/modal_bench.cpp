// SPDX-License-Identifier: MIT
// Modal precompute benchmark: box meshes of ~50k and ~150k Tet4 tets, 100 elastic modes.
// A plain main that prints one table row per solve with the time of each phase. Usage:
//   strike_modal_bench [--naive] [--only 50k|150k] [--repeat N] [--block B] [--threads T]
//                      [--max-freq F] [--max-modes N]
// --repeat N runs the hybrid solve N times (best and spread: the machine is shared), --block
// sets the block Lanczos block size, --threads our own threads (ModalSettings::threads, 1 or 2),
// --max-freq F --max-modes N a cut-off-limited request instead of 100 modes (the default).
// --naive also times a single-vector baseline (ARPACK to full accuracy, no block refinement)
// in the same process, so the printed ratio does not depend on how loaded the machine is.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "strike/fem/fem.hpp"
#include "strike/mesh/mesh.hpp"
#include "strike/modal/modal.hpp"

namespace {

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double peakRssMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is KiB on Linux
}

struct Case {
  const char* name;
  double edge_m;  // box 0.4 x 0.2 x 0.1 m
};

}  // namespace

int main(int argc, char** argv) {
  bool naive = false;
  std::string only;
  int repeat = 1, block = 0, threads = -1, max_modes = 100;
  double max_freq = 1e9;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--naive") == 0) naive = true;
    if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
    if (std::strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
    if (std::strcmp(argv[i], "--block") == 0 && i + 1 < argc) block = std::atoi(argv[++i]);
    if (std::strcmp(argv[i], "--threads") == 0 && i + 1 < argc) threads = std::atoi(argv[++i]);
    if (std::strcmp(argv[i], "--max-freq") == 0 && i + 1 < argc) max_freq = std::atof(argv[++i]);
    if (std::strcmp(argv[i], "--max-modes") == 0 && i + 1 < argc) max_modes = std::atoi(argv[++i]);
  }
  const Case cases[] = {{"50k", 0.00987}, {"150k", 0.0068}};
  strike::Material steel{"steel", 2.0e11, 0.29, 7850.0, 0.0, 0.0};
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    char load[128] = {};
    if (std::fgets(load, sizeof load, f) != nullptr) std::printf("load average at start: %s", load);
    std::fclose(f);
  }
  std::printf("%-6s %8s %8s %7s %8s %8s %9s %8s %8s %8s %8s %6s %5s %8s %8s\n", "case", "tets", "dofs", "mesh_s",
              "assemb_s", "factor_s", "lanczos_s", "(solve", "orth", "ritz)", "refine_s", "solves", "block", "total_s",
              "rss_MiB");
  for (const Case& c : cases) {
    if (!only.empty() && only != c.name) continue;
    auto t0 = std::chrono::steady_clock::now();
    strike::MeshOptions options;
    options.target_edge_m = c.edge_m;
    auto mesh = strike::makeBox(0.4, 0.2, 0.1, options);
    if (!mesh) {
      std::fprintf(stderr, "%s\n", mesh.error().message.c_str());
      return 1;
    }
    const double mesh_s = seconds(t0);
    t0 = std::chrono::steady_clock::now();
    Eigen::SparseMatrix<double> K, M;
    strike::assembleStiffnessAndMass(*mesh, steel, K, M);
    const double assembly_s = seconds(t0);
    strike::ModalSettings settings;
    settings.max_freq_hz = max_freq;
    settings.max_modes = max_modes;
    settings.block_size = block;
    if (threads >= 1) settings.threads = threads;
    std::vector<double> totals;
    strike::ModalResult modes;
    for (int r = 0; r < repeat; ++r) {
      t0 = std::chrono::steady_clock::now();
      auto result = strike::solveModes(K, M, settings);
      const double solve_s = seconds(t0);
      if (!result) {
        std::fprintf(stderr, "%s\n", result.error().message.c_str());
        return 1;
      }
      // Assembly is part of the precompute's cost (meshing of a primitive is not).
      totals.push_back(assembly_s + solve_s);
      std::printf("%-6s %8lld %8lld %7.3f %8.3f %8.3f %9.3f %8.3f %8.3f %8.3f %8.3f %6d %5d %8.3f %8.0f\n", c.name,
                  static_cast<long long>(mesh->tets.rows()), static_cast<long long>(K.rows()), mesh_s, assembly_s,
                  result->factorize_seconds, result->lanczos_seconds, result->solve_seconds,
                  result->orthogonalize_seconds, result->ritz_seconds, result->refine_seconds,
                  result->operator_applications, result->block_size, totals.back(), peakRssMiB());
      std::fflush(stdout);
      modes = std::move(result.value());
    }
    const double best = *std::min_element(totals.begin(), totals.end());
    const double worst = *std::max_element(totals.begin(), totals.end());
    std::printf(
        "       %s: best total %.3f s, spread %.3f s over %d run(s); modes %lld, f1 %.2f Hz, f100 %.2f Hz,"
        " rigid dropped %d, max residual %.2e, sigma %.3e, basis %d, reorthogonalized steps %d\n",
        c.name, best, worst - best, repeat, static_cast<long long>(modes.eigenvalues.size()),
        std::sqrt(modes.eigenvalues[0]) / (2 * M_PI),
        std::sqrt(modes.eigenvalues[modes.eigenvalues.size() - 1]) / (2 * M_PI), modes.rigid_modes_dropped,
        modes.max_relative_residual, modes.sigma, modes.lanczos_basis, modes.reorthogonalizations);
    if (naive) {
      settings.method = strike::ModalMethod::ArpackOnly;
      t0 = std::chrono::steady_clock::now();
      auto reference = strike::solveModes(K, M, settings);
      const double naive_s = seconds(t0);
      if (!reference) {
        std::fprintf(stderr, "%s\n", reference.error().message.c_str());
        return 1;
      }
      const Eigen::Index common = std::min(reference->eigenvalues.size(), modes.eigenvalues.size());
      const double max_diff = ((reference->eigenvalues.head(common) - modes.eigenvalues.head(common)).array() /
                               reference->eigenvalues.head(common).array())
                                  .abs()
                                  .maxCoeff();
      std::printf(
          "       ARPACK-only baseline (same process): factor %.3f s, lanczos %.3f s (solve %.3f s), %d solves,"
          " total %.3f s; hybrid speed-up %.2fx (best hybrid run); max relative eigenvalue difference %.2e\n",
          reference->factorize_seconds, reference->lanczos_seconds, reference->solve_seconds,
          reference->operator_applications, assembly_s + naive_s, (assembly_s + naive_s) / best, max_diff);
    }
    std::fflush(stdout);
  }
  return 0;
}
