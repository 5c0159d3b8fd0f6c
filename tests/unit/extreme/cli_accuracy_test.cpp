// SPDX-License-Identifier: MIT
// The user-visible side of issue 6 through the `strike` binary: the error estimate in
// `strike modes` and `strike info`, --no-error-estimate, --tolerance, and `strike bench accuracy`.
#include <gtest/gtest.h>

#include <fstream>

#include "cli/run_cli.hpp"

namespace strike {
namespace {

using test::runCli;

std::string temp(const std::string& name) { return "'" + ::testing::TempDir() + "/" + name + "'"; }

// Expectation: on by default for a primitive; the summary names the method and its extra cost;
// `info --json` carries one estimate per mode.
TEST(CliAccuracy, ModesReportsAnErrorEstimateByDefault) {
  const test::CliResult made = runCli("modes box:0.3,0.02,0.02 --material steel --order 2 --max-freq 6000 -o " + temp("e.modes"));
  ASSERT_EQ(made.exit_code, 0) << made.err;
  EXPECT_NE(made.err.find("est. error  max"), std::string::npos) << made.err;
  EXPECT_NE(made.err.find("richardson"), std::string::npos) << made.err;
  const test::CliResult info = runCli("info " + temp("e.modes") + " --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("\"frequency_error_estimate\""), std::string::npos);

  const test::CliResult off =
      runCli("modes box:0.3,0.02,0.02 --material steel --max-freq 6000 --no-error-estimate -o " + temp("n.modes"));
  ASSERT_EQ(off.exit_code, 0) << off.err;
  EXPECT_EQ(off.err.find("est. error"), std::string::npos) << off.err;
  EXPECT_EQ(runCli("info " + temp("n.modes") + " --json").out.find("frequency_error_estimate"), std::string::npos);
  EXPECT_EQ(runCli("modes box:0.3,0.02,0.02 --material steel --error-estimate --no-error-estimate -o " + temp("x.modes"))
                .exit_code,
            1);
}

// Expectation: --tolerance 0.5% on the steel bar (modes to 3 kHz) tries the cheapest candidates
// first, marks the chosen one, says the tolerance was met and how long it all took; it refuses
// --order/--size alongside (it chooses them) and a malformed value.
TEST(CliAccuracy, TolerancePicksTheCheapestMeshThatMeetsIt) {
  const test::CliResult r = runCli("modes box:0.3,0.02,0.02 --material steel --max-freq 3000 --tolerance 0.5% -o " + temp("t.modes"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("<- chosen"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("tolerance met after"), std::string::npos) << r.err;
  EXPECT_EQ(runCli("modes box:0.3,0.02,0.02 --material steel --tolerance 0.5% --order 2 -o " + temp("u.modes")).exit_code, 1);
  EXPECT_EQ(runCli("modes box:0.3,0.02,0.02 --material steel --tolerance fast -o " + temp("u.modes")).exit_code, 1);
  EXPECT_EQ(runCli("modes box:0.3,0.02,0.02 --material steel --tolerance 150% -o " + temp("u.modes")).exit_code, 1);
}

// Expectation: the study writes its four files, and the Euler table names the instability
// frequency near fs / pi = 15279 Hz at 48 kHz.
TEST(CliAccuracy, BenchAccuracyWritesItsTables) {
  const test::CliResult r = runCli("bench accuracy -o '" + ::testing::TempDir() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {"accuracy-fem.csv", "accuracy-fem.svg", "accuracy-synth.csv", "accuracy-euler.csv"})
    EXPECT_TRUE(std::ifstream(::testing::TempDir() + "/" + name).good()) << name;
  const std::string euler = test::slurp(::testing::TempDir() + "/accuracy-euler.csv");
  EXPECT_NE(euler.find("unstable above 1527"), std::string::npos) << euler;
  EXPECT_EQ(runCli("bench nonsense -o '" + ::testing::TempDir() + "'").exit_code, 1);
}

}  // namespace
}  // namespace strike
