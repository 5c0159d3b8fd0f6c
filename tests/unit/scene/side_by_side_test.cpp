// SPDX-License-Identifier: MIT
// runSideBySide (src/scene/side_by_side.hpp): every job once, never more at a time than the
// threads, and never jobs whose memory forecasts together exceed the budget, unless one alone
// does, which then runs alone. Upper bounds only: they hold whatever the machine's timing.
#include <gtest/gtest.h>

#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "side_by_side.hpp"

namespace strike {
namespace {

struct Watch {
  std::mutex mutex;
  std::vector<int> runs;
  unsigned running = 0, most_running = 0;
  double running_bytes = 0.0, most_bytes_with_company = 0.0;
  bool alone_when_over = true;
};

void run(size_t count, unsigned threads, double budget, const std::vector<double>& forecast, Watch& w) {
  w.runs.assign(count, 0);
  runSideBySide(
      count, threads, budget, [&](size_t i) { return forecast[i]; },
      [&](size_t i) {
        {
          std::lock_guard<std::mutex> hold(w.mutex);
          ++w.runs[i];
          ++w.running;
          w.running_bytes += forecast[i];
          w.most_running = std::max(w.most_running, w.running);
          if (w.running > 1) w.most_bytes_with_company = std::max(w.most_bytes_with_company, w.running_bytes);
          if (forecast[i] > budget && w.running > 1) w.alone_when_over = false;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        std::lock_guard<std::mutex> hold(w.mutex);
        --w.running;
        w.running_bytes -= forecast[i];
      });
}

TEST(SideBySide, NeverMoreThanTheThreadsOrTheMemoryBudgetAtOnce) {
  const std::vector<double> forecast = {3, 3, 3, 9, 1, 1, 5, 2, 2, 2};  // 9 alone exceeds the budget of 6
  Watch w;
  run(forecast.size(), 3, 6.0, forecast, w);
  for (int r : w.runs) EXPECT_EQ(r, 1);
  EXPECT_LE(w.most_running, 3u);
  EXPECT_LE(w.most_bytes_with_company, 6.0);
  EXPECT_TRUE(w.alone_when_over);
  Watch serial;
  run(forecast.size(), 1, 0.0, forecast, serial);
  for (int r : serial.runs) EXPECT_EQ(r, 1);
  EXPECT_EQ(serial.most_running, 1u);
}

}  // namespace
}  // namespace strike
