// SPDX-License-Identifier: MIT
#include "output_check.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "strike/core/atomic_file.hpp"

namespace strike::cli {
namespace {

namespace fs = std::filesystem;

std::string lowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

/// Creates and removes one file in `folder`: the only reliable test that a write will succeed
/// there (access(2) says yes to root on a read-only mount, and says nothing about quotas of 0).
Status probeWritable(const std::string& option, const std::string& shown, const std::string& probe_beside) {
  const std::string probe = temporaryPathFor(probe_beside);
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return badInput(option + " " + shown + ": cannot create a file there (" + std::strerror(errno) + ")");
  ::close(fd);
  ::unlink(probe.c_str());
  return {};
}

}  // namespace

Status checkOutputFile(const std::string& option, const std::string& path, const std::vector<std::string>& extensions) {
  if (path.empty()) return badInput(option + ": empty path");
  std::error_code ec;
  if (fs::is_directory(path, ec)) return badInput(option + " " + path + ": is a folder, expected a file name");
  if (!extensions.empty()) {
    const std::string ext = lowerExtension(path);
    if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end()) {
      std::string list;
      for (const std::string& e : extensions) list += (list.empty() ? "" : ", ") + e;
      return badInput(option + " " + path + ": unsupported file extension '" + ext + "' (supported: " + list + ")");
    }
  }
  const fs::path parent = fs::path(path).parent_path();
  const std::string folder = parent.empty() ? "." : parent.string();
  if (!fs::exists(folder, ec)) return badInput(option + " " + path + ": the folder " + folder + " does not exist");
  if (!fs::is_directory(folder, ec)) return badInput(option + " " + path + ": " + folder + " is not a folder");
  return probeWritable(option, path, path);
}

Status prepareOutputDir(const std::string& option, const std::string& dir) {
  if (dir.empty()) return badInput(option + ": empty folder name");
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    return badInput(option + " " + dir + ": exists and is not a folder");
  fs::create_directories(dir, ec);
  if (ec) return badInput(option + " " + dir + ": cannot create the folder (" + ec.message() + ")");
  return probeWritable(option, dir, (fs::path(dir) / "probe").string());
}

}  // namespace strike::cli
