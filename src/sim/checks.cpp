// SPDX-License-Identifier: MIT
// Input checks of simulate(): settings and bodies, each refused with a message naming the body,
// the field and the value.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "simulation.hpp"

namespace strike::detail {

std::string fmt(double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", value);
  return buf;
}

std::string bodyLabel(const SimBodyDesc& body, size_t index) {
  return "body " + std::to_string(index) + " \"" + body.name + "\"";
}

namespace {

template <size_t N>
Status checkFinite(const std::array<double, N>& values, const SimBodyDesc& body, size_t index, const char* field) {
  for (size_t k = 0; k < N; ++k) {
    if (!std::isfinite(values[k])) {
      return badInput(bodyLabel(body, index) + ": " + field + "[" + std::to_string(k) + "] = " + fmt(values[k]) +
                      " (must be finite)");
    }
  }
  return {};
}

/// A driven body's keyframes: finite, in strictly increasing time, unit quaternions.
Status checkPath(const SimBodyDesc& body, const std::string& label) {
  if (body.path.empty()) return {};
  if (body.is_static) return badInput(label + ": a static body cannot follow a path");
  for (size_t k = 0; k < body.path.size(); ++k) {
    const PathKey& key = body.path[k];
    const std::string at = label + ": path[" + std::to_string(k) + "]";
    bool finite = std::isfinite(key.t_s);
    for (double x : key.position_m) finite = finite && std::isfinite(x);
    for (double x : key.orientation_wxyz) finite = finite && std::isfinite(x);
    if (!finite) return badInput(at + ": t_s, position_m and orientation_wxyz must be finite");
    if (k > 0 && !(key.t_s > body.path[k - 1].t_s))
      return badInput(at + ": t_s = " + fmt(key.t_s) + " (must be later than the key before, " +
                      fmt(body.path[k - 1].t_s) + ")");
    const auto& q = key.orientation_wxyz;
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (std::abs(norm - 1.0) > 1e-9)
      return badInput(at + ": orientation_wxyz has norm " + fmt(norm) + " (must be a unit quaternion)");
  }
  return {};
}

}  // namespace

Status checkSettings(const SimSettings& settings) {
  // The contact-event times and the synth's pulse model assume sub-millisecond resolution.
  if (!std::isfinite(settings.substep_s) || settings.substep_s <= 0.0 || settings.substep_s > 1e-3) {
    return badInput("sim settings: substep_s = " + fmt(settings.substep_s) + " (must be in (0, 0.001] s)");
  }
  if (!std::isfinite(settings.duration_s) || settings.duration_s <= 0.0) {
    return badInput("sim settings: duration_s = " + fmt(settings.duration_s) + " (must be > 0)");
  }
  if (settings.duration_s / settings.substep_s > 1e9) {
    return badInput("sim settings: duration_s / substep_s = " + fmt(settings.duration_s / settings.substep_s) +
                    " substeps (at most 1e9)");
  }
  for (size_t k = 0; k < 3; ++k) {
    if (!std::isfinite(settings.gravity_m_s2[k])) {
      return badInput("sim settings: gravity_m_s2[" + std::to_string(k) + "] = " + fmt(settings.gravity_m_s2[k]) +
                      " (must be finite)");
    }
  }
  const std::pair<const char*, double> scalars[] = {
      {"ground_height_m", settings.ground_height_m}, {"ground_restitution", settings.ground_restitution},
      {"ground_friction", settings.ground_friction}, {"ground_rolling_resistance", settings.ground_rolling_resistance},
      {"min_impulse_n_s", settings.min_impulse_n_s}, {"impact_speed_m_s", settings.impact_speed_m_s}};
  for (const auto& [name, value] : scalars) {
    if (!std::isfinite(value) || (value < 0.0 && std::string(name) != "ground_height_m")) {
      return badInput(std::string("sim settings: ") + name + " = " + fmt(value) + " (must be finite and >= 0)");
    }
  }
  if (!(settings.sleep_after_still_s >= 0.0 && settings.sleep_after_still_s <= 2.0)) {
    return badInput("sim settings: sleep_after_still_s = " + fmt(settings.sleep_after_still_s) +
                    " (must be in [0, 2] s)");
  }
  for (size_t k = 0; k < settings.contact_pairs.size(); ++k) {
    const SimSettings::ContactPair& pair = settings.contact_pairs[k];
    const std::string where = "sim settings: contact_pairs[" + std::to_string(k) + "]";
    if (!std::isnan(pair.restitution) && !(pair.restitution >= 0.0 && pair.restitution <= 1.0))
      return badInput(where + ".restitution = " + fmt(pair.restitution) + " (must be in [0, 1])");
    if (!std::isnan(pair.friction) && !(pair.friction >= 0.0 && std::isfinite(pair.friction)))
      return badInput(where + ".friction = " + fmt(pair.friction) + " (must be finite and >= 0)");
    if (!std::isnan(pair.rolling_resistance) &&
        !(pair.rolling_resistance >= 0.0 && std::isfinite(pair.rolling_resistance)))
      return badInput(where + ".rolling_resistance = " + fmt(pair.rolling_resistance) + " (must be finite and >= 0)");
  }
  if (!(settings.ground_compliance_per_pa >= 0.0 && std::isfinite(settings.ground_compliance_per_pa)))
    return badInput("sim settings: ground_compliance_per_pa = " + fmt(settings.ground_compliance_per_pa) +
                    " (must be finite and >= 0)");
  if (settings.solver_iterations < 1 || settings.solver_iterations > 10000) {
    return badInput("sim settings: solver_iterations = " + std::to_string(settings.solver_iterations) +
                    " (must be in [1, 10000])");
  }
  return {};
}

Status checkBody(const SimBodyDesc& body, size_t index, btQuaternion& orientation) {
  const std::string label = bodyLabel(body, index);
  if (body.surface_positions.empty() || body.surface_triangles.empty()) {
    return badInput(label + ": empty geometry (" + std::to_string(body.surface_positions.size() / 3) + " vertices, " +
                    std::to_string(body.surface_triangles.size() / 3) + " triangles)");
  }
  if (body.surface_positions.size() % 3 != 0 || body.surface_triangles.size() % 3 != 0) {
    return badInput(label + ": surface_positions has " + std::to_string(body.surface_positions.size()) +
                    " values and surface_triangles " + std::to_string(body.surface_triangles.size()) +
                    " (both must be multiples of 3)");
  }
  const size_t vertex_count = body.surface_positions.size() / 3;
  if (vertex_count > 0x7fffffffu) return badInput(label + ": too many vertices for Bullet (int indices)");
  for (size_t k = 0; k < body.surface_positions.size(); ++k) {
    if (!std::isfinite(body.surface_positions[k])) {
      return badInput(label + ": surface_positions[" + std::to_string(k) + "] (vertex " + std::to_string(k / 3) +
                      ") = " + fmt(body.surface_positions[k]) + " (must be finite)");
    }
  }
  for (size_t k = 0; k < body.surface_triangles.size(); ++k) {
    if (body.surface_triangles[k] >= vertex_count) {
      return badInput(label + ": triangle " + std::to_string(k / 3) + " references vertex " +
                      std::to_string(body.surface_triangles[k]) + ", mesh has " + std::to_string(vertex_count) +
                      " vertices");
    }
  }
  if (Status s = checkFinite(body.position_m, body, index, "position_m"); !s) return s;
  if (Status s = checkFinite(body.orientation_wxyz, body, index, "orientation_wxyz"); !s) return s;
  if (Status s = checkFinite(body.velocity_m_s, body, index, "velocity_m_s"); !s) return s;
  if (Status s = checkFinite(body.angular_velocity_rad_s, body, index, "angular_velocity_rad_s"); !s) return s;
  const auto& q = body.orientation_wxyz;
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  // Rounded quaternions from a scene file are accepted; anything further off is a mistake.
  if (std::abs(norm - 1.0) > 1e-3) {
    return badInput(label + ": orientation_wxyz = [" + fmt(q[0]) + ", " + fmt(q[1]) + ", " + fmt(q[2]) + ", " +
                    fmt(q[3]) + "] has norm " + fmt(norm) + " (must be a unit quaternion within 1e-3)");
  }
  orientation = btQuaternion(q[1] / norm, q[2] / norm, q[3] / norm, q[0] / norm);  // Bullet is (x, y, z, w)
  for (const auto& [name, value] : {std::pair<const char*, double>{"restitution", body.restitution},
                                    std::pair<const char*, double>{"friction", body.friction},
                                    std::pair<const char*, double>{"rolling_resistance", body.rolling_resistance},
                                    std::pair<const char*, double>{"contact_radius_m", body.contact_radius_m},
                                    std::pair<const char*, double>{"compliance_per_pa", body.compliance_per_pa}}) {
    if (!std::isfinite(value) || value < 0.0) {
      return badInput(label + ": " + name + " = " + fmt(value) + " (must be finite and >= 0)");
    }
  }
  if (Status s = checkPath(body, label); !s) return s;
  if (body.is_static) return {};
  if (!std::isfinite(body.mass_kg) || body.mass_kg <= 0.0) {
    return badInput(label + ": mass_kg = " + fmt(body.mass_kg) + " (a dynamic body needs a mass > 0)");
  }
  if (Status s = checkFinite(body.centre_m, body, index, "centre_m"); !s) return s;
  if (Status s = checkFinite(body.inertia_kg_m2, body, index, "inertia_kg_m2"); !s) return s;
  const auto& inertia = body.inertia_kg_m2;
  const double trace = inertia[0] + inertia[4] + inertia[8];
  const double asymmetry = std::max(
      {std::abs(inertia[1] - inertia[3]), std::abs(inertia[2] - inertia[6]), std::abs(inertia[5] - inertia[7])});
  if (!(trace > 0.0) || asymmetry > 1e-6 * trace) {
    return badInput(label + ": inertia_kg_m2 = [" + fmt(inertia[0]) + ", " + fmt(inertia[1]) + ", " + fmt(inertia[2]) +
                    "; " + fmt(inertia[3]) + ", " + fmt(inertia[4]) + ", " + fmt(inertia[5]) + "; " + fmt(inertia[6]) +
                    ", " + fmt(inertia[7]) + ", " + fmt(inertia[8]) + "] (must be symmetric with a positive trace)");
  }
  return {};
}

}  // namespace strike::detail
