// SPDX-License-Identifier: MIT
// Modal precompute benchmark: box meshes of ~50k and ~150k Tet4 tets, 100 elastic modes.
// A plain main that prints one table row per phase (each phase runs once: the big case takes
// seconds, and repetitions would only heat a shared machine). Usage:
//   strike_modal_bench [--naive] [--only 50k|150k]
// --naive also times a single-vector baseline (ARPACK to full accuracy, no block refinement)
// in the same process, so the printed ratio does not depend on how loaded the machine is.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "strike/fem.hpp"
#include "strike/mesh.hpp"
#include "strike/modal.hpp"

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
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--naive") == 0) naive = true;
    if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
  }
  const Case cases[] = {{"50k", 0.00987}, {"150k", 0.0068}};
  strike::Material steel{"steel", 2.0e11, 0.29, 7850.0, 0.0, 0.0};
  std::printf("%-6s %8s %8s %9s %9s %9s %9s %9s %7s %9s %9s\n", "case", "tets", "dofs", "mesh_s",
              "assemb_s", "factor_s", "lanczos_s", "refine_s", "solves", "total_s", "rss_MiB");
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
    settings.max_freq_hz = 1e9;
    settings.max_modes = 100;
    t0 = std::chrono::steady_clock::now();
    auto modes = strike::solveModes(K, M, settings);
    const double solve_s = seconds(t0);
    if (!modes) {
      std::fprintf(stderr, "%s\n", modes.error().message.c_str());
      return 1;
    }
    std::printf("%-6s %8lld %8lld %9.3f %9.3f %9.3f %9.3f %9.3f %7d %9.3f %9.0f\n", c.name,
                static_cast<long long>(mesh->tets.rows()), static_cast<long long>(K.rows()), mesh_s,
                assembly_s, modes->factorize_seconds, modes->lanczos_seconds, modes->refine_seconds,
                modes->operator_applications, assembly_s + solve_s, peakRssMiB());
    std::printf("       modes %lld, f1 %.2f Hz, f100 %.2f Hz, rigid dropped %d, max residual %.2e, sigma %.3e\n",
                static_cast<long long>(modes->eigenvalues.size()),
                std::sqrt(modes->eigenvalues[0]) / (2 * M_PI),
                std::sqrt(modes->eigenvalues[modes->eigenvalues.size() - 1]) / (2 * M_PI),
                modes->rigid_modes_dropped, modes->max_relative_residual, modes->sigma);
    if (naive) {
      settings.method = strike::ModalMethod::ArpackOnly;
      t0 = std::chrono::steady_clock::now();
      auto reference = strike::solveModes(K, M, settings);
      const double naive_s = seconds(t0);
      if (!reference) {
        std::fprintf(stderr, "%s\n", reference.error().message.c_str());
        return 1;
      }
      const Eigen::Index common = std::min(reference->eigenvalues.size(), modes->eigenvalues.size());
      const double max_diff = ((reference->eigenvalues.head(common) - modes->eigenvalues.head(common)).array() /
                               reference->eigenvalues.head(common).array()).abs().maxCoeff();
      std::printf("       ARPACK-only baseline: factor %.3f s, lanczos %.3f s, %d solves, solve total %.3f s;"
                  " hybrid speed-up %.2fx; max relative eigenvalue difference %.2e\n",
                  reference->factorize_seconds, reference->lanczos_seconds, reference->operator_applications,
                  naive_s, naive_s / solve_s, max_diff);
    }
  }
  return 0;
}
