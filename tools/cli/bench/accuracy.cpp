// SPDX-License-Identifier: MIT
// `strike bench accuracy -o DIR`: the reproducible accuracy study (bench.cpp parses
// the command line).
//  - accuracy-fem.csv / .svg: mode frequency error (true, against Timoshenko theory, and the
//    bank's own estimate) against precompute time, Tet4 and Tet10, 4 resolutions each, on the
//    free-free steel bar 0.3 x 0.02 x 0.02 m, on a solid sphere R = 5 cm against Lamb's modes, and
//    (with --plate, +~45 s) on a free thick steel plate 0.1 x 0.1 x 0.01 m (h/a = 0.1) against a
//    converged Tet10 reference;
//  - accuracy-synth.csv: float vs double oscillator state at 16-192 kHz, and culling thresholds at
//    48 kHz, against a double-precision reference render of the same impact at the same rate:
//    time-domain error, spectral error (FFT peak frequency and level) and run time;
//  - accuracy-transfer.csv: the acoustic transfer solver on the analytic sphere: a
//    sphere R = 5 cm (2420 triangles) whose surface acceleration is Y_nm radiates exactly
//    A h_n(kr) Y_nm; far-field error (rms over directions, level in dB and phase in degrees of the
//    Y_nm coefficient) and the solver's own estimate against unknowns and seconds, n = 1 and 3,
//    ka = 1, 5, 10, 20;
//  - accuracy-euler.csv: symplectic Euler on the modal ODE at the audio step h = 1/fs against the
//    exact exponential update, per mode frequency, and the frequency where Euler goes unstable.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include "bench_studies.hpp"
#include "commands.hpp"
#include "output_check.hpp"
#include "references/beam_theory.hpp"  // src/references: the Timoshenko free-free bar reference
#include "references/lamb_sphere.hpp"  // src/references: Lamb's free-sphere modes
#include "strike/core/constants.hpp"
#include "strike/precompute/precompute.hpp"
#include "strike/synth/synth.hpp"
#include "strike/transfer/transfer_solver.hpp"

namespace strike::cli {
namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// The bank's error estimate for mode i; 1.0 ("unknown", as the bank writes it) when it has none.
double estimateOf(const ModeBank& bank, size_t i) {
  return i < bank.frequency_error_estimate.size() ? bank.frequency_error_estimate[i] : 1.0;
}

struct FemRow {
  std::string object;  ///< "bar" or "sphere"
  int order;
  double edge_m;
  size_t dofs;
  double seconds, estimate_seconds;
  std::vector<double> true_error, estimate;
};

/// The free thick plate: a steel square 0.1 x 0.1 x 0.01 m (h/a = 0.1), free on all edges.
/// Reference: no closed form exists for a free plate even in thin (Kirchhoff) theory (Leissa,
/// "Vibration of Plates", NASA SP-160, 1969, gives Ritz approximations), and at h/a = 0.1 shear
/// and rotary inertia lower the first mode by ~5% against thin theory, while Mindlin theory
/// itself differs from 3D elasticity by amounts of the size this study measures. So the
/// reference is this code's own Tet10 solution at half the finest study edge (2.5 mm, 177k DOF):
/// Tet10 frequency errors fall as h^4, so its error is ~1/16 of the finest Tet10 row's. Sanity
/// check against thin theory: first mode 3104 Hz; Kirchhoff with lambda = omega a^2 sqrt(rho h / D)
/// = 13.47 (the free square plate's first mode as we recall it from Leissa, J. Sound Vib. 31(3),
/// 1973, nu = 0.3; not checked against the table here) gives 3263 Hz, 5% higher, as shear
/// deformation and rotary inertia predict. The first 8 elastic modes are compared in ascending
/// order (modes 4/5 and 6/7 are degenerate pairs).
Status plateStudy(std::vector<FemRow>& rows) {
  auto settings = [](int order, double edge) {
    PrecomputeSettings s;
    s.mesh_spec = "box:0.1,0.1,0.01";
    s.material.name = "steel";
    s.material.youngs_pa = 2.0e11;
    s.material.poisson = 0.29;
    s.material.density_kg_m3 = 7850;
    s.order = order;
    s.target_edge_m = edge;
    s.max_freq_hz = 1e9;
    s.max_modes = 8;
    s.error_estimate = true;
    s.acoustic_transfer = false;  // the FEM study times the eigen-solve
    return s;
  };
  std::fprintf(stderr, "strike bench: plate reference, Tet10 size 2.5 mm (~25 s, 1.9 GB)\n");
  PrecomputeSettings reference_settings = settings(2, 0.0025);
  reference_settings.error_estimate = false;
  Result<PrecomputeResult> reference = computeModeBank(reference_settings);
  if (!reference) return reference.error();
  const std::pair<int, double> runs[] = {{1, 0.01}, {1, 0.02 / 3}, {1, 0.005},    {1, 0.01 / 3},
                                         {2, 0.02}, {2, 0.01},     {2, 0.02 / 3}, {2, 0.005}};
  for (const auto& [order, edge] : runs) {
    Result<PrecomputeResult> r = computeModeBank(settings(order, edge));
    if (!r) return r.error();
    FemRow row{"plate", order, edge, r->report.dofs, r->bank.total_seconds, r->report.error_estimate_seconds, {}, {}};
    for (size_t i = 0; i < 8 && i < r->bank.modeCount() && i < reference->bank.modeCount(); ++i) {
      const double ref = reference->bank.frequencyHz(i);
      row.true_error.push_back(std::abs(r->bank.frequencyHz(i) - ref) / ref);
      row.estimate.push_back(estimateOf(r->bank, i));
    }
    std::fprintf(stderr, "strike bench: plate Tet%d size %.4g m, %zu DOF, %.2f s, first mode error %.3g%%\n",
                 order == 2 ? 10 : 4, edge, row.dofs, row.seconds, 100 * row.true_error[0]);
    rows.push_back(std::move(row));
  }
  return {};
}

Result<std::vector<FemRow>> femStudy(bool plate) {
  const test::BarProperties bar{2.0e11, 0.29, 7850, 0.3, 0.02, 0.02};
  const std::vector<double> reference = test::timoshenkoFreeFreeHz(bar, 3);
  std::vector<FemRow> rows;
  const std::pair<int, double> runs[] = {{1, 0.01}, {1, 0.02 / 3}, {1, 0.005},    {1, 0.0025},
                                         {2, 0.02}, {2, 0.01},     {2, 0.02 / 3}, {2, 0.005}};
  for (const auto& [order, edge] : runs) {
    PrecomputeSettings s;
    s.mesh_spec = "box:0.3,0.02,0.02";
    s.material.name = "steel";
    s.material.youngs_pa = bar.youngs_pa;
    s.material.poisson = bar.poisson;
    s.material.density_kg_m3 = bar.density_kg_m3;
    s.order = order;
    s.target_edge_m = edge;
    s.max_freq_hz = 8000.0;
    s.max_modes = 12;
    s.error_estimate = true;
    s.acoustic_transfer = false;
    Result<PrecomputeResult> r = computeModeBank(s);
    if (!r) return r.error();
    FemRow row{"bar", order, edge, r->report.dofs, r->bank.total_seconds, r->report.error_estimate_seconds, {}, {}};
    // Each Timoshenko bending frequency is a degenerate pair on the square bar: take the two
    // nearest FEM modes and report the worse.
    for (double ref : reference) {
      double worst = 0, est = 0;
      std::vector<std::pair<double, size_t>> near;
      for (size_t i = 0; i < r->bank.modeCount(); ++i) near.push_back({std::abs(r->bank.frequencyHz(i) - ref), i});
      std::sort(near.begin(), near.end());
      for (size_t k = 0; k < 2 && k < near.size(); ++k) {
        const size_t i = near[k].second;
        worst = std::max(worst, near[k].first / ref);
        est = std::max(est, estimateOf(r->bank, i));
      }
      row.true_error.push_back(worst);
      row.estimate.push_back(est);
    }
    std::fprintf(stderr, "strike bench: Tet%d size %.4g m, %zu DOF, %.2f s, first bending error %.3g%%\n",
                 order == 2 ? 10 : 4, edge, row.dofs, row.seconds, 100 * row.true_error[0]);
    rows.push_back(std::move(row));
  }
  // Solid sphere, nu = 0.25: the 28 lowest modes sorted against Lamb's roots (each repeated
  // 2n + 1 times); reported per degenerate group (T2, S2, S1, T3, S3) as the group's worst.
  Material sphere_material;
  sphere_material.name = "steel-like";
  sphere_material.youngs_pa = 2.0e11;
  sphere_material.poisson = 0.25;
  sphere_material.density_kg_m3 = 7850;
  const double R = 0.05;
  const double cs =
      std::sqrt(sphere_material.youngs_pa / (2 * (1 + sphere_material.poisson)) / sphere_material.density_kg_m3);
  const std::vector<double> etas = test::lambSphereEtas(sphere_material.poisson, 7.0);
  for (int order : {1, 2})
    for (double edge : {0.03, 0.02, 0.015, 0.01}) {
      PrecomputeSettings s;
      s.mesh_spec = "sphere:0.05";
      s.material = sphere_material;
      s.order = order;
      s.target_edge_m = edge;
      s.max_freq_hz = 1e9;
      s.max_modes = 28;
      s.error_estimate = true;
      s.acoustic_transfer = false;
      Result<PrecomputeResult> r = computeModeBank(s);
      if (!r) return r.error();
      FemRow row{"sphere", order, edge, r->report.dofs, r->bank.total_seconds, r->report.error_estimate_seconds,
                 {},       {}};
      const size_t groups[][2] = {{0, 5}, {5, 10}, {10, 13}, {13, 20}, {20, 27}};
      for (const auto& g : groups) {
        double worst = 0, est = 0;
        for (size_t i = g[0]; i < g[1] && i < r->bank.modeCount(); ++i) {
          const double ref = etas[i] * cs / (2 * kPi * R);
          worst = std::max(worst, std::abs(r->bank.frequencyHz(i) - ref) / ref);
          est = std::max(est, estimateOf(r->bank, i));
        }
        row.true_error.push_back(worst);
        row.estimate.push_back(est);
      }
      std::fprintf(stderr, "strike bench: sphere Tet%d size %.4g m, %zu DOF, %.2f s, first group error %.3g%%\n",
                   order == 2 ? 10 : 4, edge, row.dofs, row.seconds, 100 * row.true_error[0]);
      rows.push_back(std::move(row));
    }
  if (plate)
    if (Status ok = plateStudy(rows); !ok) return ok.error();
  return rows;
}

/// Log-log plot: worst bending-mode error against precompute time, one polyline per order.
std::string femSvg(const std::vector<FemRow>& rows) {
  const double W = 640, H = 420, L = 70, R = 20, T = 30, B = 50;
  double tmin = 1e9, tmax = 0, emin = 1e9, emax = 0;
  for (const FemRow& r : rows) {
    const double e = std::max(*std::max_element(r.true_error.begin(), r.true_error.end()), 1e-7);
    tmin = std::min(tmin, r.seconds), tmax = std::max(tmax, r.seconds), emin = std::min(emin, e),
    emax = std::max(emax, e);
  }
  const double lt0 = std::floor(std::log10(tmin)), lt1 = std::ceil(std::log10(tmax));
  const double le0 = std::floor(std::log10(emin)), le1 = std::ceil(std::log10(emax));
  auto x = [&](double t) { return L + (std::log10(t) - lt0) / std::max(1.0, lt1 - lt0) * (W - L - R); };
  auto y = [&](double e) { return H - B - (std::log10(e) - le0) / std::max(1.0, le1 - le0) * (H - T - B); };
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H
    << "' font-family='sans-serif' font-size='12'>\n"
    << "<rect width='100%' height='100%' fill='white'/>\n"
    << "<text x='" << L
    << "' y='18'>worst mode frequency error vs precompute time (free-free bar, sphere, plate)</text>\n";
  for (double d = lt0; d <= lt1; ++d)
    s << "<line x1='" << x(std::pow(10, d)) << "' y1='" << T << "' x2='" << x(std::pow(10, d)) << "' y2='" << H - B
      << "' stroke='#ddd'/><text x='" << x(std::pow(10, d)) - 12 << "' y='" << H - B + 16 << "'>1e" << d << "</text>\n";
  for (double d = le0; d <= le1; ++d)
    s << "<line x1='" << L << "' y1='" << y(std::pow(10, d)) << "' x2='" << W - R << "' y2='" << y(std::pow(10, d))
      << "' stroke='#ddd'/><text x='8' y='" << y(std::pow(10, d)) + 4 << "'>1e" << d << "</text>\n";
  s << "<text x='" << (W / 2 - 60) << "' y='" << H - 12 << "'>precompute time (s)</text>\n";
  const char* colours[3] = {"", "#c0392b", "#2471a3"};
  int line = 0;
  for (const char* object : {"bar", "sphere", "plate"})
    for (int order : {1, 2}) {
      ++line;
      const std::string name = object;
      if (std::none_of(rows.begin(), rows.end(), [&](const FemRow& r) { return r.object == name; })) continue;
      const char* dashes = name == "bar"      ? ""
                           : name == "sphere" ? " stroke-dasharray='6,4'"
                                              : " stroke-dasharray='2,3'";
      s << "<polyline fill='none' stroke='" << colours[order] << "' stroke-width='2'" << dashes << " points='";
      for (const FemRow& r : rows)
        if (r.order == order && r.object == object)
          s << x(r.seconds) << "," << y(std::max(*std::max_element(r.true_error.begin(), r.true_error.end()), 1e-7))
            << " ";
      s << "'/>\n<text x='" << W - 150 << "' y='" << T + 18 * line << "' fill='" << colours[order] << "'>" << object
        << " Tet" << (order == 2 ? 10 : 4)
        << (name == "bar"      ? ""
            : name == "sphere" ? " (dashed)"
                               : " (dotted)")
        << "</text>\n";
    }
  s << "</svg>\n";
  return s.str();
}

struct SynthRun {
  AudioBuffer audio;
  double seconds;
};

/// 300 modes between 50 Hz and 15 kHz, struck once, 5 s at `rate`.
SynthRun synthRender(double rate, bool double_precision, double threshold) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> freq(50.0, 15000.0), gain(-1.0, 1.0);
  ModalObjectDesc object;
  std::vector<double> g(300);
  for (double& v : g) {
    object.eigenvalues.push_back(std::pow(2 * kPi * freq(rng), 2));
    v = 1e-3 * gain(rng);
  }
  object.rayleigh_stiffness = 1e-8;
  object.rayleigh_mass = 1.0;
  SynthSettings s;
  s.sample_rate_hz = rate;
  s.double_precision = double_precision;
  s.audibility_threshold = threshold;
  OscillatorBank bank(s, object);
  bank.addImpact(ImpactDesc{0.01, 5e-5, g.data()});
  SynthRun run{AudioBuffer{rate, 1, std::vector<float>(static_cast<size_t>(rate * 5))}, 0};
  const auto start = std::chrono::steady_clock::now();
  bank.render(run.audio.samples.data(), run.audio.samples.size());
  run.seconds = secondsSince(start);
  return run;
}

/// Symplectic Euler (v += h a(x, v); x += h v) on q'' + c q' + w^2 q = 0, q(0) = 0, q'(0) = 1,
/// over 1 s at step h, against the exact solution e^{-c t/2} sin(w_d t) / w_d. Returns the
/// largest error relative to the exact peak, or +inf when the solution blew up.
double symplecticEulerError(double f_hz, double c, double rate) {
  const double w = 2 * kPi * f_hz, h = 1.0 / rate, wd = std::sqrt(w * w - c * c / 4);
  double x = 0, v = 1, worst = 0, peak = 0;
  const int n = static_cast<int>(rate);
  for (int k = 1; k <= n; ++k) {
    v += h * (-w * w * x - c * v);
    x += h * v;
    const double t = k * h, exact = std::exp(-c * t / 2) * std::sin(wd * t) / wd;
    peak = std::max(peak, std::abs(exact));
    worst = std::max(worst, std::abs(x - exact));
    if (!std::isfinite(x) || std::abs(x) > 1e6 / w) return INFINITY;
  }
  return worst / peak;
}

/// The exact exponential update the synth uses (one complex multiply per sample), same setup.
double exactUpdateError(double f_hz, double c, double rate) {
  const double w = 2 * kPi * f_hz, h = 1.0 / rate, wd = std::sqrt(w * w - c * c / 4);
  const std::complex<double> step = std::exp(std::complex<double>(-c / 2, wd) * h);
  std::complex<double> z(1.0, 0.0);
  double worst = 0, peak = 0;
  for (int k = 1; k <= static_cast<int>(rate); ++k) {
    z *= step;
    const double t = k * h, exact = std::exp(-c * t / 2) * std::sin(wd * t) / wd;
    peak = std::max(peak, std::abs(exact));
    worst = std::max(worst, std::abs(z.imag() / wd - exact));
  }
  return worst / peak;
}

struct TransferRow {
  int n;
  double ka;
  uint32_t elements, chief;
  double seconds, relative, level_db, phase_deg, estimate;
};

/// The analytic sphere at fixed resolutions: surface acceleration Y_nm (radial) on a
/// sphere of radius a radiates p = A h_n(kr) Y_nm, A = -rho / (k h_n'(ka)) (e^{-i omega t}), so
/// the far-field coefficient is -rho (-i)^{n+1} / (k^2 h_n'(ka)) and every other one is zero.
Result<std::vector<TransferRow>> transferStudy() {
  const double a = 0.05, c_air = kSpeedOfSoundAir_m_s, rho = kAirDensity_kg_m3;
  Result<SurfaceMesh> mesh = makeSphereSurface(a, a / 10);
  if (!mesh) return mesh.error();
  ModeBank sphere;
  for (Eigen::Index v = 0; v < mesh->V.rows(); ++v)
    for (int c = 0; c < 3; ++c) sphere.surface_positions.push_back(mesh->V(v, c));
  sphere.surface_normals.assign(sphere.surface_positions.size(), 0.0f);
  for (Eigen::Index f = 0; f < mesh->F.rows(); ++f)
    for (int c = 0; c < 3; ++c) sphere.surface_triangles.push_back(static_cast<uint32_t>(mesh->F(f, c)));
  std::vector<TransferRow> rows;
  for (int n : {1, 3})
    for (double ka : {1.0, 5.0, 10.0, 20.0}) {
      const int m = n == 1 ? 0 : 2;
      const double k = ka / a;
      ModeBank bank = sphere;
      bank.eigenvalues = {k * k * c_air * c_air};
      std::vector<double> Y((n + 1) * (n + 1));
      for (size_t v = 0; v < bank.surfaceVertexCount(); ++v) {
        const double* p = &bank.surface_positions[3 * v];
        realSphericalHarmonics(static_cast<uint32_t>(n), p, Y.data());
        const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (int c = 0; c < 3; ++c) bank.shapes.push_back(static_cast<float>(Y[n * n + n + m] * p[c] / r));
      }
      using cd = std::complex<double>;
      auto h = [&](int order) { return cd(std::sph_bessel(order, ka), std::sph_neumann(order, ka)); };
      const cd exact = -rho * std::pow(cd(0, -1), n + 1) / (k * k * (h(n - 1) - (n + 1.0) / ka * h(n)));
      for (uint32_t elements : {100u, 200u, 400u, 700u, 1000u}) {
        TransferSettings settings;
        settings.fixed_elements = elements;
        settings.max_elements = elements;
        std::vector<TransferModeStats> stats;
        Result<AcousticTransfer> t = solveAcousticTransfer(bank, settings, {}, &stats);
        if (!t) return t.error();
        double wrong = 0;
        cd got = 0;
        for (uint64_t j = 0; j < t->offset[1]; ++j) {
          const cd c(t->coefficients[j].real(), t->coefficients[j].imag());
          const bool main = j == static_cast<uint64_t>(n * n + n + m);
          if (main) got = c;
          wrong += std::norm(main ? c - exact : c);
        }
        TransferRow row{n,
                        ka,
                        stats[0].elements,
                        stats[0].chief_points,
                        stats[0].seconds,
                        std::sqrt(wrong) / std::abs(exact),
                        20 * std::log10(std::abs(got) / std::abs(exact)),
                        std::arg(got / exact) * 180 / kPi,
                        stats[0].relative_error};
        std::fprintf(stderr,
                     "strike bench: transfer sphere n %d ka %4.1f: %4u elements, %2u CHIEF, %.3f s, error %.2f%% "
                     "(%+.2f dB, %+.2f deg), estimate %.2f%%\n",
                     n, ka, row.elements, row.chief, row.seconds, 100 * row.relative, row.level_db, row.phase_deg,
                     100 * row.estimate);
        rows.push_back(row);
      }
    }
  return rows;
}

}  // namespace
/// `strike bench accuracy`: writes the study's files to DIR (which exists) and returns the exit
/// code (bench_studies.hpp).
int benchAccuracy(const std::string& dir, bool plate) {
  auto open = [&](const std::string& name, std::ofstream& file) -> Status {
    file.open(dir + "/" + name);
    if (!file) return badInput(dir + "/" + name + ": error: cannot create file");
    return {};
  };

  Result<std::vector<FemRow>> fem = femStudy(plate);
  if (!fem) return reportError("bench", fem.error());
  std::ofstream csv;
  if (Status ok = open("accuracy-fem.csv", csv); !ok) return reportError("bench", ok.error());
  csv << "object,element,edge_m,dofs,precompute_s,estimate_s,mode,true_rel_error,estimated_rel_error\n";
  const char* sphere_groups[] = {"T2", "S2", "S1", "T3", "S3"};
  for (const FemRow& r : *fem)
    for (size_t m = 0; m < r.true_error.size(); ++m)
      csv << r.object << "," << (r.order == 2 ? "Tet10" : "Tet4") << "," << r.edge_m << "," << r.dofs << ","
          << r.seconds << "," << r.estimate_seconds << ","
          << (r.object == "bar"      ? "bending" + std::to_string(m + 1)
              : r.object == "sphere" ? std::string(sphere_groups[m])
                                     : "mode" + std::to_string(m + 1))
          << "," << r.true_error[m] << "," << r.estimate[m] << "\n";
  csv.close();
  std::ofstream svg;
  if (Status ok = open("accuracy-fem.svg", svg); !ok) return reportError("bench", ok.error());
  svg << femSvg(*fem);
  svg.close();

  // Synthesis: a 300-mode bank, 5 s, one impact, against the double-precision render at the same
  // rate: float state at 16-192 kHz, then culling thresholds at 48 kHz.
  std::ofstream synth;
  if (Status ok = open("accuracy-synth.csv", synth); !ok) return reportError("bench", ok.error());
  synth << "sample_rate,state,threshold_db,render_s,max_abs_error_rel_peak,rms_error_rel_rms,"
           "peak_freq_rel_error,peak_level_error_db,unmatched_peaks\n";
  struct Case {
    double rate;
    const char* state;
    bool dp;
    double db;
  };
  const Case cases[] = {{16000, "float", false, -999}, {44100, "float", false, -999}, {48000, "double", true, -999},
                        {48000, "float", false, -999}, {96000, "float", false, -999}, {192000, "float", false, -999},
                        {48000, "float", false, -100}, {48000, "float", false, -80},  {48000, "float", false, -60},
                        {48000, "float", false, -40}};
  double reference_rate = 0;
  SynthRun reference_run;
  double peak = 0, rms = 0;
  for (const Case& c : cases) {
    if (c.rate != reference_rate) {
      reference_run = synthRender(c.rate, true, 0.0);
      reference_rate = c.rate;
      peak = 0, rms = 0;
      for (float v : reference_run.audio.samples) peak = std::max(peak, double(std::abs(v))), rms += double(v) * v;
      rms = std::sqrt(rms / double(reference_run.audio.samples.size()));
    }
    const double threshold = c.db < -900 ? 0.0 : peak * std::pow(10.0, c.db / 20.0);
    const SynthRun run = synthRender(c.rate, c.dp, threshold);
    double max_err = 0, sq = 0;
    const std::vector<float>& out = run.audio.samples;
    for (size_t n = 0; n < out.size(); ++n) {
      const double d = double(out[n]) - reference_run.audio.samples[n];
      max_err = std::max(max_err, std::abs(d)), sq += d * d;
    }
    const SpectralDifference spectral = spectralDifference(reference_run.audio, run.audio);
    synth << c.rate << "," << c.state << "," << (c.db < -900 ? std::string("none") : std::to_string(int(c.db))) << ","
          << run.seconds << "," << max_err / peak << "," << std::sqrt(sq / double(out.size())) / rms << ","
          << spectral.max_freq_rel << "," << spectral.max_level_db << "," << spectral.unmatched_peaks << "\n";
  }
  synth.close();

  // Explicit integrator at the audio step.
  std::ofstream euler;
  if (Status ok = open("accuracy-euler.csv", euler); !ok) return reportError("bench", ok.error());
  euler << "sample_rate,freq_hz,symplectic_euler_rel_error,exact_update_rel_error\n";
  const double rate = 48000.0, c = 2.0;
  for (double f : {100.0, 1000.0, 5000.0, 10000.0, 15000.0, 15300.0, 20000.0})
    euler << rate << "," << f << "," << symplecticEulerError(f, c, rate) << "," << exactUpdateError(f, c, rate) << "\n";
  // Bisection on the frequency where symplectic Euler stops being bounded (theory, c = 0:
  // w h = 2, f = fs / pi).
  double lo = 1000.0, hi = 24000.0;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::isfinite(symplecticEulerError(mid, c, rate)) ? lo : hi) = mid;
  }
  euler << "# symplectic Euler unstable above " << lo << " Hz at " << rate << " Hz (fs/pi = " << rate / kPi
        << "); the exact update is stable at every frequency\n";
  euler.close();
  // The acoustic transfer on the analytic sphere.
  Result<std::vector<TransferRow>> transfer = transferStudy();
  if (!transfer) return reportError("bench", transfer.error());
  std::ofstream transfer_csv;
  if (Status ok = open("accuracy-transfer.csv", transfer_csv); !ok) return reportError("bench", ok.error());
  transfer_csv << "object,n,ka,elements,chief_points,solve_s,rel_error,level_error_db,phase_error_deg,"
                  "estimated_rel_error\n";
  for (const TransferRow& r : *transfer)
    transfer_csv << "sphere," << r.n << "," << r.ka << "," << r.elements << "," << r.chief << "," << r.seconds << ","
                 << r.relative << "," << r.level_db << "," << r.phase_deg << "," << r.estimate << "\n";
  transfer_csv.close();
  std::fprintf(stderr, "strike bench: wrote %s/accuracy-transfer.csv\n", dir.c_str());
  std::fprintf(stderr,
               "strike bench: wrote %s/accuracy-{fem.csv,fem.svg,synth.csv,euler.csv}; Euler unstable above %.0f Hz\n",
               dir.c_str(), lo);
  return 0;
}

}  // namespace strike::cli
