// SPDX-License-Identifier: MIT
// Golden renders: a steel bar struck, and the bar-drop example, against references committed in
// tests/data/golden/, and the synthesizer's kernels against each other.
//
// A change in the numbers anywhere on the way (mesh, FEM, eigen-solve, simulation, contact
// model, synthesis, listener) moves these renders by far more than the tolerance, so it is seen
// here and re-recorded only on purpose (tests/data/golden/README.md says how and when). The
// tolerance is what may honestly differ between machines: OpenBLAS picks other kernels on other
// CPUs (the eigen-solve's last bits: -138 dB re peak on the bar hit, measured with
// OPENBLAS_CORETYPE=Haswell, Sandybridge and SkylakeX), and the synthesizer has AVX-512, AVX2 and
// scalar kernels (-127 dB at most, measured). -100 dB re peak leaves room for both and catches
// any modelling change (a 0.1% frequency shift of a 1 s ring is already ~-20 dB).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "run_cli.hpp"
#include "strike/audio/audio.hpp"

namespace strike {
namespace {

namespace fs = std::filesystem;
using test::runCli;

constexpr double kGoldenToleranceDb = -100.0;  // re the reference's peak
constexpr double kKernelToleranceDb = -120.0;  // the bound between synth kernels

std::string shellQuoted(const std::string& path) { return "'" + path + "'"; }

AudioBuffer read(const std::string& path) {
  Result<AudioBuffer> audio = readAudio(path);
  EXPECT_TRUE(audio.ok()) << path << ": " << (audio.ok() ? "" : audio.error().message);
  return audio.ok() ? std::move(audio.value()) : AudioBuffer{};
}

/// The largest difference of b from a, in dB re a's peak, and where it is, as one line.
struct Difference {
  double db = -1000.0;
  std::string summary;
};

Difference compare(const AudioBuffer& a, const AudioBuffer& b) {
  Difference d;
  if (a.samples.size() != b.samples.size() || a.sample_rate_hz != b.sample_rate_hz || a.samples.empty()) {
    d.db = 1000.0;
    d.summary = "lengths or rates differ: " + std::to_string(a.samples.size()) + " samples at " +
                std::to_string(a.sample_rate_hz) + " Hz vs " + std::to_string(b.samples.size()) + " at " +
                std::to_string(b.sample_rate_hz) + " Hz";
    return d;
  }
  double peak = 0.0, worst = 0.0;
  size_t worst_at = 0, first_at = a.samples.size();
  for (size_t i = 0; i < a.samples.size(); ++i) {
    peak = std::max(peak, std::abs(double(a.samples[i])));
    const double diff = std::abs(double(a.samples[i]) - double(b.samples[i]));
    if (diff > 0 && first_at == a.samples.size()) first_at = i;
    if (diff > worst) {
      worst = diff;
      worst_at = i;
    }
  }
  d.db = worst > 0 ? 20.0 * std::log10(worst / std::max(peak, 1e-30)) : -1000.0;
  char line[256];
  std::snprintf(line, sizeof line,
                "peak %.4g; max difference %.3g (%.1f dB re peak) at sample %zu; first difference at sample %zu", peak,
                worst, d.db, worst_at, first_at);
  d.summary = line;
  return d;
}

class Golden : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    // ctest runs every test in its own process: bar-drop is rendered (its bar solved) once per
    // build of the tool and version of the scene, keyed by the binary's size and time as BarDrop
    // and SteelBar do in cli_test.cpp (and by the scene file's), and the other processes compare
    // that render. A rebuilt tool or an edited scene renders afresh; two processes that start
    // together share the cache, whose lock has the second read the first one's solve, and each
    // writes the same bytes atomically.
    const std::string scene = std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/bar-drop.json";
    struct stat tool {};
    struct stat scene_file {};
    stat(STRIKE_CLI, &tool);
    stat(scene.c_str(), &scene_file);
    dir_ = testing::TempDir() + "/golden-" + std::to_string(tool.st_size) + "-" + std::to_string(tool.st_mtime) + "-" +
           std::to_string(scene_file.st_size) + "-" + std::to_string(scene_file.st_mtime);
    fs::create_directories(dir_ + "/cache");
    // bar-drop for 1.5 s (the drop, the first bounces and their rings), banks cached in dir_.
    if (!fs::exists(dir_ + "/bar-drop.wav")) {
      const auto render = runCli("render " + shellQuoted(scene) + " -o " + shellQuoted(dir_ + "/bar-drop.wav") +
                                 " --duration 1.5 --cache " + shellQuoted(dir_ + "/cache") + " --quiet");
      ASSERT_EQ(render.exit_code, 0) << render.err;
    }
    // The bar's bank, as the render solved it: the only bank in the cache.
    for (const auto& entry : fs::directory_iterator(dir_ + "/cache"))
      if (entry.path().extension() == ".modes") bank_ = entry.path().string();
    ASSERT_FALSE(bank_.empty());
  }
  static std::string hit(const std::string& out, const std::string& extra = "") {
    const auto r = runCli("hit " + shellQuoted(bank_) + " -o " + shellQuoted(out) +
                          " --vertex 12 --impulse 0,0.004,-0.01 --duration 1 --quiet " + extra);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return out;
  }
  static std::string reference(const char* name) {
    return std::string(STRIKE_SOURCE_DIR) + "/tests/data/golden/" + name;
  }
  static inline std::string dir_, bank_;
};

TEST_F(Golden, BarHitMatchesTheCommittedReference) {
  const AudioBuffer expected = read(reference("bar-hit.wav"));
  const AudioBuffer got = read(hit(dir_ + "/bar-hit.wav"));
  const Difference d = compare(expected, got);
  EXPECT_LT(d.db, kGoldenToleranceDb) << "bar hit vs tests/data/golden/bar-hit.wav: " << d.summary;
  std::printf("  bar hit vs reference: %s\n", d.summary.c_str());
}

TEST_F(Golden, BarDropMatchesTheCommittedReference) {
  const AudioBuffer expected = read(reference("bar-drop.wav"));
  const AudioBuffer got = read(dir_ + "/bar-drop.wav");
  const Difference d = compare(expected, got);
  EXPECT_LT(d.db, kGoldenToleranceDb) << "bar-drop vs tests/data/golden/bar-drop.wav: " << d.summary;
  std::printf("  bar-drop vs reference: %s\n", d.summary.c_str());
}

TEST_F(Golden, SynthKernelsAgreeWithin120dB) {
  // Each kernel forced (a kernel the CPU lacks falls back to a narrower one, which is then
  // compared twice); the scalar kernel is the plainest and the reference here.
  const AudioBuffer scalar = read(hit(dir_ + "/hit-scalar.wav", "--simd scalar"));
  for (const char* kernel : {"avx2", "avx512", "auto"}) {
    const AudioBuffer other = read(hit(dir_ + "/hit-" + kernel + ".wav", std::string("--simd ") + kernel));
    const Difference d = compare(scalar, other);
    EXPECT_LT(d.db, kKernelToleranceDb) << "bar hit, scalar vs " << kernel << ": " << d.summary;
    std::printf("  bar hit, scalar vs %-6s: %s\n", kernel, d.summary.c_str());
  }
  // The same through a whole render (many impacts, contact forces).
  const std::string scene = shellQuoted(std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/bar-drop.json");
  for (const char* kernel : {"scalar", "avx2"}) {
    const std::string out = dir_ + "/bar-drop-" + kernel + ".wav";
    const auto forced = runCli(std::string("render ") + scene + " -o " + shellQuoted(out) + " --duration 1.5 --cache " +
                               shellQuoted(dir_ + "/cache") + " --quiet --simd " + kernel);
    ASSERT_EQ(forced.exit_code, 0) << forced.err;
    const Difference d = compare(read(dir_ + "/bar-drop.wav"), read(out));
    EXPECT_LT(d.db, kKernelToleranceDb) << "bar-drop, auto vs " << kernel << ": " << d.summary;
    std::printf("  bar-drop, auto vs %-6s: %s\n", kernel, d.summary.c_str());
  }
}

TEST_F(Golden, EnvironmentPicksTheKernelAndABadNameIsAnError) {
  const std::string out = dir_ + "/env.wav";
  const std::string command =
      "hit " + shellQuoted(bank_) + " -o " + shellQuoted(out) + " --vertex 12 --duration 0.1 --quiet";
  setenv("STRIKE_SIMD", "sse9", 1);
  const auto refused = runCli(command);
  unsetenv("STRIKE_SIMD");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("STRIKE_SIMD = 'sse9'"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(out));
  const auto option = runCli(command + " --simd neon");
  EXPECT_EQ(option.exit_code, 1);
  EXPECT_NE(option.err.find("--simd = 'neon'"), std::string::npos) << option.err;
}

// `strike render --via-library` sends the simulation through libstrike's C API step by step, as
// a game would; the issue asks for the normal render within -100 dB re peak on every example.
// (They are one engine, so it is in fact bit-identical: -inf dB.)
class ViaLibrary : public testing::TestWithParam<const char*> {};

TEST_P(ViaLibrary, EqualsTheRenderWithin100dB) {
  const std::string dir =
      testing::TempDir() + "/via_library_" + GetParam() + "_" + std::to_string(static_cast<long>(getpid()));
  fs::create_directories(dir + "/cache");
  const std::string scene = shellQuoted(std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/" + GetParam() + ".json");
  const std::string common = " --duration 1.2 --cache " + shellQuoted(dir + "/cache") + " --quiet";
  const auto direct = runCli("render " + scene + " -o " + shellQuoted(dir + "/direct.wav") + common);
  ASSERT_EQ(direct.exit_code, 0) << direct.err;
  const auto library =
      runCli("render " + scene + " -o " + shellQuoted(dir + "/library.wav") + common + " --via-library");
  ASSERT_EQ(library.exit_code, 0) << library.err;
  EXPECT_EQ(library.err.find("dropped"), std::string::npos) << library.err;
  const AudioBuffer a = read(dir + "/direct.wav"), b = read(dir + "/library.wav");
  double peak = 0.0;
  for (float v : a.samples) peak = std::max(peak, std::abs(double(v)));
  EXPECT_GT(peak, 1e-4) << GetParam() << " is silent: nothing compared";
  const Difference d = compare(a, b);
  std::printf("  %s: direct vs --via-library: %s\n", GetParam(), d.summary.c_str());
  EXPECT_LT(d.db, kGoldenToleranceDb) << d.summary;
  fs::remove_all(dir);
}

// Every output format goes through the same engine both ways: stereo, binaural (the KEMAR
// responses handed to libstrike through strike_output_desc) and Ambisonics of the bar drop (a
// ground, so the image is a signal of its own) equal through libstrike too; and binaural twice
// gives the same bytes.
TEST(ViaLibraryOutputs, EqualsTheRenderInEveryOutputFormat) {
  const std::string dir = testing::TempDir() + "/via_library_outputs_" + std::to_string(static_cast<long>(getpid()));
  fs::create_directories(dir + "/cache");
  const std::string scene = shellQuoted(std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/bar-drop.json");
  const std::string common = " --duration 0.6 --cache " + shellQuoted(dir + "/cache") + " --quiet";
  for (const char* format : {"stereo", "binaural", "ambix3"}) {
    const std::string output = std::string(" --output ") + format;
    const auto direct = runCli("render " + scene + " -o " + shellQuoted(dir + "/direct.wav") + common + output);
    ASSERT_EQ(direct.exit_code, 0) << direct.err;
    const auto library =
        runCli("render " + scene + " -o " + shellQuoted(dir + "/library.wav") + common + output + " --via-library");
    ASSERT_EQ(library.exit_code, 0) << library.err;
    const AudioBuffer a = read(dir + "/direct.wav"), b = read(dir + "/library.wav");
    EXPECT_EQ(a.channels, format == std::string("ambix3") ? 16 : 2);
    EXPECT_EQ(a.channels, b.channels);
    double peak = 0.0;
    for (float v : a.samples) peak = std::max(peak, std::abs(double(v)));
    EXPECT_GT(peak, 1e-4) << format << " is silent: nothing compared";
    EXPECT_TRUE(a.samples == b.samples) << format << ": " << compare(a, b).summary;
    if (format == std::string("binaural")) {
      const auto again = runCli("render " + scene + " -o " + shellQuoted(dir + "/again.wav") + common + output);
      ASSERT_EQ(again.exit_code, 0) << again.err;
      EXPECT_TRUE(read(dir + "/again.wav").samples == a.samples) << "binaural: two renders differ";
      const auto refused = runCli("render " + scene + " -o " + shellQuoted(dir + "/bad.wav") + common + output +
                                  " --hrtf " + shellQuoted(dir + "/missing.sofa"));
      EXPECT_EQ(refused.exit_code, 1);
      EXPECT_NE(refused.err.find("missing.sofa"), std::string::npos) << refused.err;
      EXPECT_FALSE(fs::exists(dir + "/bad.wav"));
    }
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(EveryExample, ViaLibrary,
                         testing::Values("ball-rolls-across-plate", "bar-drop", "block-slides-down-plank",
                                         "blocks-falling", "coin-spin", "glass-on-table", "marbles-in-bowl",
                                         "spoon-scrapes-plate"),
                         [](const testing::TestParamInfo<const char*>& param) {
                           std::string name = param.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

}  // namespace
}  // namespace strike
