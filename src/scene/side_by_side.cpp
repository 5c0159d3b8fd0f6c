// SPDX-License-Identifier: MIT
#include "side_by_side.hpp"

#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>
#include <vector>

namespace strike {

void runSideBySide(size_t count, unsigned threads, double budget_bytes,
                   const std::function<double(size_t)>& forecast_bytes, const std::function<void(size_t)>& job) {
  if (threads <= 1 || count <= 1) {
    for (size_t i = 0; i < count; ++i) job(i);
    return;
  }
  std::mutex mutex;
  std::condition_variable finished;
  unsigned running = 0;
  double running_bytes = 0.0;
  std::vector<std::thread> workers;
  workers.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    const double bytes = forecast_bytes(i);
    std::unique_lock<std::mutex> lock(mutex);
    finished.wait(lock, [&] {
      return running == 0 || (running < threads && (budget_bytes <= 0.0 || running_bytes + bytes <= budget_bytes));
    });
    ++running;
    running_bytes += bytes;
    lock.unlock();
    workers.emplace_back([&, i, bytes] {
      job(i);
      std::lock_guard<std::mutex> done(mutex);
      --running;
      running_bytes -= bytes;
      finished.notify_all();
    });
  }
  for (std::thread& worker : workers) worker.join();
}

double availableMemoryBytes() {
  std::FILE* file = std::fopen("/proc/meminfo", "r");
  if (!file) return 0.0;
  char line[256];
  unsigned long long kib = 0;
  bool found = false;
  while (!found && std::fgets(line, sizeof line, file)) found = std::sscanf(line, "MemAvailable: %llu kB", &kib) == 1;
  std::fclose(file);
  return found ? 1024.0 * static_cast<double>(kib) : 0.0;
}

}  // namespace strike
