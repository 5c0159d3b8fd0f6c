// SPDX-License-Identifier: MIT
// Nothing lost on interruption: SIGINT/SIGTERM during `strike modes`, `hit` and `render`
// leaves neither the output nor a temporary file, and the process still dies by that signal; two
// renders sharing one cache folder do not corrupt it.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "strike/core/interrupt_cleanup.hpp"

#include "cli/run_cli.hpp"
#include "common/same_bytes.hpp"

extern char** environ;

namespace strike {
namespace {

namespace fs = std::filesystem;

using test::slurp;  // tests/unit/cli/run_cli.hpp

std::vector<std::string> temporariesIn(const std::string& dir) {
  std::vector<std::string> found;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.path().filename().string().find(".tmp-") != std::string::npos) found.push_back(entry.path().string());
  return found;
}

/// Starts `strike ARGS...` with stdout/stderr to /dev/null; returns its pid.
pid_t spawnCli(const std::vector<std::string>& args) {
  std::vector<std::string> argv_storage{STRIKE_CLI};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_storage) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, STRIKE_CLI, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return rc == 0 ? pid : -1;
}

int runCli(const std::vector<std::string>& args) {
  const pid_t pid = spawnCli(args);
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

class Interrupt : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::TempDir() + "/interrupt_" + testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  std::string dir_;
};

// The mechanism alone, deterministically: a child registers a temporary file and is killed.
TEST_F(Interrupt, HandlerUnlinksRegisteredTemporariesAndDiesByTheSignal) {
  const std::string doomed = dir_ + "/out.wav.tmp-1-0", kept = dir_ + "/other.tmp-1-1";
  for (int signal_number : {SIGINT, SIGTERM}) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      installInterruptCleanup();
      std::FILE* f = std::fopen(doomed.c_str(), "wb");
      std::fputs("half a file", f);
      std::fflush(f);
      registerTemporary(doomed);
      std::FILE* g = std::fopen(kept.c_str(), "wb");
      std::fclose(g);
      unregisterTemporary(registerTemporary(kept));  // done with: must survive
      ::kill(::getpid(), signal_number);
      ::_exit(0);  // not reached
    }
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal_number) << "status " << status;
    EXPECT_FALSE(fs::exists(doomed));
    EXPECT_TRUE(fs::exists(kept));
    fs::remove(kept);
  }
}

struct KillReport {
  int runs = 0, killed = 0, killed_mid_write = 0, killed_after_rename = 0, finished = 0;
};

/// Starts the command `attempts` times and sends `signal_number` after delays spread over
/// [first_s, last_s]. After each run: killed by the signal with no output and no temporary, or
/// finished with a complete output. A signal that lands between the rename and the exit kills a
/// process whose output is already whole: then the output must equal `complete` (when given).
KillReport killRepeatedly(const std::vector<std::string>& args, const std::string& output, const std::string& dir,
                          int signal_number, double first_s, double last_s, int attempts,
                          const std::string* complete = nullptr) {
  KillReport report;
  for (int i = 0; i < attempts; ++i) {
    fs::remove(output);
    const double delay = attempts > 1 ? first_s + (last_s - first_s) * i / (attempts - 1) : first_s;
    const pid_t pid = spawnCli(args);
    EXPECT_GT(pid, 0);
    std::this_thread::sleep_for(std::chrono::duration<double>(delay));
    const bool writing = !temporariesIn(dir).empty();
    ::kill(pid, signal_number);
    int status = 0;
    EXPECT_EQ(waitpid(pid, &status, 0), pid);
    ++report.runs;
    if (WIFSIGNALED(status)) {
      EXPECT_EQ(WTERMSIG(status), signal_number);
      if (complete && fs::exists(output)) {
        EXPECT_TRUE(slurp(output) == *complete) << "killed at " << delay << " s: the output exists but is not whole";
        ++report.killed_after_rename;
      } else {
        EXPECT_FALSE(fs::exists(output)) << "killed at " << delay << " s but the output exists";
      }
      ++report.killed;
      if (writing) ++report.killed_mid_write;
    } else {
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
      EXPECT_TRUE(fs::exists(output));
      ++report.finished;
    }
    const std::vector<std::string> left = temporariesIn(dir);
    EXPECT_TRUE(left.empty()) << "after a kill at " << delay << " s: " << (left.empty() ? "" : left[0]);
  }
  return report;
}

void print(const char* what, const KillReport& r) {
  std::printf(
      "[ interrupt ] %-42s %2d runs: %2d killed (%d mid-write, %d after the rename), %2d finished; "
      "no partial output, no temporary\n",
      what, r.runs, r.killed, r.killed_mid_write, r.killed_after_rename, r.finished);
}

TEST_F(Interrupt, SigintDuringModesLeavesNothing) {
  const std::string out = dir_ + "/bar.modes";
  const std::vector<std::string> args{"modes", "box:0.3,0.04,0.04", "--material", "steel",   "--order", "2", "--size",
                                      "0.006", "--max-modes",       "60",         "--quiet", "-o",      out};
  const KillReport r = killRepeatedly(args, out, dir_, SIGINT, 0.3, 0.3, 1);
  print("SIGINT 0.3 s into strike modes", r);
  EXPECT_EQ(r.killed, 1) << "strike modes finished within 0.3 s: choose a slower input";
}

TEST_F(Interrupt, SignalsDuringHitNeverLeaveAPartialWav) {
  // A long output, so that some of the kills land while the WAV is being written.
  ASSERT_EQ(runCli({"modes", "box:0.1,0.02,0.02", "--material", "steel", "--max-modes", "8", "--quiet", "-o",
                    dir_ + "/bar.modes"}),
            0);
  const std::string out = dir_ + "/hit.wav";
  const std::vector<std::string> args{"hit",   dir_ + "/bar.modes", "--duration", "600", "--rate",
                                      "48000", "--quiet",           "-o",         out};
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(runCli(args), 0);
  const double full_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("[ interrupt ] uninterrupted hit: %.2f s, %.0f MB\n", full_s, fs::file_size(out) / 1e6);
  const std::string complete = slurp(out);
  KillReport r = killRepeatedly(args, out, dir_, SIGINT, 0.1 * full_s, 1.05 * full_s, 10, &complete);
  print("SIGINT across strike hit (600 s of audio)", r);
  const KillReport t = killRepeatedly(args, out, dir_, SIGTERM, 0.3 * full_s, 0.98 * full_s, 5, &complete);
  print("SIGTERM across strike hit", t);
  EXPECT_GT(r.killed + t.killed, 0);
}

// Its bar keeps its lowest 4 modes (max_modes): its solve with the acoustic transfer still takes
// seconds (7 s under ASan), so two renders started together race for its cache entry, in a third
// of the time of the default's 9 modes up to 20 kHz.
const char kDropScene[] =
    "{\"sample_rate\": 48000, \"duration\": 0.6, \"max_modes\": 4, \"objects\": [{\"name\": \"bar\", "
    "\"mesh\": \"box:0.2,0.03,0.03\", \"material\": \"steel\", \"position\": [0, 0, 0.1], "
    "\"orientation\": [0.9962, 0.0872, 0, 0]}]}";

// Slow enough (a fine Tet10 bar to solve) that 0.3 s lands in the middle of the render.
const char kSlowScene[] =
    "{\"sample_rate\": 48000, \"duration\": 2, \"objects\": [{\"name\": \"bar\", \"mesh\": \"box:0.3,0.04,0.04\", "
    "\"material\": \"steel\", \"order\": 2, \"size\": 0.006, \"position\": [0, 0, 0.1]}]}";

TEST_F(Interrupt, SigtermDuringRenderLeavesNothing) {
  std::ofstream(dir_ + "/scene.json") << kSlowScene;
  const std::string out = dir_ + "/drop.wav";
  const std::vector<std::string> args{
      "render", dir_ + "/scene.json", "--cache", dir_ + "/cache", "--quiet", "--events", dir_ + "/events.csv", "-o",
      out};
  const KillReport r = killRepeatedly(args, out, dir_, SIGTERM, 0.3, 0.3, 1);
  print("SIGTERM 0.3 s into strike render", r);
  EXPECT_EQ(r.killed, 1) << "strike render finished within 0.3 s: choose a slower scene";
  EXPECT_FALSE(fs::exists(dir_ + "/events.csv"));
}

TEST_F(Interrupt, ConcurrentRendersShareOneCacheSafely) {
  std::ofstream(dir_ + "/scene.json") << kDropScene;
  const std::string cache = dir_ + "/cache";
  auto args = [&](const std::string& out) {
    return std::vector<std::string>{"render", dir_ + "/scene.json", "--cache", cache, "--quiet", "-o", out};
  };
  // Two renders race to compute and store the same bank.
  const pid_t a = spawnCli(args(dir_ + "/a.wav"));
  const pid_t b = spawnCli(args(dir_ + "/b.wav"));
  int status_a = 0, status_b = 0;
  waitpid(a, &status_a, 0);
  waitpid(b, &status_b, 0);
  ASSERT_TRUE(WIFEXITED(status_a) && WEXITSTATUS(status_a) == 0);
  ASSERT_TRUE(WIFEXITED(status_b) && WEXITSTATUS(status_b) == 0);
  EXPECT_TRUE(temporariesIn(dir_).empty());
  const std::string wav_a = slurp(dir_ + "/a.wav");
  EXPECT_FALSE(wav_a.empty());
  EXPECT_TRUE(test::sameBytes(wav_a, slurp(dir_ + "/b.wav")));
  size_t entries = 0;
  for (const auto& entry : fs::directory_iterator(cache)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
    if (entry.path().extension() != ".modes") continue;  // the body's hull beside its bank
    ++entries;
    // Every bank is whole: `strike info` checks magic, length and checksum.
    EXPECT_EQ(runCli({"info", entry.path().string()}), 0) << entry.path();
  }
  EXPECT_GE(entries, 1u);
  // A third render answers from that cache and gives the same bytes.
  ASSERT_EQ(runCli(args(dir_ + "/c.wav")), 0);
  EXPECT_TRUE(test::sameBytes(wav_a, slurp(dir_ + "/c.wav")));
  std::printf("[ interrupt ] two concurrent renders on one cache: %zu entries, all valid, outputs identical\n",
              entries);
}

}  // namespace
}  // namespace strike
