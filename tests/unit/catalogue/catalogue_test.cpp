// SPDX-License-Identifier: MIT
// The bad-input catalogue: malformed or hostile inputs across every format, each run
// through the built `strike` binary under a time and memory limit. Every case must exit with code
// 1, name the file (and line or key) and say what was expected, and leave no output file and no
// temporary file. The test prints one table line per case and the count.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "cli/run_cli.hpp"

namespace strike {
namespace {

namespace fs = std::filesystem;

using test::slurp;  // tests/unit/cli/run_cli.hpp

void spit(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

struct CliRun {
  int exit_code = -1;
  std::string err;
  double seconds = 0;
};

#if defined(__SANITIZE_ADDRESS__)
const char kMemoryLimit[] = "";  // ASan reserves terabytes of address space: no ulimit -v
#else
const char kMemoryLimit[] = "ulimit -v 8388608; ";  // 8 GiB
#endif

/// Runs `strike ARGS` under `timeout 20` and an 8 GiB address-space limit.
CliRun runBounded(const std::string& args, const std::string& scratch) {
  const std::string err_path = scratch + "/last.err";
  const std::string command = std::string(kMemoryLimit) + "timeout -k 5 20 '" + std::string(STRIKE_CLI) + "' " + args +
                              " >/dev/null 2>'" + err_path + "'";
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  CliRun run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  run.err = slurp(err_path);
  return run;
}

struct Case {
  std::string name;                 ///< shown in the table
  std::string format;               ///< obj, stl, ply, msh, tetgen, scene, bank, wav, args
  std::string args;                 ///< shell text; "@" is replaced by the case directory
  std::vector<std::string> expect;  ///< substrings of stderr ("@" replaced too)
  std::string output;               ///< output path that must not exist afterwards ("@" replaced)
  int exit_code = 1;                ///< 0 for the few inputs that are repaired with a warning instead
};

std::string expand(std::string text, const std::string& dir) {
  for (size_t at = text.find('@'); at != std::string::npos; at = text.find('@', at + dir.size()))
    text.replace(at, 1, dir);
  return text;
}

std::string repeat(const std::string& s, size_t n) {
  std::string out;
  out.reserve(s.size() * n);
  for (size_t i = 0; i < n; ++i) out += s;
  return out;
}

const char kTetObj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

std::string goodScene(const std::string& object_extra, const std::string& top_extra = "") {
  return "{\"sample_rate\": 48000, \"duration\": 0.5, " + top_extra +
         "\"objects\": [{\"name\": \"bar\", \"mesh\": \"box:0.1,0.02,0.02\", \"material\": \"steel\", "
         "\"position\": [0, 0, 0.2]" +
         object_extra + "}]}";
}

class Catalogue : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing::TempDir() + "/catalogue";
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // A real bank and a real sound, to corrupt.
    CliRun bank =
        runBounded("modes box:0.1,0.02,0.02 --material steel --max-modes 8 --quiet -o '" + dir_ + "/good.modes'", dir_);
    ASSERT_EQ(bank.exit_code, 0) << bank.err;
    CliRun hit = runBounded("hit '" + dir_ + "/good.modes' --duration 0.05 --quiet -o '" + dir_ + "/good.wav'", dir_);
    ASSERT_EQ(hit.exit_code, 0) << hit.err;
  }
  static std::string dir_;
};
std::string Catalogue::dir_;

std::vector<Case> buildCatalogue(const std::string& dir) {
  const std::string bad = std::string(STRIKE_SOURCE_DIR) + "/tests/data/mesh/bad/";
  const std::string modes_out = " --material steel --quiet -o '@/out.modes'";
  std::vector<Case> cases;
  auto mesh = [&](const std::string& name, const std::string& format, const std::string& file, const std::string& bytes,
                  std::vector<std::string> expect) {
    const std::string path = dir + "/" + file;
    spit(path, bytes);
    expect.insert(expect.begin(), file);
    cases.push_back({name, format, "modes '" + path + "'" + modes_out, expect, "@/out.modes"});
  };
  auto shipped = [&](const std::string& name, const std::string& format, const std::string& file,
                     std::vector<std::string> expect) {
    expect.insert(expect.begin(), file);
    cases.push_back({name, format, "modes '" + bad + file + "'" + modes_out, expect, "@/out.modes"});
  };

  // --- OBJ ---
  mesh("obj: negative index past the start", "obj", "neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -7\n", {"neg.obj:4:"});
  shipped("obj: face index past the vertex count", "obj", "bad_index.obj", {"bad_index.obj:"});
  shipped("obj: NaN coordinate", "obj", "nan.obj", {"nan.obj:"});
  mesh("obj: Inf coordinate", "obj", "inf.obj",
       "v inf 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n", {"inf.obj:1:"});
  mesh("obj: 1e300 coordinate overflows volume", "obj", "huge.obj",
       "v 0 0 0\nv 1e300 0 0\nv 0 1e300 0\nv 0 0 1e300\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n", {"huge.obj"});
  mesh("obj: surface not closed", "obj", "open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n",
       {"open.obj"});
  mesh("obj: self-intersecting (two overlapping tets)", "obj", "selfx.obj",
       std::string(kTetObj) +
           "v 0.2 0.2 0.2\nv 1.2 0.2 0.2\nv 0.2 1.2 0.2\nv 0.2 0.2 1.2\nf 5 7 6\nf 5 6 8\nf 5 8 7\nf 6 7 8\n",
       {"selfx.obj"});
  mesh("obj: zero volume (flat, two-sided)", "obj", "flat.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n",
       {"flat.obj"});
  mesh("obj: empty file", "obj", "empty.obj", "", {"empty.obj"});
  mesh("obj: binary junk", "obj", "junk.obj", std::string("\x7f\x45\x4c\x46\x02\x01\x01\x00\xff\xfe\x00\x01", 12),
       {"junk.obj"});
  mesh("obj: face with two corners", "obj", "twocorner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
       {"twocorner.obj:4:"});
  mesh("obj: text where a number belongs", "obj", "word.obj", "v 0 zero 0\n", {"word.obj:1:"});

  // --- STL ---
  shipped("stl: binary, truncated", "stl", "truncated.stl", {"truncated.stl"});
  shipped("stl: ascii, truncated", "stl", "truncated_ascii.stl", {"truncated_ascii.stl"});
  shipped("stl: facet count would need terabytes", "stl", "huge_count.stl", {"huge_count.stl"});
  mesh("stl: ascii, garbage after 'solid'", "stl", "garbage.stl", "solid x\n  facet normal a b c\n",
       {"garbage.stl:3:", "expected"});
  {
    std::string header(80, ' ');
    std::string bytes = header + std::string("\x00\xe1\xf5\x05", 4);  // 100,000,000 facets, none present
    mesh("stl: binary header claims 1e8 facets", "stl", "1e8.stl", bytes, {"1e8.stl"});
  }

  // --- PLY ---
  shipped("ply: vertex count would need terabytes", "ply", "huge_count.ply", {"huge_count.ply"});
  shipped("ply: truncated", "ply", "truncated.ply", {"truncated.ply"});
  shipped("ply: face index past the vertex count", "ply", "bad_index.ply", {"bad_index.ply"});
  mesh("ply: wrong magic", "ply", "magic.ply", "plx\nformat ascii 1.0\nend_header\n", {"magic.ply:1:"});
  mesh("ply: header claims 1e8 vertices", "ply", "1e8.ply",
       "ply\nformat ascii 1.0\nelement vertex 100000000\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
       {"1e8.ply"});
  mesh("ply: binary, negative list count", "ply", "negcount.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n",
       {"negcount.ply"});

  // --- Gmsh ---
  shipped("msh: truncated", "msh", "truncated.msh", {"truncated.msh"});
  shipped("msh: node count would need terabytes", "msh", "huge_count.msh", {"huge_count.msh"});
  shipped("msh: tet references a missing node", "msh", "bad_index.msh", {"bad_index.msh:"});
  shipped("msh: zero-volume tet", "msh", "degenerate.msh", {"degenerate.msh"});
  shipped("msh: NaN node coordinate", "msh", "nan.msh", {"nan.msh:"});
  shipped("msh: surface only, no tets", "msh", "surface_only.msh", {"surface_only.msh"});
  mesh("msh: unknown format version", "msh", "version.msh", "$MeshFormat\n9.9 0 8\n$EndMeshFormat\n",
       {"version.msh:2:"});
  mesh("msh: wrong magic", "msh", "magic.msh", "$MashFormat\n2.2 0 8\n$EndMeshFormat\n", {"magic.msh:1:"});
  mesh("msh: negative node index", "msh", "negnode.msh",
       "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
       "$Elements\n1\n1 4 0 1 2 3 -4\n$EndElements\n",
       {"negnode.msh:"});

  // Inverted tets (negative volume, consistently orientable) are a known exporter convention:
  // they are reoriented with a warning naming the file and the count, and the run succeeds.
  for (const char* file : {"inverted.msh", "inverted_tet10.msh"})
    cases.push_back({std::string("msh: inverted tets, repaired: ") + file,
                     "msh",
                     "modes '" + bad + file + "' --material steel --max-modes 4 -o '@/out.modes'",
                     {file, "were inverted (negative volume) and have been reoriented"},
                     "",
                     0});

  // --- TetGen ---
  cases.push_back({"tetgen: .node count would need terabytes",
                   "tetgen",
                   "modes '" + bad + "huge_count.node'" + modes_out,
                   {"huge_count.node"},
                   "@/out.modes"});
  cases.push_back({"tetgen: .ele count would need terabytes",
                   "tetgen",
                   "modes '" + bad + "huge_count.ele'" + modes_out,
                   {"huge_count."},
                   "@/out.modes"});
  cases.push_back({"tetgen: .ele references a missing node",
                   "tetgen",
                   "modes '" + bad + "bad_index.ele'" + modes_out,
                   {"bad_index."},
                   "@/out.modes"});
  {
    spit(dir + "/neg.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
    spit(dir + "/neg.ele", "1 4 0\n0 0 1 2 -3\n");
    cases.push_back({"tetgen: negative node index in .ele",
                     "tetgen",
                     "modes '" + dir + "/neg.ele'" + modes_out,
                     {"neg.ele:2:"},
                     "@/out.modes"});
    spit(dir + "/short.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n");
    spit(dir + "/short.ele", "1 4 0\n0 0 1 2 3\n");
    cases.push_back({"tetgen: .node truncated",
                     "tetgen",
                     "modes '" + dir + "/short.ele'" + modes_out,
                     {"short.node"},
                     "@/out.modes"});
  }

  // --- mesh paths and arguments ---
  cases.push_back({"mesh: file does not exist",
                   "path",
                   "modes '@/nowhere/part.obj'" + modes_out,
                   {"@/nowhere/part.obj"},
                   "@/out.modes"});
  fs::create_directories(dir + "/adir.obj");
  cases.push_back({"mesh: path is a directory",
                   "path",
                   "modes '@/adir.obj'" + modes_out,
                   {"adir.obj", "directory"},
                   "@/out.modes"});
  mesh("mesh: unknown extension", "path", "part.xyz", "1 2 3\n", {".xyz"});
  cases.push_back({"modes: output in a missing directory",
                   "path",
                   "modes box:0.1,0.02,0.02 --material steel --max-modes 4 --quiet -o '@/missing/out.modes'",
                   {"@/missing/out.modes"},
                   "@/missing/out.modes"});
  cases.push_back({"modes: --max-modes beyond the cap",
                   "args",
                   "modes box:0.1,0.02,0.02 --max-modes 10000000" + modes_out,
                   {"--max-modes = 10000000"},
                   "@/out.modes"});

  spit(dir + "/good.json", goodScene(""));
  // --- size caps: each names the cap and the flag that raises it ---
  cases.push_back({"limit: box finer than --max-tets",
                   "limit",
                   "modes box:0.3,0.3,0.3 --size 0.001" + modes_out,
                   {"box:", "--max-tets"},
                   "@/out.modes"});
  cases.push_back(
      {"limit: Gmsh file over --max-tets 5",
       "limit",
       "modes '" + std::string(STRIKE_SOURCE_DIR) + "/tests/data/mesh/bad/inverted.msh' --max-tets 5" + modes_out,
       {"inverted.msh", "6 tets, more than the cap of 5 (--max-tets)"},
       "@/out.modes"});
  spit(dir + "/tet.obj", kTetObj);
  cases.push_back({"limit: surface whose TetGen estimate is over the cap",
                   "limit",
                   "modes '@/tet.obj' --size 0.001" + modes_out,
                   {"tet.obj", "--max-tets"},
                   "@/out.modes"});
  cases.push_back({"limit: --max-tets 0",
                   "args",
                   "modes box:0.1,0.1,0.1 --max-tets 0" + modes_out,
                   {"--max-tets = 0"},
                   "@/out.modes"});
  cases.push_back({"limit: render over --max-events 3",
                   "limit",
                   "render '@/good.json' --max-events 3 --no-cache --quiet -o '@/out.wav'",
                   {"more than 3 contact events", "--max-events N"},
                   "@/out.wav"});
  cases.push_back({"limit: render object over --max-tets 10",
                   "limit",
                   "render '@/good.json' --max-tets 10 --no-cache --quiet -o '@/out.wav'",
                   {"objects \"bar\"", "more than the cap of 10 (--max-tets)"},
                   "@/out.wav"});
  cases.push_back({"limit: render --max-events 0",
                   "args",
                   "render '@/good.json' --max-events 0 -o '@/out.wav'",
                   {"--max-events = 0"},
                   "@/out.wav"});

  // --- scene JSON ---
  auto scene = [&](const std::string& name, const std::string& file, const std::string& text,
                   std::vector<std::string> expect) {
    spit(dir + "/" + file, text);
    expect.insert(expect.begin(), file);
    cases.push_back({name, "scene", "render '@/" + file + "' --no-cache --quiet -o '@/out.wav'", expect, "@/out.wav"});
  };
  scene("scene: nested 100000 deep", "deep.json", repeat("[", 100000), {"deep.json:1:", "nested deeper than 64"});
  {
    std::string objects;
    for (int i = 0; i < 10001; ++i)
      objects += std::string(i ? "," : "") + "{\"name\": \"o" + std::to_string(i) + "\", \"mesh\": \"sphere:0.01\"}";
    scene("scene: 10001 objects", "many.json", "{\"objects\": [" + objects + "]}", {"objects", "limit"});
  }
  scene("scene: 70 MB of whitespace", "enormous.json", "{" + std::string(70u << 20, ' ') + "}", {"limit"});
  scene("scene: wrong type for duration", "type.json", "{\"duration\": \"three\", \"objects\": []}", {"duration"});
  scene("scene: unknown key (typo)", "typo.json", goodScene(", \"postion\": [0, 0, 1]"), {"postion"});
  scene("scene: truncated JSON", "trunc.json", goodScene("").substr(0, 60), {"trunc.json:1:"});
  scene("scene: Inf (1e999) position", "inf.json", goodScene(", \"velocity\": [1e999, 0, 0]"), {"1e999"});
  scene("scene: negative sample rate", "rate.json", "{\"sample_rate\": -48000, \"objects\": []}", {"sample_rate"});
  scene("scene: duration beyond the cap", "long.json", "{\"duration\": 1e7, \"objects\": []}", {"duration"});
  scene("scene: mesh file does not exist", "nomesh.json",
        "{\"objects\": [{\"name\": \"a\", \"mesh\": \"missing.obj\", \"material\": \"steel\"}]}", {"missing.obj"});
  scene("scene: empty file", "empty.json", "", {"empty.json"});
  scene("scene: orientation of zero length", "quat.json", goodScene(", \"orientation\": [0, 0, 0, 0]"),
        {"orientation"});
  cases.push_back({"scene: file does not exist",
                   "scene",
                   "render '@/none.json' --quiet -o '@/out.wav'",
                   {"@/none.json"},
                   "@/out.wav"});
  fs::create_directories(dir + "/sdir.json");
  cases.push_back({"scene: path is a directory",
                   "scene",
                   "render '@/sdir.json' --quiet -o '@/out.wav'",
                   {"sdir.json", "directory"},
                   "@/out.wav"});

  // --- mode bank ---
  const std::string good_bank = slurp(dir + "/good.modes");
  auto bank = [&](const std::string& name, const std::string& file, const std::string& bytes,
                  std::vector<std::string> expect) {
    spit(dir + "/" + file, bytes);
    expect.insert(expect.begin(), file);
    cases.push_back({name, "bank", "info '@/" + file + "'", expect, ""});
  };
  bank("bank: truncated to half", "half.modes", good_bank.substr(0, good_bank.size() / 2), {});
  bank("bank: wrong magic", "magic.modes", "XXXX" + good_bank.substr(4), {});
  {
    std::string flipped = good_bank;
    flipped[flipped.size() / 2] ^= 0x5a;
    bank("bank: one byte flipped (checksum)", "flip.modes", flipped, {});
  }
  bank("bank: empty file", "empty.modes", "", {});
  bank("bank: a text file", "text.modes", "this is not a mode bank\n", {});
  // The message names the damaged bank, not the scene that refers to it.
  spit(dir + "/trbank.json", "{\"objects\": [{\"name\": \"a\", \"bank\": \"half.modes\", \"position\": [0, 0, 1]}]}");
  cases.push_back({"scene: its bank file is truncated",
                   "scene",
                   "render '@/trbank.json' --no-cache --quiet -o '@/out.wav'",
                   {"half.modes", "truncated"},
                   "@/out.wav"});

  // --- hit arguments ---
  cases.push_back({"hit: --vertex past the surface",
                   "args",
                   "hit '@/good.modes' --vertex 99999999 --quiet -o '@/out.wav'",
                   {"--vertex = 99999999"},
                   "@/out.wav"});
  cases.push_back({"hit: --vertex negative",
                   "args",
                   "hit '@/good.modes' --vertex -1 --quiet -o '@/out.wav'",
                   {"--vertex"},
                   "@/out.wav"});
  cases.push_back({"hit: NaN impulse",
                   "args",
                   "hit '@/good.modes' --impulse nan,0,0 --quiet -o '@/out.wav'",
                   {"--impulse"},
                   "@/out.wav"});
  cases.push_back({"hit: duration beyond the cap",
                   "args",
                   "hit '@/good.modes' --duration 1e9 --quiet -o '@/out.wav'",
                   {"--duration = 1e9"},
                   "@/out.wav"});
  cases.push_back({"hit: output in a missing directory",
                   "path",
                   "hit '@/good.modes' --duration 0.05 --quiet -o '@/missing/out.wav'",
                   {"@/missing/out.wav"},
                   "@/missing/out.wav"});
  cases.push_back(
      {"hit: bank is a directory", "path", "hit '@/adir.obj' --quiet -o '@/out.wav'", {"adir.obj"}, "@/out.wav"});

  // --- audio (analyze) ---
  const std::string good_wav = slurp(dir + "/good.wav");
  spit(dir + "/trunc.wav", good_wav.substr(0, 30));
  cases.push_back({"wav: truncated header", "wav", "analyze '@/trunc.wav'", {"trunc.wav"}, ""});
  spit(dir + "/text.wav", "RIFF but not really\n");
  cases.push_back({"wav: text file", "wav", "analyze '@/text.wav'", {"text.wav"}, ""});
  cases.push_back({"wav: does not exist", "wav", "analyze '@/none.wav'", {"none.wav"}, ""});
  cases.push_back({"wav: path is a directory", "wav", "analyze '@/adir.obj'", {"adir.obj"}, ""});
  return cases;
}

TEST_F(Catalogue, EveryHostileInputIsRefusedCleanly) {
  const std::vector<Case> cases = buildCatalogue(dir_);
  std::printf("\nbad-input catalogue: %zu cases\n", cases.size());
  std::printf("%-3s %-7s %-48s %4s %7s  %s\n", "#", "format", "case", "exit", "time", "result / message");
  int passed = 0, repaired = 0;
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const std::string output = expand(c.output, dir_);
    const CliRun run = runBounded(expand(c.args, dir_), dir_);
    std::vector<std::string> problems;
    if (run.exit_code != c.exit_code)
      problems.push_back("exit " + std::to_string(run.exit_code) + ", expected " + std::to_string(c.exit_code));
    for (const std::string& e : c.expect)
      if (run.err.find(expand(e, dir_)) == std::string::npos)
        problems.push_back("message lacks '" + expand(e, dir_) + "'");
    if (run.err.find(c.exit_code == 0 ? "warning" : "error") == std::string::npos)
      problems.push_back(c.exit_code == 0 ? "message lacks 'warning'" : "message lacks 'error'");
    if (!output.empty() && fs::exists(output)) problems.push_back("output " + output + " exists");
    for (const auto& entry : fs::recursive_directory_iterator(dir_))
      if (entry.path().filename().string().find(".tmp-") != std::string::npos)
        problems.push_back("temporary file left: " + entry.path().string());
    if (run.seconds > 20) problems.push_back("took " + std::to_string(run.seconds) + " s");
    std::string first_line = run.err.substr(0, run.err.find('\n'));
    const size_t slash = first_line.rfind(dir_);
    if (slash != std::string::npos) first_line.replace(slash, dir_.size(), "$TMP");
    const size_t source = first_line.find(STRIKE_SOURCE_DIR);
    if (source != std::string::npos) first_line.replace(source, std::string(STRIKE_SOURCE_DIR).size(), "$SRC");
    if (first_line.size() > 150) first_line = first_line.substr(0, 147) + "...";
    std::printf("%-3zu %-7s %-48s %4d %6.2fs  %s%s\n", i + 1, c.format.c_str(), c.name.c_str(), run.exit_code,
                run.seconds,
                problems.empty() ? "ok: " : "FAIL: ", problems.empty() ? first_line.c_str() : problems[0].c_str());
    if (problems.empty()) ++passed;
    if (c.exit_code == 0) ++repaired;
    for (const std::string& p : problems) ADD_FAILURE() << c.name << ": " << p << "\nstderr: " << run.err;
    if (!output.empty()) fs::remove(output);
    fs::remove(dir_ + "/out.modes");
  }
  std::printf(
      "bad-input catalogue: %d of %zu cases as expected (%zu refused with exit 1, %d repaired with a warning)\n",
      passed, cases.size(), cases.size() - static_cast<size_t>(repaired), repaired);
  EXPECT_GE(cases.size() - static_cast<size_t>(repaired), 40u);
}

}  // namespace
}  // namespace strike
