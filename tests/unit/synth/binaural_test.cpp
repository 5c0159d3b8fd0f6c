// SPDX-License-Identifier: MIT
// Binaural output (hrtf.hpp) with the MIT KEMAR responses Debian's libmysofa installs, through
// the sound engine: the interaural time difference of a source at the side against Woodworth's
// formula, the nearer ear louder, equal ears in front, and turning the listener against moving
// the source.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "strike/audio/sofa_hrtf.hpp"
#include "strike/synth/engine.hpp"

namespace strike {
namespace {

constexpr double kRate = 48000.0;
constexpr double kDegree = M_PI / 180.0;

std::shared_ptr<const HrtfSet> kemar() {
  static const std::shared_ptr<const HrtfSet> set = [] {
    Result<std::shared_ptr<const HrtfSet>> loaded = loadSofaHrtf(kDefaultHrtfFile, kRate);
    EXPECT_TRUE(loaded.ok()) << loaded.error().message;
    return loaded.ok() ? *loaded : nullptr;
  }();
  return set;
}

// Modes at `frequencies`, heard alike in every direction, each weighted so that an impulse
// rings them all at one level (a flat line spectrum: modal acceleration g omega, weight 1/omega).
std::shared_ptr<ModeBank> modesBank(const std::vector<double>& frequencies) {
  auto bank = std::make_shared<ModeBank>();
  ModeBank& b = *bank;
  b.material.youngs_pa = 200e9;
  b.material.poisson = 0.3;
  b.material.density_kg_m3 = 7800;
  b.material.rayleigh_mass = 20.0;
  b.mass_kg = 0.1;
  for (double f : frequencies) b.eigenvalues.push_back(std::pow(2.0 * M_PI * f, 2));
  b.surface_positions = {0, 0, 0, 0.01, 0, 0, 0, 0.01, 0};
  b.surface_normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  b.surface_triangles = {0, 1, 2};
  b.surface_node_index = {0, 1, 2};
  for (size_t i = 0; i < frequencies.size(); ++i) b.shapes.insert(b.shapes.end(), {0, 0, 1, 0, 0, 1, 0, 0, 1});
  b.radiation_m2.assign(frequencies.size(), 1e-3);
  return bank;
}

struct Ears {
  std::vector<float> left, right;
};

/// One struck body at `body_at` heard binaurally by a listener at the origin turned by `yaw_deg`
/// (counter-clockwise seen from above: to its left).
Ears strike(const std::vector<double>& frequencies, const std::array<double, 3>& body_at, double yaw_deg = 0.0,
            size_t frames = 9600) {
  EngineSettings settings;
  settings.synth.sample_rate_hz = kRate;
  settings.synth.audibility_threshold = 0.0;
  settings.max_voices = 1;
  settings.max_block_frames = 256;
  settings.realtime = false;
  settings.output = OutputFormat::Binaural;
  settings.hrtf = kemar();
  SoundEngine engine(settings);
  const auto bank = modesBank(frequencies);
  VoiceDesc desc;
  desc.bank = bank;
  for (double f : frequencies) desc.weights.push_back(1000.0 / f);
  const double identity[4] = {1, 0, 0, 0};
  desc.pose.set(body_at.data(), identity);
  Voice voice(desc, settings);
  engine.install(0, &voice);
  Pose listener;
  const double origin[3] = {0, 0, 0};
  const double turn[4] = {std::cos(0.5 * yaw_deg * kDegree), 0, 0, std::sin(0.5 * yaw_deg * kDegree)};
  listener.set(origin, turn);
  engine.setListener(listener);
  EngineImpact impact;
  impact.point = {0.003, 0.003, 0.0};
  impact.impulse = {0, 0, -0.01};
  impact.contact_duration_s = 0.0;
  impact.time_s = 0.0;
  engine.impact(impact);
  Ears ears{std::vector<float>(frames), std::vector<float>(frames)};
  for (size_t at = 0; at < frames; at += 256) {
    float* blocks[2] = {ears.left.data() + at, ears.right.data() + at};
    engine.render(blocks, std::min<size_t>(256, frames - at));
  }
  return ears;
}

double energy(const std::vector<float>& x) {
  double sum = 0.0;
  for (float v : x) sum += double(v) * v;
  return sum;
}

/// How much later the right ear hears what the left hears, s: the peak of their cross-correlation
/// over lags within +-1.2 ms, refined by a parabola through it and its neighbours.
double interauralDelay(const Ears& ears) {
  const int max_lag = static_cast<int>(std::ceil(1.2e-3 * kRate));
  const int n = static_cast<int>(ears.left.size());
  std::vector<double> c(static_cast<size_t>(2 * max_lag + 1));
  for (int lag = -max_lag; lag <= max_lag; ++lag) {
    double sum = 0.0;
    for (int i = std::max(0, -lag); i < std::min(n, n - lag); ++i) sum += double(ears.left[i]) * ears.right[i + lag];
    c[static_cast<size_t>(lag + max_lag)] = sum;
  }
  const size_t best = static_cast<size_t>(std::max_element(c.begin() + 1, c.end() - 1) - c.begin());
  const double a = c[best - 1], b = c[best], d = c[best + 1];
  const double offset = 0.5 * (a - d) / (a - 2.0 * b + d);
  return (static_cast<double>(best) - max_lag + offset) / kRate;
}

// The low band's content: 15 modes from 100 to 1500 Hz, one line every 100 Hz at one level.
std::vector<double> lowBand() {
  std::vector<double> f;
  for (int k = 1; k <= 15; ++k) f.push_back(100.0 * k);
  return f;
}

TEST(Binaural, InterauralTimeDifferenceAtTheSideIsWoodworths) {
  ASSERT_TRUE(kemar());
  // A source at azimuth 90 degrees (the listener's left, 2 m): the right ear hears it later by
  // Woodworth's (a / c)(theta + sin theta) for a sphere of radius a = 8.75 cm, 656 us
  // [Woodworth 1938, Experimental Psychology], within 10%; measured as the interaural
  // cross-correlation's peak below 1.5 kHz, where the interaural time difference is heard.
  const double woodworth_s = 0.0875 / 343.0 * (M_PI / 2.0 + 1.0);
  const double left_s = interauralDelay(strike(lowBand(), {-2, 0, 0}));
  std::printf("  ITD at azimuth +90: %.0f us (Woodworth %.0f us)\n", left_s * 1e6, woodworth_s * 1e6);
  EXPECT_NEAR(left_s, woodworth_s, 0.1 * woodworth_s);
  // ...and the other side, the other way.
  const double right_s = interauralDelay(strike(lowBand(), {2, 0, 0}));
  EXPECT_NEAR(right_s, -woodworth_s, 0.1 * woodworth_s);
}

TEST(Binaural, TheNearerEarIsLouder) {
  const std::vector<double> modes = {700.0, 2500.0, 6000.0};
  for (double azimuth : {30.0, 60.0, 90.0, 120.0, 150.0}) {
    // Azimuth counter-clockwise from straight ahead (+y): positive is the listener's left.
    const std::array<double, 3> at = {-2.0 * std::sin(azimuth * kDegree), 2.0 * std::cos(azimuth * kDegree), 0.0};
    const Ears left_side = strike(modes, at);
    EXPECT_GT(10.0 * std::log10(energy(left_side.left) / energy(left_side.right)), 3.0) << azimuth;
    const Ears right_side = strike(modes, {-at[0], at[1], at[2]});
    EXPECT_GT(10.0 * std::log10(energy(right_side.right) / energy(right_side.left)), 3.0) << azimuth;
  }
}

TEST(Binaural, ASourceInFrontGivesEqualEars) {
  // The bound is the KEMAR data's own: the level difference of its two frontal responses (the
  // set is a mirrored one, so 0.000 dB), plus 0.01 dB for the render's rounding.
  const std::shared_ptr<const HrtfSet> set = kemar();
  ASSERT_TRUE(set);
  const HrtfBlend front = hrtfBlend(*set, {1.0, 0.0, 0.0});
  ASSERT_EQ(front.weight[0], 1.0);  // measured there
  double el = 0.0, er = 0.0;
  for (uint32_t k = 0; k < set->taps; ++k) {
    el += std::pow(set->left[front.index[0] * set->taps + k], 2);
    er += std::pow(set->right[front.index[0] * set->taps + k], 2);
  }
  const double bound_db = std::abs(10.0 * std::log10(el / er)) + 0.01;
  const Ears ears = strike({700.0, 2500.0, 6000.0, 11000.0}, {0, 2, 0});
  const double difference_db = 10.0 * std::log10(energy(ears.left) / energy(ears.right));
  std::printf("  front: ears differ by %.4f dB (bound %.3f dB)\n", difference_db, bound_db);
  EXPECT_LT(std::abs(difference_db), bound_db);
  EXPECT_LT(std::abs(interauralDelay(strike(lowBand(), {0, 2, 0}))), 1.0 / kRate);
}

TEST(Binaural, TurningTheListenerIsMovingTheSourceTheOtherWay) {
  // A source ahead heard by a listener turned 90 degrees to its left is on its right: the same
  // ears as a source moved 90 degrees to the right of a listener who did not turn.
  const std::vector<double> modes = {300.0, 900.0, 2500.0, 7000.0};
  const Ears turned = strike(modes, {0, 2, 0}, 90.0);
  const Ears moved = strike(modes, {2, 0, 0});
  const Ears ahead = strike(modes, {0, 2, 0});
  double error = 0.0;
  for (size_t n = 0; n < turned.left.size(); ++n)
    error +=
        std::pow(double(turned.left[n]) - moved.left[n], 2) + std::pow(double(turned.right[n]) - moved.right[n], 2);
  EXPECT_LT(10.0 * std::log10(error / (energy(moved.left) + energy(moved.right))), -100.0);
  EXPECT_GT(energy(turned.right), 2.0 * energy(turned.left));
  // ...and unlike the source ahead.
  EXPECT_GT(std::abs(10.0 * std::log10(energy(turned.right) / energy(ahead.right))), 1.0);
}

TEST(Binaural, InterpolationIsExactAtMeasuredDirectionsAndContinuousBetween) {
  const std::shared_ptr<const HrtfSet> set = kemar();
  ASSERT_TRUE(set);
  for (size_t i = 0; i < set->unit_directions.size(); i += 37) {
    const HrtfBlend blend = hrtfBlend(*set, set->unit_directions[i]);
    EXPECT_EQ(blend.weight[0], 1.0);
    EXPECT_EQ(set->unit_directions[blend.index[0]], set->unit_directions[i]);
  }
  // Along the horizon from 0 to 10 degrees in small steps, the interpolated left response moves
  // by small amounts only: no jump as the nearest directions change (modified Shepard weights
  // reach 0 as a direction leaves the three nearest).
  std::vector<float> l(set->taps), r(set->taps), previous_l(set->taps), previous_r(set->taps);
  double largest_step = 0.0, whole_change = 0.0;
  hrtfResponses(*set, hrtfBlend(*set, {1, 0, 0}), previous_l.data(), previous_r.data());
  const std::vector<float> first = previous_l;
  for (int step = 1; step <= 200; ++step) {
    const double a = 10.0 * kDegree * step / 200.0;
    const HrtfBlend blend = hrtfBlend(*set, {std::cos(a), std::sin(a), 0.0});
    double total = 0.0;
    for (double w : blend.weight) total += w;
    EXPECT_NEAR(total, 1.0, 1e-12);
    hrtfResponses(*set, blend, l.data(), r.data());
    double change = 0.0, norm = 0.0;
    for (uint32_t k = 0; k < set->taps; ++k) {
      change += std::pow(double(l[k]) - previous_l[k], 2);
      norm += double(l[k]) * l[k];
    }
    largest_step = std::max(largest_step, std::sqrt(change / norm));
    previous_l = l;
  }
  for (uint32_t k = 0; k < set->taps; ++k) whole_change += std::pow(double(l[k]) - first[k], 2);
  whole_change = std::sqrt(whole_change / energy(l));
  std::printf("  0 -> 10 degrees: largest step %.3f, whole change %.3f (relative rms)\n", largest_step, whole_change);
  EXPECT_LT(largest_step, 0.1 * whole_change);
}

// The partitioned convolution (hrtf.hpp) against the direct sum y[n] = sum_k h[k] x[n - k] in
// double, with the interpolated responses of the direction: the same output to float rounding,
// the same bits however the input is split into calls, and after a change of direction the new
// responses over the whole past input (the cross-fade's block aside).
std::vector<double> directConvolution(const std::vector<float>& h, const std::vector<float>& x) {
  std::vector<double> y(x.size(), 0.0);
  for (size_t n = 0; n < x.size(); ++n)
    for (size_t k = 0; k < h.size() && k <= n; ++k) y[n] += double(h[k]) * x[n - k];
  return y;
}

TEST(Binaural, PartitionedConvolutionIsTheDirectOneForAnySplitOfTheInput) {
  const std::shared_ptr<const HrtfSet> set = kemar();
  ASSERT_TRUE(set);
  ASSERT_GT(set->taps, 4 * BinauralPath::kPartition);  // several partitions
  std::vector<float> x(3000);
  uint32_t seed = 12345;
  for (float& v : x) {
    seed = seed * 1664525u + 1013904223u;
    v = static_cast<float>(static_cast<int32_t>(seed >> 8) - (1 << 23)) / float(1 << 23);
  }
  for (size_t n = 2000; n < 2200; ++n) x[n] = 0.0f;                                 // a silence inside
  const std::array<double, 3> first = {-1.5, 1.0, 0.3}, second = {2.0, 0.5, -0.2};  // listener frame
  auto sofa = [](const std::array<double, 3>& local) {
    const double l = std::sqrt(local[0] * local[0] + local[1] * local[1] + local[2] * local[2]);
    return std::array<double, 3>{local[1] / l, -local[0] / l, local[2] / l};
  };
  // The direction changes after sample `turn` (a call's end): from the next block on.
  const size_t turn = 1500, block = BinauralPath::kPartition;
  const size_t faded = (turn + block - 1) / block * block + block;
  auto run = [&](const std::vector<size_t>& calls) {
    BinauralPath path;
    path.init(set);
    path.aim(first, true);
    Ears ears{std::vector<float>(x.size(), 0.0f), std::vector<float>(x.size(), 0.0f)};
    size_t at = 0;
    for (size_t c = 0; at < x.size(); ++c) {
      size_t frames = std::min(calls[c % calls.size()], x.size() - at);
      if (at < turn) frames = std::min(frames, turn - at);
      if (at == turn) path.aim(second, false);
      path.process(x.data() + at, frames, ears.left.data() + at, ears.right.data() + at);
      at += frames;
    }
    return ears;
  };
  const Ears split = run({1, 7, 64, 100, 3, 256});
  const Ears whole = run({512});
  for (size_t n = 0; n < x.size(); ++n) {
    ASSERT_EQ(split.left[n], whole.left[n]) << n;
    ASSERT_EQ(split.right[n], whole.right[n]) << n;
  }
  std::vector<float> h[2][2];  // [direction][ear]
  for (int d = 0; d < 2; ++d) {
    for (std::vector<float>& ear : h[d]) ear.resize(set->taps);
    hrtfResponses(*set, hrtfBlend(*set, sofa(d == 0 ? first : second)), h[d][0].data(), h[d][1].data());
  }
  double worst_db = -400.0;
  for (int ear = 0; ear < 2; ++ear) {
    const std::vector<float>& got = ear == 0 ? split.left : split.right;
    for (int d = 0; d < 2; ++d) {
      const std::vector<double> want = directConvolution(h[d][ear], x);
      const size_t from = d == 0 ? 0 : faded, to = d == 0 ? turn : x.size();
      double error = 0.0, power = 0.0;
      for (size_t n = from; n < to; ++n) {
        error += std::pow(got[n] - want[n], 2);
        power += want[n] * want[n];
      }
      worst_db = std::max(worst_db, 10.0 * std::log10(error / power));
    }
  }
  std::printf("  partitioned against direct: %.1f dB (rms error re rms)\n", worst_db);
  EXPECT_LT(worst_db, -100.0);
}

// A moving source re-aims every call; its filter is rebuilt only once its direction has moved by
// more than 0.5 degree from the one it was built for (hrtf.cpp): 0.3 degree keeps the same bits,
// 2 degrees gives other samples.
TEST(Binaural, AFilterIsKeptWithinHalfADegreeAndRebuiltBeyond) {
  const std::shared_ptr<const HrtfSet> set = kemar();
  ASSERT_TRUE(set);
  std::vector<float> x(2048, 0.0f);
  for (size_t n = 0; n < x.size(); n += 97) x[n] = 1.0f;
  auto heard = [&](double turn_deg) {
    BinauralPath path;
    path.init(set);
    const double a = 40.0 * kDegree, b = (40.0 + turn_deg) * kDegree;
    path.aim({std::sin(a), std::cos(a), 0.0}, true);
    std::vector<float> l(x.size(), 0.0f), r(x.size(), 0.0f);
    path.process(x.data(), 1000, l.data(), r.data());
    path.aim({std::sin(b), std::cos(b), 0.0}, false);
    path.process(x.data() + 1000, x.size() - 1000, l.data() + 1000, r.data() + 1000);
    return l;
  };
  const std::vector<float> still = heard(0.0);
  EXPECT_EQ(heard(0.3), still);
  EXPECT_NE(heard(2.0), still);
}

}  // namespace
}  // namespace strike
