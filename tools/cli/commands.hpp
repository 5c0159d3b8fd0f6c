// SPDX-License-Identifier: MIT
// The `strike` subcommands. Each returns the process exit code: 0 success, 1 bad input,
// 2 internal error. Diagnostics go to stderr, data to stdout.
#pragma once

#include <string>
#include <vector>

#include "strike/core/result.hpp"

namespace strike::cli {

int runModes(const std::vector<std::string>& args);
int runInfo(const std::vector<std::string>& args);
int runHit(const std::vector<std::string>& args);
int runAnalyze(const std::vector<std::string>& args);
int runRender(const std::vector<std::string>& args);
int runBench(const std::vector<std::string>& args);  // strike bench (bench/bench.cpp)
int runCache(const std::vector<std::string>& args);
int runBatch(const std::vector<std::string>& args);        // strike batch (cmd_batch.cpp): python3 -m strike.batch
int runBenchRender(const std::vector<std::string>& args);  // strike bench render (bench/render.cpp)

/// Prints "strike <command>: error: <message>" and returns the exit code for the error's kind.
int reportError(const std::string& command, const Error& error);

}  // namespace strike::cli
