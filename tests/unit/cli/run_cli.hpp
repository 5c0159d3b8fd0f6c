// SPDX-License-Identifier: MIT
// Runs the built `strike` binary and captures its exit code, stdout and stderr.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace strike::test {

struct CliResult {
  int exit_code = -1;
  std::string out, err;
};

inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs `strike ARGS` (ARGS is shell text; quote paths yourself) in the test's temp directory.
inline CliResult runCli(const std::string& args) {
  // ctest runs tests as parallel processes: the pid keeps their capture files apart.
  static int counter = 0;
  const std::string base =
      testing::TempDir() + "/cli_" + std::to_string(static_cast<long>(getpid())) + "_" + std::to_string(++counter);
  const std::string command = std::string("'") + STRIKE_CLI + "' " + args + " >'" + base + ".out' 2>'" + base + ".err'";
  const int status = std::system(command.c_str());
  CliResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = slurp(base + ".out");
  result.err = slurp(base + ".err");
  return result;
}

}  // namespace strike::test
