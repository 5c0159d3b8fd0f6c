// SPDX-License-Identifier: MIT
// The evaluation side of the acoustic transfer (src/bank/acoustic_transfer.cpp): real spherical
// harmonics against their closed forms and their orthonormality by quadrature over the sphere,
// and the far-field sum.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "strike/acoustic_transfer.hpp"

namespace strike {
namespace {

// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n), for the quadrature over the sphere.
void gaussLegendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.resize(n);
  w.resize(n);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double step = p1 / dp;
      z -= step;
      if (std::abs(step) < 1e-16) break;
    }
    x[i] = z;
    w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

TEST(SphericalHarmonics, LowOrdersMatchTheirClosedForms) {
  const double d[3] = {0.3, -0.5, 0.812403840463596};  // unit
  const double x = d[0], y = d[1], z = d[2];
  double Y[25];
  realSphericalHarmonics(4, d, Y);
  const double pi = M_PI;
  EXPECT_NEAR(Y[0], 1.0 / std::sqrt(4 * pi), 1e-15);
  EXPECT_NEAR(Y[1], std::sqrt(3 / (4 * pi)) * y, 1e-15);  // n 1, m -1
  EXPECT_NEAR(Y[2], std::sqrt(3 / (4 * pi)) * z, 1e-15);
  EXPECT_NEAR(Y[3], std::sqrt(3 / (4 * pi)) * x, 1e-15);
  // n = 2 (Wikipedia "Table of spherical harmonics", real forms, no Condon-Shortley phase).
  EXPECT_NEAR(Y[4], 0.5 * std::sqrt(15 / pi) * x * y, 1e-14);
  EXPECT_NEAR(Y[5], 0.5 * std::sqrt(15 / pi) * y * z, 1e-14);
  EXPECT_NEAR(Y[6], 0.25 * std::sqrt(5 / pi) * (3 * z * z - 1), 1e-14);
  EXPECT_NEAR(Y[7], 0.5 * std::sqrt(15 / pi) * x * z, 1e-14);
  EXPECT_NEAR(Y[8], 0.25 * std::sqrt(15 / pi) * (x * x - y * y), 1e-14);
  // n = 3, m = 0 and m = 3.
  EXPECT_NEAR(Y[12], 0.25 * std::sqrt(7 / pi) * z * (5 * z * z - 3), 1e-14);
  EXPECT_NEAR(Y[15], 0.25 * std::sqrt(35 / (2 * pi)) * x * (x * x - 3 * y * y), 1e-14);
  // Not normalized on input; a zero vector means +z.
  const double longer[3] = {3 * x, 3 * y, 3 * z}, zero[3] = {0, 0, 0}, up[3] = {0, 0, 1};
  double Y2[25], Y3[25];
  realSphericalHarmonics(4, longer, Y2);
  for (int i = 0; i < 25; ++i) EXPECT_NEAR(Y2[i], Y[i], 1e-14);
  realSphericalHarmonics(4, zero, Y2);
  realSphericalHarmonics(4, up, Y3);
  for (int i = 0; i < 25; ++i) EXPECT_EQ(Y2[i], Y3[i]);
}

TEST(SphericalHarmonics, AreOrthonormalOverTheSphereUpToHighOrder) {
  // Gauss-Legendre in cos(theta) x uniform phi integrates products of degree <= 2 N exactly.
  const int order = 40, count = (order + 1) * (order + 1);
  std::vector<double> gx, gw;
  gaussLegendre(order + 2, gx, gw);
  const int nphi = 2 * order + 4;
  std::vector<double> gram(static_cast<size_t>(count) * count, 0.0), Y(count);
  for (size_t i = 0; i < gx.size(); ++i)
    for (int j = 0; j < nphi; ++j) {
      const double phi = 2 * M_PI * j / nphi, s = std::sqrt(1 - gx[i] * gx[i]);
      const double d[3] = {s * std::cos(phi), s * std::sin(phi), gx[i]};
      realSphericalHarmonics(order, d, Y.data());
      const double w = gw[i] * 2 * M_PI / nphi;
      for (int a = 0; a < count; ++a)
        for (int b = a; b < count; ++b) gram[static_cast<size_t>(a) * count + b] += w * Y[a] * Y[b];
    }
  double worst = 0.0;
  for (int a = 0; a < count; ++a)
    for (int b = a; b < count; ++b)
      worst = std::max(worst, std::abs(gram[static_cast<size_t>(a) * count + b] - (a == b ? 1.0 : 0.0)));
  EXPECT_LT(worst, 1e-12);
}

TEST(AcousticTransfer, EvaluatesTheSumAndItsRmsAndChecksItsShape) {
  AcousticTransfer t;
  t.order = {0, 1};
  t.offset = {0, 1, 5};
  t.coefficients = {{2.0f, 0.0f}, {0.0f, 0.0f}, {0.0f, 0.0f}, {1.0f, -1.0f}, {0.5f, 0.0f}};
  t.relative_error = {0.01f, 0.02f};
  EXPECT_EQ(t.checkConsistency(2), "");
  EXPECT_NE(t.checkConsistency(3), "");
  EXPECT_EQ(t.maxOrder(), 1u);
  const double d[3] = {0.6, 0.0, 0.8};
  double Y[4];
  realSphericalHarmonics(1, d, Y);
  std::complex<double> F[2];
  evaluateFarField(t, Y, F);
  const double c1 = std::sqrt(3 / (4 * M_PI));
  EXPECT_NEAR(F[0].real(), 2.0 / std::sqrt(4 * M_PI), 1e-7);
  EXPECT_NEAR(F[1].real(), c1 * 0.8 + 0.5 * c1 * 0.6, 1e-7);
  EXPECT_NEAR(F[1].imag(), -c1 * 0.8, 1e-7);
  EXPECT_NEAR(t.rmsFarField(1), std::sqrt((2.0 + 0.25) / (4 * M_PI)), 1e-7);
  t.offset[2] = 4;
  EXPECT_NE(t.checkConsistency(2), "");
}

// The per-impact evaluation (src/synth/sound_paths.cpp) uses the tabulated recurrence; it must
// give exactly what the plain form gives, or a render would depend on which one ran.
TEST(SphericalHarmonics, TheTabulatedRecurrenceGivesTheSameBits) {
  const double directions[][3] = {{0.3, -0.5, 0.812403840463596}, {0, 0, 1},  {0, 0, -1},   {-0.0, 0.0, 1.0},
                                  {1e-300, 0, 0},                 {1, 1, 1}, {-2, 3, -0.5}, {0.0, 0.0, 0.0}};
  for (uint32_t order : {0u, 1u, 2u, 7u, 31u, 64u}) {
    const SphericalHarmonicsTable table = sphericalHarmonicsTable(order);
    const size_t count = size_t(order + 1) * (order + 1);
    std::vector<double> plain(count), tabulated(count);
    for (const auto& d : directions) {
      realSphericalHarmonics(order, d, plain.data());
      realSphericalHarmonics(table, d, tabulated.data());
      EXPECT_EQ(std::memcmp(plain.data(), tabulated.data(), count * sizeof(double)), 0) << "order " << order;
    }
  }
}

// The fast evaluation's arithmetic as acoustic_transfer.hpp states it, written out one
// operation at a time: eight single-precision partial sums by j mod 8, then a fixed reduction.
std::complex<double> documentedSum(const std::complex<float>* c, size_t count, const double* Y) {
  float s[8][2] = {};
  for (size_t j = 0; j < count; ++j) {
    const float y = static_cast<float>(Y[j]);
    const float re = c[j].real() * y, im = c[j].imag() * y;
    s[j % 8][0] += re;
    s[j % 8][1] += im;
  }
  double part[2];
  for (int k = 0; k < 2; ++k) {
    const float even = (s[0][k] + s[2][k]) + (s[4][k] + s[6][k]);
    const float odd = (s[1][k] + s[3][k]) + (s[5][k] + s[7][k]);
    part[k] = static_cast<double>(even) + static_cast<double>(odd);
  }
  return {part[0], part[1]};
}

// Modes of orders that give every remainder mod 8 (counts 1, 4, 9, ..., 144) and differ from
// one mode to the next; random coefficients.
AcousticTransfer randomTransfer(std::vector<uint32_t> orders, uint32_t seed) {
  AcousticTransfer t;
  t.order = std::move(orders);
  t.offset = {0};
  for (uint32_t n : t.order) t.offset.push_back(t.offset.back() + uint64_t(n + 1) * (n + 1));
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  for (uint64_t j = 0; j < t.offset.back(); ++j) t.coefficients.emplace_back(uniform(random), uniform(random));
  t.relative_error.assign(t.order.size(), 0.0f);
  return t;
}

// Whatever the build (SSE2 or the portable loop) and whether one direction or two share a pass,
// the engine's evaluation gives the documented sum to the bit: a render cannot depend on the
// processor it ran on.
TEST(AcousticTransfer, TheFastEvaluationGivesTheDocumentedSumToTheBit) {
  const AcousticTransfer t = randomTransfer({3, 0, 5, 2, 9, 9, 1, 4, 6, 2, 7, 11, 8, 10}, 7);
  const uint32_t order = t.maxOrder();
  const size_t count = size_t(order + 1) * (order + 1);
  const double directions[2][3] = {{0.2, -0.7, 0.4}, {-0.5, 0.1, -0.3}};
  std::vector<double> Y[2];
  std::vector<float> weights[2];
  for (int k = 0; k < 2; ++k) {
    Y[k].resize(count);
    weights[k].resize(2 * count);
    realSphericalHarmonics(order, directions[k], Y[k].data());
    farFieldWeights(Y[k].data(), count, weights[k].data());
  }
  std::vector<std::complex<double>> both[2], alone(t.modeCount());
  for (auto& f : both) f.resize(t.modeCount());
  const float* w[2] = {weights[0].data(), weights[1].data()};
  std::complex<double>* out[2] = {both[0].data(), both[1].data()};
  evaluateFarFields(t, 2, w, out);
  for (int k = 0; k < 2; ++k) {
    const float* one_w[1] = {weights[k].data()};
    std::complex<double>* one_out[1] = {alone.data()};
    evaluateFarFields(t, 1, one_w, one_out);
    for (size_t i = 0; i < t.modeCount(); ++i) {
      const std::complex<double> expected =
          documentedSum(t.coefficients.data() + t.offset[i], t.offset[i + 1] - t.offset[i], Y[k].data());
      EXPECT_EQ(std::memcmp(&both[k][i], &expected, sizeof expected), 0) << "direction " << k << " mode " << i;
      EXPECT_EQ(std::memcmp(&alone[i], &expected, sizeof expected), 0) << "direction " << k << " mode " << i;
    }
  }
}

// Its rounding error against the plain double sum stays under the stated bound
// (count / 8 + 4) 2^-24 sum_j |c_j Y_j| [Higham 2002, "Accuracy and Stability of Numerical
// Algorithms", sec. 4.2: a sum of m terms is within (m - 1) u of exact, per term; the product
// and the rounding of Y add 2 u, the reduction 2 u]. A term left out or added twice would be
// ~1/count of the sum, far above it.
TEST(AcousticTransfer, TheFastEvaluationIsWithinItsRoundingBoundOfTheExactSum) {
  const AcousticTransfer t = randomTransfer({0, 1, 7, 20, 40, 63, 90}, 11);
  const uint32_t order = t.maxOrder();
  const size_t count = size_t(order + 1) * (order + 1);
  std::vector<double> Y(count);
  std::vector<float> weights(2 * count);
  std::vector<std::complex<double>> exact(t.modeCount()), fast(t.modeCount());
  std::mt19937 random(3);
  std::normal_distribution<double> normal;
  double worst = 0.0;  // error / bound
  for (int trial = 0; trial < 20; ++trial) {
    const double d[3] = {normal(random), normal(random), normal(random)};
    realSphericalHarmonics(order, d, Y.data());
    farFieldWeights(Y.data(), count, weights.data());
    evaluateFarField(t, Y.data(), exact.data());
    const float* w[1] = {weights.data()};
    std::complex<double>* out[1] = {fast.data()};
    evaluateFarFields(t, 1, w, out);
    for (size_t i = 0; i < t.modeCount(); ++i) {
      const size_t n = t.offset[i + 1] - t.offset[i];
      double magnitude[2] = {0.0, 0.0};
      for (size_t j = 0; j < n; ++j) {
        magnitude[0] += std::abs(double(t.coefficients[t.offset[i] + j].real()) * Y[j]);
        magnitude[1] += std::abs(double(t.coefficients[t.offset[i] + j].imag()) * Y[j]);
      }
      const double u = std::ldexp(1.0, -24), steps = double(n) / 8.0 + 4.0;
      const double bound_re = steps * u * magnitude[0] * (1.0 + 1e-6), bound_im = steps * u * magnitude[1] * (1.0 + 1e-6);
      EXPECT_LE(std::abs(fast[i].real() - exact[i].real()), bound_re) << "mode " << i;
      EXPECT_LE(std::abs(fast[i].imag() - exact[i].imag()), bound_im) << "mode " << i;
      worst = std::max({worst, std::abs(fast[i].real() - exact[i].real()) / bound_re,
                        std::abs(fast[i].imag() - exact[i].imag()) / bound_im});
    }
  }
  std::printf("  fast evaluation: worst error %.3g of its bound\n", worst);
}

// The sound engine keeps a rolling source's far-field factors while N theta <= 1e-3
// (sound_paths.cpp), relying on Bernstein's inequality: along a great circle a spherical
// polynomial of degree N changes by at most N theta times its largest value. Checked on random
// far fields, with the largest value taken over a dense grid (which can only underestimate it).
TEST(SphericalHarmonics, AFarFieldOfOrderNTurnsByAtMostNThetaOfItsPeak) {
  std::mt19937 random(11);
  std::normal_distribution<double> normal;
  for (uint32_t order : {4u, 16u, 40u}) {
    const size_t count = size_t(order + 1) * (order + 1);
    std::vector<double> c(count), Y(count);
    for (double& x : c) x = normal(random);
    auto field = [&](const double d[3]) {
      realSphericalHarmonics(order, d, Y.data());
      double f = 0.0;
      for (size_t j = 0; j < count; ++j) f += c[j] * Y[j];
      return f;
    };
    double peak = 0.0;
    const int grid = static_cast<int>(8 * order + 16);
    for (int i = 0; i <= grid; ++i)
      for (int k = 0; k < 2 * grid; ++k) {
        const double theta = M_PI * i / grid, phi = M_PI * k / grid;
        const double d[3] = {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
        peak = std::max(peak, std::abs(field(d)));
      }
    double worst = 0.0;  // largest |F(d') - F(d)| / (N theta peak)
    for (int trial = 0; trial < 2000; ++trial) {
      double a[3] = {normal(random), normal(random), normal(random)}, b[3] = {normal(random), normal(random), normal(random)};
      const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      for (double& x : a) x /= la;
      // b: a turned by a small angle about a random axis (perpendicular part of b).
      const double along = b[0] * a[0] + b[1] * a[1] + b[2] * a[2];
      for (int k = 0; k < 3; ++k) b[k] -= along * a[k];
      const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
      const double theta = 0.5 / order * std::pow(10.0, -3.0 * (trial % 4) / 3.0);
      double d[3];
      for (int k = 0; k < 3; ++k) d[k] = std::cos(theta) * a[k] + std::sin(theta) * b[k] / lb;
      worst = std::max(worst, std::abs(field(d) - field(a)) / (order * theta * peak));
    }
    EXPECT_LE(worst, 1.0) << "order " << order;
    EXPECT_GT(worst, 0.2) << "order " << order << ": the bound should be nearly reached, or the test sees nothing";
  }
}

}  // namespace
}  // namespace strike
