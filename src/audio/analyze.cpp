// SPDX-License-Identifier: MIT
// Level statistics, spectral peaks and per-peak decay rates (target strike_fftw).
#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <mutex>

#include "fftw_lock.hpp"
#include "impact_onsets.hpp"
#include "strike/audio.hpp"
#include "strike/constants.hpp"

namespace strike {
namespace {

constexpr double kNepersPerDb = 0.11512925464970229;  // ln(10) / 20
/// A spectral line must stand this many times (6 dB) above the modelled leakage of the
/// stronger lines at its frequency.
constexpr double kLeakageMargin = 2.0;
/// A line's frame-measured amplitude may fall this far (20 dB) below what its spectral peak
/// implies before the peak is taken for leakage (the frames see lines, not skirts).
constexpr double kMinLineAmplitudeRatio = 0.1;

struct Mono {
  std::vector<double> x;
  size_t onset = 0;
  double peak = 0.0;
};

/// Statistics over all channels, and the mean of the channels with non-finite samples as 0.
Mono mixdown(const AudioBuffer& audio, AudioAnalysis& analysis) {
  Mono mono;
  const size_t channels = static_cast<size_t>(audio.channels);
  const size_t frames = audio.frames();
  mono.x.assign(frames, 0.0);
  double sum_squares = 0.0;
  for (size_t f = 0; f < frames; ++f) {
    double sum = 0.0;
    for (size_t c = 0; c < channels; ++c) {
      const double s = audio.samples[f * channels + c];
      if (!std::isfinite(s)) {
        ++analysis.non_finite_samples;
        continue;
      }
      const double a = std::fabs(s);
      analysis.peak_amplitude = std::max(analysis.peak_amplitude, a);
      if (a >= 1.0) ++analysis.clipped_samples;
      sum_squares += s * s;
      sum += s;
    }
    mono.x[f] = sum / static_cast<double>(channels);
    mono.peak = std::max(mono.peak, std::fabs(mono.x[f]));
  }
  const size_t count = frames * channels;
  analysis.rms = count > 0 ? std::sqrt(sum_squares / static_cast<double>(count)) : 0.0;
  // The onset: first sample above -60 dB of the peak. Frames for the decay fit start here, so
  // none straddles the start of the sound (which would bend the log-envelope line).
  const double threshold = 1e-3 * mono.peak;
  while (mono.onset < frames && !(std::fabs(mono.x[mono.onset]) > threshold)) ++mono.onset;
  return mono;
}

size_t nextPowerOfTwo(size_t n) {
  size_t p = 1;
  while (p < n) p <<= 1;
  return p;
}

/// |X_k| scaled so that a stationary sinusoid of amplitude a peaks at a (2 |X| / sum w).
struct Spectrum {
  std::vector<double> amplitude;
  double bin_hz = 0.0;
  double window_sum = 0.0;  ///< sum of the window over the signal: a line's |X| is A sum(w) / 2
};

Spectrum wholeSpectrum(const Mono& mono, SpectrumWindow window, double rate_hz) {
  const size_t length = mono.x.size() - mono.onset;
  // Zero-padding by at least 2 keeps the quadratic interpolation's bias small (SASP, "Bias of
  // Parabolic Peak Interpolation"); above 2^24 points padding only to N bounds the memory.
  size_t size = nextPowerOfTwo(2 * length);
  if (size > (size_t{1} << 24)) size = nextPowerOfTwo(length);
  double* in = fftw_alloc_real(size);
  fftw_complex* out = fftw_alloc_complex(size / 2 + 1);
  fftw_plan plan;
  {
    std::lock_guard<std::mutex> lock(detail::fftwPlannerMutex());
    plan = fftw_plan_dft_r2c_1d(static_cast<int>(size), in, out, FFTW_ESTIMATE);
  }
  double window_sum = 0.0;
  const double n_total = static_cast<double>(length);
  for (size_t n = 0; n < size; ++n) {
    double w = 0.0;
    if (n < length) {
      const double t = static_cast<double>(n);
      if (window == SpectrumWindow::Hann) {
        const double s = std::sin(kPi * (t + 0.5) / n_total);
        w = s * s;
      } else {
        const double c = std::cos(0.5 * kPi * t / n_total);
        w = c * c;
      }
      window_sum += w;
      in[n] = w * mono.x[mono.onset + n];
    } else {
      in[n] = 0.0;
    }
  }
  fftw_execute(plan);
  Spectrum spectrum;
  spectrum.bin_hz = rate_hz / static_cast<double>(size);
  spectrum.window_sum = window_sum;
  spectrum.amplitude.resize(size / 2 + 1);
  const double scale = window_sum > 0.0 ? 2.0 / window_sum : 0.0;
  for (size_t k = 0; k <= size / 2; ++k) spectrum.amplitude[k] = scale * std::hypot(out[k][0], out[k][1]);
  {
    std::lock_guard<std::mutex> lock(detail::fftwPlannerMutex());
    fftw_destroy_plan(plan);
  }
  fftw_free(in);
  fftw_free(out);
  return spectrum;
}

/// The whole-signal window's response to one decaying complex line, in closed form: for
/// x(n) = e^{(-a + j t) n} (a = d / fs, t = 2 pi (f_line - f) / fs) and a window that is a sum of
/// complex exponentials, sum_n w(n) x(n) is a sum of geometric series (1 - q^L) / (1 - q).
/// OnsetHalfHann: cos^2(pi n / 2L) = 1/2 + (e^{j pi n / L} + e^{-j pi n / L}) / 4.
/// Hann: sin^2(pi (n + 1/2) / L) = 1/2 - (e^{j pi / L} e^{j 2 pi n / L} + conj) / 4.
/// Exact for any offset and decay (the Lorentzian line convolved with the window's transform),
/// so it gives a mode's leakage ("skirt") at any distance, not only its asymptote.
double lineShape(double offset_hz, double decay_per_s, size_t length, double rate_hz, SpectrumWindow window) {
  const double a = decay_per_s / rate_hz;
  const double l = static_cast<double>(length);
  auto series = [&](double theta) {
    // 1 - q with q = e^{-a} e^{j theta}, without cancellation when a and theta are tiny.
    const double c = std::cos(theta), s = std::sin(theta), half = std::sin(0.5 * theta);
    const std::complex<double> one_minus_q(-std::expm1(-a) * c + 2.0 * half * half, -std::exp(-a) * s);
    const std::complex<double> q_l = std::exp(std::complex<double>(-a * l, theta * l));
    if (std::abs(one_minus_q) < 1e-14) return std::complex<double>(l, 0.0);
    return (1.0 - q_l) / one_minus_q;
  };
  const double theta = -2.0 * kPi * offset_hz / rate_hz;
  if (window == SpectrumWindow::Hann) {
    const std::complex<double> e(std::cos(kPi / l), std::sin(kPi / l));
    return std::abs(0.5 * series(theta) - 0.25 * e * series(theta + 2.0 * kPi / l) -
                    0.25 * std::conj(e) * series(theta - 2.0 * kPi / l));
  }
  return std::abs(0.5 * series(theta) + 0.25 * series(theta + kPi / l) + 0.25 * series(theta - kPi / l));
}

/// -3 dB half width of lineShape (bisection: the main lobe falls monotonically to it).
double modelHalfWidthHz(double decay_per_s, size_t length, double rate_hz, SpectrumWindow window) {
  const double target = lineShape(0.0, decay_per_s, length, rate_hz, window) / std::sqrt(2.0);
  double lo = 0.0, hi = rate_hz / static_cast<double>(length);
  while (lineShape(hi, decay_per_s, length, rate_hz, window) > target && hi < 0.25 * rate_hz) hi *= 2.0;
  for (int i = 0; i < 50; ++i) {
    const double mid = 0.5 * (lo + hi);
    (lineShape(mid, decay_per_s, length, rate_hz, window) > target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// The decay whose model line is as wide as the measured one (0 if it is no wider than the
/// window's own main lobe). For the leakage test before the decay is fitted; a merged pair
/// looks wider than either mode, which over-estimates its skirt (the safe side).
double decayFromHalfWidth(double half_width_hz, size_t length, double rate_hz, SpectrumWindow window) {
  if (!(half_width_hz > modelHalfWidthHz(0.0, length, rate_hz, window))) return 0.0;
  double lo = 0.0, hi = 2.0 * kPi * half_width_hz;
  while (modelHalfWidthHz(hi, length, rate_hz, window) < half_width_hz && hi < rate_hz) hi *= 2.0;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    (modelHalfWidthHz(mid, length, rate_hz, window) < half_width_hz ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

struct Candidate {
  double freq_hz = 0.0;
  double amplitude = 0.0;
  double half_width_hz = 0.0;      ///< half width at -3 dB, for the first guess of the decay
  double skirt_decay_per_s = 0.0;  ///< decay used to model this line's leakage onto others
};

/// Quadratic interpolation of log|X| through bins k-1, k, k+1 (Smith, SASP, "Quadratic
/// Interpolation of Spectral Peaks"): offset p = (a - c) / (2 (a - 2b + c)) bins, log peak
/// b - (a - c) p / 4. On log magnitude the fit is exact for a Gaussian main lobe and close for
/// Hann-like lobes.
Candidate interpolatePeak(const Spectrum& spectrum, size_t k) {
  const double a = std::log(spectrum.amplitude[k - 1]);
  const double b = std::log(spectrum.amplitude[k]);
  const double c = std::log(spectrum.amplitude[k + 1]);
  const double denominator = a - 2.0 * b + c;
  const double p = denominator < 0.0 ? std::clamp(0.5 * (a - c) / denominator, -0.5, 0.5) : 0.0;
  Candidate candidate;
  candidate.freq_hz = (static_cast<double>(k) + p) * spectrum.bin_hz;
  candidate.amplitude = std::exp(b - 0.25 * (a - c) * p);
  return candidate;
}

/// -3 dB half width of a peak: walk out on both sides (stopping at a valley, which belongs to
/// a neighbour) and interpolate linearly.
double halfWidthHz(const Spectrum& spectrum, const Candidate& candidate) {
  const double half_power = candidate.amplitude / std::sqrt(2.0);
  const double k_peak = candidate.freq_hz / spectrum.bin_hz;
  const auto k = static_cast<size_t>(std::lround(k_peak));
  const size_t last = spectrum.amplitude.size() - 1;
  const double* a = spectrum.amplitude.data();
  auto edge = [&](int direction) {
    size_t j = k;
    for (;;) {
      const size_t next = direction > 0 ? j + 1 : j - 1;
      if (j == 0 || j == last || a[j] <= half_power || a[next] > a[j]) break;
      j = next;
    }
    if (j == k) return 0.5;
    const size_t inner = direction > 0 ? j - 1 : j + 1;
    const double y0 = a[inner], y1 = a[j];
    const double frac = y0 > y1 ? std::clamp((y0 - half_power) / (y0 - y1), 0.0, 1.0) : 1.0;
    return std::fabs(static_cast<double>(inner) + direction * frac - k_peak);
  };
  return 0.5 * (edge(+1) + edge(-1)) * spectrum.bin_hz;
}

/// Blackman-Harris 4-term window: -92 dB sidelobes, main lobe +-4 bins (Harris, "On the use of
/// windows for harmonic analysis with the discrete Fourier transform", Proc. IEEE 66(1), 1978).
double blackmanHarris(size_t n, size_t length) {
  const double x = 2.0 * kPi * (static_cast<double>(n) + 0.5) / static_cast<double>(length);
  return 0.35875 - 0.48829 * std::cos(x) + 0.14128 * std::cos(2.0 * x) - 0.01168 * std::cos(3.0 * x);
}

struct DecayFit {
  double decay_per_s = -1.0;  ///< < 0: too few usable frames
  double freq_hz = 0.0;       ///< from the phase slope of the same frames
  double amplitude = 0.0;     ///< A of A e^{-d t} cos(...) at the onset, from the line's intercept
};

/// Near-degenerate pairs. Two modes closer than the line width (a square bar's bending pairs,
/// 0.01-3 Hz apart) make one spectral peak, and the demodulated frames u_m = Y_m e^{-j w0 s_m}
/// are c1 z1^m + c2 z2^m: their magnitude beats slowly, so the log-line fit is biased (for two
/// modes of equal decay starting in antiphase the envelope can even rise). But u_m is exactly a
/// sum of two exponentials (the frames are linear and shift-invariant), so a two-pole linear
/// prediction recovers both (Prony's method; Kay, "Modern Spectral Estimation", 1988, ch. 11):
/// u_{m+2K} = p1 u_{m+K} + p2 u_m, roots r_k = z_k^K of r^2 - p1 r - p2. The lag K = count/3
/// spreads the poles by K times their one-hop separation, which is what keeps the fit
/// well-conditioned for pairs whose beat period exceeds the fit range. Used only when one
/// exponential leaves more than 1e-4 of the energy unexplained and two explain ten times more,
/// and the two decays are within a factor of 2 (a near-degenerate pair shares its damping; a
/// wider spread means the second pole is fitting something else). Then decay and frequency are
/// the |c_k|^2-weighted means of the two, i.e. the pair's, and amplitude is |c1| + |c2|.
void refineAsPair(const std::vector<double>& times_s, const std::vector<double>& logs,
                  const std::vector<double>& phases, size_t m_begin, size_t m_end, double frames_per_s, double freq_hz,
                  DecayFit& fit) {
  using C = std::complex<double>;
  const size_t count = m_end - m_begin;
  if (count < 9) return;
  std::vector<C> u(count);
  double energy = 0.0;
  for (size_t m = 0; m < count; ++m) {
    u[m] = std::polar(std::exp(logs[m_begin + m] - logs[m_begin]), phases[m_begin + m]);
    energy += std::norm(u[m]);
  }
  // One exponential, with the fit's own decay and frequency; its complex amplitude by least squares.
  auto residualOf = [&](const std::vector<C>& z, std::vector<C>& c) {
    // Least squares for u_m = sum_k c_k z_k^m (k = 1 or 2) through the normal equations.
    const size_t k_count = z.size();
    C g[2][2] = {{0.0, 0.0}, {0.0, 0.0}}, r[2] = {0.0, 0.0};
    std::vector<C> power(k_count, C(1.0, 0.0));
    for (size_t m = 0; m < count; ++m) {
      for (size_t a = 0; a < k_count; ++a) {
        r[a] += std::conj(power[a]) * u[m];
        for (size_t b = 0; b < k_count; ++b) g[a][b] += std::conj(power[a]) * power[b];
      }
      for (size_t a = 0; a < k_count; ++a) power[a] *= z[a];
    }
    c.assign(k_count, 0.0);
    if (k_count == 1) {
      c[0] = r[0] / g[0][0];
    } else {
      const C det = g[0][0] * g[1][1] - g[0][1] * g[1][0];
      if (std::abs(det) < 1e-300) return std::numeric_limits<double>::infinity();
      c[0] = (r[0] * g[1][1] - g[0][1] * r[1]) / det;
      c[1] = (g[0][0] * r[1] - g[1][0] * r[0]) / det;
    }
    double residual = 0.0;
    std::fill(power.begin(), power.end(), C(1.0, 0.0));
    for (size_t m = 0; m < count; ++m) {
      C model = 0.0;
      for (size_t a = 0; a < k_count; ++a) {
        model += c[a] * power[a];
        power[a] *= z[a];
      }
      residual += std::norm(u[m] - model);
    }
    return residual / energy;
  };
  const double hop_s = 1.0 / frames_per_s;
  std::vector<C> c1;
  const double residual1 =
      residualOf({std::exp(C(-fit.decay_per_s * hop_s, 2.0 * kPi * (fit.freq_hz - freq_hz) * hop_s))}, c1);
  if (!(residual1 > 1e-4)) return;
  const size_t lag = count / 3;
  C g00 = 0.0, g01 = 0.0, g11 = 0.0, r0 = 0.0, r1 = 0.0;
  for (size_t m = 0; m + 2 * lag < count; ++m) {
    const C a = u[m + lag], b = u[m], y = u[m + 2 * lag];
    g00 += std::norm(a);
    g01 += std::conj(a) * b;
    g11 += std::norm(b);
    r0 += std::conj(a) * y;
    r1 += std::conj(b) * y;
  }
  const C det = g00 * g11 - g01 * std::conj(g01);
  if (std::abs(det) < 1e-300) return;
  const C p1 = (r0 * g11 - g01 * r1) / det;
  const C p2 = (g00 * r1 - std::conj(g01) * r0) / det;
  const C root = std::sqrt(p1 * p1 + 4.0 * p2);
  std::vector<C> z;
  for (const C r : {0.5 * (p1 + root), 0.5 * (p1 - root)}) {
    // A growing pole, or one so far off that its K-th root is ambiguous, is not half a pair.
    if (!(std::abs(r) < 1.0) || std::fabs(std::arg(r)) > 0.9 * kPi) return;
    z.push_back(std::exp(std::log(r) / static_cast<double>(lag)));
  }
  std::vector<C> c2;
  const double residual2 = residualOf(z, c2);
  if (!(residual2 < 0.1 * residual1)) return;
  double weight = 0.0, decay = 0.0, freq = 0.0, d_min = std::numeric_limits<double>::infinity(), d_max = 0.0;
  for (size_t k = 0; k < 2; ++k) {
    const double d_k = -std::log(std::abs(z[k])) / hop_s;
    const double w = std::norm(c2[k]);
    d_min = std::min(d_min, d_k);
    d_max = std::max(d_max, d_k);
    weight += w;
    decay += w * d_k;
    freq += w * (freq_hz + std::arg(z[k]) / (2.0 * kPi * hop_s));
  }
  if (!(weight > 0.0) || !(d_max < 2.0 * d_min)) return;
  fit.decay_per_s = decay / weight;
  fit.freq_hz = freq / weight;
  fit.amplitude *= (std::abs(c2[0]) + std::abs(c2[1])) / std::abs(c1[0]);
  (void)times_s;
}

/// Decay rate from one frame length: log|Y_m| over frame starts s_m = onset + m hop, where
/// Y_m = sum_n w(n) x(s_m + n) e^{-j 2 pi f0 n / fs}. For x = A e^{-d t} cos(2 pi f t + phi),
/// Y_m = (A/2) e^{(-d + j 2 pi f) s_m / fs} * (a constant of the frame) + (what leaks in), so
/// log|Y_m| is a line of slope -d and arg Y_m a line of slope 2 pi f, for any frame length and
/// any f0 within the main lobe. The frame length decides only what else leaks in. The phase
/// slope refines the frequency: unlike the whole-signal peak it is not pulled by the
/// negative-frequency image of a wide (fast-decaying, low) line, which the window rejects.
DecayFit fitDecayWithFrame(const Mono& mono, double rate_hz, double freq_hz, double decay_guess, size_t frame) {
  const size_t available = mono.x.size() - mono.onset;
  if (frame < 16 || frame >= available) return {};
  // Sample the envelope finely enough for ~48 points over a 60 dB fall (or over the signal).
  const double signal_s = static_cast<double>(available - frame) / rate_hz;
  const double fit_s = decay_guess > 0.0 ? std::min(60.0 * kNepersPerDb / decay_guess, signal_s) : signal_s;
  const size_t hop = std::max<size_t>(1, std::min(frame / 4, static_cast<size_t>(fit_s * rate_hz / 48.0)));

  std::vector<double> wc(frame), ws(frame);
  const double omega = 2.0 * kPi * freq_hz / rate_hz;
  for (size_t n = 0; n < frame; ++n) {
    const double w = blackmanHarris(n, frame);
    wc[n] = w * std::cos(omega * static_cast<double>(n));
    ws[n] = w * std::sin(omega * static_cast<double>(n));
  }
  std::vector<double> times_s, logs, phases;
  double log_max = -std::numeric_limits<double>::infinity();
  size_t m_max = 0;
  for (size_t start = mono.onset; start + frame <= mono.x.size(); start += hop) {
    const double* x = mono.x.data() + start;
    double re = 0.0, im = 0.0;
    for (size_t n = 0; n < frame; ++n) {
      re += wc[n] * x[n];
      im += ws[n] * x[n];
    }
    const double magnitude = std::hypot(re, im);
    // Y_m = re - j im. Phase relative to the demodulation frequency, unwrapped frame to frame:
    // the residual advances (f - f0) 2 pi hop / fs per frame, far below pi.
    const double offset = std::atan2(-im, re) - omega * static_cast<double>(start - mono.onset);
    if (phases.empty()) {
      phases.push_back(std::remainder(offset, 2.0 * kPi));
    } else {
      phases.push_back(phases.back() + std::remainder(offset - phases.back(), 2.0 * kPi));
    }
    const double log_magnitude = magnitude > 0.0 ? std::log(magnitude) : -745.0;
    times_s.push_back(static_cast<double>(start - mono.onset) / rate_hz);
    logs.push_back(log_magnitude);
    if (log_magnitude > log_max) {
      log_max = log_magnitude;
      m_max = logs.size() - 1;
    }
    // 120 dB down: the rest is float rounding or the noise floor; stop computing.
    if (logs.size() > m_max + 4 && log_magnitude < log_max - 120.0 * kNepersPerDb) break;
  }
  if (logs.size() < m_max + 4) return {};
  // Noise floor: median of the last quarter of the frames. Fit from the loudest frame down to
  // 10 dB above that floor, at most 60 dB; if the whole record falls less than 16 dB (a slow
  // decay in a short file), the floor is the signal itself and every frame is used.
  std::vector<double> tail(logs.end() - static_cast<std::ptrdiff_t>(std::max<size_t>(1, logs.size() / 4)), logs.end());
  std::nth_element(tail.begin(), tail.begin() + static_cast<std::ptrdiff_t>(tail.size() / 2), tail.end());
  const double floor_log = tail[tail.size() / 2];
  double range = std::min(60.0 * kNepersPerDb, log_max - floor_log - 10.0 * kNepersPerDb);
  size_t m_end = logs.size();
  if (log_max - floor_log >= 16.0 * kNepersPerDb) {
    m_end = m_max + 1;
    while (m_end < logs.size() && logs[m_end] >= log_max - range) ++m_end;
  }
  const size_t count = m_end - m_max;
  if (count < 4) return {};
  double mean_t = 0.0, mean_y = 0.0;
  for (size_t m = m_max; m < m_end; ++m) {
    mean_t += times_s[m];
    mean_y += logs[m];
  }
  mean_t /= static_cast<double>(count);
  mean_y /= static_cast<double>(count);
  double stt = 0.0, sty = 0.0;
  for (size_t m = m_max; m < m_end; ++m) {
    stt += (times_s[m] - mean_t) * (times_s[m] - mean_t);
    sty += (times_s[m] - mean_t) * (logs[m] - mean_y);
  }
  if (!(stt > 0.0)) return {};
  // The phase line is weighted by |Y_m|^2: in additive noise the variance of arg Y_m grows as
  // 1 / |Y_m|^2 (weighted least squares), so the quiet end of the range barely counts.
  double sw = 0.0, wt = 0.0, wp = 0.0;
  for (size_t m = m_max; m < m_end; ++m) {
    const double w = std::exp(2.0 * (logs[m] - log_max));
    sw += w;
    wt += w * times_s[m];
    wp += w * phases[m];
  }
  const double wmean_t = wt / sw, wmean_p = wp / sw;
  double wstt = 0.0, wstp = 0.0;
  for (size_t m = m_max; m < m_end; ++m) {
    const double w = std::exp(2.0 * (logs[m] - log_max));
    wstt += w * (times_s[m] - wmean_t) * (times_s[m] - wmean_t);
    wstp += w * (times_s[m] - wmean_t) * (phases[m] - wmean_p);
  }
  DecayFit fit;
  fit.decay_per_s = std::max(0.0, -sty / stt);  // a rising envelope is reported as no decay
  {
    // |Y(0)| = (A / 2) sum_n w(n) e^{-d n / fs} for a line that starts at the onset.
    const double intercept = mean_y + fit.decay_per_s * mean_t;
    double gain = 0.0;
    for (size_t n = 0; n < frame; ++n)
      gain += blackmanHarris(n, frame) * std::exp(-fit.decay_per_s * static_cast<double>(n) / rate_hz);
    fit.amplitude = 2.0 * std::exp(intercept) / gain;
  }
  fit.freq_hz = wstt > 0.0 ? freq_hz + wstp / wstt / (2.0 * kPi) : freq_hz;
  refineAsPair(times_s, logs, phases, m_max, m_end, rate_hz / static_cast<double>(hop), freq_hz, fit);
  return fit;
}

/// Frame length: long enough to put the nearest other peak (df Hz away) and the peak's own
/// negative-frequency image beyond the Blackman-Harris main lobe (4 bins; 5/df s leaves a
/// margin), and at least 20 ms; short enough (<= 8/d s) that a fast-decaying mode is not
/// buried under the window's rise while a slower neighbour fills the frame; at most half of
/// the signal. No longer than that: the line fit is exact for any length, and the cost is
/// (frames) x (length).
size_t frameLengthFor(double decay_per_s, double freq_hz, double nearest_df_hz, double rate_hz, size_t available) {
  const double image_s = 2.5 / freq_hz;
  const double separation_s = nearest_df_hz > 0.0 ? 5.0 / nearest_df_hz : 0.0;
  const double high_s = decay_per_s > 0.0 ? 8.0 / decay_per_s : std::numeric_limits<double>::infinity();
  const double length_s = std::max(image_s, std::min(std::max(0.02, separation_s), high_s));
  const double max_frame = static_cast<double>(available / 2);
  return static_cast<size_t>(std::clamp(std::round(length_s * rate_hz), 16.0, std::max(16.0, max_frame)));
}

DecayFit fitDecay(const Mono& mono, double rate_hz, const Candidate& peak, double nearest_df_hz) {
  const size_t available = mono.x.size() - mono.onset;
  // First guess from the spectral -3 dB half width: a Lorentzian line has HWHM = d / (2 pi).
  double decay = 2.0 * kPi * peak.half_width_hz;
  size_t frame = frameLengthFor(decay, peak.freq_hz, nearest_df_hz, rate_hz, available);
  DecayFit fitted;
  for (int iteration = 0; iteration < 4; ++iteration) {
    DecayFit fit = fitDecayWithFrame(mono, rate_hz, peak.freq_hz, decay, frame);
    // Too few frames above the floor: the width guess was too narrow (noise ripples on a wide
    // line's top end the -3 dB walk early), so the line died within a frame or two. Retry
    // with guesses 4 and 16 times faster (shorter frames, finer hop).
    for (int retry = 0; retry < 2 && iteration == 0 && fit.decay_per_s < 0.0; ++retry) {
      decay *= 4.0;
      frame = frameLengthFor(decay, peak.freq_hz, nearest_df_hz, rate_hz, available);
      fit = fitDecayWithFrame(mono, rate_hz, peak.freq_hz, decay, frame);
    }
    if (fit.decay_per_s < 0.0) break;
    fitted = fit;
    decay = fit.decay_per_s;
    const size_t next = frameLengthFor(decay, peak.freq_hz, nearest_df_hz, rate_hz, available);
    const double ratio = static_cast<double>(next) / static_cast<double>(frame);
    if (ratio > 0.8 && ratio < 1.25) break;
    frame = next;
  }
  return fitted;
}

struct Line {
  SpectralPeak peak;      ///< decay_per_s always fitted (analyzeAudio clears it if not wanted)
  double merge_hz = 0.0;  ///< lines of other segments within this are the same line
};

/// The genuine spectral lines of one free ring, mono.x from mono.onset on, strongest first:
/// candidates of the whole-signal spectrum that pass the leakage and line tests.
std::vector<Line> findLines(const Mono& mono, double rate_hz, const AnalyzeOptions& options) {
  std::vector<Line> lines;
  const size_t length = mono.x.size() - mono.onset;
  const Spectrum spectrum = wholeSpectrum(mono, options.window, rate_hz);
  // Local maxima within 1 dB of the floor (interpolation raises a peak by less than that);
  // a long file has millions of ripples far below it.
  const double* bins = spectrum.amplitude.data();
  const double loudest_bin = *std::max_element(spectrum.amplitude.begin(), spectrum.amplitude.end());
  const double candidate_floor = loudest_bin * std::pow(10.0, (options.floor_db - 1.0) / 20.0);
  std::vector<Candidate> candidates;
  for (size_t k = 1; k + 1 < spectrum.amplitude.size(); ++k) {
    if (bins[k] >= candidate_floor && bins[k] > bins[k - 1] && bins[k] >= bins[k + 1] && bins[k - 1] > 0.0 &&
        bins[k + 1] > 0.0)
      candidates.push_back(interpolatePeak(spectrum, k));
  }
  if (candidates.empty()) return lines;
  // Strongest first; equal levels by frequency, so the order is deterministic.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.amplitude != b.amplitude ? a.amplitude > b.amplitude : a.freq_hz < b.freq_hz;
  });
  const double strongest = candidates.front().amplitude;
  const double floor_amplitude = strongest * std::pow(10.0, options.floor_db / 20.0);
  const double bin_hz = rate_hz / static_cast<double>(length);  // of the unpadded DFT
  const double min_separation_hz = options.min_separation_bins * bin_hz;
  std::vector<Candidate> accepted;
  // Enough neighbours to choose decay frame lengths; more only costs time (a very low floor
  // in a noisy file has thousands of candidates).
  const size_t max_accepted = 4 * static_cast<size_t>(options.max_peaks) + 16;
  for (const Candidate& c : candidates) {
    if (c.amplitude < floor_amplitude || accepted.size() >= max_accepted) break;
    const bool separate = std::all_of(accepted.begin(), accepted.end(), [&](const Candidate& a) {
      const double df_hz = std::fabs(a.freq_hz - c.freq_hz);
      if (df_hz < min_separation_hz) return false;
      if (options.window != SpectrumWindow::Hann) return true;
      // Hann sidelobes: |W(b)| = |sin(pi b) / (pi b (1 - b^2))| at b bins; a candidate below
      // twice the sidelobe envelope of a stronger peak may be that sidelobe (Harris 1978).
      const double b = df_hz / bin_hz;
      return b >= 1.5 && c.amplitude > 2.0 * a.amplitude / (kPi * b * (b * b - 1.0));
    });
    if (!separate) continue;
    // Leakage test. Between and beside strong decaying modes the spectrum is the sum of their
    // skirts (a line of decay d falls only as d / (2 pi df) of its peak, 1/f, whatever the
    // window), and where those skirts cross it is flat to a fraction of a dB: any ripple there
    // (interference of the skirts, the window's end) is a local maximum. A genuine line stands
    // above the summed skirts of the stronger lines, modelled exactly by lineShape (with the
    // negative-frequency images); a ripple does not: its level is at most that sum.
    double leakage = 0.0;
    for (const Candidate& a : accepted) {
      const double at_peak = lineShape(0.0, a.skirt_decay_per_s, length, rate_hz, options.window);
      leakage += a.amplitude *
                 (lineShape(c.freq_hz - a.freq_hz, a.skirt_decay_per_s, length, rate_hz, options.window) +
                  lineShape(c.freq_hz + a.freq_hz, a.skirt_decay_per_s, length, rate_hz, options.window)) /
                 at_peak;
    }
    if (!(c.amplitude > kLeakageMargin * leakage)) continue;
    Candidate kept = c;
    kept.half_width_hz = halfWidthHz(spectrum, kept);
    kept.skirt_decay_per_s = decayFromHalfWidth(kept.half_width_hz, length, rate_hz, options.window);
    accepted.push_back(kept);
  }

  // Confirmation and decay, strongest first, until max_peaks lines are confirmed. The frame fit
  // runs even when no decay is wanted: it is what tells a line from a leakage ripple.
  std::vector<char> dropped(accepted.size(), 0);
  const size_t wanted = static_cast<size_t>(options.max_peaks);
  for (size_t i = 0; i < accepted.size() && lines.size() < wanted; ++i) {
    const Candidate& c = accepted[i];
    SpectralPeak peak;
    peak.freq_hz = c.freq_hz;
    peak.level_dbfs = 20.0 * std::log10(c.amplitude);
    peak.level_db = 20.0 * std::log10(c.amplitude / strongest);
    // Neighbours include peaks above the floor that are not reported (they still leak), but
    // not candidates already found to be leakage.
    double nearest_df_hz = 0.0;
    for (size_t j = 0; j < accepted.size(); ++j) {
      if (j == i || dropped[j]) continue;
      const double df = std::fabs(accepted[j].freq_hz - c.freq_hz);
      if (nearest_df_hz == 0.0 || df < nearest_df_hz) nearest_df_hz = df;
    }
    const DecayFit fit = fitDecay(mono, rate_hz, c, nearest_df_hz);
    if (fit.decay_per_s >= 0.0) {
      // Line test. The frames reject every other peak (> 4 of their bins away) to -92 dB, so
      // they see only what is really at this frequency. A line of amplitude A (at the onset)
      // and decay d gives the whole-signal peak A lineShape(0, d) / sum(w); if the frames
      // find less than a tenth of that A, the peak was the skirts of other lines.
      const double spectral_a =
          c.amplitude * spectrum.window_sum / lineShape(0.0, fit.decay_per_s, length, rate_hz, options.window);
      if (fit.amplitude < kMinLineAmplitudeRatio * spectral_a) {
        dropped[i] = 1;
        continue;
      }
    }
    peak.decay_per_s = fit.decay_per_s;  // cleared by analyzeAudio when no decay is wanted
    if (options.fit_decay) {
      // Take the phase-slope frequency when it lies within the line's own -3 dB half width
      // (a wide line's spectral peak is pulled by up to about that much) and nearer to this
      // peak than to any other, so it cannot have locked onto a neighbour.
      const double shift_hz = std::fabs(fit.freq_hz - c.freq_hz);
      if (fit.decay_per_s >= 0.0 && shift_hz < std::max(0.5 * min_separation_hz, c.half_width_hz) &&
          (nearest_df_hz == 0.0 || shift_hz < 0.5 * nearest_df_hz))
        peak.freq_hz = fit.freq_hz;
    }
    // Lines this close to this one are the same line seen in another impact's segment: the
    // bins that could not resolve them, or the line's own -3 dB half width d / 2 pi.
    const double merge_hz = std::max(min_separation_hz, peak.decay_per_s > 0.0 ? peak.decay_per_s / (2.0 * kPi) : 0.0);
    lines.push_back({peak, merge_hz});
  }
  return lines;
}

/// Lines found in each impact's segment, merged: a line is kept from the segment where it is
/// strongest (its frequency, level and decay), and lines of other segments within either's
/// merge_hz are that line again. Strongest first, at most max_peaks, above floor_db.
std::vector<SpectralPeak> mergeSegmentLines(std::vector<Line> lines, const AnalyzeOptions& options) {
  std::stable_sort(lines.begin(), lines.end(), [](const Line& a, const Line& b) {
    return a.peak.level_dbfs != b.peak.level_dbfs ? a.peak.level_dbfs > b.peak.level_dbfs
                                                  : a.peak.freq_hz < b.peak.freq_hz;
  });
  std::vector<SpectralPeak> peaks;
  if (lines.empty()) return peaks;
  const double strongest_dbfs = lines.front().peak.level_dbfs;
  std::vector<const Line*> kept;
  for (const Line& line : lines) {
    if (peaks.size() >= static_cast<size_t>(options.max_peaks)) break;
    if (line.peak.level_dbfs < strongest_dbfs + options.floor_db) break;
    const bool same = std::any_of(kept.begin(), kept.end(), [&](const Line* k) {
      return std::fabs(k->peak.freq_hz - line.peak.freq_hz) < std::max(k->merge_hz, line.merge_hz);
    });
    if (same) continue;
    kept.push_back(&line);
    SpectralPeak peak = line.peak;
    peak.level_db = peak.level_dbfs - strongest_dbfs;
    peaks.push_back(peak);
  }
  return peaks;
}

}  // namespace

AudioAnalysis analyzeAudio(const AudioBuffer& audio, const AnalyzeOptions& options) {
  AudioAnalysis analysis;
  analysis.sample_rate_hz = audio.sample_rate_hz;
  if (audio.channels < 1 || !(audio.sample_rate_hz > 0.0)) return analysis;
  analysis.duration_s = static_cast<double>(audio.frames()) / audio.sample_rate_hz;
  const Mono mono = mixdown(audio, analysis);
  analysis.onset_s = static_cast<double>(mono.onset) / audio.sample_rate_hz;
  const size_t length = mono.x.size() - mono.onset;
  if (!(mono.peak > 0.0) || length < 16 || options.max_peaks <= 0) return analysis;

  const std::vector<size_t> onsets = detail::impactOnsets(mono.x, mono.onset, mono.peak, audio.sample_rate_hz);
  for (const size_t onset : onsets)
    analysis.impact_onsets_s.push_back(static_cast<double>(onset) / audio.sample_rate_hz);
  std::vector<Line> lines;
  if (onsets.size() <= 1) {
    lines = findLines(mono, audio.sample_rate_hz, options);
    for (const Line& line : lines) analysis.peaks.push_back(line.peak);
  } else {
    // Several impacts. Over a window that spans two of them a mode is the same line twice,
    // delayed: its spectrum is multiplied by |1 + e^{-j 2 pi f dt}|, a comb of period 1/dt Hz
    // whose teeth pass as lines, and the frames see the envelope jump at each impact. Between
    // two onsets the sound is one free ring (earlier impacts' modes go on at the same
    // frequencies and decays), so each segment is analysed alone and the lines merged.
    // A segment starts 2 ms after its onset: during the contact (a Hertz half-sine, well under
    // 1 ms for the hard bodies Strike renders) stiff modes follow the force instead of ringing,
    // a broadband click whose ripples would pass as short-lived lines (blocks-falling: 12
    // "lines" from 70 to 3200 Hz at -10 dB, decaying at the click's 440-490 /s, none a mode).
    // It ends 1 ms before the next onset (the contact may start before the block that shows
    // it). Segments under 40 ms (25 Hz bins) are skipped: their ring continues into the next
    // segment, which sees it; if all are that short, the longest is used.
    const size_t contact = static_cast<size_t>(std::lround(2e-3 * audio.sample_rate_hz));
    const size_t guard = static_cast<size_t>(std::lround(1e-3 * audio.sample_rate_hz));
    const size_t min_length = static_cast<size_t>(std::lround(0.04 * audio.sample_rate_hz));
    struct Segment {
      size_t begin, end;
    };
    std::vector<Segment> segments;
    for (size_t i = 0; i < onsets.size(); ++i) {
      const size_t end =
          i + 1 < onsets.size() ? std::max(onsets[i], onsets[i + 1] - std::min(guard, onsets[i + 1])) : mono.x.size();
      segments.push_back({std::min(end, onsets[i] + contact), end});
    }
    std::vector<Segment> used;
    for (const Segment& s : segments)
      if (s.end - s.begin >= min_length) used.push_back(s);
    if (used.empty())
      used.push_back(*std::max_element(segments.begin(), segments.end(), [](const Segment& a, const Segment& b) {
        return a.end - a.begin < b.end - b.begin;
      }));
    for (const Segment& s : used) {
      if (s.end - s.begin < 16) continue;
      Mono part;
      part.x.assign(mono.x.begin() + static_cast<std::ptrdiff_t>(s.begin),
                    mono.x.begin() + static_cast<std::ptrdiff_t>(s.end));
      for (const double v : part.x) part.peak = std::max(part.peak, std::fabs(v));
      if (!(part.peak > 0.0)) continue;
      const std::vector<Line> found = findLines(part, audio.sample_rate_hz, options);
      lines.insert(lines.end(), found.begin(), found.end());
    }
    analysis.peaks = mergeSegmentLines(std::move(lines), options);
  }
  if (!options.fit_decay)
    for (SpectralPeak& peak : analysis.peaks) peak.decay_per_s = -1.0;
  return analysis;
}

}  // namespace strike
