// SPDX-License-Identifier: MIT
// libstrike, main thread: mode banks. Loading one from a file or from memory (the format's version
// first, then its consistency, then its pressure weights at the context's reference distance),
// freeing it, and what it tells about the object: its info, its modes' frequencies, its surface.
#include "strike/strike.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "strike/synth/synth.hpp"

#include "capi_internal.hpp"
#include "main_thread.hpp"

namespace strike::detail {
namespace {

strike_status loadBank(strike_context ctx, const uint8_t* bytes, size_t size, const std::string& source,
                       strike_bank* out) {
  // Version first: a newer file gets VERSION, not PARSE (its layout may legitimately differ).
  if (size >= 12 && std::memcmp(bytes, "STRKBANK", 8) == 0) {
    uint32_t version = 0;
    for (int i = 0; i < 4; ++i) version |= static_cast<uint32_t>(bytes[8 + i]) << (8 * i);
    if (version > kBankFormatVersionMax)
      return fail(ctx, STRIKE_ERR_VERSION, "%s: mode bank format version %u is newer than this library reads (%u)",
                  source.c_str(), version, kBankFormatVersionMax);
  }
  Result<ModeBank> decoded = decodeBank(bytes, size, source);
  if (!decoded) return fail(ctx, STRIKE_ERR_PARSE, "%s", decoded.error().message.c_str());
  const std::string problem = decoded->checkConsistency();
  if (!problem.empty())
    return fail(ctx, STRIKE_ERR_PARSE, "%s: inconsistent mode bank: %s", source.c_str(), problem.c_str());
  auto loaded = std::make_shared<LoadedBank>();
  loaded->bank = std::move(decoded.value());
  // The output convention: pressure / output_full_scale_pa (1.0 = 20 Pa by default, as the tools);
  // the object's gain is applied apart.
  loaded->pressure_weights = pressureWeights(loaded->bank, ctx->config.reference_distance_m,
                                             outputPerPascal(1.0, ctx->config.output_full_scale_pa));
  void* mem = ctx->allocArray<strike_bank_s>(1);
  *out = new (mem) strike_bank_s{ctx, std::move(loaded), ctx->config.free, ctx->config.user};
  ctx->last_error[0] = '\0';
  return STRIKE_OK;
}

}  // namespace
}  // namespace strike::detail

using namespace strike;          // NOLINT: this file is the C shim over these namespaces
using namespace strike::detail;  // NOLINT

extern "C" {

STRIKE_API strike_status STRIKE_CALL strike_bank_load_file(strike_context ctx, const char* path, strike_bank* out) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  if (!path || !out) return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_bank_load_file: path and out must not be NULL");
  return guarded(ctx, "strike_bank_load_file", [&]() -> strike_status {
    collect(ctx);
    std::ifstream in(path, std::ios::binary);
    if (!in) return fail(ctx, STRIKE_ERR_IO, "%s: error: cannot open mode bank: %s", path, std::strerror(errno));
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) return fail(ctx, STRIKE_ERR_IO, "%s: error: read failed", path);
    return loadBank(ctx, bytes.data(), bytes.size(), path, out);
  });
}

STRIKE_API strike_status STRIKE_CALL strike_bank_load_memory(strike_context ctx, const void* data, size_t size,
                                                             strike_bank* out) {
  if (!ctx) return STRIKE_ERR_INVALID_ARG;
  if (!data || !out) return fail(ctx, STRIKE_ERR_INVALID_ARG, "strike_bank_load_memory: data and out must not be NULL");
  return guarded(ctx, "strike_bank_load_memory", [&]() -> strike_status {
    collect(ctx);
    return loadBank(ctx, static_cast<const uint8_t*>(data), size, "<memory>", out);
  });
}

STRIKE_API void STRIKE_CALL strike_bank_destroy(strike_bank bank) {
  if (!bank) return;
  const strike_free_fn free_fn = bank->free_fn;
  void* user = bank->user;
  bank->~strike_bank_s();
  free_fn(user, bank);
}

STRIKE_API strike_status STRIKE_CALL strike_bank_get_info(strike_bank bank, strike_bank_info* out) {
  if (!bank || !out) return STRIKE_ERR_INVALID_ARG;
  const uint32_t size = out->struct_size;
  if (size < offsetof(strike_bank_info, mode_count)) return STRIKE_ERR_INVALID_ARG;
  const ModeBank& b = bank->data->bank;
  strike_bank_info info;
  std::memset(&info, 0, sizeof info);
  info.struct_size = static_cast<uint32_t>(std::min<size_t>(size, sizeof info));
  info.mode_count = static_cast<uint32_t>(b.modeCount());
  info.surface_vertex_count = static_cast<uint32_t>(b.surfaceVertexCount());
  info.surface_triangle_count = static_cast<uint32_t>(b.surface_triangles.size() / 3);
  info.mass_kg = b.mass_kg;
  info.lowest_frequency_hz = b.modeCount() ? b.frequencyHz(0) : 0.0;
  for (int k = 0; k < 3; ++k) info.bounds_min_m[k] = HUGE_VAL, info.bounds_max_m[k] = -HUGE_VAL;
  for (size_t v = 0; v < b.surfaceVertexCount(); ++v)
    for (int k = 0; k < 3; ++k) {
      info.bounds_min_m[k] = std::min(info.bounds_min_m[k], b.surface_positions[3 * v + k]);
      info.bounds_max_m[k] = std::max(info.bounds_max_m[k], b.surface_positions[3 * v + k]);
    }
  if (b.surfaceVertexCount() == 0)
    for (int k = 0; k < 3; ++k) info.bounds_min_m[k] = info.bounds_max_m[k] = 0.0;
  info.volume_m3 = b.volume_m3;
  for (int k = 0; k < 3; ++k) info.centre_of_mass_m[k] = b.centre_m[k];
  for (int k = 0; k < 9; ++k) info.inertia_kg_m2[k] = b.inertia_kg_m2[k];
  const size_t nv = b.surfaceVertexCount();
  for (size_t t = 0; t + 2 < b.surface_triangles.size(); t += 3) {
    const uint32_t i0 = b.surface_triangles[t], i1 = b.surface_triangles[t + 1], i2 = b.surface_triangles[t + 2];
    if (i0 >= nv || i1 >= nv || i2 >= nv) continue;
    const double* p0 = &b.surface_positions[3 * i0];
    const double* p1 = &b.surface_positions[3 * i1];
    const double* p2 = &b.surface_positions[3 * i2];
    const double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]},
                 e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    const double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
                 cz = e1[0] * e2[1] - e1[1] * e2[0];
    info.surface_area_m2 += 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
  }
  info.equal_volume_radius_m = b.volume_m3 > 0.0 ? std::cbrt(3.0 * b.volume_m3 / (4.0 * M_PI)) : 0.0;
  std::snprintf(info.material_name, sizeof info.material_name, "%s", b.material.name.c_str());
  info.youngs_pa = b.material.youngs_pa;
  info.poisson = b.material.poisson;
  info.density_kg_m3 = b.material.density_kg_m3;
  info.rayleigh_stiffness_s = b.material.rayleigh_stiffness;
  info.rayleigh_mass_per_s = b.material.rayleigh_mass;
  std::memcpy(out, &info, info.struct_size);  // never past the caller's struct
  return STRIKE_OK;
}

STRIKE_API strike_status STRIKE_CALL strike_bank_mode_frequency(strike_bank bank, uint32_t mode, double* out_hz) {
  if (!bank || !out_hz || mode >= bank->data->bank.modeCount()) return STRIKE_ERR_INVALID_ARG;
  *out_hz = bank->data->bank.frequencyHz(mode);
  return STRIKE_OK;
}

STRIKE_API strike_status STRIKE_CALL strike_bank_surface_vertex(strike_bank bank, uint32_t vertex,
                                                                double out_position[3], double out_normal[3]) {
  if (!bank || vertex >= bank->data->bank.surfaceVertexCount()) return STRIKE_ERR_INVALID_ARG;
  const ModeBank& b = bank->data->bank;
  for (int k = 0; k < 3; ++k) {
    if (out_position) out_position[k] = b.surface_positions[3 * vertex + k];
    if (out_normal)
      out_normal[k] = b.surface_normals.size() == b.surface_positions.size() ? b.surface_normals[3 * vertex + k] : 0.0;
  }
  return STRIKE_OK;
}

}  // extern "C"
