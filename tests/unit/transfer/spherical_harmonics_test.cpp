// SPDX-License-Identifier: MIT
// The evaluation side of the acoustic transfer (src/transfer/spherical_harmonics.cpp, far_field.cpp): real spherical
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

#include <Eigen/Core>

#include "strike/transfer/acoustic_transfer.hpp"

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
  // Row p of A: the harmonics at node p times the square root of its weight, so the quadrature
  // of every product Y_a Y_b is (A^T A)_ab: the Gram matrix as one symmetric rank-k update
  // (blocked, as BLAS's dsyrk), not a rank-1 update per node over all count^2 / 2 entries.
  Eigen::MatrixXd A(gx.size() * nphi, count);
  std::vector<double> Y(count);
  for (size_t i = 0; i < gx.size(); ++i)
    for (int j = 0; j < nphi; ++j) {
      const double phi = 2 * M_PI * j / nphi, s = std::sqrt(1 - gx[i] * gx[i]);
      const double d[3] = {s * std::cos(phi), s * std::sin(phi), gx[i]};
      realSphericalHarmonics(order, d, Y.data());
      const double root_w = std::sqrt(gw[i] * 2 * M_PI / nphi);
      for (int a = 0; a < count; ++a) A(Eigen::Index(i * nphi + j), a) = root_w * Y[a];
    }
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(count, count);
  gram.selfadjointView<Eigen::Upper>().rankUpdate(A.transpose());
  double worst = 0.0;
  for (int a = 0; a < count; ++a)
    for (int b = a; b < count; ++b) worst = std::max(worst, std::abs(gram(a, b) - (a == b ? 1.0 : 0.0)));
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
// give exactly what the plain form gives, or a render would depend on which one ran. The orders
// cover every way the columns group (six at a time, then pairs, then one).
TEST(SphericalHarmonics, TheTabulatedRecurrenceGivesTheSameBits) {
  const double directions[][3] = {{0.3, -0.5, 0.812403840463596}, {0, 0, 1},  {0, 0, -1},   {-0.0, 0.0, 1.0},
                                  {1e-300, 0, 0},                 {1, 1, 1}, {-2, 3, -0.5}, {0.0, 0.0, 0.0}};
  for (uint32_t order : {0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u, 9u, 10u, 11u, 12u, 31u, 64u, 76u}) {
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

// Half precision (floatToHalf, halfToFloat) against its definition: a normal half is
// (-1)^s 2^(e - 15) (1 + f / 1024). Every normal half and both zeros come back from their float
// unchanged; a float goes to the nearest half (ties to the even fraction), and a value under the
// smallest normal half, 2^-14, to zero.
TEST(AcousticTransfer, HalfPrecisionRoundsToNearestEvenAndConvertsBackExactly) {
  auto value = [](uint16_t h) {
    const int e = (h >> 10) & 31, f = h & 1023;
    const double x = e == 0 ? 0.0 : std::ldexp(1.0 + f / 1024.0, e - 15);
    return (h & 0x8000) ? -x : x;
  };
  for (uint32_t h = 0; h < 65536; ++h) {
    const int e = (h >> 10) & 31;
    if (e == 31 || (e == 0 && (h & 1023) != 0)) continue;  // infinities, NaNs, subnormals: never stored
    const float x = halfToFloat(static_cast<uint16_t>(h));
    ASSERT_EQ(double(x), value(static_cast<uint16_t>(h))) << "half " << h;
    ASSERT_EQ(floatToHalf(x), h) << "half " << h;
  }
  std::mt19937 random(5);
  std::uniform_real_distribution<double> log2_magnitude(-14.0, 15.9);
  for (int trial = 0; trial < 200000; ++trial) {
    const float x = static_cast<float>((trial % 2 ? -1.0 : 1.0) * std::exp2(log2_magnitude(random)));
    const uint16_t h = floatToHalf(x);
    const double error = std::abs(double(x) - value(h));
    // No neighbour is nearer; at a tie the fraction is even.
    for (int step : {-1, 1}) {
      const uint16_t other = static_cast<uint16_t>(h + step);
      if (((other >> 10) & 31) == 0 || ((other >> 10) & 31) == 31 || (other & 0x8000) != (h & 0x8000)) continue;
      const double other_error = std::abs(double(x) - value(other));
      ASSERT_LE(error, other_error) << x;
      if (error == other_error) {
        ASSERT_EQ(h & 1, 0) << x;
      }
    }
  }
  EXPECT_EQ(floatToHalf(0x1p-15f), 0u);
  EXPECT_EQ(floatToHalf(-0x1p-15f), 0x8000u);
  EXPECT_EQ(floatToHalf(0x1p-14f), 0x0400u);
  EXPECT_EQ(floatToHalf(1.0f + 0x1p-11f), 0x3c00u);                // a tie: down to the even fraction
  EXPECT_EQ(floatToHalf(1.0f + 3 * 0x1p-11f), 0x3c02u);            // a tie: up to the even fraction
  EXPECT_EQ(floatToHalf((2.0f - 0x1p-11f) * 0x1p14f), 0x7800u);    // a tie, up: a carry into the exponent (2^15)
}

// Each mode is scaled by a power of two that puts its largest part in [2^14, 2^15).
TEST(AcousticTransfer, TheCompactFormScalesEachModeByAPowerOfTwo) {
  AcousticTransfer t;
  t.order = {0, 1, 0};
  t.offset = {0, 1, 5, 6};
  t.coefficients = {{3e-7f, -1e-9f}, {0.25f, 0.0f}, {0.0f, -0.75f}, {1e-12f, 0.0f}, {0.5f, 0.5f}, {0.0f, 0.0f}};
  t.relative_error.assign(3, 0.0f);
  const CompactTransfer c = compactTransfer(t);
  ASSERT_EQ(c.modeCount(), 3u);
  for (size_t i = 0; i < 2; ++i) {
    float largest = 0.0f;
    for (uint64_t k = 2 * c.offset[i]; k < 2 * c.offset[i + 1]; ++k)
      largest = std::max(largest, std::abs(halfToFloat(c.halves[k])));
    EXPECT_GE(largest, 0x1p14f) << "mode " << i;
    EXPECT_LT(largest, 0x1p15f) << "mode " << i;
    int exponent = 0;
    EXPECT_EQ(std::frexp(c.scale[i], &exponent), 0.5) << "mode " << i;  // a power of two
  }
  EXPECT_EQ(double(halfToFloat(c.halves[2 * 2 + 1])) * c.scale[1], -0.75);  // exact: 0.75 = 3 2^-2
  EXPECT_EQ(c.halves[2 * 3], 0u);  // 1e-12 is under 2^-28 of the mode's largest, 0.75: dropped
  EXPECT_EQ(c.scale[2], 1.0);      // a silent mode
  EXPECT_EQ(c.halves[2 * 5], 0u);
}

// Where the processor has F16C, compactTransfer converts eight values at a time with it; the
// halves must be the portable conversion's, bit for bit: ties, values dropped under 2^-14 after
// the scaling, both signs, and a count that leaves a tail.
TEST(AcousticTransfer, TheF16cCompactionGivesThePortableHalves) {
  AcousticTransfer t;
  t.order = {30, 2};
  t.offset = {0, 961, 970};
  std::mt19937 random(9);
  std::uniform_real_distribution<float> octaves(-40.0f, 0.0f);
  for (uint64_t j = 0; j < t.offset.back(); ++j) {
    const float re = std::exp2(octaves(random)), im = std::exp2(octaves(random));
    t.coefficients.emplace_back(j % 3 ? re : -re, j % 5 ? -im : im);
  }
  // Ties after scaling by 2^15 (the largest is 0.75 < 1): 1 + 2^-11 and 1 + 3 2^-11 times 2^-15.
  t.coefficients[0] = {0.75f, -0.75f};
  t.coefficients[1] = {(1.0f + 0x1p-11f) * 0x1p-15f, -(1.0f + 3 * 0x1p-11f) * 0x1p-15f};
  t.coefficients[2] = {0x1p-29f, -0x1p-29f};  // 2^-14 after scaling: kept
  t.coefficients[3] = {0x1.fffffep-30f, -0x1.fffffep-30f};  // just under: dropped
  t.relative_error.assign(2, 0.0f);
  const CompactTransfer portable = compactTransfer(t, false), fastest = compactTransfer(t);
  if (!fastest.f16c) GTEST_SKIP() << "this processor has no F16C";
  EXPECT_EQ(portable.halves, fastest.halves);
  EXPECT_EQ(portable.halves[2], 0x3c00u);  // the tie to the even fraction
  EXPECT_EQ(portable.halves[3], 0xbc02u);
  EXPECT_EQ(portable.halves[4], 0x0400u);
  EXPECT_EQ(portable.halves[6], 0u);
  EXPECT_EQ(portable.halves[7], 0x8000u);
}

// The fast evaluation's arithmetic as acoustic_transfer.hpp states it, written out one
// operation at a time: each half to its float, eight single-precision partial sums by j mod 8,
// then a fixed reduction and the mode's scale.
std::complex<double> documentedSum(const CompactTransfer& c, size_t mode, const double* Y) {
  const uint16_t* h = c.halves.data() + 2 * c.offset[mode];
  const size_t count = c.offset[mode + 1] - c.offset[mode];
  float s[8][2] = {};
  for (size_t j = 0; j < count; ++j) {
    const float y = static_cast<float>(Y[j]);
    const float re = halfToFloat(h[2 * j]) * y, im = halfToFloat(h[2 * j + 1]) * y;
    s[j % 8][0] += re;
    s[j % 8][1] += im;
  }
  double part[2];
  for (int k = 0; k < 2; ++k) {
    const float even = (s[0][k] + s[2][k]) + (s[4][k] + s[6][k]);
    const float odd = (s[1][k] + s[3][k]) + (s[5][k] + s[7][k]);
    part[k] = (static_cast<double>(even) + static_cast<double>(odd)) * c.scale[mode];
  }
  return {part[0], part[1]};
}

// Modes of orders that give every remainder mod 8 (counts 1, 4, 9, ..., 144) and differ from
// one mode to the next; random coefficients of magnitudes spread over 2^-20 .. 1, as a far
// field's orders are.
AcousticTransfer randomTransfer(std::vector<uint32_t> orders, uint32_t seed) {
  AcousticTransfer t;
  t.order = std::move(orders);
  t.offset = {0};
  for (uint32_t n : t.order) t.offset.push_back(t.offset.back() + uint64_t(n + 1) * (n + 1));
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  std::uniform_real_distribution<float> octaves(-20.0f, 0.0f);
  for (uint64_t j = 0; j < t.offset.back(); ++j) {
    const float magnitude = std::exp2(octaves(random));
    t.coefficients.emplace_back(magnitude * uniform(random), magnitude * uniform(random));
  }
  t.relative_error.assign(t.order.size(), 0.0f);
  return t;
}

// Whatever the processor (F16C with AVX2, or the portable loop) and whether one direction or two
// share a pass, the engine's evaluation gives the documented sum to the bit: a render cannot
// depend on the processor it ran on.
void expectTheDocumentedSum(const CompactTransfer& t) {
  const uint32_t order = 11;
  const size_t count = size_t(order + 1) * (order + 1);
  const double directions[2][3] = {{0.2, -0.7, 0.4}, {-0.5, 0.1, -0.3}};
  std::vector<double> Y[2];
  std::vector<float> weights[2];
  for (int k = 0; k < 2; ++k) {
    Y[k].resize(count);
    weights[k].resize(count);
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
      const std::complex<double> expected = documentedSum(t, i, Y[k].data());
      EXPECT_EQ(std::memcmp(&both[k][i], &expected, sizeof expected), 0) << "direction " << k << " mode " << i;
      EXPECT_EQ(std::memcmp(&alone[i], &expected, sizeof expected), 0) << "direction " << k << " mode " << i;
    }
  }
}

TEST(AcousticTransfer, TheFastEvaluationGivesTheDocumentedSumToTheBit) {
  const AcousticTransfer t = randomTransfer({3, 0, 5, 2, 9, 9, 1, 4, 6, 2, 7, 11, 8, 10}, 7);
  const CompactTransfer portable = compactTransfer(t, false), fastest = compactTransfer(t);
  EXPECT_FALSE(portable.f16c);
  EXPECT_EQ(portable.halves, fastest.halves);  // F16C's rounding is the portable one's
  EXPECT_EQ(portable.scale, fastest.scale);
  std::printf("  this processor: %s\n", fastest.f16c ? "F16C and AVX2" : "the portable loop only");
  expectTheDocumentedSum(portable);
  expectTheDocumentedSum(fastest);
}

// Against the plain double sum of the bank's float coefficients, the error stays under its
// bound: the halves' rounding, 2^-11 |c_j| each, plus what was dropped under 2^-28 of the
// mode's largest part, plus the sum's rounding (count / 8 + 4) 2^-24 sum_j |q_j Y_j| [Higham
// 2002, "Accuracy and Stability of Numerical Algorithms", sec. 4.2: a sum of m terms is within
// (m - 1) u of exact, per term; the product and the rounding of Y add 2 u, the reduction 2 u].
// A term left out or added twice would be ~1/count of the sum, far above it. Over directions the
// error is the halves' rounding, ~2^-11 / sqrt(3) of the rms far field: the test requires it
// between 1e-5 and 1e-3 of it (-100 to -60 dB), so it sees the rounding and no more.
TEST(AcousticTransfer, TheFastEvaluationIsWithinItsBoundOfTheExactSum) {
  const AcousticTransfer t = randomTransfer({0, 1, 7, 20, 40, 63, 90}, 11);
  const CompactTransfer c = compactTransfer(t);
  const uint32_t order = t.maxOrder();
  const size_t count = size_t(order + 1) * (order + 1);
  std::vector<double> Y(count);
  std::vector<float> weights(count);
  std::vector<std::complex<double>> exact(t.modeCount()), fast(t.modeCount());
  std::mt19937 random(3);
  std::normal_distribution<double> normal;
  double worst = 0.0;  // error / bound
  std::vector<double> error2(t.modeCount(), 0.0), value2(t.modeCount(), 0.0);
  for (int trial = 0; trial < 40; ++trial) {
    const double d[3] = {normal(random), normal(random), normal(random)};
    realSphericalHarmonics(order, d, Y.data());
    farFieldWeights(Y.data(), count, weights.data());
    evaluateFarField(t, Y.data(), exact.data());
    const float* w[1] = {weights.data()};
    std::complex<double>* out[1] = {fast.data()};
    evaluateFarFields(c, 1, w, out);
    for (size_t i = 0; i < t.modeCount(); ++i) {
      const size_t n = t.offset[i + 1] - t.offset[i];
      float largest = 0.0f;
      for (size_t j = 0; j < n; ++j)
        largest = std::max({largest, std::abs(t.coefficients[t.offset[i] + j].real()),
                            std::abs(t.coefficients[t.offset[i] + j].imag())});
      const double dropped = std::ldexp(double(largest), -28);
      double bound[2] = {0.0, 0.0};
      for (size_t j = 0; j < n; ++j) {
        const size_t k = 2 * (t.offset[i] + j);
        const double y = std::abs(Y[j]);
        const double part[2] = {t.coefficients[t.offset[i] + j].real(), t.coefficients[t.offset[i] + j].imag()};
        for (int p = 0; p < 2; ++p) {
          const double q = halfToFloat(c.halves[k + static_cast<size_t>(p)]) * c.scale[i];
          bound[p] += std::ldexp(std::abs(part[p]), -11) * y + dropped * y +
                      (double(n) / 8.0 + 4.0) * std::ldexp(std::abs(q) * y, -24);
        }
      }
      for (int p = 0; p < 2; ++p) bound[p] *= 1.0 + 1e-6;
      EXPECT_LE(std::abs(fast[i].real() - exact[i].real()), bound[0]) << "mode " << i;
      EXPECT_LE(std::abs(fast[i].imag() - exact[i].imag()), bound[1]) << "mode " << i;
      worst = std::max({worst, std::abs(fast[i].real() - exact[i].real()) / bound[0],
                        std::abs(fast[i].imag() - exact[i].imag()) / bound[1]});
      error2[i] += std::norm(fast[i] - exact[i]);
      value2[i] += std::norm(exact[i]);
    }
  }
  std::printf("  fast evaluation: worst error %.3g of its bound\n", worst);
  for (size_t i = 0; i < t.modeCount(); ++i) {
    if (t.order[i] < 7) continue;  // a few coefficients: the rms over 40 directions is too rough
    const double relative = std::sqrt(error2[i] / value2[i]);
    std::printf("  order %u: rms error %.3g of the rms far field\n", t.order[i], relative);
    EXPECT_GT(relative, 1e-5) << "order " << t.order[i];
    EXPECT_LT(relative, 1e-3) << "order " << t.order[i];
  }
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
