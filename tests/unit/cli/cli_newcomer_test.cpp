// SPDX-License-Identifier: MIT
// Issue 15, "A newcomer's first hour": outputs checked before any work (item 9), scenes that
// cannot be right named (10), silent results flagged (11), `hit --at` and the events summary
// (13), the bank cache tool (14), and the CLI reference in docs/cli.md (5).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>
#include <utime.h>
#include <chrono>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "run_cli.hpp"

namespace strike {
namespace {

namespace fs = std::filesystem;
using test::CliResult;
using test::runCli;

/// A fresh folder for one test.
std::string folder(const std::string& name) {
  const std::string dir = testing::TempDir() + "/newcomer-" + std::to_string(getpid()) + "-" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

size_t filesIn(const std::string& dir) {
  if (!fs::exists(dir)) return 0;
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

/// The banks (.modes) in a cache folder, which also holds the bodies' hulls (.hull).
std::vector<fs::path> banksIn(const std::string& dir) {
  std::vector<fs::path> banks;
  if (fs::exists(dir))
    for (const auto& entry : fs::directory_iterator(dir))
      if (entry.path().extension() == ".modes") banks.push_back(entry.path());
  return banks;
}

/// A number printed after `prefix` in `text`, or NaN.
double numberAfter(const std::string& text, const std::string& prefix) {
  const size_t at = text.find(prefix);
  if (at == std::string::npos) return NAN;
  return std::strtod(text.c_str() + at + prefix.size(), nullptr);
}

// A steel bar dropped 4 cm: a short, cheap render (the automatic order: a coarse Tet10 bar, a few
// audible bending modes).
// Tests here that check messages, warnings, counts and the cache's files, none of which depends on
// the acoustic transfer, render and solve with --no-transfer: the transfer (BEM solves) is nearly
// all of such a render's time (this bar under ASan: 14.6 s with it, 0.3 s without) and is checked
// by the transfer, golden and render tests. (NewcomerCompactBank keeps it: the one int16 bank
// written with a transfer.)
const char kDrop[] = R"({"duration": 0.3, "max_modes": 8,
  "objects": [{"name": "bar", "mesh": "box:0.2,0.03,0.02", "material": "steel", "position": [0, 0, 0.05]}]})";

// ---- Item 9: outputs are checked before any work ----------------------------------------------

TEST(NewcomerOutputs, BadOutputPathsFailBeforeTheSimulationAndLeaveNoCacheEntry) {
  const std::string dir = folder("outputs");
  write(dir + "/drop.json", kDrop);
  const std::string cache = dir + "/cache";
  struct Case {
    std::string output, expected;
  } cases[] = {{"/nonexistent-folder/x.wav", "the folder /nonexistent-folder does not exist"},
               {dir + "/x.mp3", "unsupported file extension '.mp3'"},
               {dir, "is a folder"}};
  for (const Case& c : cases) {
    CliResult r = runCli("render '" + dir + "/drop.json' -o '" + c.output + "' --cache '" + cache + "'");
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
    // Before: the eigen-solve ran and its bank was cached before the write failed.
    EXPECT_EQ(filesIn(cache), 0u) << c.output;
  }
  CliResult events = runCli("render '" + dir + "/drop.json' -o '" + dir +
                            "/ok.wav' --events /nonexistent-folder/e.csv --cache '" + cache + "'");
  EXPECT_EQ(events.exit_code, 1);
  EXPECT_NE(events.err.find("--events /nonexistent-folder/e.csv"), std::string::npos) << events.err;
  EXPECT_EQ(filesIn(cache), 0u);
  CliResult flac =
      runCli("render '" + dir + "/drop.json' -o '" + dir + "/x.flac' --format float --cache '" + cache + "'");
  EXPECT_EQ(flac.exit_code, 1);
  EXPECT_NE(flac.err.find("FLAC stores integer PCM only"), std::string::npos) << flac.err;
  EXPECT_EQ(filesIn(cache), 0u);
  CliResult hit = runCli("hit /nonexistent-bank.modes -o '" + dir + "/x.mp3'");
  EXPECT_EQ(hit.exit_code, 1);
  EXPECT_NE(hit.err.find("unsupported file extension '.mp3'"), std::string::npos) << hit.err;  // not the bank
  CliResult png = runCli("analyze /nonexistent.wav --spectrogram '" + dir + "/x.jpg'");
  EXPECT_EQ(png.exit_code, 1);
  EXPECT_NE(png.err.find("'.jpg'"), std::string::npos) << png.err;
}

TEST(NewcomerOutputs, BenchCreatesItsOutputFolder) {
  const std::string dir = folder("bench");
  // Any scene does: a 5 mm steel pebble dropped, whose bank (no mode below 20 kHz) solves in a
  // moment, where the bar's modes and their transfer took 15 s under ASan.
  write(dir + "/drop.json", R"({"duration": 0.2, "objects": [
    {"name": "pebble", "mesh": "box:0.005,0.005,0.005", "material": "steel", "position": [0, 0, 0.05]}]})");
  const std::string out = dir + "/study/nested";  // does not exist: before, the run failed at its end
  CliResult r = runCli("bench render '" + dir + "/drop.json' -o '" + out + "' --repeat 1 --cache '" + dir + "/cache'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(out + "/render.csv"));
  write(dir + "/file", "x");
  CliResult not_folder = runCli("bench render '" + dir + "/drop.json' -o '" + dir + "/file' --repeat 1");
  EXPECT_EQ(not_folder.exit_code, 1);
  EXPECT_NE(not_folder.err.find("exists and is not a folder"), std::string::npos) << not_folder.err;
  // --output: what an output costs over mono, both at the same step; each run is a CSV row named
  // by its output.
  CliResult ambix = runCli("bench render '" + dir + "/drop.json' -o '" + out + "' --repeat 1 --no-transfer --output " +
                           "ambix1 --cache '" + dir + "/cache'");
  ASSERT_EQ(ambix.exit_code, 0) << ambix.err;
  EXPECT_NE(ambix.out.find("ambix1/mono"), std::string::npos) << ambix.out;
  std::ifstream csv(out + "/render.csv");
  std::string line, configs;
  std::getline(csv, line);  // the header
  while (std::getline(csv, line))
    configs += line.substr(line.find(',') + 1, line.find(',', 2) - line.find(',') - 1) + " ";
  EXPECT_EQ(configs, "mono ambix1 ");
  CliResult bad = runCli("bench render '" + dir + "/drop.json' -o '" + out + "' --output surround");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("--output = surround"), std::string::npos) << bad.err;
}

// ---- Item 10: scenes that cannot be right ------------------------------------------------------

TEST(NewcomerScenes, OverlapsTheGroundAndUnstruckObjectsAreNamedWithNumbers) {
  const std::string dir = folder("overlap");
  write(dir + "/scene.json", R"({"duration": 0.2, "max_modes": 4, "objects": [
    {"name": "a", "mesh": "box:0.1,0.1,0.1", "material": "steel", "position": [0, 0, 0.2]},
    {"name": "b", "mesh": "box:0.1,0.1,0.1", "material": "steel", "position": [0.07, 0, 0.2]},
    {"name": "sunk", "mesh": "box:0.1,0.1,0.1", "material": "steel", "position": [1, 0, 0.04]},
    {"name": "high", "mesh": "box:0.02,0.02,0.02", "material": "steel", "position": [-1, 0, 800.01]}]})");
  CliResult r = runCli("render '" + dir + "/scene.json' -o '" + dir + "/out.wav' --no-cache --no-transfer --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: objects \"sunk\": starts 10 mm inside the ground"), std::string::npos) << r.err;
  // b's face at x = 0.02 lies 30 mm inside a (whose face is at x = 0.05).
  EXPECT_NE(r.err.find("warning: objects \"a\" and \"b\" start inside each other (a surface point 30 mm deep)"),
            std::string::npos)
      << r.err;
  // Lowest point 800 m up: sqrt(2 x 800 / 9.81) = 12.77 s of free fall.
  EXPECT_NE(r.err.find("objects \"high\": never struck (it starts at (-1, 0, 800) m, its lowest point 800 m above the "
                       "ground; falling from there takes 12.8 s, the render lasts 0.2 s)"),
            std::string::npos)
      << r.err;
}

// A scene object asked for Tet4 on a thin shape is told that its frequencies come out far too
// high, with the wall and extent that make it thin; a solid is not.
TEST(NewcomerScenes, AThinObjectAtTet4IsWarnedToUseOrder2) {
  const std::string dir = folder("thin");
  write(dir + "/scene.json", R"({"duration": 0.2, "max_modes": 4, "objects": [
    {"name": "plate", "mesh": "box:0.06,0.06,0.003", "material": "steel", "order": 1, "position": [0, 0, 0.03]},
    {"name": "cube", "mesh": "box:0.03,0.03,0.03", "material": "steel", "order": 1, "position": [0.2, 0, 0.03]}]})");
  CliResult r = runCli("render '" + dir + "/scene.json' -o '" + dir + "/a.wav' --no-cache --no-transfer --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // 2 V / A of a 60 x 60 x 3 mm plate: 2 (10.8e-6) / (7.2e-3 + 0.72e-3) = 2.73 mm, under 6 mm.
  EXPECT_NE(r.err.find("objects \"plate\": thin shape (wall 2.73 mm (2 V / A) is under 10% of the 60 mm extent"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("use order 2"), std::string::npos) << r.err;
  // A cube's 2 V / A is a third of its side: a solid, where Tet4 does not lock.
  EXPECT_EQ(r.err.find("objects \"cube\": thin shape"), std::string::npos) << r.err;
}

// A scene object that names no order gets the order `strike modes` gives the same shape (one
// rule, src/precompute/element_order.cpp): a dropped thin steel bar rings at the modes of
// `strike modes`' bank, not at Tet4's locked ones (12% sharp on this bar), and is not warned.
TEST(NewcomerScenes, ADroppedThinBarWithNoOrderRingsAtTheModesOfStrikeModes) {
  const std::string dir = folder("thin-bar");
  const std::string bar = "box:0.2,0.03,0.01";
  // A 5 mm mesh (both): the order is the point here, and it keeps the two solves to a second.
  CliResult modes = runCli("modes " + bar + " --material steel --size 0.005 --max-modes 4 --no-error-estimate " +
                           "--no-transfer -o '" + dir + "/bar.modes'");
  ASSERT_EQ(modes.exit_code, 0) << modes.err;
  EXPECT_NE(modes.err.find("Tet10 chosen"), std::string::npos) << modes.err;
  const nlohmann::json info = nlohmann::json::parse(runCli("info --json '" + dir + "/bar.modes'").out);
  const std::vector<double> bank_hz = info["frequencies_hz"].get<std::vector<double>>();
  ASSERT_EQ(bank_hz.size(), 4u);
  write(dir + "/scene.json", R"({"duration": 0.6, "max_modes": 4, "listener": {"position": [0, -0.5, 0.2]},
    "ground": {"material": "concrete"}, "objects": [
    {"name": "bar", "mesh": ")" + bar +
                                 R"(", "material": "steel", "size": 0.005, "position": [0, 0, 0.1],
     "orientation": [0.99996, 0.0, 0.00873, 0.0]}]})");
  CliResult r = runCli("render '" + dir + "/scene.json' -o '" + dir + "/drop.wav' --no-cache --no-transfer");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("thin shape"), std::string::npos) << r.err;
  const nlohmann::json a = nlohmann::json::parse(runCli("analyze --json --peaks 8 '" + dir + "/drop.wav'").out);
  ASSERT_FALSE(a["peaks"].empty());
  // Every line the render rings at (within 30 dB of the strongest) is one of the bank's modes,
  // within 0.2% (Tet4 rang at 1814 Hz for the bank's 1287 Hz).
  double strongest_db = -1e9, strongest_hz = 0;
  for (const nlohmann::json& peak : a["peaks"]) {
    const double hz = peak["freq_hz"].get<double>();
    if (peak["level_db"].get<double>() < -30.0) continue;
    double nearest = 1e9;
    for (double f : bank_hz) nearest = std::min(nearest, std::fabs(hz / f - 1.0));
    EXPECT_LT(nearest, 0.002) << hz << " Hz is none of the bank's modes";
    if (peak["level_db"].get<double>() > strongest_db) strongest_db = peak["level_db"].get<double>(), strongest_hz = hz;
  }
  EXPECT_GT(strongest_hz, 0.0);
}

TEST(NewcomerScenes, AMeshInMillimetresIsFlaggedAndUnitsMmScalesIt) {
  const std::string dir = folder("units");
  // A 100 mm cube written in millimetres.
  std::string obj;
  for (int i = 0; i < 8; ++i)
    obj += "v " + std::to_string(i & 1 ? 50 : -50) + " " + std::to_string(i & 2 ? 50 : -50) + " " +
           std::to_string(i & 4 ? 50 : -50) + "\n";
  obj += "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  write(dir + "/cube_mm.obj", obj);
  // Read as metres: a 100 m, 7.85e9 kg steel cube (warned); with "units": "mm", 0.1 m and 7.85 kg.
  write(dir + "/as-metres.json", R"({"duration": 0.05, "max_modes": 2, "objects": [
    {"name": "cube", "mesh": "cube_mm.obj", "material": "steel", "static": true, "position": [0, 0, 50]}]})");
  CliResult metres =
      runCli("render '" + dir + "/as-metres.json' -o '" + dir + "/m.wav' --no-cache --no-transfer --quiet");
  ASSERT_EQ(metres.exit_code, 0) << metres.err;
  EXPECT_NE(
      metres.err.find("objects \"cube\": 100 x 100 x 100 m, 7.85e+09 kg (7.85e+06 tonnes): implausibly large for a "
                      "sounding object; if the mesh file is in millimetres, add \"units\": \"mm\" to the object"),
      std::string::npos)
      << metres.err;
  write(dir + "/as-mm.json", R"({"duration": 0.05, "max_modes": 2, "objects": [
    {"name": "cube", "mesh": "cube_mm.obj", "units": "mm", "material": "steel", "static": true, "position": [0, 0, 0.05]}]})");
  CliResult mm = runCli("render '" + dir + "/as-mm.json' -o '" + dir + "/mm.wav' --no-cache --no-transfer --quiet");
  ASSERT_EQ(mm.exit_code, 0) << mm.err;
  EXPECT_EQ(mm.err.find("implausibly"), std::string::npos) << mm.err;
  // The bank in millimetres: volume (0.1 m)^3, mass 7850 kg/m^3 x 1e-3 m^3, to rounding.
  CliResult bank =
      runCli("modes '" + dir +
             "/cube_mm.obj' --units mm --material steel --max-modes 2 --no-error-estimate --no-transfer --quiet -o '" +
             dir + "/cube.modes'");
  ASSERT_EQ(bank.exit_code, 0) << bank.err;
  const nlohmann::json info = nlohmann::json::parse(runCli("info --json '" + dir + "/cube.modes'").out);
  EXPECT_NEAR(info["volume_m3"].get<double>(), 1e-3, 1e-12);
  EXPECT_NEAR(info["mass_kg"].get<double>(), 7.85, 1e-9);
  write(dir + "/primitive-mm.json", R"({"objects": [{"mesh": "box:1,1,1", "units": "mm", "material": "steel"}]})");
  CliResult primitive = runCli("render '" + dir + "/primitive-mm.json' -o '" + dir + "/p.wav' --no-cache");
  EXPECT_EQ(primitive.exit_code, 1);
  EXPECT_NE(primitive.err.find("objects[0].units: applies to a mesh file only"), std::string::npos) << primitive.err;
}

// ---- Item 11: silent results -------------------------------------------------------------------

TEST(NewcomerSilence, AFreeBodyWithNoAudibleModeClicksAStaticOneIsSilent) {
  // 5 mm steel cubes: first elastic mode ~ 300 kHz, nothing below 20 kHz. The falling one still
  // clicks (acceleration noise); the static one it lands on cannot move, so it is silent.
  const std::string dir = folder("silent");
  write(dir + "/pebble.json", R"({"duration": 0.2, "ground": {"reflection": false}, "objects": [
    {"name": "anvil", "mesh": "box:0.005,0.005,0.005", "material": "steel", "static": true, "position": [0, 0, 0.0025]},
    {"name": "pebble", "mesh": "box:0.005,0.005,0.005", "material": "steel", "position": [0, 0, 0.05]}]})");
  CliResult r = runCli("render '" + dir + "/pebble.json' -o '" + dir + "/p.wav' --no-cache");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: objects \"anvil\": silent: no mode in the audible band (its bank has no elastic mode "
                       "below its cut-off of 20000 Hz"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("warning: objects \"pebble\""), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("2 struck, 1 sounded, 1 silent (no mode in the audible band)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1 of those sounded only by acceleration noise"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("level       silent"), std::string::npos) << r.err;
  CliResult text = runCli("analyze '" + dir + "/p.wav'");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_EQ(text.out.find("silent: every sample is 0"), std::string::npos) << text.out;
}

// ---- Item 13: hit --at and the events summary --------------------------------------------------

TEST(NewcomerHit, AtPrintsThePointStruckAndWarnsFarFromTheSurface) {
  const std::string dir = folder("hit");
  const std::string modes = "modes box:0.3,0.02,0.02 --material steel --max-modes 4 --no-error-estimate --no-transfer";
  ASSERT_EQ(runCli(modes + " --quiet -o '" + dir + "/bar.modes'").exit_code, 0);
  CliResult far = runCli("hit '" + dir + "/bar.modes' -o '" + dir + "/far.wav' --at 5,5,5");
  ASSERT_EQ(far.exit_code, 0) << far.err;
  // The nearest surface point is the corner (0.15, 0.01, 0.01): sqrt(4.85^2 + 2 x 4.99^2) = 8.563 m away.
  EXPECT_NE(far.err.find("surface point (0.15, 0.01, 0.01) m"), std::string::npos) << far.err;
  EXPECT_NEAR(numberAfter(far.err, "warning: --at 5,5,5 is "), std::sqrt(4.85 * 4.85 + 2 * 4.99 * 4.99), 1e-3)
      << far.err;
  EXPECT_EQ(far.err.find("at (5, 5, 5) m"), std::string::npos) << far.err;
  CliResult on = runCli("hit '" + dir + "/bar.modes' -o '" + dir + "/on.wav' --at 0.1,0.003,0.01");
  ASSERT_EQ(on.exit_code, 0) << on.err;
  EXPECT_EQ(on.err.find("warning"), std::string::npos) << on.err;
  EXPECT_NEAR(numberAfter(on.err, "), "), 0.0, 1e-9) << on.err;  // "(nearest vertex N), 0 m from --at"
}

TEST(NewcomerCompactBank, ModesCompactWritesInt16ShapesWithTheSameModes) {
  const std::string dir = folder("compact");
  const std::string common =
      "modes box:0.3,0.02,0.02 --material steel --max-modes 4 --no-error-estimate --quiet -o '" + dir;
  ASSERT_EQ(runCli(common + "/f32.modes'").exit_code, 0);
  ASSERT_EQ(runCli(common + "/i16.modes' --compact").exit_code, 0);
  const nlohmann::json a = nlohmann::json::parse(runCli("info --json '" + dir + "/f32.modes'").out);
  const nlohmann::json b = nlohmann::json::parse(runCli("info --json '" + dir + "/i16.modes'").out);
  EXPECT_EQ(a["format_version"], 6);
  EXPECT_EQ(b["format_version"], 6);
  EXPECT_EQ(a["shape_encoding"], "float32");
  EXPECT_EQ(b["shape_encoding"], "int16");
  EXPECT_EQ(a["frequencies_hz"], b["frequencies_hz"]);
  EXPECT_LT(fs::file_size(dir + "/i16.modes"), fs::file_size(dir + "/f32.modes"));
}

TEST(NewcomerEvents, TheSummaryAddsUpAndMatchesTheEventsFile) {
  const std::string dir = folder("events");
  write(dir + "/drop.json", kDrop);
  CliResult r = runCli("render '" + dir + "/drop.json' -o '" + dir + "/d.wav' --events '" + dir +
                       "/e.csv' --no-cache --no-transfer");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      r.err, m,
      std::regex(R"((\d+) contact points recorded: (\d+) impacts \(closing > 5 cm/s\) \+ (\d+) resting or sliding)")))
      << r.err;
  const long total = std::stol(m[1]), impacts = std::stol(m[2]), resting = std::stol(m[3]);
  EXPECT_EQ(impacts + resting, total);
  // The events file: one row per event, impacts are the rows closing faster than 5 cm/s.
  std::ifstream csv(dir + "/e.csv");
  std::string line;
  std::getline(csv, line);
  long rows = 0, fast = 0;
  while (std::getline(csv, line)) {
    ++rows;
    size_t comma = 0;
    for (int field = 0; field < 4; ++field) comma = line.find(',', comma) + 1;
    if (std::strtod(line.c_str() + comma, nullptr) > 0.05) ++fast;
  }
  EXPECT_EQ(rows, total);
  EXPECT_EQ(fast, impacts);
  EXPECT_GT(impacts, 0);
  EXPECT_NE(r.err.find("1 struck, 1 sounded, 0 silent"), std::string::npos) << r.err;
  // One body against the ground: every event acts on exactly one sounding body.
  ASSERT_TRUE(
      std::regex_search(r.err, m, std::regex(R"(heard +(\d+) impact pulses and (\d+) resting/sliding impulses)")))
      << r.err;
  EXPECT_EQ(std::stol(m[1]), impacts);
  EXPECT_EQ(std::stol(m[2]), resting);
}

// ---- Item 14: the bank cache -------------------------------------------------------------------

void makeEntry(const std::string& path, size_t bytes, double age_s) {
  write(path, std::string(bytes, 'x'));
  const std::time_t when = std::time(nullptr) - static_cast<std::time_t>(age_s);
  struct utimbuf times {
    when, when
  };
  utime(path.c_str(), &times);
}

TEST(NewcomerCache, ListSizeAndPruneByAgeAndSize) {
  const std::string cache = folder("cache");
  makeEntry(cache + "/0000000000000001.modes", 1000, 3 * 86400.0);
  makeEntry(cache + "/0000000000000002.modes", 2000, 2 * 86400.0);
  makeEntry(cache + "/0000000000000003.modes", 3000, 3600.0);
  makeEntry(cache + "/notes.txt", 500, 9 * 86400.0);  // not an entry: never touched
  CliResult size = runCli("cache size --cache '" + cache + "'");
  ASSERT_EQ(size.exit_code, 0) << size.err;
  EXPECT_NE(size.out.find("3 files, 6.0 KB (6000 bytes)"), std::string::npos) << size.out;
  // Hulls, many and tiny, are one row of the list.
  for (const char* hull : {"00000000000000a1.hull", "00000000000000a2.hull", "00000000000000a3.hull"})
    makeEntry(cache + "/" + hull, 300, 60.0);
  CliResult list = runCli("cache list --cache '" + cache + "'");
  ASSERT_EQ(list.exit_code, 0) << list.err;
  EXPECT_TRUE(std::regex_search(list.out, std::regex(R"(\n\(3 x \.hull\) +0\.9 KB )"))) << list.out;
  EXPECT_EQ(list.out.find("00000000000000a1.hull"), std::string::npos) << list.out;
  for (const char* hull : {"00000000000000a1.hull", "00000000000000a2.hull", "00000000000000a3.hull"})
    fs::remove(cache + "/" + hull);
  EXPECT_LT(list.out.find("0000000000000001"), list.out.find("0000000000000003"))
      << list.out;  // least recently used first
  EXPECT_NE(list.out.find("unreadable"), std::string::npos) << list.out;

  CliResult dry = runCli("cache prune --older-than 1d --dry-run --cache '" + cache + "'");
  ASSERT_EQ(dry.exit_code, 0) << dry.err;
  EXPECT_NE(dry.out.find("would remove 2 banks"), std::string::npos) << dry.out;
  EXPECT_EQ(filesIn(cache), 4u);
  // A reader holding an entry open keeps reading it after the prune (removal is an unlink).
  const int fd = ::open((cache + "/0000000000000001.modes").c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  CliResult pruned = runCli("cache prune --max-size 4000 --cache '" + cache + "'");
  ASSERT_EQ(pruned.exit_code, 0) << pruned.err;
  // 6000 bytes > 4000: the oldest (1000) goes, 5000 still > 4000: the next (2000) goes, 3000 fits.
  EXPECT_NE(pruned.out.find("removed 2 banks"), std::string::npos) << pruned.out;
  EXPECT_FALSE(fs::exists(cache + "/0000000000000001.modes"));
  EXPECT_FALSE(fs::exists(cache + "/0000000000000002.modes"));
  EXPECT_TRUE(fs::exists(cache + "/0000000000000003.modes"));
  EXPECT_TRUE(fs::exists(cache + "/notes.txt"));
  char buffer[2000];
  EXPECT_EQ(::pread(fd, buffer, sizeof buffer, 0), 1000);
  ::close(fd);
  CliResult bad = runCli("cache prune --max-size 12parsecs --cache '" + cache + "'");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("--max-size = '12parsecs'"), std::string::npos) << bad.err;
}

// A folder `name` with the drop scene rendered once into its own cache, `name`/cache (one bank,
// without its transfer: a later render reads it from the cache only with --no-transfer too).
std::string folderWithOneCachedBank(const std::string& name) {
  const std::string dir = folder(name);
  write(dir + "/drop.json", kDrop);
  EXPECT_EQ(
      runCli("render '" + dir + "/drop.json' -o '" + dir + "/a.wav' --cache '" + dir + "/cache' --no-transfer --quiet")
          .exit_code,
      0);
  EXPECT_EQ(banksIn(dir + "/cache").size(), 1u);
  return dir;
}

TEST(NewcomerCache, ARenderKeepsTheCacheUnderItsCapRemovingTheLeastRecentlyUsed) {
  const std::string dir = folderWithOneCachedBank("cap");
  const std::string cache = dir + "/cache";
  ASSERT_EQ(banksIn(cache).size(), 1u);
  const uintmax_t bank_bytes = fs::file_size(banksIn(cache)[0]);
  makeEntry(cache + "/00000000000000aa.modes", 5000, 30 * 86400.0);  // an old bank of another scene
  // Cap: this render's bank fits, the old one does not.
  CliResult r = runCli("render '" + dir + "/drop.json' -o '" + dir + "/b.wav' --cache '" + cache +
                       "' --no-transfer --cache-max-size " + std::to_string(bank_bytes + 1000));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 from the cache"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("cache       removed 1 least recently used banks"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(cache + "/00000000000000aa.modes"));
  EXPECT_EQ(banksIn(cache).size(), 1u);
}

// A render that reads a bank from the cache marks it as used (its modification time), so the size
// cap, which removes the least recently used first, keeps the banks in use over those merely written
// long ago. Fails when the read leaves the entry's time alone.
TEST(NewcomerCache, ARenderThatReadsABankMarksItUsed) {
  const std::string dir = folderWithOneCachedBank("touch");
  const std::string cache = dir + "/cache";
  ASSERT_EQ(banksIn(cache).size(), 1u);
  const fs::path bank = banksIn(cache)[0];
  const auto long_ago = fs::file_time_type::clock::now() - std::chrono::hours(24 * 60);
  fs::last_write_time(bank, long_ago);
  CliResult r = runCli("render '" + dir + "/drop.json' -o '" + dir + "/b.wav' --cache '" + cache + "' --no-transfer");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 from the cache"), std::string::npos) << r.err;
  EXPECT_GT(fs::last_write_time(bank), long_ago + std::chrono::hours(24 * 59));
}

// ---- Item 5: the command line is documented in the repository ----------------------------------

TEST(NewcomerDocs, EveryOptionOfEveryCommandIsInDocsCli) {
  std::ifstream in(std::string(STRIKE_SOURCE_DIR) + "/docs/cli.md");
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(doc.empty());
  for (const char* command : {"render", "modes", "info", "hit", "analyze", "cache", "bench", "bench render"}) {
    CliResult help = runCli(std::string(command) + " --help");
    ASSERT_EQ(help.exit_code, 0) << command;
    EXPECT_NE(help.out.find("docs/cli.md"), std::string::npos) << command;
    EXPECT_EQ(help.out.find("ARCHITECTURE"), std::string::npos) << command;
    std::regex option(R"(\n  (--?[a-z][a-z0-9-]*))");
    for (std::sregex_iterator it(help.out.begin(), help.out.end(), option), end; it != end; ++it)
      EXPECT_NE(doc.find("`" + (*it)[1].str()), std::string::npos)
          << "strike " << command << " " << (*it)[1] << " is not in docs/cli.md";
  }
}

}  // namespace
}  // namespace strike
