// SPDX-License-Identifier: MIT
// The scene's parts (target strike_scene_file): a material (a name or its constants), the contact
// coefficients of an object, the ground or a pair, one "contacts" pair, and an object's path.
#include <cmath>

#include "scene_json.hpp"

namespace strike::detail {

/// "steel", or {"youngs_pa":..., "poisson":..., "density_kg_m3":..., "loss_factor" | "rayleigh_*"}.
Result<Material> material(const json& value, const Where& where) {
  if (value.is_string()) {
    Result<Material> m = builtinMaterials().find(value.get<std::string>());
    if (!m) return where.error(m.error().message);
    return m;
  }
  Status keys = checkKeys(value, where, keysOf("material"));
  if (!keys) return keys.error();
  Material m;
  m.name = value.contains("name") && value["name"].is_string() ? value["name"].get<std::string>() : "custom";
  for (const char* key : {"youngs_pa", "poisson", "density_kg_m3"})
    if (!value.contains(key))
      return where.at(key).error("missing (a material needs youngs_pa, poisson, density_kg_m3)");
  struct Field {
    const char* key;
    double* out;
  } fields[] = {{"youngs_pa", &m.youngs_pa},
                {"poisson", &m.poisson},
                {"density_kg_m3", &m.density_kg_m3},
                {"rayleigh_stiffness", &m.rayleigh_stiffness},
                {"rayleigh_mass", &m.rayleigh_mass}};
  for (const Field& f : fields) {
    if (!value.contains(f.key)) continue;
    Result<double> x = number(value[f.key], where.at(f.key));
    if (!x) return x.error();
    *f.out = *x;
  }
  if (value.contains("loss_factor")) {
    Result<double> eta = number(value["loss_factor"], where.at("loss_factor"));
    if (!eta) return eta.error();
    if (*eta < 0) return where.at("loss_factor").error("must be >= 0, got " + show(value["loss_factor"]));
    const MaterialTable& table = builtinMaterials();
    rayleighFromLossFactor(*eta, table.fit_band_low_hz, table.fit_band_high_hz, m.rayleigh_stiffness, m.rayleigh_mass);
  }
  Status valid = validateMaterial(m, where.file + ": error: " + where.key);
  if (!valid) return valid.error();
  return m;
}

/// Optional "restitution" (0 to 1), "friction" (>= 0) and "rolling_resistance" (>= 0) of an
/// object, the ground or a pair.
Status contactCoefficients(const json& value, const Where& where, double& restitution, double& friction,
                           double& rolling_resistance) {
  if (value.contains("restitution")) {
    Result<double> e = number(value["restitution"], where.at("restitution"));
    if (!e) return e.error();
    if (*e < 0 || *e > 1) return where.at("restitution").error("must be 0 to 1, got " + show(value["restitution"]));
    restitution = *e;
  }
  if (value.contains("friction")) {
    Result<double> mu = number(value["friction"], where.at("friction"));
    if (!mu) return mu.error();
    if (*mu < 0) return where.at("friction").error("must be >= 0, got " + show(value["friction"]));
    friction = *mu;
  }
  if (value.contains("rolling_resistance")) {
    Result<double> c = number(value["rolling_resistance"], where.at("rolling_resistance"));
    if (!c) return c.error();
    if (*c < 0) return where.at("rolling_resistance").error("must be >= 0, got " + show(value["rolling_resistance"]));
    rolling_resistance = *c;
  }
  return {};
}

/// One "contacts" entry: {"objects": [A, B], "restitution": e, "friction": mu}.
Result<ContactPairSpec> contactPair(const json& value, const Where& where, const std::set<std::string>& names) {
  Status keys = checkKeys(value, where, keysOf("contacts[]"));
  if (!keys) return keys.error();
  ContactPairSpec pair;
  if (!value.contains("objects") || !value["objects"].is_array() || value["objects"].size() != 2 ||
      !value["objects"][0].is_string() || !value["objects"][1].is_string())
    return where.at("objects").error("expected two object names (or \"ground\"), got " +
                                     (value.contains("objects") ? show(value["objects"]) : std::string("nothing")));
  for (size_t k = 0; k < 2; ++k) {
    const std::string name = value["objects"][k].get<std::string>();
    if (name != "ground" && names.count(name) == 0)
      return where.at("objects").index(k).error("no object named \"" + name + "\"");
    (k == 0 ? pair.object_a : pair.object_b) = name;
  }
  if (pair.object_a == pair.object_b)
    return where.at("objects").error("names one object twice: " + show(value["objects"]));
  if (!value.contains("restitution") && !value.contains("friction") && !value.contains("rolling_resistance"))
    return where.error("needs \"restitution\", \"friction\" or \"rolling_resistance\" (or several)");
  Status coefficients = contactCoefficients(value, where, pair.restitution, pair.friction, pair.rolling_resistance);
  if (!coefficients) return coefficients.error();
  return pair;
}

/// "path": [{"t": s, "position": [x, y, z], "orientation": [w, x, y, z]}, ...], at least one key,
/// in strictly increasing time from t >= 0; a key without "orientation" keeps the one before
/// (the first: [1, 0, 0, 0]).
Result<std::vector<PathKey>> pathKeys(const json& value, const Where& where) {
  if (!value.is_array() || value.empty())
    return where.error("expected a list of keyframes like {\"t\": 0, \"position\": [0, 0, 0.1]}, got " + show(value));
  std::vector<PathKey> keys;
  for (size_t k = 0; k < value.size(); ++k) {
    const json& item = value[k];
    const Where at = where.index(k);
    Status known = checkKeys(item, at, keysOf("path[]"));
    if (!known) return known.error();
    for (const char* key : {"t", "position"})
      if (!item.contains(key)) return at.at(key).error("missing (a keyframe needs \"t\" and \"position\")");
    PathKey pathKey;
    Result<double> t = number(item["t"], at.at("t"));
    if (!t) return t.error();
    if (*t < 0) return at.at("t").error("must be >= 0 s, got " + show(item["t"]));
    if (!keys.empty() && !(*t > keys.back().t_s))
      return at.at("t").error("must be later than the key before (" + show(value[k - 1]["t"]) + "), got " +
                              show(item["t"]));
    pathKey.t_s = *t;
    Result<std::array<double, 3>> p = vector<3>(item["position"], at.at("position"));
    if (!p) return p.error();
    pathKey.position_m = *p;
    if (!keys.empty()) pathKey.orientation_wxyz = keys.back().orientation_wxyz;
    if (item.contains("orientation")) {
      Result<std::array<double, 4>> q = unitQuaternion(item["orientation"], at.at("orientation"));
      if (!q) return q.error();
      pathKey.orientation_wxyz = *q;
    }
    keys.push_back(pathKey);
  }
  return keys;
}
}  // namespace strike::detail
