// SPDX-License-Identifier: MIT
// Assembly of the linear-elastic stiffness K and consistent mass M for Tet4 and Tet10.
//
// Element integrals follow Zienkiewicz, Taylor & Zhu, "The Finite Element Method", vol. 1,
// 7th ed., ch. 6 (isoparametric tets) and Hughes, "The Finite Element Method" (2000), ch. 2:
//   K_ij = int lambda g_i g_j^T + mu g_j g_i^T + mu (g_i . g_j) I dV,   g = grad N,
//   M_ij = rho int N_i N_j dV I,
// with lambda, mu the Lame constants. Tet10 is isoparametric, so curved (Gmsh) tets are handled;
// on straight-edged tets the 4-point rule integrates K exactly and the 14-point rule M exactly.
//
// Why a precomputed pattern instead of triplets: for 150k tets, triplets are ~2.4M (Tet4) to
// ~15M (Tet10) 3x3 blocks to sort and sum; the node-adjacency pattern is built once, shared
// by K and M, and element blocks are added in place (one binary search per node pair).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Dense>

#include "quadrature.hpp"
#include "strike/fem/fem.hpp"

namespace strike {

namespace {

using SpMat = Eigen::SparseMatrix<double>;

/// Node adjacency in CSR form (each list sorted, self included) and the DOF matrix layout
/// derived from it: column 3n+a holds rows 3m+b for m in adj(n), b = 0..2, in that order.
struct Pattern {
  std::vector<int> node_ptr;
  std::vector<int> node_adj;
  int64_t nnz = 0;
};

Pattern buildPattern(const TetMesh& mesh) {
  const int num_nodes = static_cast<int>(mesh.nodes.rows());
  const int64_t num_tets = mesh.tets.rows();
  const int npe = static_cast<int>(mesh.tets.cols());
  Pattern p;
  // Upper bound per node (npe per incident element), then fill, sort, unique and compact.
  std::vector<int64_t> bound(static_cast<size_t>(num_nodes) + 1, 0);
  for (int64_t t = 0; t < num_tets; ++t) {
    for (int i = 0; i < npe; ++i) bound[static_cast<size_t>(mesh.tets(t, i)) + 1] += npe;
  }
  for (int n = 0; n < num_nodes; ++n) bound[n + 1] += bound[n];
  std::vector<int> scratch(static_cast<size_t>(bound[num_nodes]));
  std::vector<int64_t> fill(bound.begin(), bound.end() - 1);
  for (int64_t t = 0; t < num_tets; ++t) {
    for (int i = 0; i < npe; ++i) {
      const int n = mesh.tets(t, i);
      for (int j = 0; j < npe; ++j) scratch[static_cast<size_t>(fill[n]++)] = mesh.tets(t, j);
    }
  }
  p.node_ptr.assign(static_cast<size_t>(num_nodes) + 1, 0);
  p.node_adj.reserve(scratch.size() / 4);
  for (int n = 0; n < num_nodes; ++n) {
    auto first = scratch.begin() + bound[n];
    auto last = scratch.begin() + bound[n + 1];
    std::sort(first, last);
    last = std::unique(first, last);
    // A node used by no tet still gets its diagonal so that the matrix has no empty column.
    if (first == last) p.node_adj.push_back(n);
    p.node_adj.insert(p.node_adj.end(), first, last);
    p.node_ptr[n + 1] = static_cast<int>(p.node_adj.size());
  }
  p.nnz = 9 * static_cast<int64_t>(p.node_adj.size());
  return p;
}

/// Allocates a compressed 3N x 3N matrix with the pattern's structure and zero values.
void allocate(const Pattern& p, SpMat& A) {
  const int num_nodes = static_cast<int>(p.node_ptr.size()) - 1;
  A = SpMat(3 * num_nodes, 3 * num_nodes);
  A.resizeNonZeros(static_cast<Eigen::Index>(p.nnz));
  int* outer = A.outerIndexPtr();
  int* inner = A.innerIndexPtr();
  for (int n = 0; n < num_nodes; ++n) {
    const int begin = p.node_ptr[n];
    const int deg = p.node_ptr[n + 1] - begin;
    for (int a = 0; a < 3; ++a) {
      const int col_start = 9 * begin + 3 * deg * a;
      outer[3 * n + a] = col_start;
      for (int k = 0; k < deg; ++k) {
        for (int b = 0; b < 3; ++b) inner[col_start + 3 * k + b] = 3 * p.node_adj[begin + k] + b;
      }
    }
  }
  outer[3 * num_nodes] = static_cast<int>(p.nnz);
  std::fill(A.valuePtr(), A.valuePtr() + p.nnz, 0.0);
}

/// Index into the value array of row 3*row_node, column 3*col_node (add 3*deg*a + b for the
/// component pair (b row, a column)).
inline int64_t blockOffset(const Pattern& p, int row_node, int col_node) {
  const int* first = p.node_adj.data() + p.node_ptr[col_node];
  const int* last = p.node_adj.data() + p.node_ptr[col_node + 1];
  const int k = static_cast<int>(std::lower_bound(first, last, row_node) - first);
  return 9 * static_cast<int64_t>(p.node_ptr[col_node]) + 3 * k;
}

/// Shape function gradients with respect to (xi, eta, zeta) at barycentric point L, and
/// shape function values. Tet10 corners N_i = L_i (2 L_i - 1), mid-edge N = 4 L_a L_b.
constexpr int kTet10Edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
const Eigen::Vector3d kDL[4] = {Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                Eigen::Vector3d(0, 0, 1)};

void tet10Shape(const std::array<double, 4>& L, double N[10], Eigen::Matrix<double, 3, 10>& dN) {
  for (int i = 0; i < 4; ++i) {
    N[i] = L[i] * (2.0 * L[i] - 1.0);
    dN.col(i) = (4.0 * L[i] - 1.0) * kDL[i];
  }
  for (int e = 0; e < 6; ++e) {
    const int a = kTet10Edges[e][0];
    const int b = kTet10Edges[e][1];
    N[4 + e] = 4.0 * L[a] * L[b];
    dN.col(4 + e) = 4.0 * (L[b] * kDL[a] + L[a] * kDL[b]);
  }
}

struct Lame {
  double lambda;
  double mu;
};

Lame lameConstants(const Material& m) {
  const double nu = m.poisson;
  return {m.youngs_pa * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), m.youngs_pa / (2.0 * (1.0 + nu))};
}

/// Adds w * [lambda g_i g_j^T + mu g_j g_i^T + mu (g_i . g_j) I] for all node pairs to Ke.
template <int Npe>
void addStiffness(const Eigen::Matrix<double, 3, Npe>& g, double w, const Lame& lame,
                  Eigen::Matrix<double, 3 * Npe, 3 * Npe>& Ke) {
  for (int j = 0; j < Npe; ++j) {
    for (int i = 0; i < Npe; ++i) {
      Eigen::Matrix3d block =
          (w * lame.lambda) * g.col(i) * g.col(j).transpose() + (w * lame.mu) * g.col(j) * g.col(i).transpose();
      block.diagonal().array() += w * lame.mu * g.col(i).dot(g.col(j));
      Ke.template block<3, 3>(3 * i, 3 * j) += block;
    }
  }
}

/// Element stiffness; returns false for a degenerate or inverted element.
template <int Npe>
bool elementStiffness(const TetMesh& mesh, int64_t t, const Lame& lame, Eigen::Matrix<double, 3 * Npe, 3 * Npe>& Ke) {
  Ke.setZero();
  Eigen::Matrix<double, 3, Npe> x;
  for (int i = 0; i < Npe; ++i) x.col(i) = mesh.nodes.row(mesh.tets(t, i)).transpose();
  if constexpr (Npe == 4) {
    // Constant gradients: columns of J^{-T} applied to the barycentric gradients.
    Eigen::Matrix3d J;
    J << x.col(1) - x.col(0), x.col(2) - x.col(0), x.col(3) - x.col(0);
    const double det = J.determinant();
    if (!(det > 0.0)) return false;
    const Eigen::Matrix3d JinvT = J.inverse().transpose();
    Eigen::Matrix<double, 3, 4> g;
    for (int i = 0; i < 4; ++i) g.col(i) = JinvT * kDL[i];
    addStiffness<4>(g, det / 6.0, lame, Ke);
  } else {
    double N[10];
    Eigen::Matrix<double, 3, 10> dN;
    for (const fem::QuadPoint& q : fem::tetRuleDegree2()) {
      tet10Shape(q.bary, N, dN);
      const Eigen::Matrix3d J = x * dN.transpose();  // J(r, c) = d x_r / d xi_c
      const double det = J.determinant();
      if (!(det > 0.0)) return false;
      const Eigen::Matrix<double, 3, 10> g = J.inverse().transpose() * dN;
      addStiffness<10>(g, q.weight * det, lame, Ke);
    }
  }
  return true;
}

/// Scalar element mass rho int N_i N_j dV (the 3x3 block is this times I).
template <int Npe>
void elementMass(const TetMesh& mesh, int64_t t, double rho, Eigen::Matrix<double, Npe, Npe>& Me) {
  Eigen::Matrix<double, 3, Npe> x;
  for (int i = 0; i < Npe; ++i) x.col(i) = mesh.nodes.row(mesh.tets(t, i)).transpose();
  if constexpr (Npe == 4) {
    Eigen::Matrix3d J;
    J << x.col(1) - x.col(0), x.col(2) - x.col(0), x.col(3) - x.col(0);
    const double volume = std::abs(J.determinant()) / 6.0;
    // Exact: int L_i L_j dV = V (1 + delta_ij) / 20.
    Me.setConstant(rho * volume / 20.0);
    Me.diagonal().array() *= 2.0;
  } else {
    Me.setZero();
    double N[10];
    Eigen::Matrix<double, 3, 10> dN;
    for (const fem::QuadPoint& q : fem::tetRuleDegree5()) {
      tet10Shape(q.bary, N, dN);
      const double det = std::abs((x * dN.transpose()).determinant());
      const Eigen::Map<const Eigen::Matrix<double, 10, 1>> n(N);
      Me.noalias() += (rho * q.weight * det) * n * n.transpose();
    }
  }
}

template <int Npe>
void scatterStiffness(const TetMesh& mesh, const Pattern& p, const Material& material, double* values) {
  const Lame lame = lameConstants(material);
  Eigen::Matrix<double, 3 * Npe, 3 * Npe> Ke;
  for (int64_t t = 0; t < mesh.tets.rows(); ++t) {
    // Degenerate elements are rejected by validateAndRepair(); here they contribute nothing
    // rather than NaN (and the eigen-solve reports the resulting singularity).
    if (!elementStiffness<Npe>(mesh, t, lame, Ke)) continue;
    for (int j = 0; j < Npe; ++j) {
      const int col_node = mesh.tets(t, j);
      const int64_t deg = p.node_ptr[col_node + 1] - p.node_ptr[col_node];
      for (int i = 0; i < Npe; ++i) {
        const int64_t base = blockOffset(p, mesh.tets(t, i), col_node);
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) values[base + 3 * deg * a + b] += Ke(3 * i + b, 3 * j + a);
        }
      }
    }
  }
}

template <int Npe>
void scatterMass(const TetMesh& mesh, const Pattern& p, double rho, double* values) {
  Eigen::Matrix<double, Npe, Npe> Me;
  for (int64_t t = 0; t < mesh.tets.rows(); ++t) {
    elementMass<Npe>(mesh, t, rho, Me);
    for (int j = 0; j < Npe; ++j) {
      const int col_node = mesh.tets(t, j);
      const int64_t deg = p.node_ptr[col_node + 1] - p.node_ptr[col_node];
      for (int i = 0; i < Npe; ++i) {
        const int64_t base = blockOffset(p, mesh.tets(t, i), col_node);
        for (int a = 0; a < 3; ++a) values[base + 3 * deg * a + a] += Me(i, j);
      }
    }
  }
}

bool isTet10(const TetMesh& mesh) { return mesh.tets.cols() == 10; }

}  // namespace

void assembleStiffness(const TetMesh& mesh, const Material& material, SpMat& K) {
  const Pattern p = buildPattern(mesh);
  allocate(p, K);
  if (isTet10(mesh)) {
    scatterStiffness<10>(mesh, p, material, K.valuePtr());
  } else {
    scatterStiffness<4>(mesh, p, material, K.valuePtr());
  }
}

void assembleMass(const TetMesh& mesh, double density_kg_m3, SpMat& M) {
  const Pattern p = buildPattern(mesh);
  allocate(p, M);
  if (isTet10(mesh)) {
    scatterMass<10>(mesh, p, density_kg_m3, M.valuePtr());
  } else {
    scatterMass<4>(mesh, p, density_kg_m3, M.valuePtr());
  }
}

void assembleStiffnessAndMass(const TetMesh& mesh, const Material& material, SpMat& K, SpMat& M) {
  const Pattern p = buildPattern(mesh);
  allocate(p, K);
  allocate(p, M);
  if (isTet10(mesh)) {
    scatterStiffness<10>(mesh, p, material, K.valuePtr());
    scatterMass<10>(mesh, p, material.density_kg_m3, M.valuePtr());
  } else {
    scatterStiffness<4>(mesh, p, material, K.valuePtr());
    scatterMass<4>(mesh, p, material.density_kg_m3, M.valuePtr());
  }
}

MassProperties computeMassProperties(const TetMesh& mesh, double density_kg_m3) {
  MassProperties props;
  if (mesh.tets.rows() == 0 || mesh.nodes.rows() == 0) return props;
  // Moments about a point inside the mesh (the first node) so that a mesh far from the
  // origin does not lose digits to cancellation in the parallel-axis shift.
  const Eigen::Vector3d origin = mesh.nodes.row(mesh.tets(0, 0)).transpose();
  double volume = 0.0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (int64_t t = 0; t < mesh.tets.rows(); ++t) {
    Eigen::Vector3d v[4];
    for (int i = 0; i < 4; ++i) v[i] = mesh.nodes.row(mesh.tets(t, i)).transpose() - origin;
    Eigen::Matrix3d J;
    J << v[1] - v[0], v[2] - v[0], v[3] - v[0];
    const double vol = J.determinant() / 6.0;
    const Eigen::Vector3d sum = v[0] + v[1] + v[2] + v[3];
    // Exact moments of a tetrahedron (Tonon, J. Math. Stat. 1(1), 2004):
    //   int x dV = V s / 4,  int x x^T dV = V / 20 (sum_i v_i v_i^T + s s^T).
    Eigen::Matrix3d outer = sum * sum.transpose();
    for (int i = 0; i < 4; ++i) outer += v[i] * v[i].transpose();
    volume += vol;
    first += vol / 4.0 * sum;
    second += vol / 20.0 * outer;
  }
  props.volume_m3 = volume;
  props.mass_kg = density_kg_m3 * volume;
  const Eigen::Vector3d centre_rel = volume != 0.0 ? Eigen::Vector3d(first / volume) : Eigen::Vector3d::Zero();
  props.centre_m = origin + centre_rel;
  // Second moment about the centre, then I = tr(C) 1 - C.
  const Eigen::Matrix3d C = density_kg_m3 * (second - volume * centre_rel * centre_rel.transpose());
  props.inertia_kg_m2 = C.trace() * Eigen::Matrix3d::Identity() - C;
  return props;
}

}  // namespace strike
