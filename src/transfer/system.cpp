// SPDX-License-Identifier: MIT
// Assembling and solving one system (and its coarse version).
#include "system.hpp"

#include <array>

#include "assembly.hpp"
#include "dense_solve.hpp"
#include "iterative_solve.hpp"

namespace strike::transfer {

namespace {

/// The square system as a hierarchical matrix (hmatrix.hpp), solved by GMRES over its product;
/// the coarse system of the estimate is R A P (its rows the fine rows row_cluster, its columns
/// the fine ones summed: the free term comes out right, row_cluster[j] being inside coarse
/// cluster j), the fine blocks restricted.
ModeSolve solveHierarchical(const Surface& s, const std::vector<NodeData>& data, double k, const NearCache& near,
                            const BigTriangles& big, ModeSolve out,
                            std::chrono::steady_clock::time_point assembly_start, TwoParts& parts,
                            const SystemOptions& options) {
  const Cut& cut = out.cut;
  const size_t n = cut.nodes.size(), rhs = data.size();
  const HSystem system =
      assembleHSystem(s, cut, out.pieces, out.piece_data, big, data, near, k, options.hmatrix, parts);
  const HMatrix& A = system.A;
  out.matrix_bytes = A.bytes();
  out.blocks = A.blocks.size();
  out.low_rank_blocks = A.lowRankBlocks();
  const Coarse coarse = coarsen(s, cut);
  const size_t nc = coarse.count;
  const bool coarse_solve = nc < n && nc > 0;
  out.assembly_seconds = secondsSince(assembly_start);
  const auto factor_start = std::chrono::steady_clock::now();
  const auto R = static_cast<Eigen::Index>(rhs);
  Eigen::MatrixXcd b(static_cast<Eigen::Index>(n), R);
  for (size_t q = 0; q < rhs; ++q)
    for (size_t i = 0; i < n; ++i) b(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(q)) = system.b[q * n + i];
  const std::vector<cd> diagonal = A.diagonal();
  std::array<IterativeReport, 2> reports;
  Eigen::MatrixXcd P, pc;
  // The fine and the coarse solve side by side, each product on its own thread.
  parts.run(size_t{2}, size_t{1}, [&](size_t begin, size_t, int) {
    if (begin == 0) {
      P = solveGmres([&](const std::vector<cd>& x, std::vector<cd>& y) { A.multiply(x, y); }, diagonal, b,
                     options.iterative_tolerance, 2000, &reports[0]);
      return;
    }
    if (!coarse_solve) return;
    const HMatrix Ac = A.restricted(coarse.row_cluster, coarse.of_cluster, nc);
    Eigen::MatrixXcd bc(static_cast<Eigen::Index>(nc), R);
    for (size_t j = 0; j < nc; ++j) bc.row(static_cast<Eigen::Index>(j)) = b.row(coarse.row_cluster[j]);
    auto product = [&](const std::vector<cd>& x, std::vector<cd>& y) { Ac.multiply(x, y); };
    const std::vector<cd> coarse_diagonal = Ac.diagonal();
    pc = solveGmres(product, coarse_diagonal, bc, options.iterative_tolerance, 2000, &reports[1]);
  });
  out.iterations = reports[0].iterations;
  out.elements = n;
  out.chief = 0;
  out.p.resize(rhs);
  out.p_diff.resize(rhs);
  for (size_t q = 0; q < rhs; ++q) {
    out.p[q] = P.col(static_cast<Eigen::Index>(q));
    out.p_diff[q] = Eigen::VectorXcd::Zero(static_cast<Eigen::Index>(n));
    if (!coarse_solve) continue;
    for (size_t c = 0; c < n; ++c)
      out.p_diff[q][static_cast<Eigen::Index>(c)] =
          out.p[q][static_cast<Eigen::Index>(c)] - pc(coarse.of_cluster[c], static_cast<Eigen::Index>(q));
  }
  out.factor_seconds = secondsSince(factor_start);
  return out;
}

}  // namespace

ModeSolve solveSystem(const Surface& s, const std::vector<NodeData>& data, double k, size_t elements, size_t chief,
                      double k_rule, std::map<size_t, NearCache>& near_caches, TwoParts& parts,
                      const SystemOptions& options) {
  ModeSolve out;
  const auto assembly_start = std::chrono::steady_clock::now();
  out.cut = cutWithCount(s, elements);
  const Cut& cut = out.cut;
  auto cached = near_caches.find(elements);
  if (cached == near_caches.end()) cached = near_caches.emplace(elements, buildNearCache(s, cut, k_rule)).first;
  const NearCache& near = cached->second;
  out.pieces = makePieces(s, cut, k);
  out.piece_data = pieceData(s, out.pieces, data);
  const BigTriangles big = bigTriangles(s, out.pieces, k);
  const size_t n = cut.nodes.size(), rhs = data.size();
  chief = std::min(chief, s.chief_candidates.size());
  if (chief == 0 && n > options.direct_max_elements && options.hierarchical)
    return solveHierarchical(s, data, k, near, big, std::move(out), assembly_start, parts, options);
  const size_t rows = n + chief;
  const auto R = static_cast<Eigen::Index>(rhs);
  Eigen::MatrixXcd A = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(n));
  Eigen::MatrixXcd b(static_cast<Eigen::Index>(rows), R);
  // Each row depends on its collocation point alone, so the two halves (always the same halves)
  // may be assembled at once, each with its own scratch, into rows of A and b the other never
  // touches: the same bits with or without the helper thread.
  std::array<RowScratch, 2> scratch;
  parts.run(rows, rows / 2, [&](size_t begin, size_t end, int part) {
    RowScratch& stack = scratch[static_cast<size_t>(part)];
    std::vector<cd> M(n), lq(rhs);
    for (size_t r = begin; r < end; ++r) {
      std::fill(M.begin(), M.end(), cd(0.0));
      std::fill(lq.begin(), lq.end(), cd(0.0));
      if (r < n) {
        const uint32_t host = s.nodes[cut.nodes[r]].rep;
        assembleRow(s, cut, out.pieces, out.piece_data, big, data, near, r, k, s.tris[host].centroid, M.data(),
                    lq.data(), stack);
      } else {
        assembleRow(s, cut, out.pieces, out.piece_data, big, data, near, r, k, s.chief_candidates[r - n], M.data(),
                    lq.data(), stack);
      }
      // 1/2 p(x) - int p dG/dn = - int G q (x on S); 0 - int p dG/dn = - int G q (x inside).
      for (size_t c = 0; c < n; ++c) A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = -M[c];
      if (r < n) A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(r)) += 0.5;
      for (size_t q = 0; q < rhs; ++q) b(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(q)) = -lq[q];
    }
  });
  // The fine and the coarse solve run side by side (below): an iterative one's products stay on
  // its own thread.
  std::array<IterativeReport, 2> reports;
  auto solve = [&](const Eigen::MatrixXcd& matrix, const Eigen::MatrixXcd& rhs_m, int which) -> Eigen::MatrixXcd {
    if (matrix.rows() != matrix.cols()) return solveLeastSquares(matrix, rhs_m);
    if (static_cast<size_t>(matrix.rows()) <= options.direct_max_elements) return solveSquare(matrix, rhs_m);
    TwoParts one_thread(false);
    return solveGmres(matrix, rhs_m, options.iterative_tolerance, 2000, one_thread,
                      &reports[static_cast<size_t>(which)]);
  };
  out.assembly_seconds = secondsSince(assembly_start);
  const auto factor_start = std::chrono::steady_clock::now();
  // The coarse solve: clusters merged with their siblings, rows a subset, columns summed. It
  // reads A and b only, so it runs beside the fine solve, on the helper thread (each solve is
  // the same whoever computes it: the same bits with or without the helper).
  const Coarse coarse = coarsen(s, cut);
  const size_t nc = coarse.count;
  const bool coarse_solve = nc < n && nc > 0;
  Eigen::MatrixXcd P, pc;
  parts.run(size_t{2}, size_t{1}, [&](size_t begin, size_t, int) {
    if (begin == 0) {
      P = solve(A, b, 0);
      return;
    }
    if (!coarse_solve) return;
    Eigen::MatrixXcd Ac = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(nc + chief), static_cast<Eigen::Index>(nc));
    Eigen::MatrixXcd bc(static_cast<Eigen::Index>(nc + chief), R);
    for (size_t j = 0; j < nc + chief; ++j) {
      const size_t fine_row = j < nc ? static_cast<size_t>(coarse.row_cluster[j]) : n + (j - nc);
      for (size_t c = 0; c < n; ++c) {
        cd m = A(static_cast<Eigen::Index>(fine_row), static_cast<Eigen::Index>(c));
        if (fine_row < n && c == fine_row) m -= 0.5;  // the free term goes to the coarse diagonal
        Ac(static_cast<Eigen::Index>(j), coarse.of_cluster[c]) += m;
      }
      if (j < nc) Ac(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)) += 0.5;
      bc.row(static_cast<Eigen::Index>(j)) = b.row(static_cast<Eigen::Index>(fine_row));
    }
    pc = solve(Ac, bc, 1);
  });
  out.iterations = reports[0].iterations;
  out.elements = n;
  out.chief = chief;
  out.p.resize(rhs);
  out.p_diff.resize(rhs);
  for (size_t q = 0; q < rhs; ++q) out.p[q] = P.col(static_cast<Eigen::Index>(q));
  if (coarse_solve) {
    for (size_t q = 0; q < rhs; ++q) {
      out.p_diff[q].resize(static_cast<Eigen::Index>(n));
      for (size_t c = 0; c < n; ++c)
        out.p_diff[q][static_cast<Eigen::Index>(c)] =
            out.p[q][static_cast<Eigen::Index>(c)] - pc(coarse.of_cluster[c], static_cast<Eigen::Index>(q));
    }
  } else {
    for (size_t q = 0; q < rhs; ++q) out.p_diff[q] = Eigen::VectorXcd::Zero(static_cast<Eigen::Index>(n));
  }
  out.factor_seconds = secondsSince(factor_start);
  out.matrix_bytes = static_cast<size_t>(A.size()) * sizeof(cd);
  return out;
}

}  // namespace strike::transfer
