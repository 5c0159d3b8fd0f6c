// SPDX-License-Identifier: MIT
// The command line end to end: bad input gets exit code 1 and a message naming the problem;
// good input gives banks and sounds whose numbers match theory.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_cli.hpp"
#include "strike/bank.hpp"

namespace strike {
namespace {

using test::CliResult;
using test::runCli;

std::string temp(const std::string& name) { return testing::TempDir() + "/" + name; }

TEST(Cli, NoArgumentsShowsUsageAndFails) {
  CliResult r = runCli("");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("usage: strike COMMAND"), std::string::npos);
  r = runCli("frobnicate");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown command 'frobnicate'"), std::string::npos);
}

TEST(Cli, HelpTeachesEveryCommand) {
  for (const char* command : {"modes", "info", "hit", "analyze"}) {
    CliResult r = runCli(std::string(command) + " --help");
    EXPECT_EQ(r.exit_code, 0) << command;
    EXPECT_NE(r.out.find("usage: strike " + std::string(command)), std::string::npos) << command;
    EXPECT_NE(r.out.find("examples:"), std::string::npos) << command;
  }
}

TEST(CliModes, UnknownMaterialListsKnownOnes) {
  CliResult r = runCli("modes box:0.1,0.1,0.1 --material unobtainium -o '" + temp("x.modes") + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown material 'unobtainium'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("steel"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(temp("x.modes")));
}

TEST(CliModes, BadMaterialNumbersNameTheOption) {
  struct Case {
    std::string args, expected;
  } cases[] = {
      {"--youngs 2e11 --poisson 0.3 --density -7850", "--density = -7850"},
      {"--youngs 2e11 --poisson 0.5 --density 7850", "--poisson = 0.5"},
      {"--youngs 2e11 --poisson 0.7 --density 7850", "--poisson = 0.7"},
      {"--youngs 0 --poisson 0.3 --density 7850", "--youngs = 0"},
      {"--youngs nan --poisson 0.3 --density 7850", "--youngs = 'nan'"},
      {"--youngs 2e11 --poisson 0.3", "no material"},
      {"--material steel --order 3", "--order = 3"},
      {"--material steel --max-freq -5", "--max-freq = -5"},
      {"--material steel --size abc", "--size = 'abc'"},
      {"--material steel --bogus 1", "unknown option '--bogus'"},
  };
  for (const Case& c : cases) {
    CliResult r = runCli("modes box:0.1,0.1,0.1 " + c.args + " -o '" + temp("bad.modes") + "'");
    EXPECT_EQ(r.exit_code, 1) << c.args;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\n" << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(temp("bad.modes")));
}

TEST(CliModes, MissingMeshFileIsNamed) {
  CliResult r = runCli("modes /nonexistent/part.obj --material steel -o '" + temp("y.modes") + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("/nonexistent/part.obj"), std::string::npos) << r.err;
}

TEST(CliInfo, TruncatedAndForeignBanksAreRefused) {
  const std::string truncated = temp("truncated.modes");
  {
    std::ofstream out(truncated, std::ios::binary);
    out << "STRKBANK\x01\x00\x00\x00";
  }
  CliResult r = runCli("info '" + truncated + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(truncated), std::string::npos) << r.err;

  const std::string foreign = temp("foreign.modes");
  {
    std::ofstream out(foreign, std::ios::binary);
    out << "solid cube\nendsolid\n";
  }
  r = runCli("info '" + foreign + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("magic"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace strike
