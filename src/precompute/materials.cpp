// SPDX-License-Identifier: MIT
#include "strike/precompute/materials.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "strike/core/format.hpp"

namespace strike {

extern const char* const kBuiltinMaterialsJson;  // generated from assets/materials.json

namespace {
std::string lowerCase(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}
}  // namespace

void rayleighFromLossFactor(double loss_factor, double f_low_hz, double f_high_hz, double& rayleigh_stiffness,
                            double& rayleigh_mass) {
  const double w1 = 2.0 * M_PI * f_low_hz, w2 = 2.0 * M_PI * f_high_hz;
  // Damping ratio xi = eta / 2 at both frequencies (the usual two-point Rayleigh fit).
  rayleigh_stiffness = loss_factor / (w1 + w2);
  rayleigh_mass = loss_factor * w1 * w2 / (w1 + w2);
}

Status validateMaterial(const Material& m, const std::string& where) {
  auto bad = [&](const char* field, double value, const char* expected) {
    return badInput(where + ": " + field + " = " + formatNumber(value, 6) + " (" + expected + ")");
  };
  if (!std::isfinite(m.youngs_pa) || m.youngs_pa <= 0) return bad("youngs_pa", m.youngs_pa, "must be > 0");
  if (!std::isfinite(m.poisson) || m.poisson <= -1.0 || m.poisson >= 0.5)
    return bad("poisson", m.poisson, "must be in (-1, 0.5)");
  if (!std::isfinite(m.density_kg_m3) || m.density_kg_m3 <= 0)
    return bad("density_kg_m3", m.density_kg_m3, "must be > 0");
  if (!std::isfinite(m.rayleigh_stiffness) || m.rayleigh_stiffness < 0)
    return bad("rayleigh_stiffness", m.rayleigh_stiffness, "must be >= 0");
  if (!std::isfinite(m.rayleigh_mass) || m.rayleigh_mass < 0)
    return bad("rayleigh_mass", m.rayleigh_mass, "must be >= 0");
  return {};
}

Result<Material> MaterialTable::find(const std::string& name) const {
  auto it = materials.find(lowerCase(name));
  if (it != materials.end()) return it->second;
  std::string known;
  for (const std::string& n : names()) known += (known.empty() ? "" : ", ") + n;
  return badInput("unknown material '" + name + "'; known materials: " + known);
}

ContactProperties MaterialTable::contactProperties(const std::string& name) const {
  auto it = contact.find(lowerCase(name));
  return it == contact.end() ? ContactProperties{} : it->second;
}

std::vector<std::string> MaterialTable::names() const {
  std::vector<std::string> out;
  for (const auto& entry : materials) out.push_back(entry.first);
  return out;
}

Result<MaterialTable> parseMaterialTable(const std::string& json_text, const std::string& source) {
  using nlohmann::json;
  json doc = json::parse(json_text, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) return badInput(source + ": error: not valid JSON");
  MaterialTable table;
  if (doc.contains("rayleigh_fit_band_hz")) {
    const json& band = doc["rayleigh_fit_band_hz"];
    if (!band.is_array() || band.size() != 2 || !band[0].is_number() || !band[1].is_number() ||
        !(band[0].get<double>() > 0) || !(band[1].get<double>() > band[0].get<double>()))
      return badInput(source + ": error: rayleigh_fit_band_hz must be [low, high] with 0 < low < high");
    table.fit_band_low_hz = band[0].get<double>();
    table.fit_band_high_hz = band[1].get<double>();
  }
  if (!doc.contains("materials") || !doc["materials"].is_object())
    return badInput(source + ": error: missing the 'materials' object");
  for (const auto& item : doc["materials"].items()) {
    // Not a structured binding: C++17 lambdas may not capture those (clang refuses; see `number`).
    const std::string& name = item.key();
    const auto& entry = item.value();
    const std::string where = source + ": materials." + name;
    if (!entry.is_object()) return badInput(where + ": expected an object");
    Material m;
    m.name = lowerCase(name);
    auto number = [&](const char* key, double& out) -> bool {
      if (!entry.contains(key)) return false;
      if (!entry[key].is_number()) return false;
      out = entry[key].get<double>();
      return true;
    };
    if (!number("youngs_pa", m.youngs_pa) || !number("poisson", m.poisson) || !number("density_kg_m3", m.density_kg_m3))
      return badInput(where + ": needs numbers youngs_pa, poisson and density_kg_m3");
    double loss_factor = 0.0;
    if (number("loss_factor", loss_factor)) {
      if (!(loss_factor >= 0.0) || !std::isfinite(loss_factor))
        return badInput(where + ".loss_factor = " + formatNumber(loss_factor, 6) + " (must be >= 0)");
      rayleighFromLossFactor(loss_factor, table.fit_band_low_hz, table.fit_band_high_hz, m.rayleigh_stiffness,
                             m.rayleigh_mass);
    } else if (!number("rayleigh_stiffness", m.rayleigh_stiffness) || !number("rayleigh_mass", m.rayleigh_mass)) {
      return badInput(where + ": needs loss_factor, or rayleigh_stiffness and rayleigh_mass");
    }
    for (const auto& field : entry.items()) {
      const std::string& key = field.key();
      static const char* const kKnown[] = {"youngs_pa",
                                           "poisson",
                                           "density_kg_m3",
                                           "loss_factor",
                                           "rayleigh_stiffness",
                                           "rayleigh_mass",
                                           "source",
                                           "restitution",
                                           "friction",
                                           "rolling_resistance",
                                           "roughness_rms_m",
                                           "roughness_correlation_m"};
      if (std::find_if(std::begin(kKnown), std::end(kKnown), [&](const char* k) { return key == k; }) ==
          std::end(kKnown))
        return badInput(where + ": unknown key '" + key + "'");
    }
    Status valid = validateMaterial(m, where);
    if (!valid) return valid.error();
    ContactProperties contact;
    if (entry.contains("restitution") &&
        (!number("restitution", contact.restitution) || !(contact.restitution >= 0 && contact.restitution <= 1)))
      return badInput(where + ".restitution must be a number in [0, 1]");
    if (entry.contains("friction") && (!number("friction", contact.friction) || !(contact.friction >= 0)))
      return badInput(where + ".friction must be a number >= 0");
    if (entry.contains("rolling_resistance") &&
        (!number("rolling_resistance", contact.rolling_resistance) || !(contact.rolling_resistance >= 0) ||
         !std::isfinite(contact.rolling_resistance)))
      return badInput(where + ".rolling_resistance must be a number >= 0");
    for (auto [key, out] : {std::pair<const char*, double*>{"roughness_rms_m", &contact.roughness_rms_m},
                            {"roughness_correlation_m", &contact.roughness_correlation_m}})
      if (entry.contains(key) && (!number(key, *out) || !(*out >= 0) || !std::isfinite(*out)))
        return badInput(where + "." + key + " must be a number >= 0");
    if (contact.roughness_rms_m > 0.0 && !(contact.roughness_correlation_m > 0.0))
      return badInput(where + ".roughness_correlation_m must be > 0 when roughness_rms_m is");
    table.contact[m.name] = contact;
    if (entry.contains("source") && entry["source"].is_string())
      table.sources[m.name] = entry["source"].get<std::string>();
    table.materials[m.name] = m;
  }
  if (table.materials.empty()) return badInput(source + ": error: no materials");
  return table;
}

const MaterialTable& builtinMaterials() {
  // Parsed once; the embedded table is checked by the tests, so failure here is a build bug.
  static const MaterialTable table = [] {
    Result<MaterialTable> parsed = parseMaterialTable(kBuiltinMaterialsJson, "assets/materials.json");
    return parsed ? parsed.value() : MaterialTable{};
  }();
  return table;
}

}  // namespace strike
