// SPDX-License-Identifier: MIT
// `strike modes MESH -o BANK.modes`: precompute an object's vibration modes.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "modes_similar.hpp"
#include "output_check.hpp"
#include "progress_reporter.hpp"
#include "strike/precompute/element_order.hpp"
#include "strike/precompute/error_estimate.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/mesh/mesh.hpp"
#include "strike/precompute/normalized_problem.hpp"
#include "strike/core/parse_size.hpp"
#include "strike/precompute/precompute.hpp"
#include "strike/scene/render.hpp"

namespace strike::cli {
namespace {

CommandSpec modesSpec() {
  CommandSpec spec;
  spec.usage = "strike modes MESH -o BANK.modes [--material NAME | --youngs PA --poisson NU --density KG_M3] [options]";
  spec.summary =
      "Computes the free vibration modes of a solid: tetrahedralizes MESH (TetGen) if it is a surface,\n"
      "assembles linear-elastic FEM stiffness K and mass M (Tet4 or Tet10), solves K x = lambda M x for the\n"
      "lowest modes with shift-invert Lanczos (ARPACK on a CHOLMOD factorization), drops the 6 rigid-body\n"
      "modes and writes the bank: frequencies, Rayleigh damping, mass-normalized shapes on the surface,\n"
      "mass properties and provenance.\n"
      "\n"
      "MESH is a surface mesh (.obj .stl .ply), a tet mesh (Gmsh .msh 2.2/4.1 ASCII, TetGen .node/.ele),\n"
      "or a primitive centred at the origin, in metres: box:LX,LY,LZ  sphere:R  cylinder:R,H";
  spec.options = {
      {"-o", "BANK.modes", "output mode bank (required); written atomically"},
      {"--material", "NAME", "a material from the built-in table (see --list-materials)"},
      {"--youngs", "PA", "Young's modulus, Pa (overrides the material's)"},
      {"--poisson", "NU", "Poisson ratio, in (-1, 0.5)"},
      {"--density", "KG_M3", "density, kg/m^3"},
      {"--rayleigh-stiffness", "A1", "Rayleigh damping a1 (s) in C = a1 K + a2 M; default 0 or the material's"},
      {"--rayleigh-mass", "A2", "Rayleigh damping a2 (1/s); default 0 or the material's"},
      {"--order", "1|2",
       "element order: 1 linear tets (Tet4), 2 quadratic (Tet10, more accurate); default: from the shape: 2 "
       "when the wall (2 x volume / area) is under 10% of the largest extent (plates, shells, bars: Tet4 locks in "
       "bending, 108% off on a mug), else 1; the summary says why"},
      {"--size", "METRES", "target tet edge length; default: chosen from the object's size"},
      {"--units", "m|cm|mm", "unit of a mesh file's coordinates (not of primitives); default m"},
      {"--max-freq", "HZ", "keep every mode up to this frequency; default 20000"},
      {"--max-modes", "N", "but at most N modes (lowest first); default 200, cap 100000"},
      {"--max-tets", "N", "refuse meshes with more tets than this (memory and time cap); default 2000000"},
      {"--error-estimate", "", "estimate each mode's frequency error (default: on for primitives and surfaces)"},
      {"--no-error-estimate", "", "skip the error estimate"},
      {"--tolerance", "PCT",
       "refine a Tet10 mesh until every mode's estimated error is below PCT: 0.5% or 0.005\n"
       "(a bare number >= 0.1 is refused as ambiguous). Each step at most triples the DOF\n"
       "and is announced with its forecast time and memory"},
      {"--max-memory", "SIZE",
       "memory budget (e.g. 4G, 500M): every solve (the eigen-solve, the transfer, each --tolerance\n"
       "step) forecasts its memory first and is refused at once, with the forecast, when it needs\n"
       "more; default: the memory available now (MemAvailable). With --transfer-max-elements\n"
       "the transfer's budget is lowered until its largest system fits in half of it"},
      {"--max-seconds", "S",
       "time budget: do not start a step (each --tolerance step, each refinement step of the\n"
       "transfer) forecast to end later than S seconds after the start; default: no limit. A\n"
       "budget stop keeps the finest result and says so (NOT met). The forecasts come from the\n"
       "rates measured on this machine, so with a budget the bank depends on its speed"},
      {"--compact", "",
       "store the mode shapes as 16-bit integers with a scale per mode (bank format 4):\n"
       "half the shape bytes, each value within 1.54e-5 of its mode's largest amplitude"},
      {"--no-transfer", "",
       "do not solve each mode's acoustic transfer (solved by default: its far field in every\n"
       "direction, with the body as an obstacle: boundary elements; docs/listener.md). Without it\n"
       "renders hear each mode at its direction-averaged level, whose sign depends on the solve.\n"
       "The transfer costs 0.8x-1.8x the eigen-solve on the order-2 examples (bowl, coin, glass,\n"
       "bar), more on plates, planks and blocks of linear tets, whose eigen-solve is cheap\n"
       "(docs/acoustic-transfer.md)"},
      {"--transfer", "", "solve the acoustic transfer (the default; kept so older scripts run)"},
      {"--transfer-tolerance", "PCT",
       "refine each mode's transfer until its estimated error (rms over directions of its far\n"
       "field's error, relative to the field's rms) is below PCT, within the element budget:\n"
       "e.g. 10% (-20 dB: the level within -0.9/+0.8 dB) or 0.05; default 5% (-26 dB, +-0.4 dB),\n"
       "or --tolerance's. Modes it cannot meet are reported (NOT met) with the reason"},
      {"--transfer-max-elements", "N",
       "the transfer's element budget: at most N unknowns per solve; default 700 (dense LU);\n"
       "above 700 a wall without interior points is solved by GMRES (memory ~48 N^2 bytes,\n"
       "forecast and kept within --max-memory)"},
      {"--similar", "",
       "solve the shape at unit size with a reference material and scale the bank to the object,\n"
       "as `strike render --similar` does: the bank that render uses (frequencies equal to a\n"
       "direct solve's to ~1e-12; some shapes of opposite sign). Not with --tolerance"},
      {"--cache", "DIR",
       "with --similar: the bank cache render uses, for the normalized solve (read if there,\n"
       "else solved and put there); default $STRIKE_CACHE_DIR or ~/.cache/strike"},
      {"--no-cache", "", "with --similar: solve, read and write no cache"},
      {"--quiet", "", "no progress or summary on stderr"},
      {"--progress", "",
       "show progress even when stderr is not a terminal (a line every 5 s: phase, object, share done, time "
       "left); on a terminal it is shown by default"},
      {"--list-materials", "",
       "print the material table (elastic constants, damping, restitution, friction) with sources and exit"},
  };
  spec.examples =
      "  strike modes box:0.3,0.02,0.02 --material steel --order 2 -o bar.modes\n"
      "  strike modes assets/meshes/bowl.obj --material ceramic -o bowl.modes\n"
      "  strike modes assets/meshes/mug.obj --material porcelain --tolerance 0.5% --max-memory 4G -o mug.modes\n"
      "  strike modes part.msh --youngs 7e10 --poisson 0.33 --density 2700 -o part.modes\n";
  spec.min_positional = 0;
  spec.max_positional = 1;
  return spec;
}

int listMaterials() {
  const MaterialTable& table = builtinMaterials();
  // The sources are long (a citation each): numbered notes under the table keep its rows short.
  std::printf("%-14s %11s %7s %9s %11s %11s %6s %6s %7s  %s\n", "material", "E (Pa)", "nu", "rho", "a1 (s)", "a2 (1/s)",
              "e", "mu", "c_rr", "source");
  std::vector<std::string> sources;
  for (const auto& [name, m] : table.materials) {
    auto source = table.sources.find(name);
    std::string note;
    if (source != table.sources.end() && !source->second.empty()) {
      auto known = std::find(sources.begin(), sources.end(), source->second);
      if (known == sources.end()) known = sources.insert(sources.end(), source->second);
      note = "[" + std::to_string(known - sources.begin() + 1) + "]";
    }
    const ContactProperties contact = table.contactProperties(name);
    std::printf("%-14s %11.3g %7.3f %9.0f %11.3g %11.3g %6.2f %6.2f %7.4f  %s\n", name.c_str(), m.youngs_pa, m.poisson,
                m.density_kg_m3, m.rayleigh_stiffness, m.rayleigh_mass, contact.restitution, contact.friction,
                contact.rolling_resistance, note.c_str());
  }
  std::printf("\nsources:\n");
  for (size_t i = 0; i < sources.size(); ++i) {
    const std::string number = "[" + std::to_string(i + 1) + "]";
    std::printf("%-5s%s\n", number.c_str(), wrapHelp(sources[i], 5, kHelpWidth).c_str());
  }
  std::printf(
      "\ne, mu: restitution and friction of the material on itself (rigid-body simulation only; rough typical\n"
      "values). Two bodies combine theirs: restitution by compliance-weighted energy loss, 1 - e^2 =\n"
      "(k1 (1 - e1^2) + k2 (1 - e2^2)) / (k1 + k2), k = (1 - nu^2) / E (the softer body decides; Hertz, Johnson\n"
      "1985); friction by the geometric mean sqrt(mu1 mu2) (Box2D). A scene overrides them per object\n"
      "(\"restitution\", \"friction\"), for the ground, and per pair (\"contacts\"): see docs/contact.md.\n"
      "c_rr: coefficient of rolling resistance (rolling force / load) of the material on itself, where a sphere\n"
      "rolls; two bodies combine theirs by the compliance-weighted mean (k1 c1 + k2 c2) / (k1 + k2)\n"
      "(\"rolling_resistance\" in a scene).\n");
  return 0;
}

/// The material from --material and/or the numeric options (numbers override the named entry).
Result<Material> materialFromArgs(const ParsedArgs& args) {
  Material material;
  const bool named = args.has("--material");
  if (named) {
    Result<Material> found = builtinMaterials().find(args.text("--material"));
    if (!found) return found.error();
    material = *found;
  } else {
    if (!args.has("--youngs") || !args.has("--poisson") || !args.has("--density"))
      return badInput("no material: give --material NAME, or all of --youngs PA --poisson NU --density KG_M3");
    material.name = "custom";
  }
  struct Field {
    const char* option;
    double* value;
  };
  const Field fields[] = {{"--youngs", &material.youngs_pa},
                          {"--poisson", &material.poisson},
                          {"--density", &material.density_kg_m3},
                          {"--rayleigh-stiffness", &material.rayleigh_stiffness},
                          {"--rayleigh-mass", &material.rayleigh_mass}};
  for (const Field& f : fields) {
    Result<double> value = args.number(f.option, *f.value);
    if (!value) return value.error();
    *f.value = *value;
    if (named && args.has(f.option)) material.name = args.text("--material") + " (modified)";
  }
  // Name the option the user typed, not the internal field.
  if (!(material.youngs_pa > 0)) return badInput("--youngs = " + args.text("--youngs", "?") + " (must be > 0)");
  if (!(material.poisson > -1.0 && material.poisson < 0.5))
    return badInput("--poisson = " + args.text("--poisson", "?") + " (must be in (-1, 0.5); 0.5 is incompressible)");
  if (!(material.density_kg_m3 > 0)) return badInput("--density = " + args.text("--density", "?") + " (must be > 0)");
  if (!(material.rayleigh_stiffness >= 0))
    return badInput("--rayleigh-stiffness = " + args.text("--rayleigh-stiffness") + " (must be >= 0)");
  if (!(material.rayleigh_mass >= 0))
    return badInput("--rayleigh-mass = " + args.text("--rayleigh-mass") + " (must be >= 0)");
  return material;
}

/// `time_cuts`: the transfer's steps that the time budget (--max-seconds) did not make.
void printSummary(const PrecomputeSettings& settings, const PrecomputeResult& result, const std::string& output,
                  size_t time_cuts) {
  const ModeBank& bank = result.bank;
  std::fprintf(stderr, "strike modes: %s, %s (E %.3g Pa, nu %.3g, rho %.4g kg/m^3)\n", settings.mesh_spec.c_str(),
               bank.material.name.c_str(), bank.material.youngs_pa, bank.material.poisson, bank.material.density_kg_m3);
  std::fprintf(stderr, "  mesh        %u nodes, %u tets (Tet%d), %zu DOF, %zu surface vertices\n", bank.mesh_nodes,
               bank.mesh_tets, bank.element_order == 2 ? 10 : 4, result.report.dofs, bank.surfaceVertexCount());
  std::fprintf(stderr, "  solid       mass %.6g kg, volume %.6g m^3\n", bank.mass_kg, bank.volume_m3);
  if (bank.modeCount() > 0)
    std::fprintf(stderr, "  modes       %zu kept, %.2f Hz to %.2f Hz\n", bank.modeCount(), bank.frequencyHz(0),
                 bank.frequencyHz(bank.modeCount() - 1));
  else
    std::fprintf(stderr,
                 "  modes       none below %.0f Hz: the object is too small or too stiff to ring in that band\n",
                 settings.max_freq_hz);
  std::fprintf(stderr, "  dropped     %u rigid-body, %u above %.0f Hz%s\n", bank.rigid_modes_dropped,
               bank.above_cutoff_dropped, settings.max_freq_hz,
               result.report.capped_by_max_modes ? ", and more below it (capped by --max-modes)" : "");
  std::fprintf(stderr, "  time        mesh %.2f s, assemble %.2f s, factorize %.2f s, Lanczos %.2f s, total %.2f s\n",
               bank.meshing_seconds, bank.assembly_seconds, bank.factorize_seconds, bank.lanczos_seconds,
               bank.total_seconds);
  if (!bank.transfer.empty()) {
    const double target = settings.transfer.target_relative_error;
    float worst = 0.0f;
    size_t worst_mode = 0;
    for (size_t i = 0; i < bank.transfer.relative_error.size(); ++i)
      if (bank.transfer.relative_error[i] > worst) worst = bank.transfer.relative_error[i], worst_mode = i;
    std::fprintf(stderr,
                 "  transfer    %.2f s (of the total), order up to %u, est. error max %.3g%% (mode %zu, %.2f Hz); "
                 "%s\n",
                 bank.transfer_seconds, bank.transfer.maxOrder(), 100.0 * worst, worst_mode,
                 bank.modeCount() > worst_mode ? bank.frequencyHz(worst_mode) : 0.0, bank.transfer.method.c_str());
    size_t over = 0;
    for (float e : bank.transfer.relative_error) over += e > target ? 1 : 0;
    // Heard modes the time budget left without a transfer.
    const size_t heard = modesAtOrBelow(bank, settings.transfer_max_freq_hz);
    const size_t unsolved = time_cuts > 0 && heard > bank.transfer.modeCount() ? heard - bank.transfer.modeCount() : 0;
    // What an estimate means for the sound: the error's level under the field's, and the
    // field's level within 20 log10(1 -+ e) dB.
    std::fprintf(stderr, "  transfer    tolerance %.3g%% (%.0f dB: a mode's level within %+.2f/%+.2f dB) %s",
                 100.0 * target, 20.0 * std::log10(target), 20.0 * std::log10(std::max(1e-6, 1.0 - target)),
                 20.0 * std::log10(1.0 + target), over == 0 && unsolved == 0 ? "met on every mode\n" : "NOT met: ");
    if (over > 0 && time_cuts == 0)
      std::fprintf(stderr,
                   "%zu of %zu modes estimated worse (max %.0f dB, %+.1f dB); the element budget (%u unknowns) stops "
                   "them short (--transfer-max-elements; docs/acoustic-transfer.md)\n",
                   over, bank.transfer.modeCount(), 20.0 * std::log10(worst), 20.0 * std::log10(1.0 + worst),
                   settings.transfer.max_elements);
    else if (over > 0 || unsolved > 0)
      std::fprintf(stderr,
                   "%zu of %zu modes estimated worse (max %.0f dB, %+.1f dB), %zu heard modes left unsolved; the time "
                   "budget (--max-seconds) cut %zu of the transfer's steps (within the element budget, %u unknowns); "
                   "this bank depends on the machine's speed\n",
                   over, bank.transfer.modeCount(), worst > 0 ? 20.0 * std::log10(worst) : -INFINITY,
                   20.0 * std::log10(1.0 + worst), unsolved, time_cuts, settings.transfer.max_elements);
    else if (time_cuts > 0)
      std::fprintf(stderr,
                   "              the time budget (--max-seconds) cut %zu of the transfer's steps, none past the "
                   "tolerance\n",
                   time_cuts);
    if (bank.transfer.modeCount() < bank.modeCount())
      std::fprintf(stderr,
                   "  heard       the transfer of the %zu modes up to %.0f Hz%s; the %zu above keep none (a render "
                   "that plays them solves theirs)\n",
                   bank.transfer.modeCount(),
                   bank.transfer.modeCount() > 0 ? bank.frequencyHz(bank.transfer.modeCount() - 1) : 0.0,
                   unsolved > 0 ? " (the time budget stopped it)" : ", what a render plays",
                   bank.modeCount() - bank.transfer.modeCount());
  }
  const std::vector<double>& error = bank.frequency_error_estimate;
  if (!error.empty()) {
    size_t worst = 0;
    for (size_t i = 1; i < error.size(); ++i)
      if (error[i] > error[worst]) worst = i;
    char ratio[48] = "";
    if (result.report.error_estimate_ratio > 0)
      std::snprintf(ratio, sizeof ratio, ", h ratio %.2f", result.report.error_estimate_ratio);
    std::fprintf(stderr, "  est. error  max %.3g%% (mode %zu, %.2f Hz), %s (coarse %zu DOF%s), extra %.2f s (%.0f%%)\n",
                 100.0 * error[worst], worst, bank.frequencyHz(worst), result.report.error_estimate_method.c_str(),
                 result.report.error_estimate_coarse_dofs, ratio, result.report.error_estimate_seconds,
                 bank.total_seconds > 0 ? 100.0 * result.report.error_estimate_seconds / bank.total_seconds : 0.0);
    if (!result.report.error_estimate_note.empty())
      std::fprintf(stderr, "              %s\n", result.report.error_estimate_note.c_str());
  } else if (!result.report.error_estimate_note.empty()) {
    std::fprintf(stderr, "  est. error  none: %s\n", result.report.error_estimate_note.c_str());
  }
  std::fprintf(stderr, "  wrote       %s\n", output.c_str());
}

/// --tolerance: "0.5%" or "0.005". A bare number >= 0.1 is refused: "0.5" is 50% to the
/// parser and half a percent to whoever typed it.
Result<double> parseTolerance(const std::string& raw, const std::string& option = "--tolerance") {
  std::string text = raw;
  const bool percent = !text.empty() && text.back() == '%';
  if (percent) text.pop_back();
  Result<double> value = parseNumber(text, option);
  if (!value) return value.error();
  if (!percent && *value >= 0.1)
    return badInput(option + " = " + raw + " is ambiguous: write " + raw + "% for " + raw +
                    " percent, or a fraction below 0.1 (0.005 = 0.5%)");
  const double tolerance = percent ? *value / 100.0 : *value;
  if (!(tolerance > 0 && tolerance < 1)) return badInput(option + " = " + raw + " (must be between 0 and 100%)");
  return tolerance;
}

/// `--tolerance PCT`: refine until the estimated error meets PCT for every kept mode, within
/// the memory and time budgets (src/precompute/error_estimate.cpp); prints each step's forecast
/// before it runs, what it cost, and how it ended.
Result<PrecomputeResult> computeToTolerance(const ParsedArgs& args, PrecomputeSettings& settings, bool quiet) {
  Result<double> tolerance = parseTolerance(args.text("--tolerance"));
  if (!tolerance) return tolerance.error();
  if (args.has("--order") || args.has("--size"))
    return badInput("--tolerance chooses --order and --size itself; give one or the other");
  if (args.has("--no-error-estimate"))
    return badInput("--tolerance needs the error estimate; drop --no-error-estimate");
  ToleranceOptions options;
  options.tolerance = *tolerance;
  // The transfer, when asked for, aims at the same relative error (its far field's, rms over
  // directions); its element budget may stop it short, and the summary says where.
  if (!args.has("--transfer-tolerance")) settings.transfer.target_relative_error = *tolerance;
  options.max_bytes = settings.max_memory_bytes;
  Result<double> seconds = args.number("--max-seconds", 0.0);
  if (!seconds) return seconds.error();
  if (args.has("--max-seconds") && !(*seconds > 0))
    return badInput("--max-seconds = " + args.text("--max-seconds") + " (must be > 0)");
  options.max_seconds = *seconds;
  if (!quiet) {
    char seconds_text[32];
    std::snprintf(seconds_text, sizeof seconds_text, "%g", options.max_seconds);
    std::fprintf(stderr, "strike modes: tolerance %.3g%%, budget %s memory%s, %s\n", 100.0 * *tolerance,
                 options.max_bytes > 0 ? (std::to_string(options.max_bytes / 1e9).substr(0, 5) + " GB").c_str() : "no",
                 args.has("--max-memory") ? "" : (options.max_bytes > 0 ? " (available now)" : ""),
                 options.max_seconds > 0 ? (std::string(seconds_text) + " s").c_str() : "no time limit");
    options.log = [](const std::string& line) { std::fprintf(stderr, "strike modes: %s\n", line.c_str()); };
  }
  Result<ToleranceResult> chosen = computeModeBankToTolerance(settings, options);
  if (!chosen) return chosen.error();
  if (!quiet) {
    for (const ToleranceTrial& t : chosen->trials)
      std::fprintf(stderr,
                   "strike modes: tolerance %.3g%%: Tet%d, size %.4g m, %zu DOF, %.2f s, max est. error %.3g%%%s\n",
                   100.0 * *tolerance, t.order == 2 ? 10 : 4, t.target_edge_m, t.dofs, t.seconds,
                   100.0 * t.max_estimate, t.met ? "  <- chosen" : "");
    if (chosen->met)
      std::fprintf(stderr, "strike modes: tolerance met after %zu steps, %.2f s in all\n", chosen->trials.size(),
                   chosen->total_seconds);
    else
      std::fprintf(
          stderr,
          "strike modes: tolerance NOT met: %s; kept the finest result (max est. error %.3g%%), %.2f s in all\n",
          chosen->stop_reason.empty() ? "no step met it" : chosen->stop_reason.c_str(),
          100.0 * chosen->trials.back().max_estimate, chosen->total_seconds);
  }
  settings.order = chosen->trials.back().order;
  settings.target_edge_m = chosen->trials.back().target_edge_m;
  PrecomputeResult out = std::move(chosen->chosen);
  return out;
}

/// --transfer-tolerance and --transfer-max-elements (and --max-memory's cap on the latter).
Status transferOptions(const ParsedArgs& args, PrecomputeSettings& settings, bool quiet) {
  if (args.has("--transfer-tolerance")) {
    Result<double> tolerance = parseTolerance(args.text("--transfer-tolerance"), "--transfer-tolerance");
    if (!tolerance) return tolerance.error();
    settings.transfer.target_relative_error = *tolerance;
  }
  if (!args.has("--transfer-max-elements")) return {};
  Result<long long> budget = args.integer("--transfer-max-elements", 700);
  if (!budget) return budget.error();
  if (*budget < 16 || *budget > 100000)
    return badInput("--transfer-max-elements = " + args.text("--transfer-max-elements") + " (must be 16 to 100000)");
  uint64_t elements = static_cast<uint64_t>(*budget);
  if (settings.max_memory_bytes > 0) {
    // Half the budget for the largest system and its coarse copy (the rest: mesh, bank, caches).
    while (elements > 16 && transferSystemBytes(elements, settings.transfer.direct_max_elements,
                                                settings.transfer.hierarchical) > 0.5 * settings.max_memory_bytes)
      elements = elements * 9 / 10;
  }
  settings.transfer.max_elements = static_cast<uint32_t>(elements);
  if (!quiet)
    std::fprintf(
        stderr, "strike modes: transfer budget %llu unknowns (forecast %.0f MB for its largest system)%s\n",
        static_cast<unsigned long long>(elements),
        transferSystemBytes(elements, settings.transfer.direct_max_elements, settings.transfer.hierarchical) / 1e6,
        elements < static_cast<uint64_t>(*budget) ? ", lowered to fit the memory budget (--max-memory)" : "");
  return {};
}

}  // namespace

int runModes(const std::vector<std::string>& raw_args) {
  const CommandSpec spec = modesSpec();
  if (wantsHelp(raw_args)) {
    std::fputs(helpText(spec).c_str(), stdout);
    return 0;
  }
  Result<ParsedArgs> parsed = parseArgs(spec, raw_args);
  if (!parsed) return reportError("modes", parsed.error());
  const ParsedArgs& args = *parsed;
  if (args.has("--list-materials")) return listMaterials();
  if (args.positional.empty()) return reportError("modes", badInput("missing MESH; usage: " + spec.usage));
  if (!args.has("-o")) return reportError("modes", badInput("missing -o BANK.modes (where to write the bank)"));
  if (Status ok = checkOutputFile("-o", args.text("-o"), {}); !ok) return reportError("modes", ok.error());
  if (const std::string out = args.text("-o"); out.size() < 6 || out.compare(out.size() - 6, 6, ".modes") != 0)
    std::fprintf(stderr,
                 "strike modes: warning: -o %s does not end in .modes: a scene's \"bank\", strike info and strike hit "
                 "read it all the same, but .modes is how banks are named (and found by `strike cache`)\n",
                 out.c_str());

  PrecomputeSettings settings;
  settings.mesh_spec = args.positional[0];
  Result<Material> material = materialFromArgs(args);
  if (!material) return reportError("modes", material.error());
  settings.material = *material;
  // No --order: the library's automatic order (src/precompute/element_order.cpp).
  Result<long long> order = args.integer("--order", kAutoOrder);
  if (!order) return reportError("modes", order.error());
  if (args.has("--order") && *order != 1 && *order != 2)
    return reportError("modes", badInput("--order = " + args.text("--order") + " (must be 1 or 2)"));
  settings.order = static_cast<int>(*order);
  if (args.has("--transfer") && args.has("--no-transfer"))
    return reportError("modes", badInput("give --transfer or --no-transfer, not both"));
  settings.acoustic_transfer = !args.has("--no-transfer");
  Result<double> size = args.number("--size", 0.0);
  if (!size) return reportError("modes", size.error());
  if (args.has("--size") && !(*size > 0))
    return reportError("modes", badInput("--size = " + args.text("--size") + " (must be > 0 metres)"));
  settings.target_edge_m = *size;
  const std::string units = args.text("--units", "m");
  if (units != "m" && units != "cm" && units != "mm")
    return reportError("modes", badInput("--units = '" + units + "' (expected m, cm or mm)"));
  if (units != "m" && isPrimitiveSpec(settings.mesh_spec))
    return reportError("modes", badInput("--units applies to a mesh file; primitives are in metres"));
  settings.mesh_scale = units == "mm" ? 0.001 : units == "cm" ? 0.01 : 1.0;
  Result<double> max_freq = args.number("--max-freq", 20000.0);
  if (!max_freq) return reportError("modes", max_freq.error());
  if (!(*max_freq > 0))
    return reportError("modes", badInput("--max-freq = " + args.text("--max-freq") + " (must be > 0 Hz)"));
  settings.max_freq_hz = *max_freq;
  Result<long long> max_modes = args.integer("--max-modes", 200);
  if (!max_modes) return reportError("modes", max_modes.error());
  if (*max_modes < 1 || *max_modes > 100000)
    return reportError("modes", badInput("--max-modes = " + args.text("--max-modes") + " (must be 1 to 100000)"));
  settings.max_modes = static_cast<int>(*max_modes);
  Result<long long> max_tets = args.integer("--max-tets", kDefaultMaxTets);
  if (!max_tets) return reportError("modes", max_tets.error());
  if (*max_tets < 1)
    return reportError("modes", badInput("--max-tets = " + args.text("--max-tets") + " (must be >= 1)"));
  settings.max_tets = *max_tets;

  Result<double> max_seconds = args.number("--max-seconds", 0.0);
  if (!max_seconds) return reportError("modes", max_seconds.error());
  if (args.has("--max-seconds") && !(*max_seconds > 0))
    return reportError("modes", badInput("--max-seconds = " + args.text("--max-seconds") + " (must be > 0)"));
  if (args.has("--max-seconds") && args.has("--similar"))
    return reportError("modes", badInput("--max-seconds bounds a direct solve; --similar's transfer is the cached "
                                         "unit transfer's, solved whole (give one or the other)"));
  if (!args.has("--tolerance")) settings.max_seconds = *max_seconds;  // (--tolerance applies it itself)
  Result<double> max_memory = memoryBudgetFromArgs(args);
  if (!max_memory) return reportError("modes", max_memory.error());
  settings.max_memory_bytes = *max_memory;
  if (Status ok = transferOptions(args, settings, args.has("--quiet")); !ok) return reportError("modes", ok.error());
  if (args.has("--error-estimate") && args.has("--no-error-estimate"))
    return reportError("modes", badInput("--error-estimate and --no-error-estimate contradict each other"));
  // Default: on when the mesh can be coarsened (Richardson, ~10-25% extra; see
  // src/include/strike/precompute/error_estimate.hpp), off for tet files (Tet4 on corners costs more, bounds less).
  settings.error_estimate =
      args.has("--error-estimate") || (!args.has("--no-error-estimate") && canRemesh(settings.mesh_spec));

  const bool quiet = args.has("--quiet");
  ProgressReporter progress("modes", quiet, args.has("--progress"));
  settings.progress = progress.callback();
  // Each decision of the transfer's time budget, with its forecast (the bank depends on them).
  size_t time_cuts = 0;
  settings.transfer.on_budget_step = [&time_cuts, quiet](const TransferBudgetStep& step) {
    time_cuts += step.made ? 0 : 1;
    if (quiet) return;
    using Kind = TransferBudgetStep::Kind;
    const char* refused = step.kind == Kind::Refinement   ? ": not made, the modes keep their last solve"
                          : step.kind == Kind::FirstSolve ? ": not made; the fewest unknowns instead, if they fit"
                                                          : ": not made, the transfer ends here (these modes and "
                                                            "those above keep none)";
    std::fprintf(stderr,
                 "strike modes: transfer time budget: modes %zu-%zu, %zu unknowns, %.1f s spent + %.1f s "
                 "forecast %s %.3g s%s\n",
                 step.first_mode, step.first_mode + step.modes - 1, step.elements, step.elapsed_s, step.forecast_s,
                 step.made ? "<=" : ">", step.budget_s, step.made ? "" : refused);
  };
  if (!args.has("--similar") && (args.has("--cache") || args.has("--no-cache")))
    return reportError("modes", badInput("--cache and --no-cache go with --similar (a direct solve is not cached)"));
  const std::string cache_dir = args.has("--no-cache") ? "" : args.text("--cache", defaultCacheDir());
  SimilarSource similar_source;
  if (args.has("--similar") && args.has("--tolerance"))
    return reportError("modes",
                       badInput("--similar and --tolerance cannot be combined (the refinement solves directly)"));
  Result<PrecomputeResult> result = args.has("--tolerance") ? computeToTolerance(args, settings, quiet)
                                    : args.has("--similar") ? similarModeBank(settings, cache_dir, similar_source)
                                                            : computeModeBank(settings);
  progress.finish();
  if (!result) return reportError("modes", result.error());
  if (!quiet)
    for (const MeshWarning& warning : result->report.warnings)
      std::fprintf(stderr, "strike modes: warning: %s\n", warning.message.c_str());
  const std::string output = args.text("-o");
  Status written =
      writeBank(output, result->bank, args.has("--compact") ? ShapeEncoding::Int16 : ShapeEncoding::Float32);
  if (!written) return reportError("modes", written.error());
  progress.written(output);
  if (!quiet) {
    printSummary(settings, *result, output, time_cuts);
    if (!result->report.order_reason.empty())
      std::fprintf(stderr, "  order       %s (--order to override)\n", result->report.order_reason.c_str());
    if (args.has("--similar")) {
      const NormalizedProblem problem = normalizeProblem(settings);
      std::fprintf(stderr, "  similar     scaled from a solve of %s (x %.9g m, its lowest %d modes)%s%s\n",
                   problem.settings.mesh_spec.c_str(), problem.scale, problem.settings.max_modes,
                   similar_source.cache_entry.empty() ? ""
                   : similar_source.from_cache        ? ", from the cache "
                                                      : ", cached as ",
                   similar_source.cache_entry.c_str());
    }
  }
  return 0;
}

}  // namespace strike::cli
