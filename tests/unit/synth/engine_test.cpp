// SPDX-License-Identifier: MIT
// The sound engine (strike/synth/engine.hpp): force steps against closed forms, the contact
// scheduler's resting, pushing and sleeping bodies, and the listener following a moving body.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "strike/synth/engine.hpp"
#include "synth_fixtures.hpp"

namespace strike {
namespace {

constexpr double kRate = 48000.0;

// ---- force steps --------------------------------------------------------------------------

// Output of a ringing mode (R = 1) to a unit force step at t = 0: the acceleration q'' of
// q'' + c q' + lambda q = H(t), q'' = e^{-sigma t} (cos w_d t - (sigma / w_d) sin w_d t).
double stepResponse(double lambda, double c, double t) {
  const double sigma = 0.5 * c, wd = std::sqrt(lambda - sigma * sigma);
  return std::exp(-sigma * t) * (std::cos(wd * t) - sigma / wd * std::sin(wd * t));
}

TEST(ForceStep, SharpStepMatchesTheClosedForm) {
  SynthSettings s;
  s.sample_rate_hz = kRate;
  s.double_precision = true;
  s.audibility_threshold = 0.0;
  const ModalObjectDesc object = test::makeObject({700.0}, 1e-7, 2.0);
  OscillatorBank bank(s, object);
  const double g = 0.3, t0 = 10.3 / kRate;
  bank.addForceStep(ForceStepDesc{t0, 0.0, &g});
  const std::vector<float> out = test::renderAll(bank, 4800);
  const double lambda = object.eigenvalues[0], c = 1e-7 * lambda + 2.0;
  double worst = 0.0;
  for (size_t n = 11; n < out.size(); ++n)
    worst = std::max(worst, std::fabs(out[n] - g * stepResponse(lambda, c, n / kRate - t0)));
  EXPECT_LT(worst, 1e-6 * g) << "a force step is its exact response, not an approximation";
  for (size_t n = 0; n <= 10; ++n) EXPECT_EQ(out[n], 0.0f) << "nothing before the step, sample " << n;
}

TEST(ForceStep, RampUpAndDownEqualsTheRampedBox) {
  // A box of force F held over tau with edges ramped over r is a ramp up by F at t0 and a ramp
  // down by F at t0 + tau (linearity): the two must agree to rounding.
  for (double r : {0.0, 1e-3, 2.5e-4}) {
    SynthSettings s;
    s.sample_rate_hz = kRate;
    const ModalObjectDesc object = test::makeObject({300.0, 1234.5, 5000.0}, 1e-8, 3.0);
    OscillatorBank steps(s, object);
    OscillatorBank box(s, object);
    const double t0 = 0.0123, tau = 0.0371;
    const std::vector<double> force = {2.0, -0.5, 0.25};  // N / sqrt(kg), per mode
    std::vector<double> down(force.size());
    for (size_t i = 0; i < force.size(); ++i) down[i] = -force[i];
    steps.addForceStep(ForceStepDesc{t0, r, force.data()});
    steps.addForceStep(ForceStepDesc{t0 + tau, r, down.data()});
    std::vector<double> impulse(force.size());
    for (size_t i = 0; i < force.size(); ++i) impulse[i] = force[i] * tau;
    ImpactDesc pulse{t0, tau, impulse.data(), PulseShape::Box};
    pulse.ramp_s = r;
    box.addImpact(pulse);
    const std::vector<float> a = test::renderAll(steps, 9600), b = test::renderAll(box, 9600);
    const double peak = test::peakAbs(b);
    ASSERT_GT(peak, 0.0);
    double worst = 0.0;
    for (size_t n = 0; n < a.size(); ++n) worst = std::max(worst, std::fabs(double(a[n]) - b[n]));
    EXPECT_LT(worst, 1e-4 * peak) << "ramp " << r;
  }
}

// ---- the contact scheduler ------------------------------------------------------------------

/// A 10 cm square steel "box" bottom as a 3x3 grid (bank of test modes) resting on the ground.
std::shared_ptr<const ModeBank> plateBank(double rayleigh_mass = 10.0) {
  auto bank = std::make_shared<ModeBank>();
  ModeBank& b = *bank;
  b.material.youngs_pa = 2.0e11;
  b.material.poisson = 0.3;
  b.material.rayleigh_stiffness = 1e-8;
  b.material.rayleigh_mass = rayleigh_mass;  // 1/s: sigma = 5/s, 60 dB in 1.4 s
  b.mass_kg = 1.0;
  b.volume_m3 = 1.0 / 7850.0;
  for (double f : {523.0, 1187.0, 2450.0, 4100.0}) b.eigenvalues.push_back(std::pow(2.0 * M_PI * f, 2));
  const double h = 0.05;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      b.surface_positions.insert(b.surface_positions.end(), {(i - 1) * h, (j - 1) * h, 0.0});
      b.surface_normals.insert(b.surface_normals.end(), {0.0f, 0.0f, -1.0f});
      b.surface_node_index.push_back(static_cast<uint32_t>(3 * j + i));
    }
  for (uint32_t j = 0; j < 2; ++j)
    for (uint32_t i = 0; i < 2; ++i) {
      const uint32_t a = 3 * j + i;
      b.surface_triangles.insert(b.surface_triangles.end(), {a, a + 4, a + 1, a, a + 3, a + 4});
    }
  // Shapes that differ from corner to corner, so moving the load between corners changes the
  // modal force (what a physics engine's flickering contact points do).
  for (size_t m = 0; m < b.eigenvalues.size(); ++m)
    for (size_t v = 0; v < 9; ++v)
      b.shapes.insert(b.shapes.end(), {0.1f * float(m), 0.0f, float(std::cos(0.7 * double(m + 1) * double(v)))});
  b.centre_m = {0.0, 0.0, 0.05};
  return bank;
}

struct Scenario {
  double frame_s = 1.0 / 60.0;
  double duration_s = 10.0;
  bool push = false;   // from 4 s on, shoved sideways: 5 N at once, then friction that varies by frame
  bool sleep = false;  // the body falls asleep at 6 s (no more contacts)
};

/// A box dropped at 0.5 s (an impact) then resting on 4 corners reported every frame, with the
/// load flickering between 2, 3 and 4 corners as physics engines do. Returns the mono output.
std::vector<float> restingBox(const Scenario& sc, EngineStats* stats = nullptr) {
  EngineSettings settings;
  settings.synth.sample_rate_hz = kRate;
  settings.max_voices = 1;
  settings.max_block_frames = 256;
  settings.contact_damping_per_s = 0.0;
  SoundEngine engine(settings);
  VoiceDesc desc;
  desc.bank = plateBank();
  desc.contact_radius_m = 0.0;
  Voice voice(desc, settings);
  engine.install(0, &voice);
  Pose listener;
  listener.position_m = {0.0, -1.0, 0.3};
  engine.setListener(listener);
  std::vector<float> out(static_cast<size_t>(sc.duration_s * kRate));
  size_t rendered = 0;
  const double m = 1.0, g = 9.81;
  const std::array<std::array<double, 3>, 4> corners = {
      {{-0.05, -0.05, 0}, {0.05, -0.05, 0}, {-0.05, 0.05, 0}, {0.05, 0.05, 0}}};
  int frame = 0;
  for (double t = sc.frame_s; t <= sc.duration_s + 1e-9; t += sc.frame_s, ++frame) {
    engine.beginStep(t, sc.frame_s);
    Pose pose;
    engine.setPose(0, pose, sc.sleep && t > 6.0);
    const double start = t - sc.frame_s;
    if (start >= 0.5 && start < 0.5 + sc.frame_s) {
      EngineContact hit;
      hit.point = corners[0];
      hit.impulse = {0.0, 0.0, 3.0};  // dropped from ~0.45 m: m (1 + e) v
      hit.normal_speed_m_s = 3.0;
      hit.time_s = 0.5;
      engine.contact(hit);
    } else if (start > 0.5 && !(sc.sleep && t > 6.0)) {
      // The resting load, m g per frame, spread over 2 to 4 points that change every frame and
      // always balance (no net moment about the centre): a diagonal pair, the centre and a
      // diagonal pair at half the share, or all four corners.
      struct Share {
        std::array<double, 3> point;
        double fraction;
      };
      Share shares[4];
      size_t count = 0;
      const std::array<double, 3> centre{0.0, 0.0, 0.0};
      auto add = [&](const std::array<double, 3>& point, double fraction) { shares[count++] = Share{point, fraction}; };
      if (frame % 3 == 0) {
        add(corners[frame % 2 ? 0 : 1], 0.5);
        add(corners[frame % 2 ? 3 : 2], 0.5);
      } else if (frame % 3 == 1) {
        add(centre, 0.5);
        add(corners[1], 0.25);
        add(corners[2], 0.25);
      } else {
        for (const auto& corner : corners) add(corner, 0.25);
      }
      const double push = sc.push && start > 4.0 ? 5.0 + 0.5 * (frame % 2) : 0.0;  // N
      for (size_t k = 0; k < count; ++k) {
        const Share& share = shares[k];
        EngineContact rest;
        rest.point = share.point;
        rest.impulse = {push * share.fraction * sc.frame_s, 0.0, m * g * share.fraction * sc.frame_s};
        rest.normal_speed_m_s = 0.0;
        rest.time_s = start;
        engine.contact(rest);
      }
    }
    engine.endStep();
    const size_t safe = static_cast<size_t>(std::floor((t - sc.frame_s) * kRate));
    while (rendered + 256 <= std::min(safe, out.size())) {
      float* ch[1] = {out.data() + rendered};
      engine.render(ch, 256);
      rendered += 256;
    }
  }
  while (rendered < out.size()) {
    float* ch[1] = {out.data() + rendered};
    const size_t n = std::min<size_t>(256, out.size() - rendered);
    engine.render(ch, n);
    rendered += n;
  }
  if (stats) *stats = engine.stats();
  return out;
}

double peakIn(const std::vector<float>& x, double from_s, double to_s) {
  double p = 0.0;
  for (size_t n = static_cast<size_t>(from_s * kRate); n < std::min(x.size(), static_cast<size_t>(to_s * kRate)); ++n)
    p = std::max(p, std::fabs(double(x[n])));
  return p;
}

TEST(ContactScheduler, ABoxRestingTenSecondsAtSixtyFramesStays60dBBelowItsImpact) {
  EngineStats stats;
  const std::vector<float> out = restingBox(Scenario{}, &stats);
  const double impact = peakIn(out, 0.5, 1.0);
  ASSERT_GT(impact, 0.0);
  // From one ring-out after the impact (the modes' 60 dB decay is < 2 s) to the end.
  const double resting = peakIn(out, 3.0, 10.0);
  EXPECT_LT(resting, impact * 1e-3) << "resting " << 20 * std::log10(resting / impact) << " dB re the impact";
  EXPECT_GT(stats.sustained_contacts, 1500u);
  // The load came on once (the first resting frame) and never changed: every frame's corners
  // differ, but its net force and moment do not.
  EXPECT_EQ(stats.load_changes, 1u);
}

TEST(ContactScheduler, ABoxPushedAlongTheGroundIsHeard) {
  Scenario pushed;
  pushed.push = true;
  EngineStats stats;
  const std::vector<float> quiet = restingBox(Scenario{}), loud = restingBox(pushed, &stats);
  const double impact = peakIn(loud, 0.5, 1.0);
  const double resting = peakIn(quiet, 4.0, 10.0), pushing = peakIn(loud, 4.0, 10.0);
  // The shove and the friction's frame-to-frame changes are changes of load: each is a force
  // step, ramped over the frame (what a 60 Hz physics engine can say about it), so it is far
  // quieter than the drop's impact, but heard where the resting box is silent.
  EXPECT_GT(stats.load_changes, 300u) << "a change of load every frame of the push";
  EXPECT_GT(pushing, impact * 1e-6);
  EXPECT_GT(pushing, 1e3 * std::max(resting, 1e-30)) << "at least 60 dB over resting";
}

TEST(ContactScheduler, ASleepingBodyKeepsItsLoadInsteadOfRingingAsIfLifted) {
  Scenario asleep;
  asleep.sleep = true;
  EngineStats stats;
  const std::vector<float> out = restingBox(asleep, &stats);
  const double impact = peakIn(out, 0.5, 1.0);
  EXPECT_LT(peakIn(out, 5.9, 10.0), impact * 1e-3);
  EXPECT_GT(stats.load_holds, 200u);  // 4 s of frames at 60 Hz
  EXPECT_EQ(stats.load_changes, 1u);
}

// ---- voices and the budget ----------------------------------------------------------------

TEST(Voices, TheBudgetPutsTheQuietestVoiceToSleepFirst) {
  // Two identical bodies struck alike, one at 1 m and one at 10 m (20 dB quieter at the
  // listener); a budget of the 4 modes of one body keeps the near one ringing whole.
  EngineSettings settings;
  settings.synth.sample_rate_hz = kRate;
  settings.max_voices = 2;
  settings.max_block_frames = 256;
  settings.max_active_modes = 4;
  SoundEngine engine(settings);
  VoiceDesc desc;
  desc.bank = plateBank();
  Voice near_voice(desc, settings), far_voice(desc, settings);
  engine.install(0, &near_voice);
  engine.install(1, &far_voice);
  Pose near_pose, far_pose;
  near_pose.position_m = {0.0, 1.0, -0.05};
  far_pose.position_m = {0.0, 10.0, -0.05};
  engine.setPose(0, near_pose);
  engine.setPose(1, far_pose);
  for (uint32_t slot : {0u, 1u}) {
    EngineImpact hit;
    hit.voice = slot;
    hit.point = {0.0, 0.0, 0.0};
    hit.impulse = {0.0, 0.0, 0.01};
    hit.contact_duration_s = 0.0;
    hit.time_s = 0.0;
    engine.impact(hit);
  }
  std::vector<float> block(256);
  float* ch[1] = {block.data()};
  for (int k = 0; k < 8; ++k) engine.render(ch, 256);  // past the far body's 29 ms delay
  const EngineStats stats = engine.stats();
  EXPECT_EQ(stats.active_modes, 4u) << "the budget holds";
  EXPECT_EQ(stats.modes_culled, 4u) << "the far body's four modes went";
  EXPECT_EQ(near_voice.synthStats().active_modes, 4u);
  EXPECT_EQ(far_voice.synthStats().active_modes, 0u);
}

TEST(ContactScheduler, AnImpactOnAnotherVoiceTakesThatVoicesMaterialRadiusAndMass) {
  // The partner given as a voice (libstrike's contact between two objects) and the same partner
  // given by its material, radius and mass (the ground, or a body that is not heard) must give
  // the same Hertz pulse: the same samples.
  auto render = [](bool as_voice) {
    EngineSettings settings;
    settings.synth.sample_rate_hz = kRate;
    settings.max_voices = 2;
    settings.max_block_frames = 256;
    settings.realtime = false;
    SoundEngine engine(settings);
    VoiceDesc desc;
    desc.bank = plateBank();
    desc.contact_radius_m = 0.02;
    Voice struck(desc, settings);
    auto soft = std::make_shared<ModeBank>(*plateBank());
    soft->material.youngs_pa = 3e9;  // a plastic partner: a longer, duller pulse
    soft->material.poisson = 0.4;
    soft->mass_kg = 0.05;
    VoiceDesc other = desc;
    other.bank = soft;
    other.contact_radius_m = 0.01;
    Voice partner(other, settings);
    engine.install(0, &struck);
    engine.install(1, &partner);
    EngineContact c;
    c.point = {0.0, 0.0, 0.0};
    c.impulse = {0.0, 0.0, 0.05};
    c.normal_speed_m_s = 2.0;
    c.time_s = 0.001;
    if (as_voice) {
      c.partner.voice = 1;
    } else {
      c.partner.youngs_pa = 3e9;
      c.partner.poisson = 0.4;
      c.partner.radius_m = 0.01;
      c.partner.mass_kg = 0.05;
    }
    engine.beginStep(0.002, 0.001);
    engine.contact(c);
    engine.endStep();
    EXPECT_NEAR(engine.contactDuration(0, c.partner, 2.0),
                hertzContactDuration(2e11, 0.3, 0.02, 1.0, 3e9, 0.4, 0.01, 0.05, 2.0), 1e-15);
    std::vector<float> out(4096);
    for (size_t n = 0; n < out.size(); n += 256) {
      float* ch[1] = {out.data() + n};
      engine.render(ch, 256);
    }
    return out;
  };
  const std::vector<float> by_voice = render(true), by_material = render(false);
  ASSERT_GT(test::peakAbs(by_voice), 0.0);
  for (size_t n = 0; n < by_voice.size(); ++n) ASSERT_EQ(by_voice[n], by_material[n]) << "sample " << n;
}

// ---- the listener follows the body --------------------------------------------------------

TEST(Listener, EachBounceIsHeardWithTheDelayAndLevelOfItsDistance) {
  // A body struck five times identically while it moves away from the listener along x: the
  // k-th strike at distance d_k is heard at t_k + d_k / c with amplitude proportional to 1 / d_k.
  EngineSettings settings;
  settings.synth.sample_rate_hz = kRate;
  settings.max_voices = 1;
  settings.max_block_frames = 256;
  SoundEngine engine(settings);
  VoiceDesc desc;
  desc.bank = plateBank(40.0);  // sigma = 20/s: a strike has decayed by 87 dB before the next
  Voice voice(desc, settings);
  engine.install(0, &voice);
  engine.setListener(Pose{});
  const std::vector<double> times = {0.1, 0.6, 1.1, 1.6, 2.1};
  const std::vector<double> distances = {1.0, 3.0, 7.0, 15.0, 31.0};  // along x, from the centre
  const double step = 1e-3;
  std::vector<float> out(static_cast<size_t>(2.5 * kRate));
  size_t rendered = 0, next = 0;
  for (double t = step; t <= 2.5 + 1e-9; t += step) {
    engine.beginStep(t, step);
    size_t k = 0;
    while (k + 1 < times.size() && t - step > times[k + 1] - 0.25) ++k;  // it moves between strikes
    Pose pose;
    pose.position_m = {distances[k], 0.0, -0.05};  // centre of mass at (d_k, 0, 0)
    engine.setPose(0, pose);
    if (next < times.size() && times[next] >= t - step && times[next] < t) {
      EngineContact hit;
      hit.point = {0.0, 0.0, 0.0};
      hit.impulse = {0.0, 0.0, 0.01};
      hit.normal_speed_m_s = 1.0;
      hit.time_s = times[next++];
      engine.contact(hit);
    }
    engine.endStep();
    while (rendered + 256 <= static_cast<size_t>(std::floor((t - step) * kRate))) {
      float* ch[1] = {out.data() + rendered};
      engine.render(ch, 256);
      rendered += 256;
    }
  }
  auto rms = [&](double from_s, double to_s) {
    double sum = 0.0;
    const size_t a = static_cast<size_t>(from_s * kRate), b = static_cast<size_t>(to_s * kRate);
    for (size_t n = a; n < b; ++n) sum += double(out[n]) * out[n];
    return std::sqrt(sum / double(b - a));
  };
  double first_level = 0.0, first_peak = peakIn(out, 0.0, 0.5);
  for (size_t k = 0; k < times.size(); ++k) {
    const double point_distance = std::hypot(distances[k], 0.05);
    const double arrival = times[k] + point_distance / kSpeedOfSoundAir_m_s;
    // The onset: the first sample above 1e-3 of what this strike's peak should be (the last
    // strike's ring has decayed far below that).
    const double expected_peak = first_peak * distances[0] / distances[k];
    size_t onset = static_cast<size_t>(times[k] * kRate);
    while (onset < out.size() && std::fabs(out[onset]) < 1e-3 * expected_peak) ++onset;
    EXPECT_NEAR(onset / kRate, arrival, 1.5 / kRate) << "strike " << k << " at " << distances[k] << " m";
    // 1/d: the rms of its first 20 ms relative to the first strike's, within 0.05 dB.
    const double level = rms(arrival + 1e-3, arrival + 21e-3);
    if (k == 0) first_level = level;
    EXPECT_NEAR(20 * std::log10(level / first_level), 20 * std::log10(distances[0] / distances[k]), 0.05)
        << "strike " << k;
  }
}

}  // namespace
}  // namespace strike
