// SPDX-License-Identifier: MIT
// "The first hour, round two": what still tripped a new user. Memory forecasts refuse a solve
// over --max-memory before it starts; help and messages; the CLI reference covers every command.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "run_cli.hpp"
#include "strike/bank/bank.hpp"

namespace strike {
namespace {

namespace fs = std::filesystem;
using test::CliResult;
using test::runCli;

std::string folder(const std::string& name) {
  const std::string dir = testing::TempDir() + "/first-hour-" + std::to_string(getpid()) + "-" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(FirstHourMemory, ASolveForecastOverMaxMemoryIsRefusedWithItsForecastAndWritesNothing) {
  const std::string dir = folder("memory");
  const std::string bar = "modes box:0.3,0.02,0.02 --material steel --order 2 --no-transfer --no-error-estimate ";
  // The bar's factorization alone is ~80 MB: 50M cannot hold it.
  const CliResult small = runCli(bar + "--max-memory 50M -o " + dir + "/a.modes");
  EXPECT_EQ(small.exit_code, 1) << small.err;
  EXPECT_NE(small.err.find("would need about"), std::string::npos) << small.err;
  EXPECT_NE(small.err.find("more than the memory budget of 53 MB"), std::string::npos) << small.err;
  EXPECT_NE(small.err.find("--max-memory"), std::string::npos) << small.err;
  EXPECT_FALSE(fs::exists(dir + "/a.modes"));
  // Every mode of the mesh in the band (1e7 Hz), 10000 asked for: ~40 GB, refused before the
  // factorization.
  const CliResult all = runCli(bar + "--max-freq 1e7 --max-modes 10000 --max-memory 4G -o " + dir + "/b.modes");
  EXPECT_EQ(all.exit_code, 1) << all.err;
  EXPECT_NE(all.err.find("the band holds all its modes"), std::string::npos) << all.err;
  EXPECT_FALSE(fs::exists(dir + "/b.modes"));
  // --max-memory guards a plain solve (no --tolerance needed); a budget that holds it solves.
  const CliResult fits =
      runCli("modes box:0.05,0.03,0.02 --material steel --no-transfer --no-error-estimate --max-memory 2G -o " + dir +
             "/c.modes");
  EXPECT_EQ(fits.exit_code, 0) << fits.err;
  EXPECT_TRUE(fs::exists(dir + "/c.modes"));
  const CliResult zero = runCli("modes box:0.05,0.03,0.02 --material steel --max-memory 0 -o " + dir + "/d.modes");
  EXPECT_EQ(zero.exit_code, 1);
  EXPECT_NE(zero.err.find("--max-memory = 0"), std::string::npos) << zero.err;
}

// --max-seconds bounds the transfer too: with a budget the eigen-solve alone overruns, the
// transfer's first solve is made (it measures the rates), its refinement is not, and the groups
// above are left without a transfer (a render that plays them solves theirs); the summary says
// NOT met and why, the bank is whole and the command exits 0. A budget that never binds changes
// nothing in the transfer.
TEST(FirstHourTime, ATransferOverMaxSecondsKeepsItsCoarserSolvesAndSaysSo) {
  const std::string dir = folder("time");
  // A steel block: three modes, each refined from its first solve when no budget stops it.
  const std::string block = "modes box:0.12,0.04,0.03 --material steel --max-modes 12 --no-error-estimate ";
  const CliResult cut = runCli(block + "--max-seconds 0.001 -o " + dir + "/cut.modes");
  ASSERT_EQ(cut.exit_code, 0) << cut.err;
  EXPECT_NE(cut.err.find("transfer time budget"), std::string::npos) << cut.err;
  EXPECT_NE(cut.err.find("forecast >"), std::string::npos) << cut.err;
  EXPECT_NE(cut.err.find("NOT met"), std::string::npos) << cut.err;
  EXPECT_NE(cut.err.find("the time budget (--max-seconds) cut"), std::string::npos) << cut.err;
  const CliResult unbounded = runCli(block + "-o " + dir + "/free.modes");
  ASSERT_EQ(unbounded.exit_code, 0) << unbounded.err;
  EXPECT_EQ(unbounded.err.find("time budget"), std::string::npos) << unbounded.err;
  const CliResult loose = runCli(block + "--max-seconds 1e6 -o " + dir + "/loose.modes");
  ASSERT_EQ(loose.exit_code, 0) << loose.err;
  Result<ModeBank> a = readBank(dir + "/cut.modes"), b = readBank(dir + "/free.modes"),
                   c = readBank(dir + "/loose.modes");
  ASSERT_TRUE(a && b && c);
  EXPECT_EQ(a->checkConsistency(), "");
  ASSERT_GT(b->transfer.modeCount(), 1u);
  ASSERT_GE(a->transfer.modeCount(), 1u);  // the first solve, always made
  EXPECT_LT(a->transfer.modeCount(), b->transfer.modeCount());
  EXPECT_NE(cut.err.find("left unsolved"), std::string::npos) << cut.err;
  EXPECT_NE(a->transfer.method.find("time budget"), std::string::npos) << a->transfer.method;
  // Cut short: no estimate better than the unbounded solve's, the first worse (not refined).
  for (size_t i = 0; i < a->transfer.modeCount(); ++i)
    EXPECT_GE(a->transfer.relative_error[i], 0.999f * b->transfer.relative_error[i]) << i;
  EXPECT_GT(a->transfer.relative_error[0], 1.001f * b->transfer.relative_error[0]);
  // A budget that never binds: the same transfer, to the bit.
  EXPECT_EQ(c->transfer.method, b->transfer.method);
  EXPECT_EQ(c->transfer.order, b->transfer.order);
  EXPECT_EQ(c->transfer.relative_error, b->transfer.relative_error);
  EXPECT_TRUE(c->transfer.coefficients == b->transfer.coefficients);
  const CliResult zero = runCli(block + "--max-seconds 0 -o " + dir + "/zero.modes");
  EXPECT_EQ(zero.exit_code, 1);
  EXPECT_NE(zero.err.find("--max-seconds = 0"), std::string::npos) << zero.err;
}

struct Interrupted {
  bool by_sigint = false;  ///< ended by SIGINT (a shell shows exit status 130)
  std::string err;
};

/// Starts `strike ARGS...` with SIGINT at its default action (a test runner may ignore it),
/// sends it SIGINT after `after_s`, and waits for it (killed outright after 60 s, then failed).
Interrupted interruptAfter(const std::vector<std::string>& args, double after_s, const std::string& err_path) {
  Interrupted out;
  const pid_t child = fork();
  if (child == 0) {
    signal(SIGINT, SIG_DFL);
    const int fd = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, STDERR_FILENO);
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(STRIKE_CLI));
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(STRIKE_CLI, argv.data());
    _exit(127);
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(after_s));
  kill(child, SIGINT);
  int status = 0;
  const auto start = std::chrono::steady_clock::now();
  while (waitpid(child, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() - start > std::chrono::seconds(60)) {
      kill(child, SIGKILL);
      waitpid(child, &status, 0);
      ADD_FAILURE() << "still running 60 s after SIGINT";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  out.by_sigint = WIFSIGNALED(status) && WTERMSIG(status) == SIGINT;
  out.err = test::slurp(err_path);
  return out;
}

TEST(FirstHourInterrupt, SigintStopsTheSolveAndTheRenderSaysWhatAndLeavesNothing) {
  const std::string dir = folder("interrupt");
  // The bar's solve and its transfer take seconds: interrupted in its first second.
  const Interrupted modes =
      interruptAfter({"modes", "box:0.3,0.02,0.02", "--material", "steel", "--order", "2", "-o", dir + "/bar.modes"},
                     0.8, dir + "/modes.err");
  EXPECT_TRUE(modes.by_sigint) << modes.err;
  EXPECT_NE(modes.err.find("strike modes: interrupted during "), std::string::npos) << modes.err;
  EXPECT_NE(modes.err.find("; nothing was written"), std::string::npos) << modes.err;
  const Interrupted render =
      interruptAfter({"render", std::string(STRIKE_SOURCE_DIR) + "/examples/scenes/bar-drop.json", "-o",
                      dir + "/bar.wav", "--no-cache", "--events", dir + "/bar.csv"},
                     1.0, dir + "/render.err");
  EXPECT_TRUE(render.by_sigint) << render.err;
  EXPECT_NE(render.err.find("strike render: interrupted during "), std::string::npos) << render.err;
  // Only the two error captures are left: no output, no temporary.
  std::vector<std::string> left;
  for (const auto& entry : fs::directory_iterator(dir)) left.push_back(entry.path().filename().string());
  EXPECT_EQ(left.size(), 2u) << left.back();
}

TEST(FirstHourMessages, ASlipOfOneOrTwoLettersIsAnsweredWithDidYouMean) {
  const CliResult command = runCli("rendr scene.json -o x.wav");
  EXPECT_EQ(command.exit_code, 1);
  EXPECT_NE(command.err.find("unknown command 'rendr'; did you mean render?"), std::string::npos) << command.err;
  const CliResult option = runCli("render scene.json -o x.wav --rat 44100");
  EXPECT_EQ(option.exit_code, 1);
  EXPECT_NE(option.err.find("unknown option '--rat'; did you mean --rate?"), std::string::npos) << option.err;
  const CliResult swapped = runCli("modes box:0.1,0.1,0.1 --material steel -o x.modes --quite");
  EXPECT_NE(swapped.err.find("did you mean --quiet?"), std::string::npos) << swapped.err;
  // Nothing near: no guess.
  const CliResult far = runCli("hit x.modes -o x.wav --loudness 3");
  EXPECT_EQ(far.exit_code, 1);
  EXPECT_EQ(far.err.find("did you mean"), std::string::npos) << far.err;
}

// Every command `strike --help` lists has its section in docs/cli.md, with every option its --help
// lists; its option rows fit in 100 columns, their continuation lines under the first (column 31).
TEST(FirstHourMessages, EveryCommandIsDocumentedAndItsHelpRowsLineUp) {
  std::ifstream in(std::string(STRIKE_SOURCE_DIR) + "/docs/cli.md");
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(doc.empty());
  const CliResult usage = runCli("--help");
  ASSERT_EQ(usage.exit_code, 0);
  std::istringstream lines(usage.out.substr(usage.out.find("commands:")));
  std::string line;
  std::getline(lines, line);
  std::vector<std::string> commands;
  while (std::getline(lines, line) && line.rfind("  ", 0) == 0) {
    std::istringstream words(line);
    std::string command, sub;
    words >> command >> sub;
    if (command == "bench") command += " " + sub;
    commands.push_back(command);
  }
  ASSERT_GE(commands.size(), 10u) << usage.out;
  for (const std::string& command : commands) {
    EXPECT_NE(doc.find("## `strike " + command.substr(0, command.find(' '))), std::string::npos)
        << "strike " << command << " has no section in docs/cli.md";
    const CliResult help = runCli(command + " --help");
    ASSERT_EQ(help.exit_code, 0) << command;
    EXPECT_NE(help.out.find("examples:"), std::string::npos) << command;
    const size_t options = help.out.find("\noptions:\n");
    if (options == std::string::npos) continue;
    std::istringstream rows(help.out.substr(options + 10, help.out.find("\n\n", options + 10) - options - 10));
    while (std::getline(rows, line)) {
      EXPECT_LE(line.size(), 100u) << command << ": " << line;
      if (line.rfind("  -", 0) == 0) {
        const std::string option = line.substr(2, line.find(' ', 2) - 2);
        EXPECT_NE(doc.find("`" + option), std::string::npos) << "strike " << command << " " << option;
      } else {
        EXPECT_EQ(line.find_first_not_of(' '), 30u) << command << ": " << line;
      }
    }
  }
}

TEST(FirstHourMessages, ABankNotNamedModesIsWarnedAndNoNumberPrintsAsMinusZero) {
  const std::string dir = folder("names");
  const CliResult modes =
      runCli("modes box:0.05,0.03,0.02 --material steel --no-transfer --no-error-estimate -o " + dir + "/bar.mode");
  ASSERT_EQ(modes.exit_code, 0) << modes.err;
  EXPECT_NE(modes.err.find("warning: -o " + dir + "/bar.mode does not end in .modes"), std::string::npos) << modes.err;
  // The default impulse is the inward normal: on the top face (0, 0, 1) it is (-0.0, -0.0, -0.01).
  const CliResult hit = runCli("hit " + dir + "/bar.mode -o " + dir + "/hit.wav --duration 0.1 --at 0,0,0.01");
  ASSERT_EQ(hit.exit_code, 0) << hit.err;
  const size_t impulse = hit.err.find("impulse (");
  ASSERT_NE(impulse, std::string::npos) << hit.err;
  const std::string printed = hit.err.substr(impulse, hit.err.find('\n', impulse) - impulse);
  EXPECT_EQ(printed.find("-0,"), std::string::npos) << printed;
  EXPECT_EQ(printed.find("-0)"), std::string::npos) << printed;
  EXPECT_NE(printed.find("0, 0"), std::string::npos) << printed;
}

TEST(FirstHourMessages, TheMaterialTableFitsATerminalWithItsSourcesAsNotes) {
  const CliResult table = runCli("modes --list-materials");
  ASSERT_EQ(table.exit_code, 0) << table.err;
  std::istringstream lines(table.out);
  std::string line;
  size_t rows = 0;
  while (std::getline(lines, line) && !line.empty()) {
    EXPECT_LE(line.size(), 100u) << line;
    ++rows;
  }
  EXPECT_GT(rows, 10u);
  EXPECT_NE(table.out.find("\nsources:\n[1]  "), std::string::npos) << table.out;
}

TEST(FirstHourInfo, VerticesListsEverySurfaceVertexWithItsOutwardNormal) {
  const std::string dir = folder("vertices");
  const CliResult modes =
      runCli("modes box:0.1,0.05,0.02 --material steel --no-transfer --no-error-estimate -o " + dir + "/box.modes");
  ASSERT_EQ(modes.exit_code, 0) << modes.err;
  const CliResult json = runCli("info " + dir + "/box.modes --json --vertices");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json j = nlohmann::json::parse(json.out);
  const auto& positions = j.at("surface_vertices_m");
  const auto& normals = j.at("surface_normals");
  ASSERT_EQ(positions.size(), j.at("mesh").at("surface_vertices").get<size_t>());
  ASSERT_EQ(normals.size(), positions.size());
  size_t top = 0;
  for (size_t v = 0; v < positions.size(); ++v) {
    const double nx = normals[v][0], ny = normals[v][1], nz = normals[v][2];
    EXPECT_NEAR(nx * nx + ny * ny + nz * nz, 1.0, 1e-6) << v;
    // On the box's top face (z = 0.01, away from its edges) the normal is +z.
    const double x = positions[v][0], y = positions[v][1], z = positions[v][2];
    if (std::fabs(z - 0.01) < 1e-9 && std::fabs(x) < 0.049 && std::fabs(y) < 0.024) {
      EXPECT_NEAR(nz, 1.0, 1e-6) << v;
      ++top;
    }
  }
  EXPECT_GT(top, 0u);
  const CliResult table = runCli("info " + dir + "/box.modes --vertices");
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_NE(table.out.find("vertex        x m        y m        z m      nx      ny      nz"), std::string::npos)
      << table.out;
  EXPECT_NE(table.out.find("\n" + std::string(6 - std::to_string(positions.size() - 1).size(), ' ') +
                           std::to_string(positions.size() - 1) + " "),
            std::string::npos);
}

TEST(FirstHourMessages, ATet10FileWithNoOrderGivenKeepsItsOrderWithoutAWarning) {
  const std::string dir = folder("tet10");
  const CliResult r =
      runCli("modes " + std::string(STRIKE_SOURCE_DIR) +
             "/tests/data/mesh/cube_tet10_v22.msh --material steel --no-transfer -o " + dir + "/c.modes");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(Tet10)"), std::string::npos) << r.err;
}

// Every `strike ...` command line in README.md's and docs/'s shell blocks names a command that
// exists and only options its --help lists (a renamed or removed option fails here), also the
// ones DocsCommands.EveryCommandInTheReadmeAndDocsRuns does not run; that test runs them, and the
// whole scenes of the docs are run by Docs.EveryWholeSceneInTheDocsRunsAsWrittenWithoutWarnings.
TEST(FirstHourDocs, EveryCommandLineInTheDocsUsesOptionsTheCommandHas) {
  const fs::path root = STRIKE_SOURCE_DIR;
  std::vector<fs::path> files = {root / "README.md"};
  for (const auto& e : fs::directory_iterator(root / "docs"))
    if (e.path().extension() == ".md") files.push_back(e.path());
  size_t lines_checked = 0;
  for (const fs::path& file : files) {
    std::ifstream in(file);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    bool in_shell = false;
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
      if (line.rfind("```", 0) == 0) {
        in_shell = !in_shell && (line == "```sh" || line == "```bash" || line == "```");
        continue;
      }
      const size_t start = line.find_first_not_of(' ');
      if (!in_shell || start == std::string::npos || line.compare(start, 7, "strike ") != 0) continue;
      std::string command_line =
          line.substr(start, line.find('#') == std::string::npos ? std::string::npos : line.find('#') - start);
      command_line = command_line.substr(0, command_line.find('|'));
      std::istringstream words(command_line);
      std::string word, command;
      std::vector<std::string> options;
      words >> word >> command;
      // A synopsis (`strike COMMAND [ARGS]`, `strike --version`) or a printed message
      // (`strike render: wrote ...`) is not a command line.
      const std::vector<std::string> known = {"render", "modes", "info", "hit", "analyze", "cache", "batch", "bench"};
      if (std::find(known.begin(), known.end(), command) == known.end()) continue;
      if (command == "bench" || command == "cache") {
        std::string sub;
        words >> sub;
        if (command == "bench") command += " " + sub;
      }
      while (words >> word)
        if (word.rfind("--", 0) == 0) options.push_back(word.substr(0, word.find('=')));
      const CliResult help = runCli(command + " --help");
      ASSERT_EQ(help.exit_code, 0) << file << ": `" << command_line << "`: no command " << command;
      for (const std::string& option : options)
        EXPECT_NE(help.out.find("  " + option + " "), std::string::npos) << file << ": `" << command_line << "`";
      ++lines_checked;
    }
  }
  EXPECT_GE(lines_checked, 15u);
}

}  // namespace
}  // namespace strike
