// SPDX-License-Identifier: MIT
// ModeBank helpers that do not touch files.
#include <algorithm>
#include <cmath>
#include <string>

#include "strike/bank/bank.hpp"

namespace strike {

double ModeBank::frequencyHz(size_t mode) const {
  // The undamped natural frequency of mode i is sqrt(lambda_i) / 2pi (K x = lambda M x).
  const double lambda = eigenvalues[mode];
  return lambda > 0.0 ? std::sqrt(lambda) / (2.0 * M_PI) : 0.0;
}

double ModeBank::dampingCoefficient(size_t mode) const {
  return rayleighDamping(material.rayleigh_stiffness, material.rayleigh_mass, eigenvalues[mode]);
}

std::string ModeBank::checkConsistency(bool shapes_loaded) const {
  const size_t modes = eigenvalues.size();
  const size_t vertices = surfaceVertexCount();
  if (surface_positions.size() % 3 != 0) return "surface positions are not a multiple of 3";
  if (!shapes_loaded && !shapes.empty()) return "mode shapes are loaded where none were expected";
  if (shapes_loaded && shapes.size() != modes * vertices * 3)
    return "mode shapes hold " + std::to_string(shapes.size()) + " values, expected " + std::to_string(modes) +
           " modes x " + std::to_string(vertices) + " vertices x 3";
  if (!surface_normals.empty() && surface_normals.size() != vertices * 3)
    return "surface normals hold " + std::to_string(surface_normals.size()) + " values, expected " +
           std::to_string(vertices * 3);
  if (!surface_node_index.empty() && surface_node_index.size() != vertices)
    return "surface node index holds " + std::to_string(surface_node_index.size()) + " values, expected " +
           std::to_string(vertices);
  if (surface_triangles.size() % 3 != 0) return "surface triangles are not a multiple of 3";
  for (size_t t = 0; t < surface_triangles.size(); ++t)
    if (surface_triangles[t] >= vertices)
      return "surface triangle " + std::to_string(t / 3) + " references vertex " +
             std::to_string(surface_triangles[t]) + ", the surface has " + std::to_string(vertices);
  if (!frequency_error_estimate.empty() && frequency_error_estimate.size() != modes)
    return "frequency error estimates hold " + std::to_string(frequency_error_estimate.size()) + " values, expected " +
           std::to_string(modes);
  if (!radiation_m2.empty() && radiation_m2.size() != modes)
    return "radiation strengths hold " + std::to_string(radiation_m2.size()) + " values, expected " +
           std::to_string(modes);
  for (double v : radiation_m2)
    if (!std::isfinite(v) || v < 0) return "a radiation strength is negative or not finite";
  if (transfer.modeCount() > modes)
    return "the acoustic transfer has " + std::to_string(transfer.modeCount()) + " modes, the bank " +
           std::to_string(modes);
  for (size_t i = 0; i < modes; ++i) {
    if (!std::isfinite(eigenvalues[i]) || eigenvalues[i] < 0.0)
      return "eigenvalue " + std::to_string(i) + " is " + std::to_string(eigenvalues[i]) + " (must be finite, >= 0)";
    if (i > 0 && eigenvalues[i] < eigenvalues[i - 1])
      return "eigenvalues are not ascending at mode " + std::to_string(i);
  }
  for (float v : shapes)
    if (!std::isfinite(v)) return "a mode shape value is not finite";
  for (double v : surface_positions)
    if (!std::isfinite(v)) return "a surface position is not finite";
  const double material_values[] = {material.youngs_pa, material.poisson, material.density_kg_m3,
                                    material.rayleigh_stiffness, material.rayleigh_mass};
  for (double v : material_values)
    if (!std::isfinite(v)) return "a material value is not finite";
  if (!(mass_kg >= 0.0) || !std::isfinite(mass_kg)) return "mass is " + std::to_string(mass_kg);
  return {};
}

const float* ShapeRows::row(uint32_t vertex) const {
  const auto it = std::lower_bound(vertices.begin(), vertices.end(), vertex);
  if (it == vertices.end() || *it != vertex) return nullptr;
  return values.data() + static_cast<size_t>(it - vertices.begin()) * modes * 3;
}

}  // namespace strike
