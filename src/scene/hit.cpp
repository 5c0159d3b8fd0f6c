// SPDX-License-Identifier: MIT
// One impact on one object (strike/scene/hit.hpp): moved out of tools/cli/cmd_hit.cpp unchanged so the
// CLI and the Python package share it.
#include "strike/scene/hit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "strike/synth/engine.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/scene/render.hpp"

namespace strike {

double objectSizeM(const ModeBank& bank) {
  double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < bank.surfaceVertexCount(); ++v)
    for (int a = 0; a < 3; ++a) {
      low[a] = std::min(low[a], double(bank.surface_positions[v * 3 + a]));
      high[a] = std::max(high[a], double(bank.surface_positions[v * 3 + a]));
    }
  return std::max({high[0] - low[0], high[1] - low[1], high[2] - low[2], 0.0});
}

size_t loudestVertex(const ModeBank& bank) {
  size_t best = 0;
  double best_score = -1.0;
  for (size_t v = 0; v < bank.surfaceVertexCount(); ++v) {
    const float* n = &bank.surface_normals[v * 3];
    double score = 0.0;
    for (size_t i = 0; i < bank.modeCount(); ++i) {
      const float* phi = bank.shapeAt(i, v);
      const double along = phi[0] * n[0] + phi[1] * n[1] + phi[2] * n[2];
      if (bank.eigenvalues[i] > 0) score += along * along / bank.eigenvalues[i];
    }
    if (score > best_score) best_score = score, best = v;
  }
  return best;
}

Result<HitResult> renderHit(const ModeBank& bank, const HitSettings& settings) {
  if (bank.surfaceVertexCount() == 0) return badInput("the bank has no surface");
  HitResult out;
  // Where: a vertex, or the nearest surface point to `at`.
  size_t vertex = 0;
  double point[3];
  double requested[3] = {0, 0, 0};
  if (settings.at_m) {
    for (int a = 0; a < 3; ++a) requested[a] = (*settings.at_m)[a];
    // The point struck is the nearest point on the surface (what projectImpulse uses): report
    // it, not the point asked for, and how far apart they are.
    const SurfaceLocator locator(bank);
    uint32_t corners[3] = {0, 0, 0};
    double weights[3] = {1, 0, 0};
    locator.nearest(requested, corners, weights);
    double best_weight = -1.0;
    point[0] = point[1] = point[2] = 0.0;
    for (int k = 0; k < 3; ++k) {
      if (weights[k] > best_weight) best_weight = weights[k], vertex = corners[k];  // the impulse's default normal
      for (int a = 0; a < 3; ++a) point[a] += weights[k] * bank.surface_positions[corners[k] * 3 + a];
    }
    out.off_surface_m = std::sqrt(std::pow(point[0] - requested[0], 2) + std::pow(point[1] - requested[1], 2) +
                                  std::pow(point[2] - requested[2], 2));
  } else {
    vertex = settings.vertex ? *settings.vertex : loudestVertex(bank);
    if (vertex >= bank.surfaceVertexCount())
      return badInput("vertex = " + std::to_string(vertex) + " (the bank has surface vertices 0 to " +
                      std::to_string(bank.surfaceVertexCount() - 1) + ")");
    for (int a = 0; a < 3; ++a) point[a] = bank.surface_positions[vertex * 3 + a];
  }
  const float* normal = &bank.surface_normals[vertex * 3];
  double impulse[3] = {-0.01 * normal[0], -0.01 * normal[1], -0.01 * normal[2]};
  if (settings.impulse_n_s)
    for (int a = 0; a < 3; ++a) impulse[a] = (*settings.impulse_n_s)[a];

  // How long the contact lasts: Hertz theory for a ball striking a locally flat surface, at the
  // speed that gives this impulse in an elastic rebound (tapSpeed); the engine's own rule. The
  // default striker is the library's (defaultStriker: steel, 5 mm), as libstrike's.
  ContactPartner striker_ball;
  double speed = 0.0;
  if (!settings.contact_time_s) {
    Result<Material> striker = builtinMaterials().find(settings.striker);
    if (!striker) return striker.error();
    striker_ball.youngs_pa = striker->youngs_pa;
    striker_ball.poisson = striker->poisson;
    striker_ball.radius_m = settings.striker_radius_m;
    striker_ball.mass_kg = ballMass(striker->density_kg_m3, settings.striker_radius_m);
    const double j_normal = std::fabs(impulse[0] * normal[0] + impulse[1] * normal[1] + impulse[2] * normal[2]);
    speed = tapSpeed(j_normal, striker_ball.mass_kg, bank.mass_kg);
  }

  // The sound engine with one voice, as `strike render` and libstrike run it. The listener is
  // distance_m from the object's centre of mass, on the side struck.
  EngineSettings engine_settings;
  engine_settings.synth.sample_rate_hz = settings.sample_rate_hz;
  engine_settings.synth.simd = settings.simd;
  engine_settings.max_voices = 1;
  engine_settings.max_block_frames = kRenderBlockFrames;
  engine_settings.max_contact_duration_s = 1.0;  // --contact-time allows up to 1 s
  engine_settings.realtime = false;
  SoundEngine engine(engine_settings);
  VoiceDesc desc;
  desc.bank = std::shared_ptr<const ModeBank>(std::shared_ptr<const ModeBank>(), &bank);  // not owned
  desc.pressure_scale = outputPerPascal(settings.gain);
  desc.weights = pressureWeights(bank, engine_settings.reference_distance_m, desc.pressure_scale);
  Voice voice(desc, engine_settings);
  engine.install(0, &voice);
  std::array<double, 3> side = {point[0] - bank.centre_m[0], point[1] - bank.centre_m[1], point[2] - bank.centre_m[2]};
  double side_length = std::sqrt(side[0] * side[0] + side[1] * side[1] + side[2] * side[2]);
  if (!(side_length > 1e-12)) side = {-normal[0], -normal[1], -normal[2]}, side_length = 1.0;
  Pose listener;
  for (int a = 0; a < 3; ++a) listener.position_m[a] = bank.centre_m[a] + settings.distance_m * side[a] / side_length;
  if (settings.listener_m) listener.position_m = *settings.listener_m;
  engine.setListener(listener);
  const double contact_time_s = settings.contact_time_s ? *settings.contact_time_s
                                : speed > 0.0           ? engine.contactDuration(0, striker_ball, speed)
                                                        : 0.0;
  EngineImpact impact;
  impact.voice = 0;
  if (settings.at_m)
    impact.point = {requested[0], requested[1], requested[2]};
  else
    impact.surface_vertex = static_cast<int32_t>(vertex);
  impact.impulse = {impulse[0], impulse[1], impulse[2]};
  impact.contact_duration_s = contact_time_s;
  impact.time_s = 0.0;
  engine.impact(impact);

  out.audio.sample_rate_hz = settings.sample_rate_hz;
  out.audio.channels = 1;
  out.audio.samples.resize(static_cast<size_t>(std::llround(settings.duration_s * settings.sample_rate_hz)));
  for (size_t done = 0; done < out.audio.samples.size(); done += kRenderBlockFrames) {
    float* channels[1] = {out.audio.samples.data() + done};
    engine.render(channels, std::min(kRenderBlockFrames, out.audio.samples.size() - done));
  }
  for (float s : out.audio.samples) {
    out.peak = std::max(out.peak, static_cast<double>(std::fabs(s)));
    if (std::fabs(s) >= 1.0f) ++out.clipped_samples;
  }
  out.stats = voice.synthStats();
  out.vertex = vertex;
  for (int a = 0; a < 3; ++a) out.point_m[a] = point[a], out.impulse_n_s[a] = impulse[a];
  out.contact_time_s = contact_time_s;
  return out;
}

}  // namespace strike
