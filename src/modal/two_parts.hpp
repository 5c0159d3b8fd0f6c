// SPDX-License-Identifier: MIT
// Splits a loop over [0, count) in two fixed parts, the second on one persistent helper thread
// when it is free, so that the numbers never depend on the timing.
//
// The block Lanczos stage streams its basis and the factor through one core otherwise.
// OpenBLAS's own threads would do the same split, but its idle threads spin (sched_yield), and
// on a shared 2-core machine they take the core from the thread doing the work; and its results
// depend on its thread count (measured: the CHOLMOD factor of the same matrix has other bits
// with two OpenBLAS threads than with one), which follows the core count and
// OPENBLAS_NUM_THREADS. The helper here sleeps on a
// condition variable between parts. On a loaded machine a second thread gains nothing and can
// lose (a thread woken per call waits a scheduler slice before it first runs), so a part the
// helper has not picked up within kStartWait is done by the caller.
//
// Determinism: the two parts are ALWAYS the same, [0, split) and [split, count), whoever
// computes them, and also without a helper thread at all. A BLAS kernel may give other bits for
// a block of 16 columns than for two blocks of 8 (OpenBLAS's AVX-512 kernels do: 17% of the
// values of a CHOLMOD solve differ in the last bits), so "rows of a product do not depend on
// where the range is cut" cannot be assumed: the cut never moves.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <system_error>
#include <thread>

namespace strike {

class TwoParts {
 public:
  /// Starts the helper thread when `use_helper` (and the system can start one). `helper_delay`
  /// is for tests: the helper sleeps that long before it picks up each part.
  explicit TwoParts(bool use_helper, std::chrono::microseconds helper_delay = {}) : helper_delay_(helper_delay) {
    if (!use_helper) return;
    try {
      helper_ = std::thread([this] { helperLoop(); });
    } catch (const std::system_error&) {
      // No helper: every run() is done by the caller, in the same two parts.
    }
  }
  ~TwoParts() {
    if (!helper_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_one();
    helper_.join();
  }
  TwoParts(const TwoParts&) = delete;
  TwoParts& operator=(const TwoParts&) = delete;

  /// Calls work(0, split, 0) and work(split, count, 1): the second in the helper thread when
  /// it picks it up within kStartWait, else in this thread after the first. `work` must not
  /// throw: a throw in the helper thread would end the process.
  template <class Index, class Work>
  void run(Index count, Index split, const Work& work) {
    auto by_itself = [&] {
      work(Index{0}, split, 0);
      work(split, count, 1);
    };
    if (!helper_.joinable() || !(split > 0 && split < count)) {
      by_itself();
      return;
    }
    std::unique_lock<std::mutex> lock(mutex_);
    task_ = [&work, split, count] { work(split, count, 1); };
    claimed_ = false;
    done_ = false;
    ++generation_;
    wake_.notify_one();
    if (!started_.wait_for(lock, kStartWait, [this] { return claimed_; })) {
      claimed_ = true;  // withdrawn: the helper skips it
      lock.unlock();
      by_itself();
      return;
    }
    lock.unlock();
    work(Index{0}, split, 0);
    lock.lock();
    finished_.wait(lock, [this] { return done_; });
  }

  /// How long a run waits for the helper to start its part (an idle core wakes it in tens of
  /// microseconds; a block solve takes milliseconds).
  static constexpr std::chrono::microseconds kStartWait{300};

 private:
  void helperLoop() {
    unsigned long seen = 0;
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      if (helper_delay_.count() > 0) {
        lock.unlock();
        std::this_thread::sleep_for(helper_delay_);
        lock.lock();
        if (stop_) return;
        if (generation_ != seen) continue;  // that run is over; a newer one waits
      }
      if (claimed_) continue;  // the caller did this part itself
      claimed_ = true;
      started_.notify_one();
      lock.unlock();
      task_();
      lock.lock();
      done_ = true;
      finished_.notify_one();
    }
  }

  std::chrono::microseconds helper_delay_;
  std::thread helper_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable started_;
  std::condition_variable finished_;
  std::function<void()> task_;
  unsigned long generation_ = 0;
  bool claimed_ = false;
  bool done_ = false;
  bool stop_ = false;
};

}  // namespace strike
