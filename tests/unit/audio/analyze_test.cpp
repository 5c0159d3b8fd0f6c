// SPDX-License-Identifier: MIT
// analyzeAudio against closed forms: stationary tones (frequency, level), exponentially
// decaying tones (decay rate), level statistics, clipping, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>

#include "audio/test_util.hpp"
#include "strike/audio.hpp"

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
  const AudioBuffer audio = partials({{440.0, 0.5, 0.0, 0.3}, {1234.5, 0.05, 0.0, 1.1}, {5000.0, 0.005, 0.0, 2.0}}, rate, 1.0);
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
                static_cast<int>(window), expected_f[i], rel_f, std::fabs(p.freq_hz - expected_f[i]) * 1.0,
                p.level_db, p.level_db - expected_db[i], p.level_dbfs - (expected_db[i] + 20.0 * std::log10(0.5)));
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
      std::printf("    f %7.1f Hz d %6.1f /s: fitted %9.4f /s (error %+.3f%%), frequency error %.2e\n", f, d, p.decay_per_s,
                  100.0 * err, std::fabs(p.freq_hz - f) / f);
      EXPECT_LT(std::fabs(err), 0.03) << "f " << f << " d " << d;
      EXPECT_LT(std::fabs(p.freq_hz - f) / f, 1e-3);
    }
}

TEST(Analyze, ModesOfAnImpactKeepTheirDecays) {
  // A struck-bar-like spectrum: faster decay at higher modes; all start at t = 0.
  const std::vector<test::Partial> modes = {
      {523.0, 0.4, 2.0, 0.0}, {1441.0, 0.3, 8.0, 1.0}, {2826.0, 0.2, 25.0, 2.0}, {4671.0, 0.1, 70.0, 3.0}, {6977.0, 0.05, 180.0, 4.0}};
  const AudioBuffer audio = partials(modes, 48000.0, 1.5);
  const AudioAnalysis a = analyzeAudio(audio, AnalyzeOptions{});
  for (const test::Partial& m : modes) {
    const SpectralPeak* p = nearest(a, m.freq_hz);
    ASSERT_NE(p, nullptr);
    std::printf("    mode %6.0f Hz: %9.3f Hz, d %7.3f (true %5.1f, error %+.3f%%), level %7.2f dB\n", m.freq_hz, p->freq_hz,
                p->decay_per_s, m.decay_per_s, 100.0 * (p->decay_per_s - m.decay_per_s) / m.decay_per_s, p->level_db);
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
    std::printf("    df %4.1f Hz: %.3f Hz d %.4f (true 3, %+.3f%%); %.3f Hz d %.4f (true 9, %+.3f%%)\n", df, p1->freq_hz,
                p1->decay_per_s, 100.0 * (p1->decay_per_s - 3.0) / 3.0, p2->freq_hz, p2->decay_per_s,
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
  std::printf("    quantized d 40: fitted %.4f (%+.3f%%)\n", a.peaks[0].decay_per_s, 100.0 * (a.peaks[0].decay_per_s - 40.0) / 40.0);
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
  audio.samples[10] = 1.0f;     // exactly full scale counts as clipped
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

}  // namespace
}  // namespace strike
