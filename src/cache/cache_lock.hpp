// SPDX-License-Identifier: MIT
// An exclusive lock on one bank cache entry, across processes and machines sharing the cache
// folder (flock(2); on NFS Linux maps it to fcntl byte-range locks). A render takes it before
// solving a bank it did not find, looks again, and solves only if the bank is still missing: so
// workers of a batch that need the same bank solve it once, never twice at the same time.
// The lock file (KEY.lock, empty) lives only while its holder works: it is removed when the lock
// is let go (and on SIGINT/SIGTERM, as a temporary), so the cache folder holds banks only. A
// process that opened the file before its removal still gets the lock, looks again and finds the
// bank; only if a solve fails to store its bank may two later renders solve it at once. The kernel
// drops the lock when its holder dies, however it dies (SIGKILL leaves an empty KEY.lock behind).
#pragma once

#include <string>

namespace strike {

class CacheEntryLock {
 public:
  CacheEntryLock() = default;
  /// Blocks until the lock on `path` is held. Fails open: if the lock file cannot be made (a
  /// read-only cache), holds nothing, and the caller computes without it (as before locks).
  explicit CacheEntryLock(const std::string& path);
  ~CacheEntryLock();
  CacheEntryLock(CacheEntryLock&& other) noexcept;
  CacheEntryLock& operator=(CacheEntryLock&& other) noexcept;
  CacheEntryLock(const CacheEntryLock&) = delete;
  CacheEntryLock& operator=(const CacheEntryLock&) = delete;
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
  std::string path_;
  int temporary_slot_ = -1;  ///< registerTemporary's slot: removed on interruption
  void release();
};

}  // namespace strike
