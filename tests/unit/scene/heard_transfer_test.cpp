// SPDX-License-Identifier: MIT
// The acoustic transfer is solved only for the modes a render can play (at or below
// synthesizedTopHz: min(20 kHz, 0.45 x the sample rate)); the bank records which (a prefix), a
// render that plays more solves the rest and caches them, and what is heard does not depend on
// which way the transfer was made. The object: a steel bar 12 x 2 x 1.5 cm (Tet10, 1 cm), modes
// at 5.1, 6.6, 11.8, 13.1, 16.1 and 21.0 kHz: four below a 32 kHz render's band (14.4 kHz), five
// below 20 kHz, the sixth only in a 96 kHz render that plays to 21.6 kHz.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <complex>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "strike/bank/bank.hpp"
#include "strike/scene/hit.hpp"
#include "strike/precompute/materials.hpp"
#include "strike/precompute/precompute.hpp"
#include "strike/scene/render.hpp"
#include "strike/scene/scene.hpp"
#include "strike/synth/synth.hpp"

namespace strike {
namespace {

constexpr char kBar[] = "box:0.12,0.02,0.015";

PrecomputeSettings barSettings(double transfer_max_freq_hz) {
  PrecomputeSettings s;
  s.mesh_spec = kBar;
  s.material = *builtinMaterials().find("steel");
  s.order = 2;
  s.target_edge_m = 0.01;
  s.max_freq_hz = synthesizedTopHz(1e9, 48000.0);  // 21.6 kHz: a mode above the heard band is kept
  s.acoustic_transfer = true;
  s.transfer_max_freq_hz = transfer_max_freq_hz;
  return s;
}

ModeBank barBank(double transfer_max_freq_hz) {
  Result<PrecomputeResult> r = computeModeBank(barSettings(transfer_max_freq_hz));
  EXPECT_TRUE(r) << (r ? "" : r.error().message);
  return r ? r->bank : ModeBank{};
}

/// The modes of `bank` at or below `hz`, counted here from the frequencies.
size_t modesUpTo(const ModeBank& bank, double hz) {
  size_t count = 0;
  for (size_t i = 0; i < bank.modeCount(); ++i) count += bank.frequencyHz(i) <= hz ? 1 : 0;
  return count;
}

bool sameBits(const AcousticTransfer& a, const AcousticTransfer& b) {
  return a.order == b.order && a.offset == b.offset && a.coefficients.size() == b.coefficients.size() &&
         std::memcmp(a.coefficients.data(), b.coefficients.data(),
                     a.coefficients.size() * sizeof(std::complex<float>)) == 0 &&
         a.relative_error.size() == b.relative_error.size() &&
         std::memcmp(a.relative_error.data(), b.relative_error.data(), a.relative_error.size() * sizeof(float)) == 0 &&
         std::memcmp(a.translation_dipole_m3.data(), b.translation_dipole_m3.data(), sizeof a.translation_dipole_m3) ==
             0 &&
         a.centre_m == b.centre_m;
}

TEST(HeardTransfer, ABankSolvedFor48kHzHasTheTransferOfExactlyTheModesBelowItsBand) {
  const double band_hz = synthesizedTopHz(20000.0, 48000.0);  // min(20 kHz, 21.6 kHz)
  const ModeBank bank = barBank(band_hz);
  const size_t heard = modesUpTo(bank, band_hz);
  ASSERT_GT(heard, 0u);
  ASSERT_LT(heard, bank.modeCount()) << "the bar must keep a mode above 20 kHz for the test to mean anything";
  EXPECT_EQ(bank.transfer.modeCount(), heard);
  EXPECT_LE(bank.frequencyHz(heard - 1), band_hz);
  EXPECT_GT(bank.frequencyHz(heard), band_hz);
  EXPECT_EQ(bank.transfer.checkConsistency(heard), "");
  // The file records it (format 6), and reads back as written.
  const std::vector<uint8_t> bytes = encodeBank(bank);
  Result<ModeBank> read = decodeBank(bytes.data(), bytes.size(), "heard.modes");
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read->format_version, 6u);
  EXPECT_EQ(read->modeCount(), bank.modeCount());
  EXPECT_TRUE(sameBits(read->transfer, bank.transfer));
}

TEST(HeardTransfer, ATransferExtendedToMoreModesHasTheBitsOfOneSolvedAtOnce) {
  // Solved for a 32 kHz render (14.4 kHz), then extended to a 48 kHz render's band: each mode's
  // transfer depends on its own data only, so the extension equals a cold solve to 20 kHz.
  const double low_hz = synthesizedTopHz(20000.0, 32000.0), high_hz = synthesizedTopHz(20000.0, 48000.0);
  ModeBank extended = barBank(low_hz);
  const size_t low = extended.transfer.modeCount(), high = modesUpTo(extended, high_hz);
  ASSERT_EQ(low, modesUpTo(extended, low_hz));
  ASSERT_LT(low, high);
  ASSERT_TRUE(extendTransfer(extended, high, barSettings(high_hz).transfer));
  const ModeBank cold = barBank(high_hz);
  ASSERT_EQ(cold.eigenvalues, extended.eigenvalues);
  EXPECT_EQ(extended.transfer.modeCount(), high);
  EXPECT_TRUE(sameBits(extended.transfer, cold.transfer))
      << "an extension differs from a cold solve: the solver's modes depend on each other";
}

TEST(HeardTransfer, AFormat5BankStillReadsAndOneThatContradictsItselfIsRefused) {
  // Format 5 is format 6's layout with every mode's transfer: what the previous writer wrote.
  ModeBank bank = barBank(1e9);
  ASSERT_EQ(bank.transfer.modeCount(), bank.modeCount());
  std::vector<uint8_t> bytes = encodeBank(bank);
  const uint32_t five = 5;
  std::memcpy(bytes.data() + 8, &five, 4);  // the version is in the header, outside the checksum
  Result<ModeBank> read = decodeBank(bytes.data(), bytes.size(), "five.modes");
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read->format_version, 5u);
  EXPECT_TRUE(sameBits(read->transfer, bank.transfer));
  // A format 5 file whose transfer stops short of its modes contradicts its format.
  ModeBank heard = barBank(20000.0);
  ASSERT_LT(heard.transfer.modeCount(), heard.modeCount());
  bytes = encodeBank(heard);
  std::memcpy(bytes.data() + 8, &five, 4);
  Result<ModeBank> refused = decodeBank(bytes.data(), bytes.size(), "five.modes");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("ACTF"), std::string::npos) << refused.error().message;
}

/// |sum_n w[n] x[n] e^{-2 pi i f n / rate}| with a Hann window w (sidelobes falling as 1/df^3, so
/// a loud mode 1.5 kHz away leaks nothing measurable): the level of the mode at f.
double levelAt(const std::vector<float>& x, double f_hz, double rate_hz) {
  std::complex<double> sum = 0.0;
  const double n_total = static_cast<double>(x.size());
  for (size_t n = 0; n < x.size(); ++n) {
    const double w = 0.5 - 0.5 * std::cos(2.0 * M_PI * double(n) / n_total);
    sum += w * double(x[n]) * std::polar(1.0, -2.0 * M_PI * f_hz * double(n) / rate_hz);
  }
  return std::abs(sum);
}

TEST(HeardTransfer, AModeWithoutATransferIsHeardAsInABankWithoutOneTheOthersWithTheirs) {
  // Solved for a 32 kHz render: modes 0-3 have a transfer, mode 4 (16.1 kHz) none. Heard at
  // 48 kHz, mode 4 sounds at its direction-averaged level, as in the bank without any transfer;
  // modes 0-3 as in the bank with every mode's (the same bits for them: extended).
  const ModeBank part = barBank(synthesizedTopHz(20000.0, 32000.0));
  ASSERT_EQ(part.transfer.modeCount(), 4u);
  ModeBank all = part, none = part;
  ASSERT_TRUE(extendTransfer(all, all.modeCount(), barSettings(1e9).transfer));
  none.transfer = AcousticTransfer{};
  HitSettings h;
  h.at_m = std::array<double, 3>{0.03, 0.0, 0.0075};
  h.duration_s = 0.3;
  h.listener_m = std::array<double, 3>{0.2, -0.6, 0.3};
  Result<HitResult> p = renderHit(part, h), a = renderHit(all, h), n = renderHit(none, h);
  ASSERT_TRUE(p && a && n);
  const double rate = h.sample_rate_hz;
  double loudest = 0.0;
  for (size_t i = 0; i < 5; ++i) loudest = std::max(loudest, levelAt(a->audio.samples, part.frequencyHz(i), rate));
  size_t compared = 0;
  for (size_t i = 0; i < 5; ++i) {
    const double f = part.frequencyHz(i);
    const double lp = levelAt(p->audio.samples, f, rate), la = levelAt(a->audio.samples, f, rate),
                 ln = levelAt(n->audio.samples, f, rate);
    std::printf("mode %zu %8.1f Hz: part %.4g, every mode's transfer %.4g, none %.4g\n", i, f, lp, la, ln);
    // Modes this strike hardly excites (the torsion and in-plane ones, -100 dB) are left out:
    // their level there is the window's floor, not the mode's.
    if (la < 1e-4 * loudest) {
      ASSERT_LT(i, 4u) << "the test needs mode 4 excited";
      continue;
    }
    ++compared;
    if (i < 4) {
      EXPECT_NEAR(lp, la, 1e-3 * la) << "mode " << i;
    } else {
      EXPECT_NEAR(lp, ln, 1e-2 * ln) << "mode " << i;
      EXPECT_GT(std::fabs(la - ln), 0.1 * ln) << "this direction must tell the transfer from the average";
    }
  }
  EXPECT_GE(compared, 3u);
}

std::string barDrop() {
  return std::string(R"({"sample_rate": 48000, "duration": 0.3, "max_freq": 21600,
    "listener": {"position": [0.3, -0.4, 0.3]},
    "objects": [{"name": "bar", "mesh": ")") +
         kBar + R"(", "material": "steel", "order": 2, "size": 0.01,
       "position": [0, 0, 0.05], "angular_velocity": [1, 2, 0]}]})";
}

RenderResult renderBar(double rate_hz, bool everything, const std::string& cache) {
  Result<Scene> scene = parseScene(barDrop(), "/tmp/heard-bar.json");
  EXPECT_TRUE(scene) << (scene ? "" : scene.error().message);
  if (!scene) return {};
  RenderSettings settings;
  settings.cache_dir = cache;
  settings.sample_rate_hz = rate_hz;
  settings.acoustic_transfer = true;
  settings.leave_nothing_out = everything;  // plays every mode up to 0.45 x the rate, 21.6 kHz here
  Result<RenderResult> out = renderScene(*scene, settings);
  EXPECT_TRUE(out) << (out ? "" : out.error().message);
  return out ? *out : RenderResult{};
}

TEST(HeardTransfer, ARenderThatPlaysMoreModesSolvesTheirTransferCachesItAndSoundsAsACold) {
  const std::string base = testing::TempDir() + "/heard-" + std::to_string(static_cast<long>(getpid()));
  const std::string warm = base + "-warm", cold = base + "-cold";
  std::filesystem::remove_all(warm);
  std::filesystem::remove_all(cold);
  // 48 kHz: the bank's transfer stops at 20 kHz (its mode at 21 kHz is kept without one).
  const RenderResult first = renderBar(48000.0, false, warm);
  ASSERT_EQ(first.report.banks_computed, 1u);
  // 96 kHz, every mode to 21.6 kHz: the same bank from the cache, its sixth mode's transfer now.
  const RenderResult extended = renderBar(96000.0, true, warm);
  EXPECT_EQ(extended.report.banks_cached, 1u);
  EXPECT_EQ(extended.report.transfers_extended, 1u);
  // ...written back: the next such render solves nothing.
  const RenderResult again = renderBar(96000.0, true, warm);
  EXPECT_EQ(again.report.transfers_extended, 0u);
  const RenderResult fresh = renderBar(96000.0, true, cold);
  EXPECT_EQ(fresh.report.banks_computed, 1u);
  ASSERT_FALSE(fresh.audio.samples.empty());
  double peak = 0.0, worst = 0.0;
  for (size_t k = 0; k < fresh.audio.samples.size() && k < extended.audio.samples.size(); ++k) {
    peak = std::max(peak, std::fabs(double(fresh.audio.samples[k])));
    worst = std::max(worst, std::fabs(double(extended.audio.samples[k]) - fresh.audio.samples[k]));
  }
  std::printf("extended vs cold: worst difference %.3g of the peak\n", worst / peak);
  // The same bytes: each group's transfer depends on its own modes alone (transferGroups), and a
  // transfer ends at a group's end, so the five modes solved for 48 kHz are the bits of the same
  // modes solved with the sixth.
  EXPECT_EQ(worst, 0.0) << "an extended bank sounds unlike a cold one";
  EXPECT_EQ(again.audio.samples, extended.audio.samples) << "the extension did not read back as it was written";
  std::filesystem::remove_all(warm);
  std::filesystem::remove_all(cold);
}

}  // namespace
}  // namespace strike

namespace strike {
namespace {

// Objects solve side by side: a render with three new objects solves their banks (eigen-solve and
// acoustic transfer) one after another and two at a time, and gets the same banks to the bit and
// the same output bytes.
std::string threeObjects() {
  return R"({"sample_rate": 48000, "duration": 0.3, "listener": {"position": [0.2, -0.5, 0.3]}, "max_modes": 6,
    "objects": [
      {"name": "bar", "mesh": "box:0.12,0.02,0.015", "material": "steel", "order": 2, "size": 0.01,
       "position": [0, 0, 0.04], "angular_velocity": [1, 2, 0]},
      {"name": "plank", "mesh": "box:0.2,0.03,0.01", "material": "aluminium", "order": 2, "size": 0.01,
       "position": [0, 0.15, 0.05], "angular_velocity": [0, 1, 2]},
      {"name": "block", "mesh": "box:0.1,0.04,0.02", "material": "brass", "order": 2, "size": 0.01,
       "position": [0, -0.15, 0.06]}]})";
}

struct SolvedRender {
  std::vector<float> samples;
  std::vector<ModeBank> banks;  ///< as cached, in the objects' order
  size_t computed = 0;
  double precompute_seconds = 0.0;
};

SolvedRender renderWith(unsigned solve_threads) {
  const std::string cache = testing::TempDir() + "/side-by-side-" + std::to_string(static_cast<long>(getpid())) + "-" +
                            std::to_string(solve_threads);
  std::filesystem::remove_all(cache);
  Result<Scene> scene = parseScene(threeObjects(), "/tmp/side-by-side.json");
  EXPECT_TRUE(scene) << (scene ? "" : scene.error().message);
  if (!scene) return {};
  RenderSettings settings;
  settings.cache_dir = cache;
  settings.acoustic_transfer = true;
  settings.solve_threads = solve_threads;
  Result<RenderResult> out = renderScene(*scene, settings);
  EXPECT_TRUE(out) << (out ? "" : out.error().message);
  if (!out) return {};
  SolvedRender r{out->audio.samples, {}, out->report.banks_computed, out->report.precompute_seconds};
  char name[32];
  for (const BodyBank& b : out->banks) {
    std::snprintf(name, sizeof name, "/%016llx.modes", static_cast<unsigned long long>(b.cache_key));
    Result<ModeBank> bank = readBank(cache + name);
    EXPECT_TRUE(bank) << (bank ? "" : bank.error().message);
    if (bank) r.banks.push_back(std::move(*bank));
  }
  std::filesystem::remove_all(cache);
  return r;
}

TEST(SideBySide, BanksSolvedAtOnceAreTheBanksOfASerialSolve) {
  const SolvedRender serial = renderWith(1), two = renderWith(2);
  std::printf("banks solved in %.2f s one after another, %.2f s two at a time\n", serial.precompute_seconds,
              two.precompute_seconds);
  ASSERT_EQ(serial.computed, 3u);
  ASSERT_EQ(serial.banks.size(), 3u);
  for (const SolvedRender* other : {&two}) {
    EXPECT_EQ(other->computed, 3u);
    ASSERT_EQ(other->banks.size(), 3u);
    for (size_t b = 0; b < 3; ++b) {
      const ModeBank &x = serial.banks[b], &y = other->banks[b];
      EXPECT_GT(x.transfer.modeCount(), 0u);
      EXPECT_EQ(x.eigenvalues, y.eigenvalues) << "bank " << b;
      EXPECT_EQ(std::memcmp(x.shapes.data(), y.shapes.data(), x.shapes.size() * sizeof(float)), 0) << "bank " << b;
      EXPECT_TRUE(x.shapes.size() == y.shapes.size() && sameBits(x.transfer, y.transfer)) << "bank " << b;
    }
    ASSERT_FALSE(serial.samples.empty());
    EXPECT_EQ(other->samples, serial.samples);
  }
}

}  // namespace
}  // namespace strike
