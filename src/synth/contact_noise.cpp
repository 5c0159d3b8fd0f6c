// SPDX-License-Identifier: MIT
// The audio-rate force of a rolling, sliding or scraping contact (strike/synth/contact_noise.hpp;
// docs/contact.md derives what follows). Per output sample, for each of the two surfaces:
//  1. the contact point moves over the surface: where it is comes from the physics steps' spots
//     (linear between steps), how far it went from the track speed (a resting body whose contact
//     points flicker between steps travels nowhere);
//  2. the profile: an Ornstein-Uhlenbeck process in track length s with rms sigma and
//     correlation length l, updated exactly whenever the point enters a new cell of a cubic grid
//     in the body's frame, h <- rho h + sigma sqrt(1 - rho^2) w, rho = exp(-ds / l), w of zero
//     mean and unit variance from a hash of the cell and the surface: exact second-order
//     statistics at any spacing, and the same spot always gives the same w;
//  3. the patch: two cascaded one-pole low-passes in track length, of length 0.41 a each (the
//     low-wavenumber roll-off of the average over the patch diameter 2a).
// The two filtered profiles add (a bump on either surface pushes the bodies apart) and drive the
// contact: m x'' = F - N, F = N (delta / delta0)^e + c delta', delta = delta0 + h - x, F >= 0,
// with e = 3/2 and delta0 = a^2 / R* for a Hertz contact, e = 1 and delta0 = the combined rms
// roughness for flat on flat (the load of a rough contact grows in proportion to the approach over
// a range of one roughness [Greenwood & Williamson 1966]), integrated with substeps of at most
// 0.4 / omega_c (semi-implicit Euler). delta <= 0 is lost contact (F = 0): what makes a fast roll
// over a bumpy surface rattle [Rath & Rocchesso 2005, "Continuous sonic feedback from a rolling
// ball", IEEE MultiMedia 12(2)]. Output: the substeps' mean F minus N.
#include "strike/synth/contact_noise.hpp"

#include <algorithm>
#include <cmath>

namespace strike {
namespace {

constexpr double kCellUnit_m = 1e-7;  // grid spacings are kCellUnit_m * 2^level

uint64_t mix64(uint64_t z) {  // splitmix64 finalizer
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// Zero mean, unit variance (uniform on +-sqrt 3): the profile's spectrum needs only the first two
// moments, and the sum over many cells is Gaussian.
double cellNoise(uint64_t seed, int level, const int64_t cell[3]) {
  // Unsigned: the product wraps by definition (signed overflow is undefined; UBSan found it).
  uint64_t k = mix64(seed ^ (static_cast<uint64_t>(static_cast<int64_t>(level)) * 0x632be59bd9b4e019ull));
  k = mix64(k ^ static_cast<uint64_t>(cell[0]));
  k = mix64(k ^ static_cast<uint64_t>(cell[1]));
  k = mix64(k ^ static_cast<uint64_t>(cell[2]));
  const double u = static_cast<double>(k >> 11) * (1.0 / 9007199254740992.0);  // [0, 1)
  return (2.0 * u - 1.0) * 1.7320508075688772;
}

double lerp(double a, double b, double t) { return a + (b - a) * t; }

}  // namespace

double contactDampingRatio(double restitution) {
  if (!(restitution > 0.0)) return 1.0;
  if (restitution >= 1.0) return 0.0;
  const double l = std::log(restitution);
  return -l / std::sqrt(M_PI * M_PI + l * l);
}

double RoughContact::stiffness(const RoughContactDesc& d, double normal_force_n, double patch_radius_m) {
  if (!(normal_force_n > 0.0)) return 0.0;
  const bool hertz = std::isfinite(d.radius_m) && d.radius_m > 0.0;
  if (hertz) {
    double a = patch_radius_m;
    if (!(a > 0.0) && d.modulus_pa > 0.0) a = std::cbrt(3.0 * normal_force_n * d.radius_m / (4.0 * d.modulus_pa));
    if (!(a > 0.0)) return 0.0;
    return 1.5 * normal_force_n * d.radius_m / (a * a);  // (3/2) N / delta0 = 2 E* a
  }
  const double sigma = std::hypot(d.a.rms_m, d.b.rms_m);
  return sigma > 0.0 ? normal_force_n / sigma : 0.0;
}

double RoughContact::patchLength(const RoughContactDesc& d, double patch_radius_m) {
  // Average over a length W: |H|^2 = 1 - (pi k W)^2 / 3 + ...; two one-poles of length L:
  // 1 - 8 (pi k L)^2 + ...; equal for L = W / sqrt(24), W = 2a. A flat contact touches at
  // asperities whose radius is about the correlation length (their curvature radius is ~ l^2 /
  // sigma, pressed in by ~sigma) [Greenwood & Williamson 1966].
  const bool hertz = std::isfinite(d.radius_m) && d.radius_m > 0.0;
  if (hertz && patch_radius_m > 0.0) return 2.0 * patch_radius_m / std::sqrt(24.0);
  const double l = std::max(d.a.correlation_m, d.b.correlation_m);
  return 2.0 * l / std::sqrt(24.0);
}

void RoughContact::start(const RoughContactDesc& desc, uint64_t first_sample) {
  desc_ = desc;
  fs_ = desc.sample_rate_hz > 0.0 && std::isfinite(desc.sample_rate_hz) ? desc.sample_rate_hz : 48000.0;
  h_ = 1.0 / fs_;
  pos_ = first_sample;
  active_ = desc.a.rms_m > 0.0 || desc.b.rms_m > 0.0;
  head_ = count_ = 0;
  ta_ = Track{};
  tb_ = Track{};
  lp1_ = lp2_ = lp_prev_ = 0.0;
  x_ = v_ = 0.0;
  level_ = -1000;
  lost_samples_ = 0;
  still_samples_ = 0;
}

bool RoughContact::push(double at, const RoughContactState& state) {
  if (count_ == kMaxStates) return false;
  const size_t i = (head_ + count_) % kMaxStates;
  at_[i] = at;
  states_[i] = state;
  ++count_;
  if (desc_.a.rms_m > 0.0 || desc_.b.rms_m > 0.0) active_ = true;
  return true;
}

void RoughContact::sampleState(double at, RoughContactState& out, bool& ended) const {
  ended = false;
  if (count_ == 0) {
    ended = true;
    return;
  }
  const size_t i0 = head_;
  if (count_ == 1 || at <= at_[i0]) {
    out = states_[i0];
    if (count_ == 1 && at > at_[i0] + kHold_s * fs_) ended = true;
    return;
  }
  const size_t i1 = (head_ + 1) % kMaxStates;
  const RoughContactState &s0 = states_[i0], &s1 = states_[i1];
  const double span = at_[i1] - at_[i0];
  const double t = span > 0.0 ? std::clamp((at - at_[i0]) / span, 0.0, 1.0) : 1.0;
  out.normal_force_n = lerp(s0.normal_force_n, s1.normal_force_n, t);
  out.speed_a_m_s = lerp(s0.speed_a_m_s, s1.speed_a_m_s, t);
  out.speed_b_m_s = lerp(s0.speed_b_m_s, s1.speed_b_m_s, t);
  out.patch_radius_m = lerp(s0.patch_radius_m, s1.patch_radius_m, t);
  for (int k = 0; k < 3; ++k) {
    out.spot_a[k] = lerp(s0.spot_a[k], s1.spot_a[k], t);
    out.spot_b[k] = lerp(s0.spot_b[k], s1.spot_b[k], t);
  }
}

void RoughContact::advanceTrack(Track& t, const SurfaceRoughness& r, const std::array<double, 3>& spot, double ds_m,
                                double cell_m, int level) {
  if (!(r.rms_m > 0.0)) return;
  int64_t cell[3];
  for (int k = 0; k < 3; ++k) {
    // Clamped before the conversion: an absurd position (hostile input) must not overflow it.
    const double index = std::floor(spot[k] / cell_m);
    cell[k] = index > -4e18 && index < 4e18 ? static_cast<int64_t>(index) : 0;  // NaN -> 0
  }
  if (!t.placed || t.cell_m != cell_m) {
    t.placed = true;
    t.cell_m = cell_m;
    std::copy(cell, cell + 3, t.cell);
  } else if (cell[0] != t.cell[0] || cell[1] != t.cell[1] || cell[2] != t.cell[2]) {
    // Exact for any spacing: the OU process sampled ds apart.
    const double rho = std::exp(-t.since_m / r.correlation_m);
    t.h = rho * t.h + r.rms_m * std::sqrt(std::max(0.0, 1.0 - rho * rho)) * cellNoise(r.seed, level, cell);
    t.since_m = 0.0;
    std::copy(cell, cell + 3, t.cell);
  }
  t.since_m += ds_m;
}

void RoughContact::generate(float* out, size_t frames) {
  for (size_t n = 0; n < frames; ++n, ++pos_) {
    out[n] = 0.0f;
    if (!active_) continue;
    const double at = static_cast<double>(pos_);
    while (count_ >= 2 && at_[(head_ + 1) % kMaxStates] <= at) head_ = (head_ + 1) % kMaxStates, --count_;
    RoughContactState s;
    bool ended = false;
    sampleState(at, s, ended);
    if (ended || !(s.normal_force_n > 0.0)) {
      // The contact ended (or carries no load): nothing drives the mass any more.
      if (ended) active_ = false, count_ = 0;
      x_ = v_ = 0.0;
      continue;
    }
    const double va = s.speed_a_m_s >= kStillSpeed_m_s ? s.speed_a_m_s : 0.0;
    const double vb = s.speed_b_m_s >= kStillSpeed_m_s ? s.speed_b_m_s : 0.0;
    // Still for kSettle_s: the contact resonance (a few ms at most) has rung out; nothing moves.
    still_samples_ = va == 0.0 && vb == 0.0 ? still_samples_ + 1 : 0;
    if (static_cast<double>(still_samples_) > kSettle_s * fs_) {
      x_ = v_ = 0.0;
      continue;
    }
    const double ds_a = va * h_, ds_b = vb * h_;
    const double N = s.normal_force_n;
    const bool hertz = std::isfinite(desc_.radius_m) && desc_.radius_m > 0.0 && desc_.modulus_pa > 0.0;
    double patch = s.patch_radius_m;
    if (hertz && !(patch > 0.0)) patch = std::cbrt(3.0 * N * desc_.radius_m / (4.0 * desc_.modulus_pa));
    const double patch_len = patchLength(desc_, patch);
    // Grid: a quarter of the patch or finer, no finer than half a sample's travel (power-of-two spacings,
    // so a slowly changing load does not keep moving the grid).
    if ((pos_ & 63) == 0 || level_ == -1000) {
      const double want = std::max(0.25 * patch_len, std::max(va, vb) * h_);
      int level = want > kCellUnit_m ? static_cast<int>(std::floor(std::log2(want / kCellUnit_m))) : 0;
      level = std::clamp(level, 0, 40);
      if (level != level_) level_ = level, cell_m_ = std::ldexp(kCellUnit_m, level);
    }
    advanceTrack(ta_, desc_.a, s.spot_a, ds_a, cell_m_, level_);
    advanceTrack(tb_, desc_.b, s.spot_b, ds_b, cell_m_, level_);
    // The patch filter runs in track length on each surface's own profile.
    // One cascade for the sum, at the faster track's rate: a surface that moves slower under the
    // patch changes less within it (a sliding block's own profile stands still), so this is exact
    // for rolling (equal speeds) and for sliding (one surface still).
    const double ds = std::max(ds_a, ds_b);
    const double k = patch_len > 0.0 ? -std::expm1(-ds / patch_len) : 1.0;
    const double hin = ta_.h + tb_.h;
    lp1_ += k * (hin - lp1_);
    lp2_ += k * (lp1_ - lp2_);
    const double hf = lp2_, hdot = (hf - lp_prev_) * fs_;
    const double h_prev = lp_prev_;
    lp_prev_ = hf;

    const double delta0 = hertz ? patch * patch / desc_.radius_m : std::hypot(desc_.a.rms_m, desc_.b.rms_m);
    if (!(delta0 > 0.0)) continue;
    const double stiff = (hertz ? 1.5 : 1.0) * N / delta0;
    const double m = desc_.mass_kg;
    const bool moves = std::isfinite(m) && m > 0.0;
    auto elastic = [&](double d) {
      if (!(d > 0.0)) return 0.0;
      const double r = d / delta0;
      return hertz ? N * r * std::sqrt(r) : N * r;
    };
    if (!moves) {
      const double d = delta0 + hf;
      const double f = elastic(d);
      if (!(d > 0.0)) ++lost_samples_;
      out[n] = static_cast<float>(f - N);
      continue;
    }
    const double omega = std::sqrt(stiff / m);
    const double c = 2.0 * desc_.damping_ratio * std::sqrt(stiff * m);
    const int sub = std::clamp(static_cast<int>(std::ceil(omega * h_ / 0.4)), 1, 64);
    const double dt = h_ / sub;
    double f_sum = 0.0;
    bool lost = false;
    for (int j = 1; j <= sub; ++j) {
      const double hs = h_prev + (hf - h_prev) * (static_cast<double>(j) / sub);
      const double d = delta0 + hs - x_;
      double f = 0.0;
      if (d > 0.0) {
        f = std::max(0.0, elastic(d) + c * (hdot - v_));
      } else {
        lost = true;
      }
      v_ += (f - N) / m * dt;
      x_ += v_ * dt;
      f_sum += f;
    }
    if (lost) ++lost_samples_;
    out[n] = static_cast<float>(f_sum / sub - N);
  }
}

}  // namespace strike
