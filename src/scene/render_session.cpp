// SPDX-License-Identifier: MIT
#include "strike/scene/render_session.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <utility>

#include "strike/bank/bank.hpp"
#include "strike/synth/synth.hpp"

namespace strike {
namespace {

/// A fast hash of doubles' bits, to find a candidate entry (whose points are then compared byte
/// for byte): 64-bit multiply-xorshift per word, 8x fewer steps than FNV-1a per byte.
uint64_t hashWords(const std::vector<double>& values, uint64_t seed) {
  uint64_t h = seed ^ (values.size() * 0x9e3779b97f4a7c15ull);
  for (double value : values) {
    uint64_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    h = (h ^ bits) * 0xff51afd7ed558ccdull;
    h ^= h >> 32;
  }
  return h;
}

uint64_t bitsOf(double value) {
  uint64_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}

template <class T>
uint64_t bytesOf(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

/// Memory of a bank header: its arrays (the shapes are not in it).
uint64_t headerBytes(const ModeBank& bank) {
  return sizeof(ModeBank) + bytesOf(bank.eigenvalues) + bytesOf(bank.frequency_error_estimate) +
         bytesOf(bank.radiation_m2) + bytesOf(bank.surface_positions) + bytesOf(bank.surface_normals) +
         bytesOf(bank.surface_triangles) + bytesOf(bank.surface_node_index) + bank.mesh_source.size();
}

/// An upper estimate of a SurfaceLocator's memory, from the grid its constructor lays (one
/// triangle per cell on the surface, at most 256 cells a side; a triangle in ~8 cells).
uint64_t locatorBytes(const ModeBank& bank) {
  const size_t nv = bank.surface_positions.size() / 3, nt = bank.surface_triangles.size() / 3;
  if (nv == 0 || nt == 0) return 64;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], bank.surface_positions[3 * v + k]);
      hi[k] = std::max(hi[k], bank.surface_positions[3 * v + k]);
    }
  const double ext[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  const double area = 2.0 * (ext[0] * ext[1] + ext[1] * ext[2] + ext[0] * ext[2]);
  const double cell = std::max(std::sqrt(area / double(nt)), 1e-12);
  double cells = 1.0;
  for (double e : ext) cells *= std::clamp(e / cell + 1.0, 1.0, 256.0);
  return 4 * uint64_t(cells + 1.0) + 4 * 8 * uint64_t(nt);
}

}  // namespace

struct RenderSession::Impl {
  struct Entry {
    uint64_t hash = 0;
    // A hull: the points it was made of, byte for byte, and the shrink.
    std::vector<double> points;
    uint64_t shrink_bits = 0, clamp_bits = 0;
    std::shared_ptr<const SimHull> hull;
    // A bank file's surface.
    BankSurface surface;
    uint64_t bytes = 0;
    uint64_t last_used = 0;
  };
  mutable std::mutex mutex;
  uint64_t max_bytes = 0;
  std::vector<Entry> entries;  // few (a dataset's shapes): a linear scan costs nothing next to a hull
  uint64_t bytes = 0, clock = 0, hits = 0, misses = 0, evicted = 0;

  /// The entry of this hash that `same` accepts, marked as just used; nullptr if none. The caller
  /// holds the mutex; the pointer lasts until the entries change.
  template <class Same>
  Entry* find(uint64_t hash, const Same& same) {
    for (Entry& e : entries)
      if (e.hash == hash && same(e)) {
        e.last_used = ++clock;
        return &e;
      }
    return nullptr;
  }

  /// `get` of the kept entry that `same` accepts, or of the entry `build` makes now (outside the
  /// lock: a hull or a locator takes milliseconds, and other threads' lookups need not wait).
  /// Two threads that miss the same key together both build; the second to finish finds the
  /// first's entry on its second look, returns that one and drops its own, so the session holds
  /// one entry per key and every caller shares it. Both lookups count as misses: each built.
  template <class Same, class Build, class Get>
  auto findOrBuild(uint64_t hash, const Same& same, const Build& build, const Get& get) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (Entry* kept = find(hash, same)) {
        ++hits;
        return get(*kept);
      }
      ++misses;
    }
    Entry entry = build();
    entry.hash = hash;
    std::lock_guard<std::mutex> lock(mutex);
    if (Entry* kept = find(hash, same)) return get(*kept);
    auto made = get(entry);
    add(std::move(entry));
    return made;
  }

  /// Keeps `entry`, then drops the least recently used entries until the rest fit (the new one
  /// stays even alone over the cap: the render holds it anyway).
  void add(Entry entry) {
    entry.last_used = ++clock;
    bytes += entry.bytes;
    entries.push_back(std::move(entry));
    while (bytes > max_bytes && entries.size() > 1) {
      auto oldest = std::min_element(entries.begin(), entries.end() - 1,
                                     [](const Entry& a, const Entry& b) { return a.last_used < b.last_used; });
      bytes -= oldest->bytes;
      entries.erase(oldest);
      ++evicted;
    }
  }
};

RenderSession::RenderSession(uint64_t max_bytes) : impl_(std::make_unique<Impl>()) { impl_->max_bytes = max_bytes; }
RenderSession::~RenderSession() = default;

RenderSession::BankSurface RenderSession::bankSurface(const BankFile& file) {
  const ModeBank& header = file.bank();
  auto same = [&](const Impl::Entry& e) {
    // The content key decides; the arrays the locator and the voice read most are compared too.
    return e.surface.bank && e.surface.bank->surface_positions == header.surface_positions &&
           e.surface.bank->surface_triangles == header.surface_triangles &&
           e.surface.bank->eigenvalues == header.eigenvalues;
  };
  auto build = [&] {
    Impl::Entry entry;
    auto bank = file.sharedBank();  // the file's own bank object: no copy
    entry.surface.locator = std::make_shared<const SurfaceLocator>(*bank);
    entry.surface.bank = std::move(bank);
    entry.bytes = headerBytes(*entry.surface.bank) + locatorBytes(*entry.surface.bank);
    return entry;
  };
  return impl_->findOrBuild(file.contentKey(), same, build, [](const Impl::Entry& e) { return e.surface; });
}

std::shared_ptr<const SimHull> RenderSession::hull(const std::vector<double>& points_xyz, double shrink_m,
                                                   double shrink_clamp, const std::function<SimHull()>& compute) {
  const uint64_t shrink_bits = bitsOf(shrink_m), clamp_bits = bitsOf(shrink_clamp);
  auto same = [&](const Impl::Entry& e) {
    return e.hull && e.shrink_bits == shrink_bits && e.clamp_bits == clamp_bits &&
           e.points.size() == points_xyz.size() &&
           std::memcmp(e.points.data(), points_xyz.data(), points_xyz.size() * sizeof(double)) == 0;
  };
  auto build = [&] {
    Impl::Entry entry;
    entry.points = points_xyz;
    entry.shrink_bits = shrink_bits;
    entry.clamp_bits = clamp_bits;
    entry.hull = std::make_shared<const SimHull>(compute());
    entry.bytes = sizeof(Impl::Entry) + bytesOf(entry.points) + sizeof(SimHull) + bytesOf(entry.hull->vertices_xyz);
    return entry;
  };
  return impl_->findOrBuild(hashWords(points_xyz, shrink_bits * 31 + clamp_bits), same, build,
                            [](const Impl::Entry& e) { return e.hull; });
}

SimHullMemo RenderSession::hullMemo() {
  return [this](const std::vector<double>& points_xyz, double shrink_m, double shrink_clamp,
                const std::function<SimHull()>& compute) { return hull(points_xyz, shrink_m, shrink_clamp, compute); };
}

RenderSession::Stats RenderSession::stats() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  Stats s;
  s.entries = impl_->entries.size();
  s.bytes = impl_->bytes;
  s.max_bytes = impl_->max_bytes;
  s.hits = impl_->hits;
  s.misses = impl_->misses;
  s.evicted = impl_->evicted;
  return s;
}

void RenderSession::clear() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->entries.clear();
  impl_->bytes = 0;
}

}  // namespace strike
