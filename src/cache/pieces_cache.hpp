// SPDX-License-Identifier: MIT
// The convex pieces of a concave moving body (its collision shape, see src/sim/convex_pieces.hpp)
// cached beside the mode banks, keyed by a hash of the body's surface: computing them costs
// 0.1-1 s a body, reading them a millisecond. Internal to strike_scene.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "strike/core/result.hpp"

namespace strike {

using ConvexPiecePoints = std::vector<std::vector<double>>;  ///< per piece: x, y, z, ... (mesh frame, m)

/// Content key of a surface (positions and triangles) and of how pieces are made
/// (ConvexPiecesRecipe).
uint64_t surfaceHash(const std::vector<double>& positions, const std::vector<uint32_t>& triangles);

/// "<cache_dir>/<16 hex digits>.pieces".
std::string piecesPath(const std::string& cache_dir, uint64_t surface_hash);

/// Reads a pieces file written for this surface; an error if it is missing, damaged (checksum)
/// or for another surface: the caller then computes the pieces again.
Result<ConvexPiecePoints> readPieces(const std::string& path, uint64_t surface_hash);

/// Writes a pieces file atomically. Format (little-endian): "STRKPCS1", u64 surface hash,
/// u32 piece count, per piece u32 point count and 3 f64 per point, then u64 FNV-1a of all before.
Status writePieces(const std::string& path, uint64_t surface_hash, const ConvexPiecePoints& pieces);

}  // namespace strike
