// SPDX-License-Identifier: MIT
#include "pieces_cache.hpp"

#include <cstdio>
#include <cstring>

#include "strike/atomic_file.hpp"
#include "strike/bank.hpp"
#include "strike/sim.hpp"

namespace strike {
namespace {

constexpr char kMagic[8] = {'S', 'T', 'R', 'K', 'P', 'C', 'S', '1'};
constexpr uint64_t kMaxFileBytes = uint64_t(1) << 28;  // 256 MiB: far above any real decomposition

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

uint64_t surfaceHash(const std::vector<double>& positions, const std::vector<uint32_t>& triangles) {
  // The recipe too: pieces made another way are not these.
  const double recipe[4] = {double(ConvexPiecesRecipe::version), ConvexPiecesRecipe::concavity_of_size,
                            ConvexPiecesRecipe::max_edge_of_size, double(ConvexPiecesRecipe::max_pieces)};
  uint64_t h = fnv1a64(recipe, sizeof recipe);
  h = fnv1a64(positions.data(), positions.size() * sizeof(double), h);
  return fnv1a64(triangles.data(), triangles.size() * sizeof(uint32_t), h);
}

std::string piecesPath(const std::string& cache_dir, uint64_t surface_hash) {
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.pieces", static_cast<unsigned long long>(surface_hash));
  return cache_dir + "/" + name;
}

Result<ConvexPiecePoints> readPieces(const std::string& path, uint64_t surface_hash) {
  Result<std::string> bytes = readWholeFile(path, kMaxFileBytes);
  if (!bytes) return bytes.error();
  const std::string& in = *bytes;
  auto damaged = [&](const char* what) { return badInput(path + ": damaged pieces file (" + what + ")"); };
  if (in.size() < sizeof kMagic + 2 * sizeof(uint64_t) + sizeof(uint32_t) ||
      std::memcmp(in.data(), kMagic, sizeof kMagic) != 0)
    return damaged("no STRKPCS1 header");
  const size_t body_end = in.size() - sizeof(uint64_t);
  uint64_t checksum = 0;
  size_t at = body_end;
  get(in, at, in.size(), checksum);
  if (checksum != fnv1a64(in.data(), body_end)) return damaged("checksum");
  at = sizeof kMagic;
  uint64_t hash = 0;
  uint32_t count = 0;
  get(in, at, body_end, hash);
  get(in, at, body_end, count);
  if (hash != surface_hash) return damaged("another surface");
  ConvexPiecePoints pieces(count);
  for (std::vector<double>& points : pieces) {
    uint32_t n = 0;
    if (!get(in, at, body_end, n) || n < 4 || (body_end - at) / (3 * sizeof(double)) < n) return damaged("truncated");
    points.resize(3 * size_t(n));
    for (double& x : points) get(in, at, body_end, x);
  }
  if (at != body_end || pieces.empty()) return damaged("size");
  return pieces;
}

Status writePieces(const std::string& path, uint64_t surface_hash, const ConvexPiecePoints& pieces) {
  std::string out(kMagic, sizeof kMagic);
  put(out, surface_hash);
  put(out, uint32_t(pieces.size()));
  for (const std::vector<double>& points : pieces) {
    put(out, uint32_t(points.size() / 3));
    for (double x : points) put(out, x);
  }
  put(out, fnv1a64(out.data(), out.size()));
  return writeFileAtomically(path, out.data(), out.size());
}

}  // namespace strike
