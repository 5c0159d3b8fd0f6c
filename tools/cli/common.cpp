// SPDX-License-Identifier: MIT
#include <cstdio>

#include "commands.hpp"

namespace strike::cli {

int reportError(const std::string& command, const Error& error) {
  // File errors already read "path:line: error: ..."; others get the "error:" label here.
  const bool labelled = error.message.find("error: ") != std::string::npos;
  const char* label = error.kind == ErrorKind::Internal ? "internal error: " : (labelled ? "" : "error: ");
  std::fprintf(stderr, "strike %s: %s%s\n", command.c_str(), label, error.message.c_str());
  return static_cast<int>(error.kind);
}

}  // namespace strike::cli
