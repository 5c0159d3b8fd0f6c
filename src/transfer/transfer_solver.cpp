// SPDX-License-Identifier: MIT
// The acoustic transfer solver's driver: groups of modes, refinement to the target, the
// estimate and the order kept per mode, and the rigid translation's dipole
// (src/include/strike/transfer/transfer_solver.hpp, docs/acoustic-transfer.md).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "../modal/two_parts.hpp"
#include "error_estimate.hpp"
#include "far_field_projection.hpp"
#include "strike/transfer/transfer_solver.hpp"
#include "surface.hpp"
#include "system.hpp"

namespace strike {

using namespace transfer;

namespace {

/// The wavenumber at which a group's near quadrature rules are chosen: k rounded up to the grid
/// 2^(j/4) (a rule fine enough there is fine enough at k). A group's rules thus depend on its own
/// wavenumber alone, never on the other modes solved in the same call, and groups within a
/// quarter octave share their near caches. Exact (frexp / ldexp and constants): the same bits
/// on every machine.
double ruleWavenumber(double k) {
  if (!(k > 0)) return 0.0;
  int exponent = 0;
  const double f = 2.0 * std::frexp(k, &exponent);  // k = f 2^(exponent - 1), f in [1, 2)
  constexpr double kGrid[] = {1.0, 1.189207115002721, 1.4142135623730951, 1.681792830507429, 2.0};
  double q = 2.0;
  for (double g : kGrid)
    if (g >= f) {
      q = g;
      break;
    }
  return std::ldexp(q, exponent - 1);
}

/// Unknowns the target error asks for at wavenumber k, within the budget.
size_t elementsFor(const Surface& s, const TransferSettings& settings, double k) {
  if (settings.fixed_elements > 0) return std::min<size_t>(settings.fixed_elements, s.tris.size());
  // Constant elements: far-field error ~ h^2, so elements per wavelength ~ 1/sqrt(target);
  // 6 per wavelength at 5%.
  const double per_wavelength = 6.0 * std::sqrt(0.05 / std::max(settings.target_relative_error, 1e-4));
  const double h = 2.0 * M_PI / std::max(k, 1e-30) / per_wavelength;
  const double wanted = s.area / (h * h);
  const size_t lo = settings.min_elements, hi = std::max<size_t>(settings.max_elements, lo);
  return std::min(std::clamp(static_cast<size_t>(std::ceil(wanted)), lo, hi), s.tris.size());
}

/// Interior points used at wavenumber k: none below the interior resonance range. The lowest
/// interior Dirichlet eigenvalue of a domain containing a ball of radius r_in is at most
/// pi / r_in (domain monotonicity), and is about that for chunky bodies; thin walls have none in
/// the audible band. Points are added from 0.5 pi / r_in on.
size_t chiefPointsFor(const Surface& s, const TransferSettings& settings, double k, size_t elements) {
  if (!settings.chief || s.chief_candidates.empty() || !(s.inner_radius > 0)) return 0;
  if (k * s.inner_radius < 0.5 * M_PI) return 0;
  return std::min(s.chief_candidates.size(), std::max<size_t>(8, elements / 10));
}

/// A solve measured, the basis of the time budget's forecasts.
struct MeasuredSolve {
  size_t elements = 0;  // 0: none yet
  double k = 0.0, assembly_s = 0.0, factor_s = 0.0, far_field_s = 0.0;
};

/// The seconds of a solve of `elements` unknowns at wavenumber k, forecast from a measured one:
/// the assembly grows as the unknowns (rows x pieces), the factorization as their cube (dense LU
/// or QR) or square (GMRES's products), the far field as k^2 (its directions ~ order^2) and not
/// with the unknowns.
double forecastSolveSeconds(const MeasuredSolve& m, size_t elements, double k, size_t direct_max) {
  const double n = static_cast<double>(elements) / static_cast<double>(std::max<size_t>(m.elements, 1));
  const double kk = m.k > 0 ? std::max(1.0, (k / m.k) * (k / m.k)) : 1.0;
  return m.assembly_s * n + m.factor_s * std::pow(n, elements > direct_max ? 2.0 : 3.0) + m.far_field_s * kk;
}

}  // namespace

std::vector<size_t> transferGroups(const ModeBank& bank, const TransferSettings& settings) {
  // Modes of (nearly) one frequency, as degenerate pairs of symmetric bodies are (split by the
  // mesh's asymmetry), share the system and its factorization: solved at the first one's
  // wavenumber, which changes the others' far fields by about (relative frequency gap) x (1 + ka),
  // added to their estimates. Shared while that is at most a tenth of the target (in quadrature,
  // +0.5% of an estimate at the target).
  constexpr double kSharedGapShare = 0.1;
  const double radius = surfaceRadius(bank), c_air = settings.speed_of_sound_m_s;
  const size_t modes = bank.modeCount();
  std::vector<size_t> group_start;
  for (size_t mode = 0; mode < modes; ++mode) {
    const double omega = std::sqrt(std::max(bank.eigenvalues[mode], 0.0));
    const double first = group_start.empty() ? -1.0 : std::sqrt(std::max(bank.eigenvalues[group_start.back()], 0.0));
    const double allowed = kSharedGapShare * settings.target_relative_error / (1.0 + first / c_air * radius);
    if (group_start.empty() || !(std::abs(omega - first) <= allowed * first)) group_start.push_back(mode);
  }
  group_start.push_back(modes);
  return group_start;
}

Result<AcousticTransfer> solveAcousticTransfer(const ModeBank& bank, const TransferSettings& settings,
                                               const ProgressFn& progress, std::vector<TransferModeStats>* stats) {
  const auto start = std::chrono::steady_clock::now();
  if (!(settings.air_density_kg_m3 > 0) || !std::isfinite(settings.air_density_kg_m3))
    return badInput("transfer air density = " + std::to_string(settings.air_density_kg_m3) + " (must be > 0)");
  if (!(settings.speed_of_sound_m_s > 0) || !std::isfinite(settings.speed_of_sound_m_s))
    return badInput("transfer speed of sound = " + std::to_string(settings.speed_of_sound_m_s) + " (must be > 0)");
  if (!(settings.target_relative_error > 0))
    return badInput("transfer target error = " + std::to_string(settings.target_relative_error) + " (must be > 0)");
  const size_t modes = bank.modeCount();
  const size_t vertices = bank.surfaceVertexCount();
  if (bank.shapes.size() != modes * vertices * 3) return badInput("the bank's shapes are not loaded: no transfer");
  Result<Surface> made = makeSurface(bank);
  if (!made) return made.error();
  const Surface& s = *made;
  const double rho = settings.air_density_kg_m3, c_air = settings.speed_of_sound_m_s;

  AcousticTransfer out;
  out.centre_m = bank.centre_m;
  out.air_density_kg_m3 = rho;
  out.speed_of_sound_m_s = c_air;
  out.offset.push_back(0);
  if (stats) stats->assign(modes, {});
  // The assembly's helper thread, as the eigen-solve's block stage has (src/modal/two_parts.hpp).
  TwoParts parts(settings.threads >= 2 && std::thread::hardware_concurrency() >= 2);

  // Triangle -> its three vertex indices (degenerate ones were dropped: match them up again).
  std::vector<std::array<uint32_t, 3>> corners;
  corners.reserve(s.tris.size());
  for (size_t t = 0; t < bank.surface_triangles.size() / 3; ++t) {
    const uint32_t* v = &bank.surface_triangles[3 * t];
    const V3 p0(&bank.surface_positions[3 * v[0]]), p1(&bank.surface_positions[3 * v[1]]),
        p2(&bank.surface_positions[3 * v[2]]);
    if ((p1 - p0).cross(p2 - p0).norm() > 0) corners.push_back({v[0], v[1], v[2]});
  }

  const std::vector<size_t> group_start = transferGroups(bank, settings);
  SystemOptions system_options;
  system_options.direct_max_elements = settings.direct_max_elements;
  system_options.hierarchical = settings.hierarchical;
  system_options.iterative_tolerance = std::min(1e-5, 0.01 * settings.target_relative_error);

  // The near quadrature per cut, its rules chosen at the group's wavenumber rounded up to a
  // quarter octave (ruleWavenumber): kept while the groups' rule wavenumber stays the same.
  std::map<size_t, NearCache> near_caches;
  double near_caches_k = -1.0;

  // The time budget (settings.max_seconds): the last solve measured, the modes it left coarser
  // than the target asked, and where it ended the transfer.
  MeasuredSolve measured;
  size_t modes_cut = 0, modes_solved = modes;
  using Kind = TransferBudgetStep::Kind;
  auto budgetAllows = [&](Kind kind, size_t first_mode, size_t group_modes, size_t elements, double k) {
    if (!(settings.max_seconds > 0) || measured.elements == 0) return true;
    TransferBudgetStep step;
    step.kind = kind;
    step.first_mode = first_mode;
    step.modes = group_modes;
    step.elements = elements;
    step.elapsed_s = secondsSince(start);
    step.forecast_s = forecastSolveSeconds(measured, elements, k, settings.direct_max_elements);
    step.budget_s = settings.max_seconds;
    step.made = step.elapsed_s + step.forecast_s <= settings.max_seconds;
    if (settings.on_budget_step) settings.on_budget_step(step);
    return step.made;
  };

  std::vector<NodeData> data;
  std::vector<std::vector<cd>> coef;
  std::vector<double> energy, diff;
  for (size_t g = 0; g + 1 < group_start.size(); ++g) {
    const auto group_begin = std::chrono::steady_clock::now();
    const size_t first = group_start[g], last = group_start[g + 1], rhs = last - first;
    const double omega = std::sqrt(std::max(bank.eigenvalues[first], 0.0));
    const double k = omega / c_air;
    // q = dp/dn = -rho a_n, a_n the normal component of the shape (per unit modal acceleration).
    data.assign(rhs, {});
    for (size_t r = 0; r < rhs; ++r) {
      data[r].q.resize(s.tris.size());
      for (size_t t = 0; t < s.tris.size(); ++t) {
        V3 shape = V3::Zero();
        for (uint32_t v : corners[t]) {
          const float* u = bank.shapeAt(first + r, v);
          shape += V3(u[0], u[1], u[2]);
        }
        data[r].q[t] = -rho * s.tris[t].normal.dot(shape / 3.0);
      }
      nodeData(s, data[r]);
    }
    const double kr = k * s.radius;
    const int n_cap = std::min(120, static_cast<int>(std::ceil(kr + 4.0 * std::cbrt(kr))) + 6);
    // The far field is first projected to a lower order (the directions cost ~ order^2): enough
    // for every mode seen so far (the orders kept are ~kR + 3 (kR)^{1/3}); a mode whose top two
    // orders there still hold more than the tail allowed is projected again up to n_cap.
    const int n_try = std::min(n_cap, static_cast<int>(std::ceil(kr + 3.0 * std::cbrt(kr))) + 3);
    // Refine while an estimate exceeds the target and the budget allows: the mode's pattern
    // (not only the wavelength) sets the resolution, and the estimate sees it.
    size_t elements = elementsFor(s, settings, k);
    const size_t cap = settings.fixed_elements > 0 ? elements : std::min<size_t>(settings.max_elements, s.tris.size());
    // A first solve forecast past the time budget is made with the fewest unknowns instead; when
    // even that is, the transfer ends before this group.
    bool group_cut = false;
    const size_t fewest = std::min<size_t>(settings.min_elements, s.tris.size());
    if (elements > fewest && !budgetAllows(Kind::FirstSolve, first, rhs, elements, k)) {
      elements = fewest;
      group_cut = true;
    }
    if (elements <= fewest && !budgetAllows(Kind::Fewest, first, rhs, elements, k)) {
      modes_solved = first;
      break;
    }
    const double k_rule = ruleWavenumber(k);
    if (k_rule != near_caches_k) {
      near_caches.clear();
      near_caches_k = k_rule;
    }
    // Per mode: the far field of the first resolution that met the target (or the last).
    std::vector<double> total(rhs, 0.0);
    std::vector<char> done(rhs, 0);
    std::vector<uint32_t> mode_elements(rhs, 0), mode_chief(rhs, 0), mode_iterations(rhs, 0);
    size_t group_matrix_bytes = 0, group_near_bytes = 0;  // the most the group's solves held
    std::vector<int> mode_cap(rhs, n_cap);                // the order up to which the mode's far field was projected
    diff.assign(rhs, 0.0);
    energy.assign(rhs * (n_cap + 1), 0.0);
    coef.assign(rhs, {});
    double assembly_seconds = 0.0, factor_seconds = 0.0, far_field_seconds = 0.0;
    uint32_t solves = 0;
    std::vector<std::vector<cd>> step_coef, step_dcoef;
    while (true) {
      const size_t chief = chiefPointsFor(s, settings, k, elements);
      const ModeSolve solved = solveSystem(s, data, k, elements, chief, k_rule, near_caches, parts, system_options);
      group_matrix_bytes = std::max(group_matrix_bytes, solved.matrix_bytes);
      group_near_bytes = std::max(group_near_bytes, nearCacheBytes(near_caches));
      ++solves;
      assembly_seconds += solved.assembly_seconds;
      factor_seconds += solved.factor_seconds;
      const auto far_start = std::chrono::steady_clock::now();
      int projected = n_try;
      projectFarField(s, solved.pieces, solved.piece_data, data, k, projected, solved.p, solved.p_diff, step_coef,
                      step_dcoef, parts);
      if (n_try < n_cap && !seriesConverged(step_coef, done, n_try)) {
        projected = n_cap;
        projectFarField(s, solved.pieces, solved.piece_data, data, k, projected, solved.p, solved.p_diff, step_coef,
                        step_dcoef, parts);
      }
      far_field_seconds += secondsSince(far_start);
      measured = {solved.elements, k, solved.assembly_seconds, solved.factor_seconds, secondsSince(far_start)};
      const bool last_step = elements >= cap;
      for (size_t r = 0; r < rhs; ++r) {
        if (done[r]) continue;
        double* e = &energy[r * (n_cap + 1)];
        std::fill(e, e + n_cap + 1, 0.0);
        total[r] = 0.0;
        diff[r] = 0.0;
        for (int n = 0; n <= projected; ++n)
          for (int m = -n; m <= n; ++m) {
            e[n] += std::norm(step_coef[r][n * n + n + m]);
            diff[r] += std::norm(step_dcoef[r][n * n + n + m]);
          }
        for (int n = 0; n <= projected; ++n) total[r] += e[n];
        coef[r] = step_coef[r];
        mode_cap[r] = projected;
        mode_elements[r] = static_cast<uint32_t>(solved.elements);
        mode_chief[r] = static_cast<uint32_t>(solved.chief);
        mode_iterations[r] = static_cast<uint32_t>(solved.iterations);
        done[r] = last_step || !(diff[r] > std::pow(settings.target_relative_error, 2) * total[r]);
      }
      if (std::all_of(done.begin(), done.end(), [](char d) { return d != 0; })) break;
      // Next: 2.5x the unknowns, or straight to the budget when even that is predicted to fall
      // short of the target (the error of constant elements falls as h^2, i.e. as 1 / unknowns):
      // the steps between would be solved only to be dropped.
      // (Of a shared solve: when every mode still refining is predicted to fall short.)
      double best = 1e300;
      for (size_t r = 0; r < rhs; ++r)
        if (!done[r]) best = std::min(best, total[r] > 0 ? std::sqrt(diff[r] / total[r]) : 0.0);
      const double asked = static_cast<double>(elements) * best / settings.target_relative_error;
      elements = asked >= static_cast<double>(cap) ? cap : std::min(cap, elements * 5 / 2);
      if (!budgetAllows(Kind::Refinement, first, rhs, elements, k)) {  // the modes not done keep this solve
        group_cut = true;
        break;
      }
    }
    const double group_seconds = secondsSince(group_begin);

    for (size_t r = 0; r < rhs; ++r) {
      const size_t mode = first + r;
      const double* e = &energy[r * (n_cap + 1)];
      // Order: the smallest whose tail holds at most kTailEnergy of the energy.
      const double tail_allowed = kTailEnergy * total[r];
      const int top = mode_cap[r];
      int order = top;
      double tail = 0.0;
      while (order > 0 && tail + e[order] <= tail_allowed) tail += e[order--];
      // Error: the coarse solve's difference, the dropped tail, what the last computed orders
      // still hold (a series not yet converged at n_cap), and a shared solve's frequency gap.
      const double unresolved = e[top] + (top > 0 ? e[top - 1] : 0.0);
      const double omega_mode = std::sqrt(std::max(bank.eigenvalues[mode], 0.0));
      const double gap = omega > 0 ? std::abs(omega_mode - omega) / omega * (1.0 + kr) : 0.0;
      const double relative =
          total[r] > 0 ? std::sqrt((diff[r] + tail + (order == top ? unresolved : 0.0)) / total[r] + gap * gap) : 0.0;

      out.order.push_back(static_cast<uint32_t>(order));
      for (int i = 0; i < (order + 1) * (order + 1); ++i)
        out.coefficients.push_back(
            std::complex<float>(static_cast<float>(coef[r][i].real()), static_cast<float>(coef[r][i].imag())));
      out.offset.push_back(out.coefficients.size());
      out.relative_error.push_back(static_cast<float>(relative));
      if (group_cut && relative > settings.target_relative_error) ++modes_cut;
      if (stats) {
        TransferModeStats& st = (*stats)[mode];
        st.ka = omega_mode / c_air * s.radius;
        st.elements = mode_elements[r];
        st.chief_points = mode_chief[r];
        st.order = static_cast<uint32_t>(order);
        st.relative_error = relative;
        // A shared solve's time is split evenly between its modes.
        st.seconds = group_seconds / static_cast<double>(rhs);
        st.assembly_seconds = assembly_seconds / static_cast<double>(rhs);
        st.factor_seconds = factor_seconds / static_cast<double>(rhs);
        st.far_field_seconds = far_field_seconds / static_cast<double>(rhs);
        st.solves = solves;
        st.iterations = mode_iterations[r];
        st.matrix_bytes = group_matrix_bytes;
        st.near_cache_bytes = group_near_bytes;
      }
    }
    if (progress) progress("transfer", static_cast<double>(last) / static_cast<double>(modes + 1));
  }

  // Rigid translation in the compact limit: the Laplace problem (k = 0) with dp/dn = -n_j
  // (rho factored out). M_ij = V delta_ij + int n_i p_j dS (docs: from the far field's first
  // order in k, the volume term by the divergence theorem).
  {
    Eigen::Matrix3d dipole = Eigen::Matrix3d::Identity() * s.volume;
    const size_t elements = std::min<size_t>(settings.max_elements, s.tris.size());
    data.assign(3, {});
    for (int j = 0; j < 3; ++j) {
      data[j].q.resize(s.tris.size());
      for (size_t t = 0; t < s.tris.size(); ++t) data[j].q[t] = -s.tris[t].normal[j];
      nodeData(s, data[j]);
    }
    near_caches.clear();  // (rules at k = 0)
    const ModeSolve solved = solveSystem(s, data, 0.0, elements, 0, 0.0, near_caches, parts,
                                         system_options);  // the three right-hand sides at once
    for (int j = 0; j < 3; ++j)
      for (size_t c = 0; c < solved.cut.nodes.size(); ++c) {
        const V3 va = s.nodes[solved.cut.nodes[c]].vector_area;
        for (int i = 0; i < 3; ++i) dipole(i, j) += va[i] * solved.p[j][static_cast<Eigen::Index>(c)].real();
      }
    const Eigen::Matrix3d symmetric = 0.5 * (dipole + dipole.transpose());
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out.translation_dipole_m3[i * 3 + j] = symmetric(i, j);
  }
  if (progress) progress("transfer", 1.0);
  out.solve_seconds = secondsSince(start);
  char method[160];
  std::snprintf(method, sizeof method,
                "bem collocation, clustered constant elements (%u-%u), chief, target %.3g, %zu triangles",
                settings.min_elements, settings.max_elements, settings.target_relative_error, s.tris.size());
  out.method = method;
  if (modes_cut > 0 || modes_solved < modes) {  // said in the bank: a time budget's transfer
    std::snprintf(method, sizeof method, "; time budget %.3g s: %zu modes cut short of the target, %zu left unsolved",
                  settings.max_seconds, modes_cut, modes - modes_solved);
    out.method += method;
  }
  return out;
}

}  // namespace strike
