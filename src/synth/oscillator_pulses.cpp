// SPDX-License-Identifier: MIT
// The oscillator bank's scheduling: a contact pulse (half-sine or box) integrated exactly into
// each mode it touches, its transient and its injection (oscillator_bank.cpp describes the
// method); a box or a change of sustained force as a few ideal injections; contact damping
// changes on the block grid. The impact records come from a pool, so that a reserved bank
// schedules without allocating.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "oscillator_bank_impl.hpp"

namespace strike {

using detail::Complex;
using detail::Impact;
using detail::kBlock;
using detail::ModeKind;

// When one pulse acts, in the terms every mode's response to it needs.
struct OscillatorBank::Impl::PulseTiming {
  double tau_s = 0.0;        // duration
  double after_end_s = 0.0;  // from the pulse's end to its injection sample
  double first_u_s = 0.0;    // from its start to the first sample of its transient
  double pulse_omega = 0.0;  // Om: the augmented pulse state (f, f'/Om) rotates at Om (0: box)
  double extra_damping = 0.0;
  bool ideal = false, box = false;
};

// Every record can hold an impact on the object and a pulse of max_transient samples.
void OscillatorBank::Impl::reserveImpacts(size_t records, size_t max_transient) {
  const size_t max_modes = modes.size();
  const bool grew = max_modes > reserved_hits || max_transient > reserved_transient;
  reserved_hits = std::max(reserved_hits, max_modes);
  reserved_transient = std::max(reserved_transient, max_transient);
  const size_t old_size = pool.size();
  pool.reserve(records);
  free_records.reserve(records);
  while (pool.size() < records) {
    pool.emplace_back();
    free_records.push_back(static_cast<uint32_t>(pool.size() - 1));
  }
  pending.reserve(pool.size());
  free_records.reserve(pool.size());
  // Only new records need capacity unless the reservation itself grew.
  for (size_t i = grew ? 0 : old_size; i < pool.size(); ++i) {
    pool[i].hits.reserve(reserved_hits);
    pool[i].transient.reserve(reserved_transient);
  }
}

// The extra (contact) damping in force at `sample`: pulses and the oscillators they feed must
// use the same pole.
double OscillatorBank::Impl::extraDampingAt(uint64_t sample) const {
  auto after = std::upper_bound(damping_schedule.begin(), damping_schedule.end(),
                                std::make_pair(sample, static_cast<double>(INFINITY)));
  return after != damping_schedule.begin() ? std::prev(after)->second : 0.0;
}

void OscillatorBank::Impl::insertPending(uint32_t record) {
  auto at = std::upper_bound(pending.begin(), pending.end(), pool[record].start_sample,
                             [this](uint64_t s, uint32_t other) { return s < pool[other].start_sample; });
  pending.insert(at, record);  // capacity >= pool.size(): no allocation
}

// A free record (there must be one) for injections at the first sample at or after at_sample.
uint32_t OscillatorBank::Impl::takeRecord(double at_sample) {
  const uint32_t record = free_records.back();
  free_records.pop_back();
  Impact& im = pool[record];
  im.start_sample = im.end_sample = std::max<uint64_t>(static_cast<uint64_t>(std::ceil(at_sample - 1e-7)), pos);
  im.injected = false;
  im.hits.clear();
  im.transient.clear();
  return record;
}

// no_alloc: fail with NoCapacity rather than grow a record or the pool.
ImpactResult OscillatorBank::Impl::addImpact(const ImpactDesc& desc, bool no_alloc) {
  const double now = static_cast<double>(pos);
  double t0 = (desc.time_s + delay_s) * fs;  // in samples
  if (!(t0 >= now)) t0 = now;                // late (or NaN): start now
  double tau = desc.duration_s * fs;         // in samples
  if (!(tau > 0.0) || !std::isfinite(tau)) tau = 0.0;
  // Below 1e-9 samples a pulse is an impulse at its centroid to ~1e-18 relative.
  const bool ideal = tau < 1e-9;
  if (ideal) t0 += 0.5 * tau, tau = 0.0;
  // A sample counts as "at or after" an instant up to 1e-7 samples of rounding; the formulas
  // below are analytic, so evaluating them a hair before the instant is harmless.
  uint64_t start_sample = static_cast<uint64_t>(std::ceil(t0 - 1e-7));
  uint64_t end_sample = ideal ? start_sample : static_cast<uint64_t>(std::ceil(t0 + tau - 1e-7));
  start_sample = std::max<uint64_t>(start_sample, pos);
  end_sample = std::max(end_sample, start_sample);
  const size_t transient_len = static_cast<size_t>(end_sample - start_sample);
  if (desc.shape == PulseShape::Box && !ideal && !no_alloc && onlyRinging(desc)) return addBoxAsSteps(desc, t0, tau);
  if (free_records.empty()) {
    if (no_alloc) return ImpactResult::NoCapacity;
    reserveImpacts(std::max<size_t>(16, pool.size() * 2), 0);  // geometric: O(1) amortized
  }
  const uint32_t record = free_records.back();
  Impact& im = pool[record];
  if (no_alloc && (im.hits.capacity() < modes.size() || im.transient.capacity() < transient_len))
    return ImpactResult::NoCapacity;
  free_records.pop_back();
  ++stats.impacts;
  im.start_sample = start_sample;
  im.end_sample = end_sample;
  im.injected = false;
  im.hits.clear();
  im.transient.assign(transient_len, 0.0);  // within capacity: no allocation
  PulseTiming pt;
  pt.tau_s = tau * h;
  pt.after_end_s = (static_cast<double>(im.end_sample) - (t0 + tau)) * h;
  pt.first_u_s = (static_cast<double>(im.start_sample) - t0) * h;
  pt.ideal = ideal;
  pt.box = desc.shape == PulseShape::Box && !ideal;
  pt.pulse_omega = ideal || pt.box ? 0.0 : M_PI / pt.tau_s;
  // Contact damping scheduled at the pulse's start (setExtraDamping is called before the
  // impacts it covers), so pulses and the oscillators they feed use the same pole.
  pt.extra_damping = extraDampingAt(start_sample);
  if (std::memcmp(&pulse.tau_s, &pt.tau_s, sizeof pt.tau_s) != 0 ||
      std::memcmp(&pulse.extra_damping, &pt.extra_damping, sizeof pt.extra_damping) != 0 || pulse.box != pt.box) {
    pulse.tau_s = pt.tau_s, pulse.extra_damping = pt.extra_damping, pulse.box = pt.box;
    ++pulse.stamp;
  }
  for (uint32_t j = 0; j < modes.size() && desc.modal_impulse; ++j) {
    const Complex factor = desc.modal_transfer ? desc.modal_transfer[j] : Complex(1.0, 0.0);
    const double g = desc.modal_impulse[j];
    if (g == 0.0 || !std::isfinite(g) || !(std::isfinite(factor.real()) && std::isfinite(factor.imag()))) continue;
    if (modes[j].kind == ModeKind::Ringing)
      ringingHit(j, g, factor, pt, im);
    else if (modes[j].kind == ModeKind::Damped)
      dampedHit(j, g * factor.real(), pt, im);  // no phase to turn: the factor's real part scales it
  }
  if (im.hits.empty()) {
    ++stats.impacts_inaudible;
    free_records.push_back(record);
    return ImpactResult::Inaudible;
  }
  insertPending(record);
  return ImpactResult::Scheduled;
}

// A ringing mode's share of a pulse: its injection and, unless the pulse is ideal, its transient.
void OscillatorBank::Impl::ringingHit(uint32_t mi, double g, Complex factor, const PulseTiming& pt, Impact& im) {
  ModeInfo& m = modes[mi];
  const double tau_s = pt.tau_s;
  // The pole in force when the pulse starts (contact damping may have moved it).
  const Complex pole = m.base_pole - pt.extra_damping;
  const Complex step = pt.extra_damping == 0.0 ? m.base_step : std::exp(pole * h);
  if (!pt.ideal && m.end_stamp != pulse.stamp) {
    m.pulse_end = pt.box ? detail::boxResponse(pole, tau_s, tau_s) : detail::halfSineResponse(pole, tau_s, tau_s);
    m.end_stamp = pulse.stamp;
  }
  const Complex y_end = pt.ideal ? Complex(1.0, 0.0) : m.pulse_end;
  const Complex bg = g * m.out_weight * factor;
  const Complex v = bg * std::exp(pole * pt.after_end_s) * y_end;
  if (!(std::abs(v) >= threshold)) return;
  im.hits.push_back({mi, v});
  if (im.transient.empty()) return;
  if (pt.box) {
    // Transient of the box: y(U) = E(0, p, U) / tau, E(0, p, U + h) = e^{ph} E(0, p, U) + E(0, p, h).
    Complex e0 = detail::expDividedDifference(Complex(0.0, 0.0), pole, pt.first_u_s);
    const Complex h0 = detail::expDividedDifference(Complex(0.0, 0.0), pole, h);
    const Complex k = bg / tau_s;
    // A box is a sustained force, so its feedthrough g R f (left out of the ringing output)
    // is added back while it acts: a constant force then gives exactly zero acceleration
    // once its onset has rung out, instead of a DC offset of -g R F. Point samples of the
    // half-open box [t0, t0 + tau) tile exactly when boxes are contiguous.
    const double feedthrough = g * factor.real() * m.radiation / tau_s;
    for (double& out : im.transient) {
      out += (k * e0).real() + feedthrough;
      e0 = step * e0 + h0;
    }
    return;
  }
  // Transient: y(U) = K (E(i Om, p, U) - E(-i Om, p, U)) / 2i at U = first_u + n h, with
  // E(a, p, U + h) = e^{ph} E(a, p, U) + e^{aU} E(a, p, h): exact, stable recurrences.
  const Complex ia(0.0, pt.pulse_omega);
  const detail::ExpPair first = detail::expDividedDifferencePair(ia, -ia, pole, pt.first_u_s);
  if (m.step_stamp != pulse.stamp) {
    m.pulse_step = detail::expDividedDifferencePair(ia, -ia, pole, h);
    m.step_stamp = pulse.stamp;
  }
  const detail::ExpPair& one_step = m.pulse_step;
  Complex ep = first.plus, em = first.minus;
  const Complex hp = one_step.plus, hm = one_step.minus;
  Complex rot_p = first.exp_plus, rot_m = std::conj(rot_p);  // e^{i Om U}
  const Complex turn_p = one_step.exp_plus, turn_m = std::conj(turn_p);
  const Complex k = bg * (M_PI / (2.0 * tau_s)) / Complex(0.0, 2.0);
  for (double& out : im.transient) {
    out += (k * (ep - em)).real();
    ep = step * ep + rot_p * hp;
    em = step * em + rot_m * hm;
    rot_p *= turn_p;
    rot_m *= turn_m;
  }
}

// A non-ringing mode's share of a pulse, by exponentiating the pulse-augmented 4x4 system.
void OscillatorBank::Impl::dampedHit(uint32_t mi, double gr, const PulseTiming& pt, Impact& im) const {
  const ModeInfo& m = modes[mi];
  const double tau_s = pt.tau_s;
  const detail::Mat4 a = detail::augmentedMatrix(m.omega0, m.damping_c, pt.pulse_omega);
  // Half-sine: f = (pi / 2 tau) sin(Om u) enters as f'/Om = pi / (2 tau) at u = 0; box: f = 1 / tau.
  const std::array<double, 4> x0 = pt.box ? std::array<double, 4>{0.0, 0.0, 1.0 / tau_s, 0.0}
                                          : std::array<double, 4>{0.0, 0.0, 0.0, pt.ideal ? 0.0 : M_PI / (2.0 * tau_s)};
  std::array<double, 4> x_end{0.0, 1.0, 0.0, 0.0};
  if (!pt.ideal) x_end = detail::mul4(detail::expm4(a, tau_s), x0);
  x_end[2] = x_end[3] = 0.0;  // the pulse is over
  const std::array<double, 4> x_inj =
      detail::mul4(detail::expm4(detail::augmentedMatrix(m.omega0, m.damping_c, 0.0), pt.after_end_s), x_end);
  const Complex v(gr * x_inj[0], gr * x_inj[1]);
  if (!(dampedAmplitude(m, v.real(), v.imag()) >= threshold)) return;
  im.hits.push_back({mi, v});
  if (im.transient.empty()) return;
  const detail::Mat4 step = detail::expm4(a, h);
  std::array<double, 4> x = detail::mul4(detail::expm4(a, pt.first_u_s), x0);
  const double w = gr * m.radiation;
  for (double& out : im.transient) {
    // The box's feedthrough f = x[2] is part of the output while it acts (see above).
    out += w * (-m.omega0 * x[0] - m.damping_c * x[1] + (pt.box ? x[2] : 0.0));
    x = detail::mul4(step, x);
  }
}

// Mode j's share of a box or a force change whose modal input is `modal` (impulse or force
// change) and per-mode factor `transfer`: b g times the factor, and its pole under the contact
// damping. False for a zero or non-finite input or a mode that does not ring.
bool OscillatorBank::Impl::ringingInput(uint32_t j, const double* modal, const Complex* transfer, double extra_damping,
                                        RingingInput& out) const {
  const double g = modal[j];
  if (g == 0.0 || !std::isfinite(g)) return false;
  const ModeInfo& m = modes[j];
  if (m.kind != ModeKind::Ringing) return false;
  out = {j, g * m.out_weight * (transfer ? transfer[j] : Complex(1.0, 0.0)), m.base_pole - extra_damping};
  return true;
}

// True when every mode the impact touches rings (no over- or critically damped ones).
bool OscillatorBank::Impl::onlyRinging(const ImpactDesc& desc) const {
  for (uint32_t j = 0; j < modes.size() && desc.modal_impulse; ++j)
    if (modes[j].kind == ModeKind::Damped && desc.modal_impulse[j] != 0.0) return false;
  return true;
}

// A box of force g / tau on [t0, t0 + tau] is, for a ringing mode, exactly two steps: the
// ringing part of its response is (e^{pU} - H(U - tau) e^{p(U - tau)}) / (p tau), and the rest,
// the static deflection -1/(p tau) while it acts, cancels the box's own feedthrough g R / tau.
// So it costs two ideal injections, +-b g / (p tau), however long it lasts (a body resting for
// seconds), instead of a transient of tau * fs samples.
ImpactResult OscillatorBank::Impl::addBoxAsSteps(const ImpactDesc& desc, double t0, double tau) {
  const double tau_s = tau * h;
  const double extra_damping = extraDampingAt(std::max<uint64_t>(static_cast<uint64_t>(std::ceil(t0 - 1e-7)), pos));
  // With ramped edges (the box convolved with a unit box of r), each edge is two ramps and
  // the ringing part is e^{pU} / (p^2 tau r) at t0, t0 + r, t0 + tau, t0 + tau + r with signs
  // + - - +; the polynomial parts again cancel the feedthrough g R f. min_freq_hz >= 20 Hz keeps
  // |p r| >= 0.06 for r >= 0.5 ms, so the four injections cancel to at most ~250x float rounding.
  const double ramp = desc.ramp_s * fs;  // samples
  const bool ramped = ramp >= 1e-6 && std::isfinite(ramp);
  const double ramp_s = ramped ? ramp * h : 0.0;
  ++stats.impacts;
  bool audible = false;
  const int edges = ramped ? 4 : 2;
  for (int edge = 0; edge < edges; ++edge) {
    const double te =
        !ramped ? (edge == 0 ? t0 : t0 + tau) : t0 + (edge == 1 || edge == 3 ? ramp : 0.0) + (edge >= 2 ? tau : 0.0);
    if (free_records.empty()) reserveImpacts(std::max<size_t>(16, pool.size() * 2), 0);
    const uint32_t record = takeRecord(te);
    Impact& im = pool[record];
    const double after_s = (static_cast<double>(im.start_sample) - te) * h;
    const double sign = (edge == 0 || edge == 3) ? 1.0 : -1.0;
    for (uint32_t j = 0; j < modes.size() && desc.modal_impulse; ++j) {
      RingingInput in;
      if (!ringingInput(j, desc.modal_impulse, desc.modal_transfer, extra_damping, in)) continue;
      const Complex bg = in.bg, pole = in.pole;
      const Complex step_amplitude = ramped ? bg / (pole * pole * tau_s * ramp_s) : bg / (pole * tau_s);
      // Audible when the net ringing after the box, |b g (e^{p tau} - 1) / (p tau)|, is (one
      // audible mode is enough: the rest are not asked).
      if (edge == 0 && !audible && std::abs(bg * (std::exp(pole * tau_s) - 1.0) / (pole * tau_s)) >= threshold)
        audible = true;
      im.hits.push_back({in.mode, sign * step_amplitude * std::exp(pole * after_s)});
    }
    insertPending(record);
  }
  if (!audible) ++stats.impacts_inaudible;
  return ImpactResult::Scheduled;
}

// A change dF of a sustained force, ramped linearly over [t0, t0 + r] (r = 0: a step). For a
// ringing mode the force ramp's response is, besides the static deflection that cancels the
// force's own feedthrough (as for the box above), e^{pU} b g / (p^2 r) at t0 minus the same at
// t0 + r, g = phi . dF; for r = 0 one injection b g / p. A non-ringing mode's deviation from its
// new static deflection starts at (omega0 q, q') = (-g / omega0, 0), taken at the ramp's
// centroid (such modes decay within a few periods, far shorter than anything heard of a ramp).
// Cost: two or three injections, whatever the force.
ImpactResult OscillatorBank::Impl::addForceStep(const ForceStepDesc& desc, bool no_alloc) {
  const uint32_t mode_count = static_cast<uint32_t>(modes.size());
  double t0 = (desc.time_s + delay_s) * fs;
  if (!(t0 >= static_cast<double>(pos))) t0 = static_cast<double>(pos);
  const double ramp = desc.ramp_s * fs;
  const bool ramped = ramp >= 1e-6 && std::isfinite(ramp);
  const double ramp_s = ramped ? ramp * h : 0.0;
  const int ringing_edges = ramped ? 2 : 1;
  bool has_damped = false;
  for (uint32_t j = 0; j < mode_count && desc.modal_force_change; ++j)
    if (modes[j].kind == ModeKind::Damped && desc.modal_force_change[j] != 0.0) has_damped = true;
  const size_t records = static_cast<size_t>(ringing_edges) + (has_damped ? 1 : 0);
  if (free_records.size() < records) {
    if (no_alloc) return ImpactResult::NoCapacity;
    reserveImpacts(std::max<size_t>(16, pool.size() * 2 + records), 0);
  }
  if (no_alloc)
    for (size_t k = 0; k < records; ++k)
      if (pool[free_records[free_records.size() - 1 - k]].hits.capacity() < mode_count) return ImpactResult::NoCapacity;
  const double extra_damping = extraDampingAt(std::max<uint64_t>(static_cast<uint64_t>(std::ceil(t0 - 1e-7)), pos));
  ++stats.impacts;
  bool audible = false;
  auto schedule = [&](uint32_t record) {
    if (pool[record].hits.empty())
      free_records.push_back(record);
    else
      insertPending(record);
  };
  // The ramp's two edges share each mode's amplitude, and their sub-sample offsets are usually
  // the same bits (the edges a whole number of samples apart): one division per mode, and one
  // exponential where the offsets agree.
  uint32_t edge_record[2] = {0, 0};
  double edge_after_s[2] = {0.0, 0.0};
  for (int edge = 0; edge < ringing_edges; ++edge) {
    const double te = t0 + (edge == 1 ? ramp : 0.0);
    edge_record[edge] = takeRecord(te);
    edge_after_s[edge] = (static_cast<double>(pool[edge_record[edge]].start_sample) - te) * h;
  }
  const bool same_offset = std::memcmp(&edge_after_s[0], &edge_after_s[1], sizeof(double)) == 0;
  for (uint32_t j = 0; j < mode_count && desc.modal_force_change; ++j) {
    RingingInput in;
    if (!ringingInput(j, desc.modal_force_change, desc.modal_transfer, extra_damping, in)) continue;
    const Complex bg = in.bg, pole = in.pole;
    const Complex amplitude = ramped ? bg / (pole * pole * ramp_s) : bg / pole;
    // Audible when the net ringing after the ramp, |b g (e^{p r} - 1) / (p^2 r)|, is (one
    // audible mode is enough: the rest are not asked).
    if (!audible) {
      const Complex net = ramped ? amplitude * (std::exp(pole * ramp_s) - 1.0) : amplitude;
      audible = std::abs(net) >= threshold;
    }
    const Complex rise = std::exp(pole * edge_after_s[0]);
    pool[edge_record[0]].hits.push_back({in.mode, amplitude * rise});
    if (ringing_edges == 2) {
      const Complex fall = same_offset ? rise : std::exp(pole * edge_after_s[1]);
      pool[edge_record[1]].hits.push_back({in.mode, -amplitude * fall});
    }
  }
  for (int edge = 0; edge < ringing_edges; ++edge) schedule(edge_record[edge]);
  if (has_damped) {
    const double centroid = t0 + 0.5 * (ramped ? ramp : 0.0);
    // Injected at the ramp's end or later, evolved from the centroid.
    const uint32_t record = takeRecord(t0 + (ramped ? ramp : 0.0));
    Impact& im = pool[record];
    const double after_s = (static_cast<double>(im.start_sample) - centroid) * h;
    for (uint32_t j = 0; j < mode_count && desc.modal_force_change; ++j) {
      const double g = desc.modal_force_change[j];
      const ModeInfo& m = modes[j];
      if (m.kind != ModeKind::Damped || g == 0.0 || !std::isfinite(g)) continue;
      const double gr = g * (desc.modal_transfer ? desc.modal_transfer[j].real() : 1.0);
      const std::array<double, 4> x0{-gr / m.omega0, 0.0, 0.0, 0.0};
      const std::array<double, 4> x =
          detail::mul4(detail::expm4(detail::augmentedMatrix(m.omega0, m.damping_c, 0.0), after_s), x0);
      if (!(dampedAmplitude(m, x[0], x[1]) >= threshold)) continue;
      audible = true;
      im.hits.push_back({j, Complex(x[0], x[1])});
    }
    schedule(record);
  }
  if (!audible) {
    ++stats.impacts_inaudible;
    return ImpactResult::Inaudible;
  }
  return ImpactResult::Scheduled;
}

// no_alloc: refuse (false) rather than grow the schedules beyond what setUpModes reserved.
bool OscillatorBank::Impl::scheduleExtraDamping(double time_s, double extra_decay_per_s, bool no_alloc) {
  if (!(extra_decay_per_s >= 0.0) || !std::isfinite(extra_decay_per_s)) return false;
  const double t = (time_s + delay_s) * fs;
  // Changes take effect at block ends: round up to the block grid so impacts know exactly
  // which pole is in force.
  uint64_t sample = t > static_cast<double>(pos) ? static_cast<uint64_t>(std::ceil(t)) : pos;
  sample = (sample + kBlock - 1) / kBlock * kBlock;
  auto& schedule = damping_schedule;
  // Entries in the past matter only through the last of them (the pole in force now).
  size_t past = 0;
  while (past + 1 < schedule.size() && schedule[past + 1].first <= pos) ++past;
  if (past > 0) schedule.erase(schedule.begin(), schedule.begin() + static_cast<std::ptrdiff_t>(past));
  if (no_alloc && (schedule.size() == schedule.capacity() || damping_changes.size() == damping_changes.capacity()))
    return false;
  const auto change = std::make_pair(sample, extra_decay_per_s);
  schedule.insert(
      std::upper_bound(schedule.begin(), schedule.end(), std::make_pair(sample, static_cast<double>(INFINITY))),
      change);
  auto at = std::upper_bound(damping_changes.begin(), damping_changes.end(), sample,
                             [](uint64_t s0, const std::pair<uint64_t, double>& c) { return s0 < c.first; });
  damping_changes.insert(at, change);
  return true;
}

}  // namespace strike
