// SPDX-License-Identifier: MIT
// analyzeAudio against closed forms: stationary tones (frequency, level), exponentially
// decaying tones (decay rate), level statistics, clipping, determinism; struck-bar spectra
// (near-degenerate pairs, weak modes, no leakage ripples reported as peaks).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "audio/test_util.hpp"
#include "strike/audio/audio.hpp"

namespace strike {
namespace {

using test::partials;

const SpectralPeak* nearest(const AudioAnalysis& a, double freq_hz) {
  const SpectralPeak* best = nullptr;
  for (const SpectralPeak& p : a.peaks)
    if (!best || std::fabs(p.freq_hz - freq_hz) < std::fabs(best->freq_hz - freq_hz)) best = &p;
  return best;
}

void checkThreeTones(SpectrumWindow window) {
  const double rate = 48000.0;
  // 440 Hz at 0 dB, 1234.5 Hz at -20 dB, 5000 Hz at -40 dB (amplitudes 0.5, 0.05, 0.005).
  const AudioBuffer audio =
      partials({{440.0, 0.5, 0.0, 0.3}, {1234.5, 0.05, 0.0, 1.1}, {5000.0, 0.005, 0.0, 2.0}}, rate, 1.0);
  AnalyzeOptions options;
  options.window = window;
  options.fit_decay = false;
  const AudioAnalysis a = analyzeAudio(audio, options);
  ASSERT_GE(a.peaks.size(), 3u);
  const double expected_f[] = {440.0, 1234.5, 5000.0};
  const double expected_db[] = {0.0, -20.0, -40.0};
  for (int i = 0; i < 3; ++i) {
    const SpectralPeak& p = a.peaks[static_cast<size_t>(i)];  // by decreasing level
    const double rel_f = std::fabs(p.freq_hz - expected_f[i]) / expected_f[i];
    std::printf("    window %d: %8.3f Hz: frequency error %.2e (%.4f bins), level %.4f dB (error %.4f dB), %.4f dBFS\n",
                static_cast<int>(window), expected_f[i], rel_f, std::fabs(p.freq_hz - expected_f[i]) * 1.0, p.level_db,
                p.level_db - expected_db[i], p.level_dbfs - (expected_db[i] + 20.0 * std::log10(0.5)));
    EXPECT_LT(rel_f, 1e-4);
    EXPECT_NEAR(p.level_db, expected_db[i], 0.1);
    EXPECT_NEAR(p.level_dbfs, expected_db[i] + 20.0 * std::log10(0.5), 0.1);
  }
  // Nothing else within 10 dB of the weakest tone: no sidelobe or leakage reported as a peak.
  for (size_t i = 3; i < a.peaks.size(); ++i) EXPECT_LT(a.peaks[i].level_db, -50.0) << a.peaks[i].freq_hz;
}

TEST(Analyze, ThreeStationaryTonesOnsetWindow) { checkThreeTones(SpectrumWindow::OnsetHalfHann); }
TEST(Analyze, ThreeStationaryTonesHannWindow) { checkThreeTones(SpectrumWindow::Hann); }

TEST(Analyze, OffBinFrequenciesAcrossTheBand) {
  // Worst case for interpolation is half a bin between bins; sweep fractional positions.
  const double rate = 44100.0;
  for (double f : {97.3, 440.25, 1000.5, 3333.3, 12345.6, 19000.1}) {
    const AudioBuffer audio = partials({{f, 0.3, 0.0}}, rate, 0.5);
    AnalyzeOptions options;
    options.fit_decay = false;
    const AudioAnalysis a = analyzeAudio(audio, options);
    ASSERT_FALSE(a.peaks.empty());
    EXPECT_LT(std::fabs(a.peaks[0].freq_hz - f) / f, 1e-4) << f;
    EXPECT_NEAR(a.peaks[0].level_dbfs, 20.0 * std::log10(0.3), 0.1) << f;
  }
}

TEST(Analyze, DecayRatesFromOneToTwoHundredPerSecond) {
  const double rate = 48000.0;
  for (double d : {1.0, 2.0, 5.0, 10.0, 30.0, 100.0, 200.0})
    for (double f : {150.0, 1000.0, 7000.0}) {
      const AudioBuffer audio = partials({{f, 0.8, d, 0.7}}, rate, 2.0);
      const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
      ASSERT_FALSE(a.peaks.empty());
      const SpectralPeak& p = a.peaks[0];
      const double err = (p.decay_per_s - d) / d;
      std::printf("    f %7.1f Hz d %6.1f /s: fitted %9.4f /s (error %+.3f%%), frequency error %.2e\n", f, d,
                  p.decay_per_s, 100.0 * err, std::fabs(p.freq_hz - f) / f);
      EXPECT_LT(std::fabs(err), 0.03) << "f " << f << " d " << d;
      EXPECT_LT(std::fabs(p.freq_hz - f) / f, 1e-3);
    }
}

TEST(Analyze, ModesOfAnImpactKeepTheirDecays) {
  // A struck-bar-like spectrum: faster decay at higher modes; all start at t = 0.
  const std::vector<test::Partial> modes = {{523.0, 0.4, 2.0, 0.0},
                                            {1441.0, 0.3, 8.0, 1.0},
                                            {2826.0, 0.2, 25.0, 2.0},
                                            {4671.0, 0.1, 70.0, 3.0},
                                            {6977.0, 0.05, 180.0, 4.0}};
  const AudioBuffer audio = partials(modes, 48000.0, 1.5);
  const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
  for (const test::Partial& m : modes) {
    const SpectralPeak* p = nearest(a, m.freq_hz);
    ASSERT_NE(p, nullptr);
    std::printf("    mode %6.0f Hz: %9.3f Hz, d %7.3f (true %5.1f, error %+.3f%%), level %7.2f dB\n", m.freq_hz,
                p->freq_hz, p->decay_per_s, m.decay_per_s, 100.0 * (p->decay_per_s - m.decay_per_s) / m.decay_per_s,
                p->level_db);
    EXPECT_LT(std::fabs(p->freq_hz - m.freq_hz) / m.freq_hz, 1e-3);
    EXPECT_LT(std::fabs(p->decay_per_s - m.decay_per_s) / m.decay_per_s, 0.03);
  }
}

TEST(Analyze, TwoClosePeaksHaveSeparateDecays) {
  for (double df : {7.0, 15.0}) {
    const double f1 = 440.0, f2 = 440.0 + df;
    const AudioBuffer audio = partials({{f1, 0.4, 3.0, 0.0}, {f2, 0.4, 9.0, 1.3}}, 48000.0, 2.0);
    const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
    ASSERT_GE(a.peaks.size(), 2u);
    const SpectralPeak* p1 = nearest(a, f1);
    const SpectralPeak* p2 = nearest(a, f2);
    ASSERT_NE(p1, p2);
    std::printf("    df %4.1f Hz: %.3f Hz d %.4f (true 3, %+.3f%%); %.3f Hz d %.4f (true 9, %+.3f%%)\n", df,
                p1->freq_hz, p1->decay_per_s, 100.0 * (p1->decay_per_s - 3.0) / 3.0, p2->freq_hz, p2->decay_per_s,
                100.0 * (p2->decay_per_s - 9.0) / 9.0);
    EXPECT_NEAR(p1->freq_hz, f1, 0.5);
    EXPECT_NEAR(p2->freq_hz, f2, 0.5);
    EXPECT_NEAR(p1->decay_per_s, 3.0, 0.03 * 3.0);
    EXPECT_NEAR(p2->decay_per_s, 9.0, 0.03 * 9.0);
  }
}

TEST(Analyze, DecayThroughSixteenBitQuantizationAndSilenceBeforeOnset) {
  // 16-bit noise floor (-101 dBFS) and 50 ms of silence before the impact.
  const double rate = 44100.0;
  AudioBuffer audio = partials({{880.0, 0.9, 40.0, 0.0}}, rate, 1.0);
  audio.samples.insert(audio.samples.begin(), static_cast<size_t>(0.05 * rate), 0.0f);
  for (float& s : audio.samples) s = static_cast<float>(std::nearbyint(s * 32768.0) / 32768.0);
  const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
  ASSERT_FALSE(a.peaks.empty());
  EXPECT_NEAR(a.onset_s, 0.05, 1e-3);
  EXPECT_NEAR(a.peaks[0].freq_hz, 880.0, 0.5);
  std::printf("    quantized d 40: fitted %.4f (%+.3f%%)\n", a.peaks[0].decay_per_s,
              100.0 * (a.peaks[0].decay_per_s - 40.0) / 40.0);
  EXPECT_NEAR(a.peaks[0].decay_per_s, 40.0, 0.03 * 40.0);
}

TEST(Analyze, DecayAboveAWhiteNoiseFloor) {
  // Noise 74 dB below the start of the tone: the fit must stop above the floor, not bend into it.
  for (double d : {5.0, 20.0, 150.0}) {
    AudioBuffer audio = partials({{2000.0, 0.5, d, 0.4}, {3100.0, 0.3, 2.0 * d, 0.9}}, 48000.0, 1.5);
    uint32_t state = 99u;
    for (float& s : audio.samples) {
      double sum = 0.0;  // Irwin-Hall: sum of 12 uniforms - 6 is near-Gaussian with unit variance
      for (int i = 0; i < 12; ++i) {
        state = state * 1664525u + 1013904223u;
        sum += static_cast<double>(state) / 4294967296.0;
      }
      s += static_cast<float>(1e-4 * (sum - 6.0));
    }
    const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
    const SpectralPeak* p1 = nearest(a, 2000.0);
    const SpectralPeak* p2 = nearest(a, 3100.0);
    ASSERT_TRUE(p1 && p2);
    std::printf("    noise, d %5.1f: fitted %.4f (%+.3f%%), 2d: fitted %.4f (%+.3f%%)\n", d, p1->decay_per_s,
                100.0 * (p1->decay_per_s - d) / d, p2->decay_per_s, 100.0 * (p2->decay_per_s - 2.0 * d) / (2.0 * d));
    EXPECT_NEAR(p1->decay_per_s, d, 0.03 * d);
    EXPECT_NEAR(p2->decay_per_s, 2.0 * d, 0.03 * 2.0 * d);
    EXPECT_NEAR(p1->freq_hz, 2000.0, 0.1);
  }
}

TEST(Analyze, LevelStatisticsAndClipping) {
  AudioBuffer audio = partials({{1000.0, 0.5, 0.0}}, 48000.0, 1.0, 2);
  audio.samples[10] = 1.0f;  // exactly full scale counts as clipped
  audio.samples[11] = -1.25f;
  audio.samples[12] = 3.0f;
  audio.samples[13] = std::nanf("");
  const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
  EXPECT_EQ(a.sample_rate_hz, 48000.0);
  EXPECT_DOUBLE_EQ(a.duration_s, 1.0);
  EXPECT_EQ(a.clipped_samples, 3);
  EXPECT_EQ(a.non_finite_samples, 1);
  EXPECT_DOUBLE_EQ(a.peak_amplitude, 3.0);
  EXPECT_NEAR(a.rms, 0.5 / std::sqrt(2.0), 2e-3);  // the four odd samples move it a little

  const AudioAnalysis clean = analyzeAudio(partials({{1000.0, 0.5, 0.0}}, 48000.0, 1.0), AnalyzeOptions{});
  EXPECT_EQ(clean.clipped_samples, 0);
  EXPECT_NEAR(clean.peak_amplitude, 0.5, 1e-4);
  EXPECT_NEAR(clean.rms, 0.5 / std::sqrt(2.0), 1e-5);
}

TEST(Analyze, MixdownIsTheMeanOfChannels) {
  // Left 440 Hz, right 660 Hz: each at half amplitude in the mixdown, equal levels.
  AudioBuffer audio;
  audio.sample_rate_hz = 48000.0;
  audio.channels = 2;
  for (int n = 0; n < 48000; ++n) {
    const double t = n / 48000.0;
    audio.samples.push_back(static_cast<float>(0.6 * std::sin(2.0 * test::kPi * 440.0 * t)));
    audio.samples.push_back(static_cast<float>(0.6 * std::sin(2.0 * test::kPi * 660.0 * t)));
  }
  const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
  ASSERT_GE(a.peaks.size(), 2u);
  EXPECT_NEAR(nearest(a, 440.0)->level_dbfs, 20.0 * std::log10(0.3), 0.1);
  EXPECT_NEAR(nearest(a, 660.0)->level_dbfs, 20.0 * std::log10(0.3), 0.1);
}

TEST(Analyze, MaxPeaksAndFloorLimitTheList) {
  const AudioBuffer audio = partials({{300.0, 0.5, 0.0}, {900.0, 0.05, 0.0}, {2700.0, 0.0005, 0.0}}, 48000.0, 0.5);
  AnalyzeOptions options;
  options.fit_decay = false;
  options.max_peaks = 1;
  EXPECT_EQ(analyzeAudio(audio, options).peaks.size(), 1u);
  options.max_peaks = 20;
  options.floor_db = -30.0;
  const AudioAnalysis a = analyzeAudio(audio, options);
  ASSERT_EQ(a.peaks.size(), 2u);
  for (const SpectralPeak& p : a.peaks) EXPECT_LT(p.decay_per_s, 0.0);  // not fitted
}

TEST(Analyze, SameInputSameResult) {
  const AudioBuffer audio = partials({{523.0, 0.4, 2.0}, {1441.0, 0.3, 8.0}}, 48000.0, 1.0);
  const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
  const AudioAnalysis b = analyzeAudio(audio, AnalyzeOptions{});
  ASSERT_EQ(a.peaks.size(), b.peaks.size());
  for (size_t i = 0; i < a.peaks.size(); ++i) {
    EXPECT_EQ(a.peaks[i].freq_hz, b.peaks[i].freq_hz);
    EXPECT_EQ(a.peaks[i].level_db, b.peaks[i].level_db);
    EXPECT_EQ(a.peaks[i].decay_per_s, b.peaks[i].decay_per_s);
  }
  EXPECT_EQ(a.rms, b.rms);
}

TEST(Analyze, SilenceAndEmptyInputGiveNoPeaks) {
  AudioBuffer silent;
  silent.samples.assign(4800, 0.0f);
  EXPECT_TRUE(analyzeAudio(silent, AnalyzeOptions{}).peaks.empty());
  AudioBuffer empty;
  const AudioAnalysis a = analyzeAudio(empty, AnalyzeOptions{});
  EXPECT_TRUE(a.peaks.empty());
  EXPECT_EQ(a.duration_s, 0.0);
  AudioBuffer tiny;
  tiny.samples = {0.5f, -0.5f, 0.25f};
  EXPECT_TRUE(analyzeAudio(tiny, AnalyzeOptions{}).peaks.empty());
}

// ---- struck-bar spectra: only genuine lines ------------------------------------------------

/// Expected whole-spectrum peak of a line alone, by direct summation of the analyzer's
/// definition: 2 |sum_n w(n) x(n) e^{-j 2 pi f n / fs}| / sum_n w(n), with the default onset
/// half-Hann window w = cos^2(pi n / 2N), at f (a pair: at its amplitude-weighted centre).
double expectedPeak(const std::vector<test::Partial>& parts, double freq_hz, double rate, double duration_s) {
  const AudioBuffer audio = test::partials(parts, rate, duration_s);
  const size_t length = audio.samples.size();
  double sum_w = 0.0, re = 0.0, im = 0.0;
  for (size_t n = 0; n < length; ++n) {
    const double c = std::cos(0.5 * test::kPi * static_cast<double>(n) / static_cast<double>(length));
    const double phase = 2.0 * test::kPi * freq_hz * static_cast<double>(n) / rate;
    sum_w += c * c;
    re += c * c * audio.samples[n] * std::cos(phase);
    im += c * c * audio.samples[n] * std::sin(phase);
  }
  return 2.0 * std::hypot(re, im) / sum_w;
}

struct Line {  // one mode, or a near-degenerate pair (second frequency > 0)
  double freq_hz, freq2_hz, amplitude, amplitude2, decay_per_s, phase, phase2;
};

std::vector<test::Partial> partialsOf(const std::vector<Line>& lines) {
  std::vector<test::Partial> parts;
  for (const Line& l : lines) {
    parts.push_back({l.freq_hz, l.amplitude, l.decay_per_s, l.phase});
    if (l.freq2_hz > 0.0) parts.push_back({l.freq2_hz, l.amplitude2, l.decay_per_s * (1.0 + 1e-4), l.phase2});
  }
  return parts;
}

/// Every reported peak above -60 dB is within 0.1 % of a true frequency; every line whose
/// expected level is above -50 dB is reported; decays within `isolated_tol` (isolated modes)
/// and `pair_tol` (pairs, as one peak).
void checkBar(const std::vector<Line>& lines, double isolated_tol, double pair_tol) {
  const double rate = 48000.0, duration = 2.0;
  const AudioBuffer audio = test::partials(partialsOf(lines), rate, duration);
  AnalyzeOptions options;
  options.max_peaks = 40;
  const AudioAnalysis a = analyzeAudio(audio, options);
  std::vector<double> expected;
  for (const Line& l : lines) {
    const double centre = l.freq2_hz > 0.0
                              ? (l.amplitude * l.freq_hz + l.amplitude2 * l.freq2_hz) / (l.amplitude + l.amplitude2)
                              : l.freq_hz;
    expected.push_back(expectedPeak(partialsOf({l}), centre, rate, duration));
  }
  const double loudest = *std::max_element(expected.begin(), expected.end());
  std::vector<double> expected_db;
  for (double e : expected) expected_db.push_back(20.0 * std::log10(e / loudest));
  for (const SpectralPeak& p : a.peaks) {
    if (p.level_db < -60.0) continue;
    double best = 1.0;
    for (const Line& l : lines) {
      best = std::min(best, std::fabs(p.freq_hz - l.freq_hz) / l.freq_hz);
      if (l.freq2_hz > 0.0) best = std::min(best, std::fabs(p.freq_hz - l.freq2_hz) / l.freq2_hz);
    }
    EXPECT_LT(best, 1e-3) << "spurious peak " << p.freq_hz << " Hz at " << p.level_db << " dB";
  }
  for (size_t i = 0; i < lines.size(); ++i) {
    const Line& l = lines[i];
    const SpectralPeak* p = nearest(a, l.freq_hz);
    const double tol_hz = 1e-3 * l.freq_hz + (l.freq2_hz > 0.0 ? l.freq2_hz - l.freq_hz : 0.0);
    const bool found = p && std::fabs(p->freq_hz - l.freq_hz) < tol_hz;
    if (expected_db[i] > -50.0) {
      EXPECT_TRUE(found) << "missed line " << l.freq_hz << " Hz at " << expected_db[i] << " dB";
    }
    if (!found) {
      std::printf("    %s %9.2f Hz (%5.1f dB expected): not reported\n", l.freq2_hz > 0.0 ? "pair" : "mode", l.freq_hz,
                  expected_db[i]);
      continue;
    }
    const double err = (p->decay_per_s - l.decay_per_s) / l.decay_per_s;
    std::printf("    %s %9.2f Hz (%5.1f dB expected): %9.3f Hz %7.2f dB, d %8.4f (true %7.3f, %+.3f%%)\n",
                l.freq2_hz > 0.0 ? "pair" : "mode", l.freq_hz, expected_db[i], p->freq_hz, p->level_db, p->decay_per_s,
                l.decay_per_s, 100.0 * err);
    EXPECT_LT(std::fabs(err), l.freq2_hz > 0.0 ? pair_tol : isolated_tol) << l.freq_hz;
  }
}

TEST(Analyze, BarWithNearDegeneratePairsAndWeakModesReportsOnlyLines) {
  // Strong pairs 0.1-0.4 Hz apart (below the 0.5 Hz resolution of 2 s), some starting in
  // antiphase (their envelope beats or rises within the record); isolated strong modes; weak
  // modes 40-60 dB down, > 150 Hz from strong ones; decays 0.6-65 /s, growing with frequency.
  const std::vector<Line> lines = {
      {1300.00, 1300.12, 0.30, 0.20, 0.65, 0.3, 2.0},  {2200.0, 0.0, 2e-3, 0.0, 1.5, 1.0, 0.0},   // weak
      {3045.09, 3045.19, 0.40, 0.50, 2.0, 1.9, -1.27},                                            // antiphase
      {4819.0, 0.0, 3e-3, 0.0, 4.4, -1.1, 0.0},                                                   // weak
      {5754.23, 5754.59, 0.60, 0.70, 6.1, 2.1, 0.2},   {7000.0, 0.0, 1e-2, 0.0, 10.0, 0.5, 0.0},  // weak
      {8410.0, 0.0, 0.30, 0.0, 12.5, -0.7, 0.0},       {9101.2, 9101.5, 0.50, 0.50, 14.6, -0.7, 2.4},
      {9638.3, 0.0, 0.02, 0.0, 16.3, 2.5, 0.0},        {12945.5, 12945.9, 0.50, 0.40, 29.1, -0.3, 2.9},
      {14458.3, 0.0, 0.10, 0.0, 36.2, 3.0, 0.0},       {16000.0, 0.0, 5e-2, 0.0, 48.0, 0.1, 0.0},  // weak
      {19279.3, 0.0, 0.20, 0.0, 64.1, -2.8, 0.0},
  };
  checkBar(lines, 0.03, 0.05);
}

TEST(Analyze, RenderedSteelBarRegression) {
  // The 18 modes of a 0.3 x 0.02 x 0.02 m steel bar (strike precompute, bar-info.json) with the
  // amplitudes and phases fitted to its rendered single hit, in which the analyzer reported
  // leakage ripples between 9101 and 9638 Hz as peaks (-49.5 dB, where the two modes' skirts
  // cross) and mis-fitted the beating pairs (3045 Hz: 1.53 /s for 2.02; 5754 Hz: 6.88 for 6.10).
  struct Mode {
    double f, d, a, phase;
  };
  const Mode modes[] = {
      {1135.2128057253058, 0.6492315042778163, 8.8345e-05, -1.476},
      {1135.2223871390183, 0.6492352320309218, 1.5738e-04, 1.678},
      {3045.093674358744, 2.017347244980382, 8.8961e-04, 1.875},
      {3045.186773257054, 2.017444405599014, 1.4217e-03, -1.268},
      {4818.9716037206945, 4.407795119378677, 5.2861e-05, -1.123},
      {5754.2287636138235, 6.102312165202826, 2.2868e-03, 2.145},
      {5754.589310170104, 6.103023215815074, 3.1525e-03, 2.140},
      {8409.981604259841, 12.548284851123897, 1.3343e-03, -0.740},
      {9101.192464760205, 14.622406651977519, 3.3106e-03, -0.676},
      {9102.128469642286, 14.625326344905286, 3.7067e-03, -0.664},
      {9638.283916003722, 16.347108899992648, 2.7840e-04, 2.540},
      {12945.555518845107, 29.146110025731897, 2.7994e-03, -0.307},
      {12947.48202295022, 29.15465796401182, 2.5421e-03, -0.269},
      {14458.283889414408, 36.2497477302109, 1.1209e-03, 3.007},
      {16804.24610705206, 48.81738312683433, 1.1736e-03, -3.045},
      {17166.926342229013, 50.92864868303711, 1.0797e-03, 0.051},
      {17170.337332584175, 50.94871901763319, 8.0929e-04, -3.123},
      {19279.3308892947, 64.12149391304267, 2.1915e-03, -2.804},
  };
  // partials() uses sin(); the fit used cos(phase) - j sin(phase) terms: sin(x + phase + pi/2).
  std::vector<test::Partial> parts;
  for (const Mode& m : modes) parts.push_back({m.f, m.a, m.d, -m.phase + 0.5 * test::kPi});
  const AudioAnalysis a = analyzeAudio(test::partials(parts, 48000.0, 2.0), AnalyzeOptions{});
  for (const SpectralPeak& p : a.peaks) {
    double best = 1.0;
    for (const Mode& m : modes) best = std::min(best, std::fabs(p.freq_hz - m.f) / m.f);
    std::printf("    %10.3f Hz %7.2f dB d %8.4f\n", p.freq_hz, p.level_db, p.decay_per_s);
    EXPECT_LT(best, 1e-3) << "spurious peak " << p.freq_hz << " Hz at " << p.level_db << " dB";
  }
  // Pairs reported once, with the decay they share; isolated modes to 3 %.
  const double pair_f[] = {3045.14, 5754.41, 9101.66, 12946.5};
  const double pair_d[] = {2.0174, 6.1027, 14.624, 29.150};
  for (int i = 0; i < 4; ++i) {
    int count = 0;
    for (const SpectralPeak& p : a.peaks) count += std::fabs(p.freq_hz - pair_f[i]) < 2.0;
    EXPECT_EQ(count, 1) << pair_f[i];
    const SpectralPeak* p = nearest(a, pair_f[i]);
    ASSERT_NE(p, nullptr);
    EXPECT_LT(std::fabs(p->decay_per_s - pair_d[i]) / pair_d[i], 0.03) << pair_f[i];
  }
  for (const Mode& m : {modes[4], modes[7], modes[10], modes[13], modes[14], modes[17]}) {
    const SpectralPeak* p = nearest(a, m.f);
    ASSERT_NE(p, nullptr);
    EXPECT_LT(std::fabs(p->freq_hz - m.f), 0.05) << m.f;
    EXPECT_LT(std::fabs(p->decay_per_s - m.d) / m.d, 0.03) << m.f;
  }
}

TEST(Analyze, WeakModeBesideAStrongOneIsKept) {
  // A -58 dB line 1.5 kHz from a 0 dB one of the same decay (just inside the -60 dB floor):
  // the strong line's skirt there, (d / 2 pi + 1 / pi T) / df of its peak (Lorentzian plus the
  // onset step), is -70 dB, so the weak line stands 12 dB above it and is a line, not leakage.
  // Nothing else is reported.
  const AudioBuffer audio =
      partials({{3000.0, 0.5, 2.0, 0.2}, {4500.0, 0.5 * std::pow(10.0, -58.0 / 20.0), 2.0, 1.1}}, 48000.0, 2.0);
  const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
  const SpectralPeak* p = nearest(a, 4500.0);
  ASSERT_NE(p, nullptr);
  EXPECT_NEAR(p->freq_hz, 4500.0, 0.05);
  EXPECT_NEAR(p->level_db, -58.0, 1.5);  // the skirt, 12 dB down, adds or cancels up to 2.3 dB
  EXPECT_NEAR(p->decay_per_s, 2.0, 0.03 * 2.0);
  for (const SpectralPeak& q : a.peaks)
    EXPECT_TRUE(std::fabs(q.freq_hz - 3000.0) < 0.1 || std::fabs(q.freq_hz - 4500.0) < 0.1) << q.freq_hz;
}

/// One impact per tap: every mode (f, a, d) rings as g a e^{-d (t - t0)} sin(2 pi f (t - t0)) from
/// the tap's time t0 with the tap's gain g, summed (a linear body struck several times).
struct Tap {
  double time_s;
  double gain;
};
AudioBuffer tappedModes(const std::vector<test::Partial>& modes, const std::vector<Tap>& taps, double rate_hz,
                        double duration_s) {
  AudioBuffer audio;
  audio.sample_rate_hz = rate_hz;
  const auto frames = static_cast<size_t>(std::llround(duration_s * rate_hz));
  audio.samples.resize(frames);
  for (size_t n = 0; n < frames; ++n) {
    const double t = static_cast<double>(n) / rate_hz;
    double x = 0.0;
    for (const Tap& tap : taps) {
      if (t < tap.time_s) continue;
      const double s = t - tap.time_s;
      for (const test::Partial& m : modes)
        x += tap.gain * m.amplitude * std::exp(-m.decay_per_s * s) * std::sin(2.0 * test::kPi * m.freq_hz * s);
    }
    audio.samples[n] = static_cast<float>(x);
  }
  return audio;
}

TEST(Analyze, RepeatedTapsOfOneModeAreOnePeakWithItsDecay) {
  // Issue 15: four taps of one mode (bank: d = 38.3 /s) were reported as a comb of peaks at
  // 5562-5572 Hz, 1/(time between taps) apart, with a decay of 2.45 /s: over the whole file the
  // line is multiplied by |sum_i g_i e^{-j 2 pi f t_i}|. Expected: one peak at f, decay d.
  const double f = 5567.0, d = 38.3;
  const std::vector<Tap> taps = {{0.05, 1.0}, {0.31, 0.7}, {0.52, 1.2}, {0.86, 0.5}};
  const AudioAnalysis a = analyzeAudio(tappedModes({{f, 0.2, d}}, taps, 48000.0, 1.5), AnalyzeOptions{});
  for (const SpectralPeak& p : a.peaks)
    std::printf("    %10.3f Hz %7.2f dB d %8.4f\n", p.freq_hz, p.level_db, p.decay_per_s);
  ASSERT_EQ(a.peaks.size(), 1u);  // a sum of damped sinusoids of one frequency has one line
  EXPECT_NEAR(a.peaks[0].freq_hz, f, 0.05);
  EXPECT_NEAR(a.peaks[0].decay_per_s, d, 0.01 * d);
  ASSERT_EQ(a.impact_onsets_s.size(), taps.size());
  for (size_t i = 0; i < taps.size(); ++i) EXPECT_NEAR(a.impact_onsets_s[i], taps[i].time_s, 1e-3);
}

TEST(Analyze, BlocksFallingImpactsGiveNoComb) {
  // The three lowest modes of blocks-falling.json's wooden block (strike info on its bank:
  // 8047 Hz d 384 /s, 9444 Hz d 524 /s, 10145 Hz d 602 /s) struck at the render's four audible
  // impacts (0.059, 0.299, 0.424, 0.468 s). The old analyzer reported 20 peaks from 7958 to
  // 8117 Hz, ~8 Hz apart (the impacts' comb), with T60 0.57 s for 0.018 s.
  const std::vector<test::Partial> modes = {{8047.0, 0.05, 384.0}, {9444.0, 0.03, 524.0}, {10145.0, 0.03, 602.0}};
  const std::vector<Tap> taps = {{0.059, 0.4}, {0.299, 0.3}, {0.424, 1.0}, {0.468, 0.6}};
  const AudioAnalysis a = analyzeAudio(tappedModes(modes, taps, 48000.0, 3.0), AnalyzeOptions{});
  for (const SpectralPeak& p : a.peaks)
    std::printf("    %10.3f Hz %7.2f dB d %8.4f\n", p.freq_hz, p.level_db, p.decay_per_s);
  EXPECT_EQ(a.peaks.size(), modes.size());
  for (const test::Partial& m : modes) {
    int count = 0;
    for (const SpectralPeak& p : a.peaks) count += std::fabs(p.freq_hz - m.freq_hz) < 200.0;
    EXPECT_EQ(count, 1) << m.freq_hz;
    const SpectralPeak* p = nearest(a, m.freq_hz);
    ASSERT_NE(p, nullptr);
    EXPECT_NEAR(p->freq_hz, m.freq_hz, 0.5);
    EXPECT_NEAR(p->decay_per_s, m.decay_per_s, 0.03 * m.decay_per_s) << m.freq_hz;
  }
}

}  // namespace
}  // namespace strike
