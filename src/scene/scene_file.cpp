// SPDX-License-Identifier: MIT
// Strict scene parsing: every key is known, every value checked, every error names the key
// path ("objects[2].velocity[1]") and the value.
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>

#include "strike/atomic_file.hpp"
#include "strike/listener.hpp"
#include "strike/materials.hpp"
#include "strike/mesh.hpp"
#include "strike/scene.hpp"
#include "strike/spatializer.hpp"

namespace strike {
namespace {

using nlohmann::json;

constexpr int kMaxNestingDepth = 64;  // a scene is shallow; deeper input is hostile
constexpr uint64_t kMaxSceneBytes = 64ull << 20;
constexpr size_t kMaxObjects = 10000;

/// Context for messages: the file and the key path.
struct Where {
  const std::string& file;
  std::string key;
  Where at(const std::string& child) const { return Where{file, key.empty() ? child : key + "." + child}; }
  Where index(size_t i) const { return Where{file, key + "[" + std::to_string(i) + "]"}; }
  Error error(const std::string& what) const { return badInput(file + ": error: " + key + ": " + what); }
};

std::string show(const json& value) {
  std::string text = value.dump();
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}

/// Line and column of a byte offset, for JSON syntax errors.
std::string lineColumn(const std::string& text, size_t offset) {
  size_t line = 1, column = 1;
  for (size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n')
      ++line, column = 1;
    else
      ++column;
  }
  return std::to_string(line) + ":" + std::to_string(column);
}

/// Rejects nesting deeper than kMaxNestingDepth before the recursive parser sees it.
std::optional<size_t> tooDeepAt(const std::string& text) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      if (++depth > kMaxNestingDepth) return i;
    } else if (c == '}' || c == ']') {
      --depth;
    }
  }
  return std::nullopt;
}

const std::vector<const char*>& keysOf(const char* where) {
  for (const SceneKeyTable& table : sceneKeyTables())
    if (std::string(table.where) == where) return table.keys;
  static const std::vector<const char*> none;
  return none;
}

Status checkKeys(const json& object, const Where& where, const std::vector<const char*>& known) {
  if (!object.is_object()) return where.error("expected an object, got " + show(object));
  for (const auto& item : object.items()) {
    bool found = false;
    for (const char* k : known) found = found || item.key() == k;
    if (!found) {
      std::string list;
      for (const char* k : known) list += std::string(list.empty() ? "" : ", ") + k;
      return where.at(item.key()).error("unknown key (known keys here: " + list + ")");
    }
  }
  return {};
}

Result<double> number(const json& value, const Where& where) {
  if (!value.is_number()) return where.error("expected a number, got " + show(value));
  const double x = value.get<double>();
  if (!std::isfinite(x)) return where.error("expected a finite number, got " + show(value));
  return x;
}

template <size_t N>
Result<std::array<double, N>> vector(const json& value, const Where& where) {
  if (!value.is_array() || value.size() != N)
    return where.error("expected an array of " + std::to_string(N) + " numbers, got " + show(value));
  std::array<double, N> out{};
  for (size_t i = 0; i < N; ++i) {
    Result<double> x = number(value[i], where.index(i));
    if (!x) return x.error();
    out[i] = *x;
  }
  return out;
}

/// [w, x, y, z] within 0.001 of unit length, normalized.
Result<std::array<double, 4>> unitQuaternion(const json& value, const Where& where) {
  Result<std::array<double, 4>> q = vector<4>(value, where);
  if (!q) return q.error();
  const double norm = std::sqrt((*q)[0] * (*q)[0] + (*q)[1] * (*q)[1] + (*q)[2] * (*q)[2] + (*q)[3] * (*q)[3]);
  if (std::fabs(norm - 1.0) > 1e-3)
    return where.error("expected a unit quaternion [w, x, y, z], got " + show(value) + " (norm " +
                       std::to_string(norm) + ")");
  std::array<double, 4> unit{};
  for (int i = 0; i < 4; ++i) unit[i] = (*q)[i] / norm;
  return unit;
}

Result<std::string> text(const json& value, const Where& where) {
  if (!value.is_string()) return where.error("expected a string, got " + show(value));
  return value.get<std::string>();
}

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

std::string resolvePath(const std::string& scene_path, const std::string& relative) {
  namespace fs = std::filesystem;
  if (relative.empty() || fs::path(relative).is_absolute()) return relative;
  return (fs::path(scene_path).parent_path() / relative).lexically_normal().string();
}

Result<SceneObject> object(const json& value, const Where& where, const std::string& scene_path) {
  Status keys = checkKeys(value, where, keysOf("objects[]"));
  if (!keys) return keys.error();
  SceneObject o;
  if (value.contains("name")) {
    Result<std::string> name = text(value["name"], where.at("name"));
    if (!name) return name.error();
    o.name = *name;
  }
  if (!value.contains("mesh") && !value.contains("bank"))
    return where.error("needs \"mesh\" (a file or primitive like \"box:0.3,0.02,0.02\") or \"bank\"");
  if (value.contains("mesh")) {
    Result<std::string> mesh = text(value["mesh"], where.at("mesh"));
    if (!mesh) return mesh.error();
    o.mesh = isPrimitiveSpec(*mesh) ? *mesh : resolvePath(scene_path, *mesh);
    if (!isPrimitiveSpec(*mesh) && !std::filesystem::is_regular_file(o.mesh))
      return where.at("mesh").error("file not found: " + o.mesh);
  }
  if (value.contains("bank")) {
    Result<std::string> bank = text(value["bank"], where.at("bank"));
    if (!bank) return bank.error();
    o.bank = resolvePath(scene_path, *bank);
    if (!std::filesystem::is_regular_file(o.bank)) return where.at("bank").error("file not found: " + o.bank);
  }
  if (value.contains("material")) {
    Result<Material> m = material(value["material"], where.at("material"));
    if (!m) return m.error();
    o.material = *m;
  } else if (o.bank.empty()) {
    return where.error(
        "needs \"material\" (a name like \"steel\" or an object with youngs_pa, poisson, density_kg_m3)");
  }
  if (value.contains("units")) {
    // A mesh exported in millimetres read as metres is 1000x too large (a 264,000-tonne
    // mug); the file's unit is declared here instead of rescaling the file.
    Result<std::string> units = text(value["units"], where.at("units"));
    if (!units) return units.error();
    if (*units == "m")
      o.mesh_scale = 1.0;
    else if (*units == "cm")
      o.mesh_scale = 0.01;
    else if (*units == "mm")
      o.mesh_scale = 0.001;
    else
      return where.at("units").error("expected \"m\", \"cm\" or \"mm\", got " + show(value["units"]));
    if (!value.contains("mesh") || isPrimitiveSpec(value["mesh"].get<std::string>()))
      return where.at("units").error("applies to a mesh file only (primitives and banks are in metres), got " +
                                     show(value["units"]));
    o.units = *units;
  }
  if (value.contains("order")) {
    if (!value["order"].is_number_integer() || (value["order"] != 1 && value["order"] != 2))
      return where.at("order").error("expected 1 or 2, got " + show(value["order"]));
    o.order = value["order"].get<int>();
  }
  if (value.contains("size")) {
    Result<double> size = number(value["size"], where.at("size"));
    if (!size) return size.error();
    if (*size <= 0) return where.at("size").error("must be > 0 metres, got " + show(value["size"]));
    o.size_m = *size;
  }
  if (value.contains("static")) {
    if (!value["static"].is_boolean())
      return where.at("static").error("expected true or false, got " + show(value["static"]));
    o.is_static = value["static"].get<bool>();
  }
  if (value.contains("shape")) {
    Result<std::string> shape = text(value["shape"], where.at("shape"));
    if (!shape) return shape.error();
    if (*shape != "auto" && *shape != "convex" && *shape != "concave" && *shape != "pieces")
      return where.at("shape").error("expected \"auto\", \"convex\", \"pieces\" or \"concave\", got " +
                                     show(value["shape"]));
    o.shape = *shape;
  }
  struct Vec3Field {
    const char* key;
    std::array<double, 3>* out;
  } vectors[] = {
      {"position", &o.position_m}, {"velocity", &o.velocity_m_s}, {"angular_velocity", &o.angular_velocity_rad_s}};
  for (const Vec3Field& f : vectors) {
    if (!value.contains(f.key)) continue;
    Result<std::array<double, 3>> v = vector<3>(value[f.key], where.at(f.key));
    if (!v) return v.error();
    *f.out = *v;
  }
  if (value.contains("orientation")) {
    Result<std::array<double, 4>> q = unitQuaternion(value["orientation"], where.at("orientation"));
    if (!q) return q.error();
    o.orientation_wxyz = *q;
  }
  if (value.contains("path")) {
    Result<std::vector<PathKey>> path_keys = pathKeys(value["path"], where.at("path"));
    if (!path_keys) return path_keys.error();
    if (o.is_static) return where.at("path").error("a static object never moves: remove \"static\" or the path");
    for (const char* key : {"position", "orientation", "velocity", "angular_velocity"})
      if (value.contains(key))
        return where.at(key).error("not used with \"path\", got " + show(value[key]) +
                                   ": the path's first key is where the object starts, and it moves as the path says");
    o.path = std::move(*path_keys);
  }
  Status coefficients = contactCoefficients(value, where, o.restitution, o.friction, o.rolling_resistance);
  if (!coefficients) return coefficients.error();
  for (auto [key, out] : {std::pair<const char*, double*>{"roughness_rms_m", &o.roughness_rms_m},
                          {"roughness_correlation_m", &o.roughness_correlation_m}}) {
    if (!value.contains(key)) continue;
    Result<double> r = number(value[key], where.at(key));
    if (!r) return r.error();
    if (*r < 0) return where.at(key).error("must be >= 0 metres, got " + show(value[key]));
    *out = *r;
  }
  if (o.roughness_correlation_m == 0.0 && !(o.roughness_rms_m == 0.0))
    return where.at("roughness_correlation_m").error("must be > 0 metres, got 0");
  return o;
}

}  // namespace

const std::vector<SceneKeyTable>& sceneKeyTables() {
  static const std::vector<SceneKeyTable> tables = {
      {"top level",
       {"sample_rate", "duration", "gravity", "listener", "ground", "objects", "max_freq", "max_modes",
        "contact_damping", "contacts", "air"}},
      {"air", {"temperature", "humidity", "pressure"}},
      {"listener", {"position", "orientation", "look_at"}},
      {"contacts[]", {"objects", "restitution", "friction", "rolling_resistance"}},
      {"ground", {"material", "height", "restitution", "friction", "rolling_resistance", "reflection"}},
      {"objects[]",
       {"name", "mesh", "units", "bank", "material", "order", "size", "static", "shape", "position", "orientation",
        "velocity", "angular_velocity", "restitution", "friction", "rolling_resistance", "roughness_rms_m",
        "roughness_correlation_m", "path"}},
      {"path[]", {"t", "position", "orientation"}},
      {"material",
       {"name", "youngs_pa", "poisson", "density_kg_m3", "loss_factor", "rayleigh_stiffness", "rayleigh_mass"}},
  };
  return tables;
}

Result<Scene> parseScene(const std::string& json_text, const std::string& path) {
  if (std::optional<size_t> at = tooDeepAt(json_text))
    return badInput(path + ":" + lineColumn(json_text, *at) + ": error: JSON nested deeper than " +
                    std::to_string(kMaxNestingDepth) + " levels");
  json doc = json::parse(json_text, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) {
    // Re-parse with exceptions only to learn where it failed (the message has the byte offset).
    try {
      const json unused = json::parse(json_text);
      (void)unused;
    } catch (const json::parse_error& e) {
      return badInput(path + ":" + lineColumn(json_text, e.byte > 0 ? e.byte - 1 : 0) +
                      ": error: invalid JSON: " + std::string(e.what()).substr(std::string(e.what()).find(':') + 2));
    } catch (const json::exception& e) {  // e.g. a number too large for a double
      // The library does not say where: find the number it names ("... parsing '1e999'") as a
      // value of its own in the text.
      const std::string what = std::string(e.what()).substr(std::string(e.what()).find(']') + 2);
      std::string where;
      const size_t open = what.find('\''), close = what.rfind('\'');
      if (open != std::string::npos && close > open + 1) {
        const std::string number = what.substr(open + 1, close - open - 1);
        auto partOfNumber = [](char c) {
          return std::isdigit(static_cast<unsigned char>(c)) || std::strchr(".eE+-", c);
        };
        for (size_t at = json_text.find(number); at != std::string::npos; at = json_text.find(number, at + 1)) {
          const bool starts = at == 0 || !partOfNumber(json_text[at - 1]) || json_text[at - 1] == '-';
          const size_t end = at + number.size();
          if (starts && (end == json_text.size() || !partOfNumber(json_text[end]))) {
            where = ":" + lineColumn(json_text, at);
            break;
          }
        }
      }
      return badInput(path + where + ": error: invalid JSON: " + what +
                      (what.find("overflow") != std::string::npos ? " (larger than any double, ~1.8e308)" : ""));
    }
    return badInput(path + ": error: invalid JSON");
  }
  const Where root{path, ""};
  Scene scene;
  scene.path = path;
  Status keys = checkKeys(doc, Where{path, "(top level)"}, keysOf("top level"));
  if (!keys) return keys.error();
  if (doc.contains("sample_rate")) {
    Result<double> rate = number(doc["sample_rate"], root.at("sample_rate"));
    if (!rate) return rate.error();
    if (*rate < 8000 || *rate > 384000)
      return root.at("sample_rate").error("must be 8000 to 384000 Hz, got " + show(doc["sample_rate"]));
    scene.sample_rate_hz = *rate;
  }
  if (doc.contains("duration")) {
    Result<double> duration = number(doc["duration"], root.at("duration"));
    if (!duration) return duration.error();
    if (*duration <= 0 || *duration > 3600)
      return root.at("duration").error("must be in (0, 3600] s, got " + show(doc["duration"]));
    scene.duration_s = *duration;
  }
  if (doc.contains("gravity")) {
    Result<std::array<double, 3>> g = vector<3>(doc["gravity"], root.at("gravity"));
    if (!g) return g.error();
    scene.gravity_m_s2 = *g;
  }
  if (doc.contains("max_freq")) {
    Result<double> f = number(doc["max_freq"], root.at("max_freq"));
    if (!f) return f.error();
    if (*f <= 0) return root.at("max_freq").error("must be > 0 Hz, got " + show(doc["max_freq"]));
    scene.max_freq_hz = *f;
  }
  if (doc.contains("contact_damping")) {
    Result<double> c = number(doc["contact_damping"], root.at("contact_damping"));
    if (!c) return c.error();
    if (*c < 0) return root.at("contact_damping").error("must be >= 0 (1/s), got " + show(doc["contact_damping"]));
    scene.contact_damping_per_s = *c;
  }
  if (doc.contains("air")) {
    const json& air = doc["air"];
    const Where where = root.at("air");
    if (air.is_boolean()) {
      scene.air_absorption = air.get<bool>();
    } else {
      Status air_keys = checkKeys(air, where, keysOf("air"));
      if (!air_keys) return air_keys.error();
      scene.air_absorption = true;
      struct Field {
        const char* key;
        double* value;
        double low, high;
        const char* rule;
      };
      const Field fields[] = {
          {"temperature", &scene.air.temperature_c, -50.0, 60.0, "must be -50 to 60 (degrees C)"},
          {"humidity", &scene.air.relative_humidity_percent, 0.0, 100.0, "must be 0 to 100 (% relative humidity)"},
          {"pressure", &scene.air.pressure_kpa, 50.0, 200.0, "must be 50 to 200 (kPa)"},
      };
      for (const Field& f : fields) {
        if (!air.contains(f.key)) continue;
        Result<double> x = number(air[f.key], where.at(f.key));
        if (!x) return x.error();
        if (!(*x >= f.low && *x <= f.high))
          return where.at(f.key).error(std::string(f.rule) + ", got " + show(air[f.key]));
        *f.value = *x;
      }
    }
  }
  if (doc.contains("max_modes")) {
    if (!doc["max_modes"].is_number_integer() || doc["max_modes"].get<long long>() < 1 ||
        doc["max_modes"].get<long long>() > 100000)
      return root.at("max_modes").error("expected a whole number 1 to 100000, got " + show(doc["max_modes"]));
    scene.max_modes = doc["max_modes"].get<int>();
  }
  if (doc.contains("listener")) {
    const Where where = root.at("listener");
    Status listener_keys = checkKeys(doc["listener"], where, keysOf("listener"));
    if (!listener_keys) return listener_keys.error();
    if (doc["listener"].contains("position")) {
      Result<std::array<double, 3>> p = vector<3>(doc["listener"]["position"], where.at("position"));
      if (!p) return p.error();
      scene.listener_position_m = *p;
    }
    if (doc["listener"].contains("orientation") && doc["listener"].contains("look_at"))
      return where.at("look_at").error("give either orientation or look_at, not both");
    if (doc["listener"].contains("orientation")) {
      Result<std::array<double, 4>> q = unitQuaternion(doc["listener"]["orientation"], where.at("orientation"));
      if (!q) return q.error();
      scene.listener_orientation_wxyz = *q;
    }
    if (doc["listener"].contains("look_at")) {
      Result<std::array<double, 3>> target = vector<3>(doc["listener"]["look_at"], where.at("look_at"));
      if (!target) return target.error();
      const std::optional<std::array<double, 4>> q = lookAtOrientation(scene.listener_position_m, *target);
      if (!q)
        return where.at("look_at").error(
            "must be a point beside the listener's position (not on it, nor straight above "
            "or below it), got " +
            show(doc["listener"]["look_at"]));
      scene.listener_orientation_wxyz = *q;
    }
  }
  scene.ground_material = *builtinMaterials().find("concrete");
  if (doc.contains("ground")) {
    const json& ground = doc["ground"];
    const Where where = root.at("ground");
    if (ground.is_null() || (ground.is_boolean() && !ground.get<bool>())) {
      scene.has_ground = false;
    } else {
      Status ground_keys = checkKeys(ground, where, keysOf("ground"));
      if (!ground_keys) return ground_keys.error();
      if (ground.contains("material")) {
        Result<Material> m = material(ground["material"], where.at("material"));
        if (!m) return m.error();
        scene.ground_material = *m;
      }
      if (ground.contains("height")) {
        Result<double> h = number(ground["height"], where.at("height"));
        if (!h) return h.error();
        scene.ground_height_m = *h;
      }
      Status coefficients = contactCoefficients(ground, where, scene.ground_restitution, scene.ground_friction,
                                                scene.ground_rolling_resistance);
      if (!coefficients) return coefficients.error();
      if (ground.contains("reflection")) {
        const json& r = ground["reflection"];
        if (r.is_boolean()) {
          scene.ground_reflects = r.get<bool>();
        } else {
          Result<double> coefficient = number(r, where.at("reflection"));
          if (!coefficient) return coefficient.error();
          if (!(*coefficient >= -1.0 && *coefficient <= 1.0))
            return where.at("reflection")
                .error("a pressure reflection coefficient is between -1 and 1, got " + show(r));
          scene.ground_reflection = *coefficient;
        }
      }
    }
  }
  if (!doc.contains("objects")) return root.at("objects").error("missing: a scene needs a list of objects");
  const json& objects = doc["objects"];
  if (!objects.is_array()) return root.at("objects").error("expected a list, got " + show(objects));
  if (objects.empty()) return root.at("objects").error("the list is empty: nothing to hear");
  if (objects.size() > kMaxObjects)
    return root.at("objects").error(std::to_string(objects.size()) + " objects, more than the limit of " +
                                    std::to_string(kMaxObjects));
  std::set<std::string> names;
  for (size_t i = 0; i < objects.size(); ++i) {
    Result<SceneObject> o = object(objects[i], root.at("objects").index(i), path);
    if (!o) return o.error();
    if (o->name.empty()) o->name = "object" + std::to_string(i);
    if (!names.insert(o->name).second)
      return root.at("objects").index(i).at("name").error("duplicate name \"" + o->name + "\"");
    scene.objects.push_back(std::move(*o));
  }
  if (doc.contains("contacts")) {
    const json& contacts = doc["contacts"];
    if (!contacts.is_array()) return root.at("contacts").error("expected a list, got " + show(contacts));
    for (size_t i = 0; i < contacts.size(); ++i) {
      Result<ContactPairSpec> pair = contactPair(contacts[i], root.at("contacts").index(i), names);
      if (!pair) return pair.error();
      scene.contact_pairs.push_back(*pair);
    }
  }
  return scene;
}

double groundReflectionCoefficient(const Material& m) {
  const double nu = m.poisson, rho = m.density_kg_m3;
  const double p_wave_modulus = m.youngs_pa * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
  if (!(p_wave_modulus > 0.0) || !(rho > 0.0) || !std::isfinite(p_wave_modulus)) return 1.0;
  const double z_solid = std::sqrt(p_wave_modulus * rho);  // rho c_p
  const double z_air = kAirDensity_kg_m3 * kSpeedOfSoundAir_m_s;
  return (z_solid - z_air) / (z_solid + z_air);
}

Result<Scene> loadScene(const std::string& path) {
  Result<std::string> text = readWholeFile(path, kMaxSceneBytes);
  if (!text) return text.error();
  return parseScene(*text, path);
}

}  // namespace strike
