// SPDX-License-Identifier: MIT
#include "hull_cache.hpp"

#include <cstdio>
#include <cstring>

#include "strike/atomic_file.hpp"
#include "strike/hash.hpp"
#include "strike/read_file.hpp"

namespace strike {
namespace {

constexpr char kMagic[8] = {'S', 'T', 'R', 'K', 'H', 'U', 'L', '1'};
constexpr uint64_t kMaxFileBytes = uint64_t(1) << 26;  // 64 MiB: a hull of two million vertices

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // the project's targets are little-endian (bank format too)
  out.append(bytes, sizeof(T));
}

template <typename T>
bool get(const std::string& in, size_t& at, size_t end, T& value) {
  if (end - at < sizeof(T)) return false;
  std::memcpy(&value, in.data() + at, sizeof(T));
  at += sizeof(T);
  return true;
}

}  // namespace

uint64_t hullKey(const std::vector<double>& points_xyz, double shrink_m, double shrink_clamp) {
  const double recipe[3] = {double(simHullRecipe()), shrink_m, shrink_clamp};
  const uint64_t h = fnv1a64(recipe, sizeof recipe);
  return fnv1a64(points_xyz.data(), points_xyz.size() * sizeof(double), h);
}

std::string hullPath(const std::string& cache_dir, uint64_t key) {
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.hull", static_cast<unsigned long long>(key));
  return cache_dir + "/" + name;
}

Result<SimHull> readHull(const std::string& path, uint64_t key) {
  Result<std::string> bytes = readWholeFile(path, kMaxFileBytes);
  if (!bytes) return bytes.error();
  const std::string& in = *bytes;
  auto damaged = [&](const char* what) { return badInput(path + ": damaged hull file (" + what + ")"); };
  if (in.size() < sizeof kMagic + 4 * sizeof(uint64_t) + sizeof(uint32_t) ||
      std::memcmp(in.data(), kMagic, sizeof kMagic) != 0)
    return damaged("no STRKHUL1 header");
  const size_t body_end = in.size() - sizeof(uint64_t);
  uint64_t checksum = 0;
  size_t at = body_end;
  get(in, at, in.size(), checksum);
  if (checksum != fnv1a64(in.data(), body_end)) return damaged("checksum");
  at = sizeof kMagic;
  uint64_t stored_key = 0;
  uint32_t count = 0;
  SimHull hull;
  get(in, at, body_end, stored_key);
  get(in, at, body_end, hull.shrink_m);
  get(in, at, body_end, hull.volume_m3);
  get(in, at, body_end, count);
  if (stored_key != key) return damaged("another body");
  if ((body_end - at) / (3 * sizeof(double)) != count || (body_end - at) % (3 * sizeof(double)) != 0)
    return damaged("size");
  hull.vertices_xyz.resize(3 * size_t(count));
  for (double& x : hull.vertices_xyz) get(in, at, body_end, x);
  return hull;
}

Status writeHull(const std::string& path, uint64_t key, const SimHull& hull) {
  std::string out(kMagic, sizeof kMagic);
  put(out, key);
  put(out, hull.shrink_m);
  put(out, hull.volume_m3);
  put(out, uint32_t(hull.vertices_xyz.size() / 3));
  for (double x : hull.vertices_xyz) put(out, x);
  put(out, fnv1a64(out.data(), out.size()));
  return writeFileAtomically(path, out.data(), out.size());
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
