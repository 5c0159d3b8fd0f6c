// SPDX-License-Identifier: MIT
// Private to strike_scene_file: reading the scene's JSON strictly. The text into a json value
// (scene_json.cpp: nesting, syntax and number errors with line and column), typed values with the
// key path in every message (Where, number, vector, unitQuaternion, text, checkKeys), and the
// readers of the scene's parts: materials, contact coefficients, contact pairs and paths
// (scene_values.cpp) and objects (scene_object.cpp). parseScene (scene_file.cpp) reads the
// sections in the documented order with them.
#pragma once

#include <array>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "strike/precompute/materials.hpp"
#include "strike/core/result.hpp"
#include "strike/scene/scene.hpp"

namespace strike::detail {

using nlohmann::json;

/// Context for messages: the file and the key path.
struct Where {
  const std::string& file;
  std::string key;
  Where at(const std::string& child) const { return Where{file, key.empty() ? child : key + "." + child}; }
  Where index(size_t i) const { return Where{file, key + "[" + std::to_string(i) + "]"}; }
  Error error(const std::string& what) const { return badInput(file + ": error: " + key + ": " + what); }
};
/// A value for a message, cut at 60 characters.
std::string show(const json& value);

/// The scene's text as JSON, or an error naming the line and column (nesting deeper than 64
/// levels is refused before the recursive parser sees it).
Result<json> readJson(const std::string& json_text, const std::string& path);

/// The known keys of a part of the scene (sceneKeyTables), by its name ("objects[]").
const std::vector<const char*>& keysOf(const char* where);
/// An object whose keys are all known; the message lists the known keys.
Status checkKeys(const json& object, const Where& where, const std::vector<const char*>& known);
/// A finite number.
Result<double> number(const json& value, const Where& where);
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
Result<std::array<double, 4>> unitQuaternion(const json& value, const Where& where);
/// A string.
Result<std::string> text(const json& value, const Where& where);

/// "steel", or {"youngs_pa":..., "poisson":..., "density_kg_m3":..., "loss_factor" | "rayleigh_*"}.
Result<Material> material(const json& value, const Where& where);
/// Optional "restitution" (0 to 1), "friction" (>= 0) and "rolling_resistance" (>= 0) of an
/// object, the ground or a pair.
Status contactCoefficients(const json& value, const Where& where, double& restitution, double& friction,
                           double& rolling_resistance);
/// One "contacts" entry: {"objects": [A, B], "restitution": e, "friction": mu}.
Result<ContactPairSpec> contactPair(const json& value, const Where& where, const std::set<std::string>& names);
/// "path": [{"t": s, "position": [x, y, z], "orientation": [w, x, y, z]}, ...], at least one key,
/// in strictly increasing time from t >= 0; a key without "orientation" keeps the one before
/// (the first: [1, 0, 0, 0]).
Result<std::vector<PathKey>> pathKeys(const json& value, const Where& where);
/// One "objects" entry; relative mesh and bank paths are resolved against the scene's folder.
Result<SceneObject> object(const json& value, const Where& where, const std::string& scene_path);

}  // namespace strike::detail
