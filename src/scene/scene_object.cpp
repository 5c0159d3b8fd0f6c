// SPDX-License-Identifier: MIT
// One "objects" entry of a scene (target strike_scene_file): its mesh or bank (paths relative to
// the scene's folder), material, units, order, size, collision shape, initial state or path,
// contact coefficients and surface roughness, each checked with its key path in the message.
#include <filesystem>

#include "scene_json.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike::detail {
namespace {

std::string resolvePath(const std::string& scene_path, const std::string& relative) {
  namespace fs = std::filesystem;
  if (relative.empty() || fs::path(relative).is_absolute()) return relative;
  return (fs::path(scene_path).parent_path() / relative).lexically_normal().string();
}
}  // namespace

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
}  // namespace strike::detail
