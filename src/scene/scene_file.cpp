// SPDX-License-Identifier: MIT
// Strict scene parsing: every key is known, every value checked, every error names the key
// path ("objects[2].velocity[1]") and the value. The JSON and its typed values are read by
// scene_json.cpp, materials, contacts and paths by scene_values.cpp, objects by
// scene_object.cpp (all declared in scene_json.hpp); this file reads the sections in the
// documented order.
#include <cmath>
#include <set>

#include "scene_json.hpp"
#include "strike/core/atomic_file.hpp"
#include "strike/core/air.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/scene/scene.hpp"
#include "strike/synth/spatializer.hpp"

namespace strike {
namespace {

using detail::checkKeys;
using detail::contactCoefficients;
using detail::json;
using detail::keysOf;
using detail::number;
using detail::show;
using detail::unitQuaternion;
using detail::vector;
using detail::Where;

constexpr uint64_t kMaxSceneBytes = 64ull << 20;
constexpr size_t kMaxObjects = 10000;

/// sample_rate, duration, gravity, max_freq and contact_damping.
Status readRenderSettings(const json& doc, const Where& root, Scene& scene) {
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
  return {};
}

/// "air": true/false, or the air's temperature, humidity and pressure (absorption on).
Status readAir(const json& doc, const Where& root, Scene& scene) {
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
  return {};
}

Status readMaxModes(const json& doc, const Where& root, Scene& scene) {
  if (doc.contains("max_modes")) {
    if (!doc["max_modes"].is_number_integer() || doc["max_modes"].get<long long>() < 1 ||
        doc["max_modes"].get<long long>() > 100000)
      return root.at("max_modes").error("expected a whole number 1 to 100000, got " + show(doc["max_modes"]));
    scene.max_modes = doc["max_modes"].get<int>();
  }
  return {};
}

/// The listener's position, and its orientation or the point it looks at.
Status readListener(const json& doc, const Where& root, Scene& scene) {
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
  return {};
}

/// The ground (concrete at z = 0 unless said otherwise), or none.
Status readGround(const json& doc, const Where& root, Scene& scene) {
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
        Result<Material> m = detail::material(ground["material"], where.at("material"));
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
  return {};
}

/// The objects, each with a name of its own ("object<i>" when it has none).
Status readObjects(const json& doc, const Where& root, const std::string& path, Scene& scene) {
  if (!doc.contains("objects")) return root.at("objects").error("missing: a scene needs a list of objects");
  const json& objects = doc["objects"];
  if (!objects.is_array()) return root.at("objects").error("expected a list, got " + show(objects));
  if (objects.empty()) return root.at("objects").error("the list is empty: nothing to hear");
  if (objects.size() > kMaxObjects)
    return root.at("objects").error(std::to_string(objects.size()) + " objects, more than the limit of " +
                                    std::to_string(kMaxObjects));
  std::set<std::string> names;
  for (size_t i = 0; i < objects.size(); ++i) {
    Result<SceneObject> o = detail::object(objects[i], root.at("objects").index(i), path);
    if (!o) return o.error();
    if (o->name.empty()) o->name = "object" + std::to_string(i);
    if (!names.insert(o->name).second)
      return root.at("objects").index(i).at("name").error("duplicate name \"" + o->name + "\"");
    scene.objects.push_back(std::move(*o));
  }
  return {};
}

/// The "contacts" pairs, by the objects' names (or "ground").
Status readContacts(const json& doc, const Where& root, Scene& scene) {
  std::set<std::string> names;
  for (const SceneObject& o : scene.objects) names.insert(o.name);
  if (doc.contains("contacts")) {
    const json& contacts = doc["contacts"];
    if (!contacts.is_array()) return root.at("contacts").error("expected a list, got " + show(contacts));
    for (size_t i = 0; i < contacts.size(); ++i) {
      Result<ContactPairSpec> pair = detail::contactPair(contacts[i], root.at("contacts").index(i), names);
      if (!pair) return pair.error();
      scene.contact_pairs.push_back(*pair);
    }
  }
  return {};
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
  Result<json> doc = detail::readJson(json_text, path);
  if (!doc) return doc.error();
  const Where root{path, ""};
  Scene scene;
  scene.path = path;
  Status ok = checkKeys(*doc, Where{path, "(top level)"}, keysOf("top level"));
  if (ok) ok = readRenderSettings(*doc, root, scene);
  if (ok) ok = readAir(*doc, root, scene);
  if (ok) ok = readMaxModes(*doc, root, scene);
  if (ok) ok = readListener(*doc, root, scene);
  if (ok) ok = readGround(*doc, root, scene);
  if (ok) ok = readObjects(*doc, root, path, scene);
  if (ok) ok = readContacts(*doc, root, scene);
  if (!ok) return ok.error();
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
