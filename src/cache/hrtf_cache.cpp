// SPDX-License-Identifier: MIT
#include "hrtf_cache.hpp"

#include "cache_file.hpp"
#include "strike/core/hash.hpp"

namespace strike {
namespace {

constexpr char kMagic[8] = {'S', 'T', 'R', 'K', 'H', 'R', 'T', '1'};
constexpr uint64_t kMaxFileBytes = uint64_t(1) << 28;  // 256 MiB, as many as prepareHrtfSet allows and more
constexpr size_t kHeaderBytes = sizeof(uint64_t) + sizeof(double) + 2 * sizeof(uint32_t);

}  // namespace

uint64_t hrtfKey(const std::string& sofa_bytes, double sample_rate_hz) {
  const double recipe[2] = {1.0, sample_rate_hz};  // the format's version, the rate
  uint64_t h = fnv1a64(recipe, sizeof recipe);
  const size_t words = sofa_bytes.size() / 8;
  h = hashWords64(sofa_bytes.data(), words, h);
  const uint64_t size = sofa_bytes.size();
  h = fnv1a64(&size, sizeof size, h);
  return fnv1a64(sofa_bytes.data() + 8 * words, sofa_bytes.size() - 8 * words, h);
}

std::string hrtfPath(const std::string& cache_dir, uint64_t key) { return cache_file::path(cache_dir, key, ".hrtf"); }

Result<HrtfSet> readHrtf(const std::string& path, uint64_t key) {
  Result<cache_file::Checked> file = cache_file::read(path, kMagic, "hrtf", kMaxFileBytes, kHeaderBytes);
  if (!file) return file.error();
  auto damaged = [&](const char* what) { return cache_file::damaged(path, "hrtf", what); };
  uint64_t stored_key = 0;
  uint32_t taps = 0, count = 0;
  HrtfSet set;
  file->get(stored_key);
  file->get(set.sample_rate_hz);
  file->get(taps);
  file->get(count);
  if (stored_key != key) return damaged("another file or rate");
  const uint64_t want = uint64_t(count) * (3 * sizeof(double) + 2 * uint64_t(taps) * sizeof(float));
  if (file->body_end - file->at != want) return damaged("size");
  set.taps = taps;
  set.directions.resize(count);
  for (std::array<double, 3>& d : set.directions)
    for (double& x : d) file->get(x);
  set.left.resize(size_t(count) * taps);
  set.right.resize(size_t(count) * taps);
  for (float& x : set.left) file->get(x);
  for (float& x : set.right) file->get(x);
  return set;
}

Status writeHrtf(const std::string& path, uint64_t key, const HrtfSet& set) {
  std::string out(kMagic, sizeof kMagic);
  out.reserve(sizeof kMagic + kHeaderBytes + set.directions.size() * 3 * sizeof(double) +
              (set.left.size() + set.right.size()) * sizeof(float) + sizeof(uint64_t));
  cache_file::put(out, key);
  cache_file::put(out, set.sample_rate_hz);
  cache_file::put(out, uint32_t(set.taps));
  cache_file::put(out, uint32_t(set.directions.size()));
  for (const std::array<double, 3>& d : set.directions)
    for (double x : d) cache_file::put(out, x);
  out.append(reinterpret_cast<const char*>(set.left.data()), set.left.size() * sizeof(float));
  out.append(reinterpret_cast<const char*>(set.right.data()), set.right.size() * sizeof(float));
  return cache_file::write(path, std::move(out));
}

}  // namespace strike
