// SPDX-License-Identifier: MIT
#include "cache_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <utility>

#include "strike/core/interrupt_cleanup.hpp"

namespace strike {

CacheEntryLock::CacheEntryLock(const std::string& path) {
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd_ < 0) return;
  int status;
  do status = ::flock(fd_, LOCK_EX);
  while (status != 0 && errno == EINTR);
  if (status != 0) {
    ::close(fd_);
    fd_ = -1;
    return;
  }
  path_ = path;
  temporary_slot_ = registerTemporary(path);
}

void CacheEntryLock::release() {
  if (fd_ < 0) return;
  // Remove the file only while the name is still ours (not a newer lock file of another render).
  struct stat mine {
  }, named{};
  if (::fstat(fd_, &mine) == 0 && ::stat(path_.c_str(), &named) == 0 && mine.st_dev == named.st_dev &&
      mine.st_ino == named.st_ino)
    ::unlink(path_.c_str());
  unregisterTemporary(temporary_slot_);
  ::close(fd_);  // closing the last descriptor releases the flock
  fd_ = -1;
  temporary_slot_ = -1;
}

CacheEntryLock::~CacheEntryLock() { release(); }

CacheEntryLock::CacheEntryLock(CacheEntryLock&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      path_(std::move(other.path_)),
      temporary_slot_(std::exchange(other.temporary_slot_, -1)) {}

CacheEntryLock& CacheEntryLock::operator=(CacheEntryLock&& other) noexcept {
  if (this != &other) {
    release();
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    temporary_slot_ = std::exchange(other.temporary_slot_, -1);
  }
  return *this;
}

}  // namespace strike
