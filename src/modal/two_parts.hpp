// SPDX-License-Identifier: MIT
// Splits a loop over [0, count) in two parts, the second on one persistent helper thread.
//
// The block Lanczos stage streams its basis and the factor through one core otherwise.
// OpenBLAS's own threads would do the same split, but its idle threads spin (sched_yield),
// which on a shared 2-core machine takes the core from the thread doing the work. The helper
// here sleeps on a condition variable between parts. On a loaded machine a second thread
// gains nothing and can lose: a thread started per call waits a scheduler slice before it
// first runs (measured 30% slower than one thread at load 7), and a split block solve costs
// 1.4x the CPU of an unsplit one. So a run is split only when the helper picks its part up
// within kStartWait; otherwise the caller does the work alone: the whole range in one part
// when the parts' results do not depend on where the range is cut (rows of a product), or
// both parts in turn when they do (a sum over rows), so that the numbers never depend on
// the machine's load.
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
  /// Starts the helper thread when `enabled` (and the system can start one).
  explicit TwoParts(bool enabled) {
    if (!enabled) return;
    try {
      helper_ = std::thread([this] { helperLoop(); });
    } catch (const std::system_error&) {
      // No helper: every run() is serial.
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
  /// True when a helper thread runs.
  bool active() const { return helper_.joinable(); }
  TwoParts(const TwoParts&) = delete;
  TwoParts& operator=(const TwoParts&) = delete;

  enum class Alone { WholeRange, BothParts };

  /// Calls work(0, split, 0) in this thread and work(split, count, 1) in the helper. Without
  /// a helper, or when it does not start within kStartWait, this thread does it alone: with
  /// Alone::WholeRange as work(0, count, 0), with Alone::BothParts as the two calls above in
  /// turn. `work` must not throw: a throw in the helper thread would end the process.
  template <class Index, class Work>
  void run(Index count, Index split, Alone alone, const Work& work) {
    auto by_itself = [&] {
      if (alone == Alone::WholeRange) {
        work(Index{0}, count, 0);
      } else {
        work(Index{0}, split, 0);
        work(split, count, 1);
      }
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
  /// microseconds; a block solve takes tens of milliseconds).
  static constexpr std::chrono::microseconds kStartWait{300};

 private:
  void helperLoop() {
    unsigned long seen = 0;
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
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
