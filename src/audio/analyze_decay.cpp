// SPDX-License-Identifier: MIT
// The analysis' decay fits (target strike_fftw): frames of the ring demodulated at one line,
// their log magnitude and phase fitted by lines (decay and frequency), near-degenerate pairs by
// two-pole linear prediction, and the frame length chosen for the line and its neighbours.
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include "analyze_lines.hpp"
#include "strike/core/constants.hpp"

namespace strike::detail {
namespace {

constexpr double kNepersPerDb = 0.11512925464970229;  // ln(10) / 20

/// Blackman-Harris 4-term window: -92 dB sidelobes, main lobe +-4 bins (Harris, "On the use of
/// windows for harmonic analysis with the discrete Fourier transform", Proc. IEEE 66(1), 1978).
double blackmanHarris(size_t n, size_t length) {
  const double x = 2.0 * kPi * (static_cast<double>(n) + 0.5) / static_cast<double>(length);
  return 0.35875 - 0.48829 * std::cos(x) + 0.14128 * std::cos(2.0 * x) - 0.01168 * std::cos(3.0 * x);
}

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

}  // namespace

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

}  // namespace strike::detail
