// SPDX-License-Identifier: MIT
// "The first hour, round two": what still tripped a new user. Memory forecasts refuse a solve
// over --max-memory before it starts; help and messages; the CLI reference covers every command.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "run_cli.hpp"

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

}  // namespace
}  // namespace strike
