// SPDX-License-Identifier: MIT
// `strike batch MANIFEST.jsonl -o DIR ...`: runs the Python package's batch renderer
// (python/strike/batch.py, on Dask) with the Python this build found, by exec: the same process,
// so its exit code and signals are the batch's.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.hpp"

namespace strike::cli {

int runBatch(const std::vector<std::string>& args) {
#ifndef STRIKE_PYTHON_EXECUTABLE
  (void)args;
  std::fputs(
      "strike batch: error: this strike was built without the Python package (STRIKE_BUILD_PYTHON=OFF); "
      "see README, Python\n",
      stderr);
  return 1;
#else
  // The package beside this executable: the build tree (BUILD/tools/strike, BUILD/python/strike)
  // or an install (PREFIX/bin/strike, PREFIX/STRIKE_PYTHON_INSTALL_DIR/strike). Else Python's own path.
  namespace fs = std::filesystem;
  std::error_code ignored;
  const fs::path self = fs::read_symlink("/proc/self/exe", ignored);
  std::string python_path;
  for (const fs::path& dir :
       {self.parent_path().parent_path() / "python", self.parent_path().parent_path() / STRIKE_PYTHON_INSTALL_DIR}) {
    if (fs::is_regular_file(dir / "strike" / "__init__.py", ignored)) {
      python_path = dir.string();
      break;
    }
  }
  if (!python_path.empty()) {
    const char* old = std::getenv("PYTHONPATH");
    if (old && *old) python_path += ":" + std::string(old);
    ::setenv("PYTHONPATH", python_path.c_str(), 1);
  }
  std::vector<std::string> command = {STRIKE_PYTHON_EXECUTABLE, "-m", "strike.batch"};
  command.insert(command.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : command) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(argv[0], argv.data());
  std::fprintf(stderr, "strike batch: error: cannot run %s: %s (install python3; see README, Python)\n",
               STRIKE_PYTHON_EXECUTABLE, std::strerror(errno));
  return 1;
#endif
}

}  // namespace strike::cli
