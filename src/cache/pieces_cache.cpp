// SPDX-License-Identifier: MIT
#include "pieces_cache.hpp"

#include <cstdio>
#include <cstring>

#include "cache_file.hpp"
#include "strike/bank/bank.hpp"
#include "strike/sim/sim.hpp"

namespace strike {
namespace {

constexpr char kMagic[8] = {'S', 'T', 'R', 'K', 'P', 'C', 'S', '1'};
constexpr uint64_t kMaxFileBytes = uint64_t(1) << 28;  // 256 MiB: far above any real decomposition

}  // namespace

uint64_t surfaceHash(const std::vector<double>& positions, const std::vector<uint32_t>& triangles) {
  // The recipe too: pieces made another way are not these.
  const double recipe[4] = {double(ConvexPiecesRecipe::version), ConvexPiecesRecipe::concavity_of_size,
                            ConvexPiecesRecipe::max_edge_of_size, double(ConvexPiecesRecipe::max_pieces)};
  uint64_t h = fnv1a64(recipe, sizeof recipe);
  h = fnv1a64(positions.data(), positions.size() * sizeof(double), h);
  return fnv1a64(triangles.data(), triangles.size() * sizeof(uint32_t), h);
}

std::string piecesPath(const std::string& cache_dir, uint64_t surface_hash) { return cache_file::path(cache_dir, surface_hash, ".pieces"); }

Result<ConvexPiecePoints> readPieces(const std::string& path, uint64_t surface_hash) {
  Result<cache_file::Checked> file =
      cache_file::read(path, kMagic, "pieces", kMaxFileBytes, sizeof(uint64_t) + sizeof(uint32_t));
  if (!file) return file.error();
  auto damaged = [&](const char* what) { return cache_file::damaged(path, "pieces", what); };
  uint64_t hash = 0;
  uint32_t count = 0;
  file->get(hash);
  file->get(count);
  if (hash != surface_hash) return damaged("another surface");
  ConvexPiecePoints pieces(count);
  for (std::vector<double>& points : pieces) {
    uint32_t n = 0;
    if (!file->get(n) || n < 4 || (file->body_end - file->at) / (3 * sizeof(double)) < n) return damaged("truncated");
    points.resize(3 * size_t(n));
    for (double& x : points) file->get(x);
  }
  if (file->at != file->body_end || pieces.empty()) return damaged("size");
  return pieces;
}

Status writePieces(const std::string& path, uint64_t surface_hash, const ConvexPiecePoints& pieces) {
  std::string out(kMagic, sizeof kMagic);
  cache_file::put(out, surface_hash);
  cache_file::put(out, uint32_t(pieces.size()));
  for (const std::vector<double>& points : pieces) {
    cache_file::put(out, uint32_t(points.size() / 3));
    for (double x : points) cache_file::put(out, x);
  }
  return cache_file::write(path, std::move(out));
}

}  // namespace strike
