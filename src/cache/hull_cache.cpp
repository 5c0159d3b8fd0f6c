// SPDX-License-Identifier: MIT
#include "hull_cache.hpp"

#include <cstdio>
#include <cstring>

#include "cache_file.hpp"
#include "strike/core/hash.hpp"

namespace strike {
namespace {

constexpr char kMagic[8] = {'S', 'T', 'R', 'K', 'H', 'U', 'L', '1'};
constexpr uint64_t kMaxFileBytes = uint64_t(1) << 26;  // 64 MiB: a hull of two million vertices

}  // namespace

uint64_t hullKey(const std::vector<double>& points_xyz, double shrink_m, double shrink_clamp) {
  const double recipe[3] = {double(simHullRecipe()), shrink_m, shrink_clamp};
  const uint64_t h = fnv1a64(recipe, sizeof recipe);
  // The points' bits, a word at a time (fnv1a64 byte by byte was ~1% of a cached render of
  // 20 plates).
  static_assert(sizeof(double) == sizeof(uint64_t));
  return hashWords64(points_xyz.data(), points_xyz.size(), h);
}

std::string hullPath(const std::string& cache_dir, uint64_t key) { return cache_file::path(cache_dir, key, ".hull"); }

Result<SimHull> readHull(const std::string& path, uint64_t key) {
  Result<cache_file::Checked> file =
      cache_file::read(path, kMagic, "hull", kMaxFileBytes, 3 * sizeof(uint64_t) + sizeof(uint32_t));
  if (!file) return file.error();
  auto damaged = [&](const char* what) { return cache_file::damaged(path, "hull", what); };
  uint64_t stored_key = 0;
  uint32_t count = 0;
  SimHull hull;
  file->get(stored_key);
  file->get(hull.shrink_m);
  file->get(hull.volume_m3);
  file->get(count);
  if (stored_key != key) return damaged("another body");
  const size_t left = file->body_end - file->at;
  if (left % (3 * sizeof(double)) != 0 || left / (3 * sizeof(double)) != count) return damaged("size");
  hull.vertices_xyz.resize(3 * size_t(count));
  for (double& x : hull.vertices_xyz) file->get(x);
  return hull;
}

Status writeHull(const std::string& path, uint64_t key, const SimHull& hull) {
  std::string out(kMagic, sizeof kMagic);
  cache_file::put(out, key);
  cache_file::put(out, hull.shrink_m);
  cache_file::put(out, hull.volume_m3);
  cache_file::put(out, uint32_t(hull.vertices_xyz.size() / 3));
  for (double x : hull.vertices_xyz) cache_file::put(out, x);
  return cache_file::write(path, std::move(out));
}

SimHullMemo cachedHullMemo(const std::string& cache_dir, SimHullMemo inner) {
  return [cache_dir, inner](const std::vector<double>& points_xyz, double shrink_m, double shrink_clamp,
                            const std::function<SimHull()>& compute) {
    const std::function<SimHull()> from_cache = [&] {
      const uint64_t key = hullKey(points_xyz, shrink_m, shrink_clamp);
      const std::string path = hullPath(cache_dir, key);
      if (Result<SimHull> cached = readHull(path, key)) return std::move(*cached);
      SimHull hull = compute();
      (void)writeHull(path, key, hull);  // a failed cache write costs the next render time, never this one its result
      return hull;
    };
    return inner ? inner(points_xyz, shrink_m, shrink_clamp, from_cache) : std::make_shared<const SimHull>(from_cache());
  };
}

}  // namespace strike
