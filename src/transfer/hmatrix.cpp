// SPDX-License-Identifier: MIT
// The hierarchical collocation matrix: block tree, adaptive cross approximation with partial
// pivoting (Bebendorf 2000, alg. of sec. 3; Rjasanow & Steinbach 2007, alg. 3.5), products.
#include "hmatrix.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "assembly.hpp"

namespace strike::transfer {

namespace {

double norm2(cd z) { return z.real() * z.real() + z.imag() * z.imag(); }

/// 1 / z without libm (the same bits everywhere).
cd inverse(cd z) {
  const double d = norm2(z);
  return {z.real() / d, -z.imag() / d};
}

/// The clusters under each node at or above the cut: [first, last) (cutAt numbers them depth
/// first, left before right, so they are consecutive).
struct ClusterRanges {
  std::vector<int32_t> first, last;
  std::vector<char> leaf;  // a leaf of the cluster tree: a cut node, or few enough clusters
};

ClusterRanges clusterRanges(const Surface& s, const Cut& cut, size_t leaf_clusters) {
  ClusterRanges r;
  const size_t count = s.nodes.size();
  r.first.assign(count, -1);
  r.last.assign(count, -1);
  r.leaf.assign(count, 0);
  for (size_t i = count; i-- > 0;) {
    const int32_t c = cut.cluster_of_node[i];
    if (c >= 0) {
      if (cut.nodes[static_cast<size_t>(c)] == static_cast<int32_t>(i)) {
        r.first[i] = c;
        r.last[i] = c + 1;
        r.leaf[i] = 1;
      }
      continue;
    }
    const Node& n = s.nodes[i];
    r.first[i] = r.first[static_cast<size_t>(n.left)];
    r.last[i] = r.last[static_cast<size_t>(n.right)];
    r.leaf[i] = static_cast<size_t>(r.last[i] - r.first[i]) <= leaf_clusters ? 1 : 0;
  }
  return r;
}

/// Axis-aligned bounding boxes of the nodes (of their triangles' corners).
struct Boxes {
  std::vector<V3> lo, hi;
};

Boxes boundingBoxes(const Surface& s) {
  Boxes b;
  const size_t count = s.nodes.size();
  b.lo.assign(count, V3::Constant(1e300));
  b.hi.assign(count, V3::Constant(-1e300));
  for (size_t i = count; i-- > 0;) {
    const Node& n = s.nodes[i];
    if (n.leaf()) {
      for (const V3& v : s.tris[s.order[n.begin]].v) {
        b.lo[i] = b.lo[i].cwiseMin(v);
        b.hi[i] = b.hi[i].cwiseMax(v);
      }
      continue;
    }
    b.lo[i] = b.lo[static_cast<size_t>(n.left)].cwiseMin(b.lo[static_cast<size_t>(n.right)]);
    b.hi[i] = b.hi[static_cast<size_t>(n.left)].cwiseMax(b.hi[static_cast<size_t>(n.right)]);
  }
  return b;
}

/// Well separated [Hackbusch 2015, sec. 5.2; Rjasanow & Steinbach 2007, sec. 3.2]: the smaller
/// box's diagonal at most eta times the distance between the boxes, and no triangle of the
/// columns near any collocation point of the rows (nearLeaf: within kFarRatio longest edges of
/// its centroid, both inside the boxes), so that no entry of the block comes from the near
/// quadrature.
bool admissible(const Boxes& boxes, const Node& cols, size_t a, size_t b, double eta) {
  double gap2 = 0.0;
  for (int d = 0; d < 3; ++d) {
    const double g = std::max({0.0, boxes.lo[a][d] - boxes.hi[b][d], boxes.lo[b][d] - boxes.hi[a][d]});
    gap2 += g * g;
  }
  const double gap = std::sqrt(gap2);
  const double diam_a = (boxes.hi[a] - boxes.lo[a]).norm(), diam_b = (boxes.hi[b] - boxes.lo[b]).norm();
  if (!(std::min(diam_a, diam_b) <= eta * gap)) return false;
  return gap > 1.001 * kFarRatio * cols.max_edge;
}

struct BlockSpec {
  int32_t row_node, col_node;
  bool admissible;
};

void buildBlocks(const Surface& s, const Boxes& boxes, const ClusterRanges& r, int32_t a, int32_t b, double eta,
                 std::vector<BlockSpec>& out) {
  const Node& na = s.nodes[static_cast<size_t>(a)];
  const Node& nb = s.nodes[static_cast<size_t>(b)];
  if (a != b && admissible(boxes, nb, static_cast<size_t>(a), static_cast<size_t>(b), eta)) {
    out.push_back({a, b, true});
    return;
  }
  const bool leaf_a = r.leaf[static_cast<size_t>(a)] != 0, leaf_b = r.leaf[static_cast<size_t>(b)] != 0;
  if (leaf_a && leaf_b) {
    out.push_back({a, b, false});
    return;
  }
  if (leaf_a) {
    buildBlocks(s, boxes, r, a, nb.left, eta, out);
    buildBlocks(s, boxes, r, a, nb.right, eta, out);
  } else if (leaf_b) {
    buildBlocks(s, boxes, r, na.left, b, eta, out);
    buildBlocks(s, boxes, r, na.right, b, eta, out);
  } else {
    for (int32_t x : {na.left, na.right})
      for (int32_t y : {nb.left, nb.right}) buildBlocks(s, boxes, r, x, y, eta, out);
  }
}

/// What a block's computation needs, per thread.
struct Worker {
  const Surface& s;
  const Cut& cut;
  const Pieces& pieces;
  const PieceData& piece_data;
  const BigTriangles& big;
  const std::vector<size_t>& piece_begin;
  const std::vector<NodeData>& data;
  const NearCache& near;
  double k;
  std::vector<double> q_max;  // per right-hand side: max |q| over the triangles
  RowScratch w;
  std::vector<cd> M, lq;

  V3 point(size_t row) const { return s.tris[s.nodes[static_cast<size_t>(cut.nodes[row])].rep].centroid; }

  /// Row `row`'s entries M[j] for j in [cb, ce), and lq = sum_j int_j G q; `near`: from the near
  /// cache for its near triangles (false: the columns hold none).
  void rowEntries(size_t row, size_t cb, size_t ce, bool with_near) {
    for (size_t j = cb; j < ce; ++j) M[j] = 0.0;
    std::fill(lq.begin(), lq.end(), cd(0.0));
    const RowRange range = rowRange(big, piece_begin, cb, ce, with_near);
    assembleRowRange(s, cut, pieces, piece_data, big, data, near, row, k, point(row), range, M.data(), lq.data(), w);
  }
};

/// A well-separated block by adaptive cross approximation with partial pivoting of the matrix
/// S = [-M_block, -L_1 beta_1, ..., -L_R beta_R] (L_r[i][j] = int over cluster j of G q_r, beta_r
/// scaling it to the size of M's entries; `distance` between the blocks' centroids), until the new cross is within the tolerance of the
/// approximation's Frobenius norm. Falls back to the dense block when the rank would hold more
/// than the dense values. Returns false then (the caller computes it densely).
bool crossApproximation(Worker& wk, HBlock& blk, double distance, double tolerance, std::vector<cd>& rhs_part) {
  const size_t m = blk.rows(), n = blk.cols(), rhs = wk.data.size(), width = n * (1 + rhs);
  const size_t max_rank = std::max<size_t>(1, (m * n) / (m + n));
  std::vector<cd> U, V;  // m x rank, width x rank (column-major)
  // M's entries are ~ area / (4 pi d^2) (times the cosine between the normal and the line to x,
  // which vanishes between coplanar clusters), L_r's ~ area |q_r| / (4 pi d): scaled by
  // 1 / (max |q_r| d), L_r weighs in the approximation as a non-coplanar M would, whatever M's
  // own size (a flat face's M is zero, its L is not).
  std::vector<double> beta(rhs, 1.0);
  for (size_t r = 0; r < rhs; ++r)
    if (wk.q_max[r] > 0 && distance > 0) beta[r] = 1.0 / (wk.q_max[r] * distance);
  std::vector<char> row_used(m, 0);
  std::vector<cd> row(width), col(m), lq_cluster(n * rhs);
  // Columns are computed for a cluster at once (its M and L_r): keep them for a later pivot.
  std::map<size_t, std::vector<cd>> columns;  // cluster -> m x (1 + rhs)
  auto stackedRow = [&](size_t i) {
    for (size_t j = 0; j < n; ++j) {  // one cluster at a time: L_r per cluster
      wk.rowEntries(blk.row_begin + i, blk.col_begin + j, blk.col_begin + j + 1, false);
      for (size_t r = 0; r < rhs; ++r) lq_cluster[r * n + j] = wk.lq[r];
    }
    for (size_t j = 0; j < n; ++j) row[j] = -wk.M[blk.col_begin + j];
    for (size_t r = 0; r < rhs; ++r)
      for (size_t j = 0; j < n; ++j) row[(r + 1) * n + j] = -lq_cluster[r * n + j] * beta[r];
  };
  auto stackedColumn = [&](size_t jw) {
    const size_t j = jw % n, which = jw / n;
    auto found = columns.find(j);
    if (found == columns.end()) {
      std::vector<cd> values(m * (1 + rhs));
      const size_t cluster = blk.col_begin + j;
      for (size_t i = 0; i < m; ++i) {
        wk.rowEntries(blk.row_begin + i, cluster, cluster + 1, false);
        values[i] = -wk.M[cluster];
        for (size_t r = 0; r < rhs; ++r) values[(r + 1) * m + i] = -wk.lq[r] * beta[r];
      }
      found = columns.emplace(j, std::move(values)).first;
    }
    std::copy(found->second.begin() + static_cast<std::ptrdiff_t>(which * m),
              found->second.begin() + static_cast<std::ptrdiff_t>((which + 1) * m), col.begin());
  };
  double approx_norm2 = 0.0;
  size_t rank = 0, next_row = 0;
  while (true) {
    if (rank >= max_rank) return false;
    row_used[next_row] = 1;
    stackedRow(next_row);
    for (size_t l = 0; l < rank; ++l) {
      const cd ul = U[l * m + next_row];
      for (size_t j = 0; j < width; ++j) row[j] -= ul * V[l * width + j];
    }
    size_t pivot = 0;
    double best = -1.0;
    for (size_t j = 0; j < width; ++j)
      if (norm2(row[j]) > best) {
        best = norm2(row[j]);
        pivot = j;
      }
    if (!(best > 0)) {
      // A row already approximated exactly: try the next unused one.
      size_t i = 0;
      while (i < m && row_used[i]) ++i;
      if (i == m) break;
      next_row = i;
      continue;
    }
    const cd scale = inverse(row[pivot]);
    for (size_t j = 0; j < width; ++j) row[j] *= scale;
    stackedColumn(pivot);
    for (size_t l = 0; l < rank; ++l) {
      const cd vl = V[l * width + pivot];
      for (size_t i = 0; i < m; ++i) col[i] -= vl * U[l * m + i];
    }
    // |S_k|^2 = |S_(k-1)|^2 + 2 Re sum_l (u_l^H u)(v_l^H v) + |u|^2 |v|^2.
    double u2 = 0.0, v2 = 0.0;
    for (size_t i = 0; i < m; ++i) u2 += norm2(col[i]);
    for (size_t j = 0; j < width; ++j) v2 += norm2(row[j]);
    double cross = 0.0;
    for (size_t l = 0; l < rank; ++l) {
      cd uu = 0.0, vv = 0.0;
      for (size_t i = 0; i < m; ++i) uu += std::conj(U[l * m + i]) * col[i];
      for (size_t j = 0; j < width; ++j) vv += std::conj(V[l * width + j]) * row[j];
      cross += (uu * vv).real();
    }
    approx_norm2 += 2.0 * cross + u2 * v2;
    U.insert(U.end(), col.begin(), col.end());
    V.insert(V.end(), row.begin(), row.end());
    ++rank;
    if (u2 * v2 <= tolerance * tolerance * approx_norm2) break;
    // Next row: the largest of the new column among the rows not used yet.
    best = -1.0;
    size_t choice = m;
    for (size_t i = 0; i < m; ++i)
      if (!row_used[i] && norm2(col[i]) > best) {
        best = norm2(col[i]);
        choice = i;
      }
    if (choice == m) break;
    next_row = choice;
  }
  blk.low_rank = true;
  blk.rank = static_cast<uint32_t>(rank);
  blk.u = std::move(U);
  blk.v.assign(n * rank, cd(0.0));
  for (size_t l = 0; l < rank; ++l)
    for (size_t j = 0; j < n; ++j) blk.v[j * rank + l] = V[l * width + j];
  // b's part: - sum_j L_r = sum_l u_l (sum_j v_l[(r + 1) n + j]) / beta_r.
  rhs_part.assign(m * rhs, cd(0.0));
  for (size_t r = 0; r < rhs; ++r) {
    std::vector<cd> t(rank, cd(0.0));
    for (size_t l = 0; l < rank; ++l) {
      cd sum = 0.0;
      for (size_t j = 0; j < n; ++j) sum += V[l * width + (r + 1) * n + j];
      t[l] = sum / beta[r];
    }
    for (size_t i = 0; i < m; ++i) {
      cd sum = 0.0;
      for (size_t l = 0; l < rank; ++l) sum += blk.u[l * m + i] * t[l];
      rhs_part[r * m + i] = sum;
    }
  }
  return true;
}

}  // namespace

void HMatrix::multiply(const std::vector<cd>& x, std::vector<cd>& y) const {
  y.assign(n, cd(0.0));
  std::vector<double> t_re, t_im;
  std::vector<cd> gathered;
  for (const HBlock& blk : blocks) {
    const size_t m = blk.rows(), c = blk.cols();
    const cd* xs = x.data() + blk.col_begin;
    if (!blk.col_index.empty()) {
      gathered.resize(c);
      for (size_t j = 0; j < c; ++j) gathered[j] = x[blk.col_index[j]];
      xs = gathered.data();
    }
    auto add = [&](const double* re, const double* im) {
      if (blk.row_index.empty())
        for (size_t i = 0; i < m; ++i) y[blk.row_begin + i] += cd(re[i], im[i]);
      else
        for (size_t i = 0; i < m; ++i) y[blk.row_index[i]] += cd(re[i], im[i]);
    };
    if (!blk.low_rank) {
      // Column by column (contiguous), each row's sum in column order.
      t_re.assign(m, 0.0);
      t_im.assign(m, 0.0);
      double* __restrict acc_re = t_re.data();
      double* __restrict acc_im = t_im.data();
      for (size_t j = 0; j < c; ++j) {
        const cd* a = blk.dense.data() + j * m;
        const double x_re = xs[j].real(), x_im = xs[j].imag();
        for (size_t i = 0; i < m; ++i) {
          acc_re[i] += a[i].real() * x_re - a[i].imag() * x_im;
          acc_im[i] += a[i].real() * x_im + a[i].imag() * x_re;
        }
      }
      add(acc_re, acc_im);
      continue;
    }
    // Low rank: t = v^T x walked by columns j (each t_l's sum in j order), then y += u t
    // walked by the rank's columns (each row's sum in l order): contiguous, vectorizable.
    const size_t rank = blk.rank;
    t_re.assign(rank + m, 0.0);
    t_im.assign(rank + m, 0.0);
    {
      double* __restrict acc_re = t_re.data();
      double* __restrict acc_im = t_im.data();
      for (size_t j = 0; j < c; ++j) {
        const cd* v = blk.v.data() + j * rank;
        const double x_re = xs[j].real(), x_im = xs[j].imag();
        for (size_t l = 0; l < rank; ++l) {
          acc_re[l] += v[l].real() * x_re - v[l].imag() * x_im;
          acc_im[l] += v[l].real() * x_im + v[l].imag() * x_re;
        }
      }
    }
    {
      const double* __restrict tr = t_re.data();
      const double* __restrict ti = t_im.data();
      double* __restrict acc_re = t_re.data() + rank;
      double* __restrict acc_im = t_im.data() + rank;
      for (size_t l = 0; l < rank; ++l) {
        const cd* u = blk.u.data() + l * m;
        const double t_r = tr[l], t_i = ti[l];
        for (size_t i = 0; i < m; ++i) {
          acc_re[i] += u[i].real() * t_r - u[i].imag() * t_i;
          acc_im[i] += u[i].real() * t_i + u[i].imag() * t_r;
        }
      }
      add(acc_re, acc_im);
    }
  }
}

std::vector<cd> HMatrix::diagonal() const {
  std::vector<cd> d(n, cd(0.0));
  std::vector<int32_t> col_at(n, -1);  // a column's place in the block
  for (const HBlock& blk : blocks) {
    const size_t m = blk.rows(), c = blk.cols();
    auto row = [&](size_t i) { return blk.row_index.empty() ? blk.row_begin + i : size_t{blk.row_index[i]}; };
    auto col = [&](size_t j) { return blk.col_index.empty() ? blk.col_begin + j : size_t{blk.col_index[j]}; };
    for (size_t j = 0; j < c; ++j) col_at[col(j)] = static_cast<int32_t>(j);
    for (size_t i = 0; i < m; ++i) {
      const int32_t j = col_at[row(i)];
      if (j < 0) continue;
      const auto jj = static_cast<size_t>(j);
      if (!blk.low_rank) {
        d[row(i)] += blk.dense[i + jj * m];
        continue;
      }
      cd sum = 0.0;
      for (size_t l = 0; l < blk.rank; ++l) sum += blk.u[l * m + i] * blk.v[jj * blk.rank + l];
      d[row(i)] += sum;
    }
    for (size_t j = 0; j < c; ++j) col_at[col(j)] = -1;
  }
  return d;
}

HMatrix HMatrix::restricted(const std::vector<int32_t>& rows, const std::vector<int32_t>& column_of,
                            size_t columns) const {
  HMatrix out;
  out.n = rows.size();
  std::vector<int32_t> row_of(n, -1);
  for (size_t j = 0; j < rows.size(); ++j) row_of[static_cast<size_t>(rows[j])] = static_cast<int32_t>(j);
  std::vector<int32_t> place(columns, -1);
  for (const HBlock& blk : blocks) {
    HBlock r;
    std::vector<uint32_t> local_rows;
    for (size_t i = blk.row_begin; i < blk.row_end; ++i)
      if (row_of[i] >= 0) {
        r.row_index.push_back(static_cast<uint32_t>(row_of[i]));
        local_rows.push_back(static_cast<uint32_t>(i - blk.row_begin));
      }
    if (local_rows.empty()) continue;
    std::vector<uint32_t> local_col(blk.cols());  // fine column -> its place among r's columns
    for (size_t j = blk.col_begin; j < blk.col_end; ++j) {
      const auto to = static_cast<size_t>(column_of[j]);
      if (place[to] < 0) {
        place[to] = static_cast<int32_t>(r.col_index.size());
        r.col_index.push_back(static_cast<uint32_t>(to));
      }
      local_col[j - blk.col_begin] = static_cast<uint32_t>(place[to]);
    }
    for (uint32_t to : r.col_index) place[to] = -1;
    const size_t m = blk.rows(), mr = local_rows.size(), cr = r.col_index.size();
    r.low_rank = blk.low_rank;
    if (!blk.low_rank) {
      r.dense.assign(mr * cr, cd(0.0));
      for (size_t j = 0; j < blk.cols(); ++j)
        for (size_t i = 0; i < mr; ++i) r.dense[i + local_col[j] * mr] += blk.dense[local_rows[i] + j * m];
    } else {
      r.rank = blk.rank;
      r.u.resize(mr * blk.rank);
      for (size_t l = 0; l < blk.rank; ++l)
        for (size_t i = 0; i < mr; ++i) r.u[l * mr + i] = blk.u[l * m + local_rows[i]];
      r.v.assign(cr * blk.rank, cd(0.0));
      for (size_t j = 0; j < blk.cols(); ++j)
        for (size_t l = 0; l < blk.rank; ++l) r.v[local_col[j] * blk.rank + l] += blk.v[j * blk.rank + l];
    }
    out.blocks.push_back(std::move(r));
  }
  return out;
}

size_t HMatrix::bytes() const {
  size_t total = 0;
  for (const HBlock& blk : blocks)
    total += (blk.dense.size() + blk.u.size() + blk.v.size()) * sizeof(cd) +
             (blk.row_index.size() + blk.col_index.size()) * sizeof(uint32_t);
  return total;
}

size_t HMatrix::lowRankBlocks() const {
  size_t count = 0;
  for (const HBlock& blk : blocks) count += blk.low_rank ? 1 : 0;
  return count;
}

HSystem assembleHSystem(const Surface& s, const Cut& cut, const Pieces& pieces, const PieceData& piece_data,
                        const BigTriangles& big, const std::vector<NodeData>& data, const NearCache& near, double k,
                        const HMatrixOptions& options, TwoParts& parts) {
  HSystem out;
  const size_t n = cut.nodes.size(), rhs = data.size();
  out.A.n = n;
  out.rhs = rhs;
  const ClusterRanges ranges = clusterRanges(s, cut, options.leaf_clusters);
  std::vector<BlockSpec> specs;
  const Boxes boxes = boundingBoxes(s);
  buildBlocks(s, boxes, ranges, 0, 0, options.eta, specs);
  out.A.blocks.resize(specs.size());
  std::vector<std::vector<cd>> rhs_parts(specs.size());
  // The two halves of the blocks by their forecast cost (entries computed), a cut that depends
  // on the block tree alone.
  std::vector<double> cost(specs.size());
  double total_cost = 0.0;
  for (size_t b = 0; b < specs.size(); ++b) {
    HBlock& blk = out.A.blocks[b];
    const auto rn = static_cast<size_t>(specs[b].row_node), cn = static_cast<size_t>(specs[b].col_node);
    blk.row_begin = static_cast<uint32_t>(ranges.first[rn]);
    blk.row_end = static_cast<uint32_t>(ranges.last[rn]);
    blk.col_begin = static_cast<uint32_t>(ranges.first[cn]);
    blk.col_end = static_cast<uint32_t>(ranges.last[cn]);
    const double m = static_cast<double>(blk.rows()), c = static_cast<double>(blk.cols());
    cost[b] = specs[b].admissible ? std::min(m * c, 16.0 * (m + c)) : 0.0;
    total_cost += cost[b];
  }
  size_t split = 0;
  for (double acc = 0.0; split < specs.size() && acc < 0.5 * total_cost; ++split) acc += cost[split];
  const std::vector<size_t> piece_begin = pieceBegin(pieces, n);
  std::vector<double> q_max(rhs, 0.0);
  for (size_t r = 0; r < rhs; ++r)
    for (double q : data[r].q) q_max[r] = std::max(q_max[r], std::abs(q));
  auto worker = [&] {
    return Worker{s,
                  cut,
                  pieces,
                  piece_data,
                  big,
                  piece_begin,
                  data,
                  near,
                  k,
                  q_max,
                  {},
                  std::vector<cd>(n),
                  std::vector<cd>(rhs)};
  };
  std::array<Worker, 2> workers{worker(), worker()};
  // The well-separated blocks first (a block whose rank would hold more than its dense values
  // becomes dense).
  std::vector<char> dense(specs.size(), 1);
  parts.run(specs.size(), split, [&](size_t begin, size_t end, int part) {
    Worker& wk = workers[static_cast<size_t>(part)];
    for (size_t b = begin; b < end; ++b)
      if (specs[b].admissible && crossApproximation(wk, out.A.blocks[b],
                                                    (s.nodes[static_cast<size_t>(specs[b].row_node)].centroid -
                                                     s.nodes[static_cast<size_t>(specs[b].col_node)].centroid)
                                                        .norm(),
                                                    options.aca_tolerance, rhs_parts[b]))
        dense[b] = 0;
  });
  // The dense blocks row by row: each row's columns in all its dense blocks at once (one pass
  // over its near quadrature), the blocks in their order; b's dense part per row.
  std::vector<std::vector<uint32_t>> row_blocks(n);
  std::vector<double> row_cost(n, 0.0);
  double dense_cost = 0.0;
  for (size_t b = 0; b < specs.size(); ++b) {
    if (!dense[b]) continue;
    HBlock& blk = out.A.blocks[b];
    blk.low_rank = false;
    blk.dense.assign(blk.rows() * blk.cols(), cd(0.0));
    for (size_t i = blk.row_begin; i < blk.row_end; ++i) {
      row_blocks[i].push_back(static_cast<uint32_t>(b));
      row_cost[i] += static_cast<double>(blk.cols());
    }
    dense_cost += static_cast<double>(blk.rows() * blk.cols());
  }
  size_t row_split = 0;
  for (double acc = 0.0; row_split < n && acc < 0.5 * dense_cost; ++row_split) acc += row_cost[row_split];
  std::vector<cd> dense_rhs(n * rhs, cd(0.0));
  parts.run(n, row_split, [&](size_t begin, size_t end, int part) {
    Worker& wk = workers[static_cast<size_t>(part)];
    std::vector<RowRange> row_ranges;
    for (size_t i = begin; i < end; ++i) {
      row_ranges.clear();
      for (uint32_t b : row_blocks[i]) {
        const HBlock& blk = out.A.blocks[b];
        row_ranges.push_back(rowRange(big, piece_begin, blk.col_begin, blk.col_end, true));
        for (size_t j = blk.col_begin; j < blk.col_end; ++j) wk.M[j] = 0.0;
      }
      std::fill(wk.lq.begin(), wk.lq.end(), cd(0.0));
      assembleRowRanges(s, cut, pieces, piece_data, big, data, near, i, k, wk.point(i), row_ranges.data(),
                        row_ranges.size(), wk.M.data(), wk.lq.data(), wk.w);
      for (uint32_t b : row_blocks[i]) {
        HBlock& blk = out.A.blocks[b];
        const size_t m = blk.rows(), local = i - blk.row_begin;
        for (size_t j = blk.col_begin; j < blk.col_end; ++j) blk.dense[local + (j - blk.col_begin) * m] = -wk.M[j];
        if (i >= blk.col_begin && i < blk.col_end) blk.dense[local + (i - blk.col_begin) * m] += 0.5;
      }
      for (size_t r = 0; r < rhs; ++r) dense_rhs[r * n + i] = -wk.lq[r];
    }
  });
  // b: the dense part, then the low-rank blocks' in their order.
  out.b = std::move(dense_rhs);
  for (size_t b = 0; b < specs.size(); ++b) {
    if (dense[b]) continue;
    const HBlock& blk = out.A.blocks[b];
    const size_t m = blk.rows();
    for (size_t r = 0; r < rhs; ++r)
      for (size_t i = 0; i < m; ++i) out.b[r * n + blk.row_begin + i] += rhs_parts[b][r * m + i];
  }
  return out;
}

}  // namespace strike::transfer
