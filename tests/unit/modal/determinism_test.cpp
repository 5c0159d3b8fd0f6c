// SPDX-License-Identifier: MIT
// Same inputs, same bits: the eigen-solve under hostile timing.
//
// The block Lanczos stage splits its solves and products between the calling thread and one
// helper thread, which is used only when it picks its part up promptly. On a loaded machine it
// often does not, and the caller then does the work alone. Whatever happens, the eigenvalues and
// the mode shapes must be the same bits, or a bank cache holds whichever answer came first and
// a scene renders differently depending on what else the machine was doing. Each case below
// makes the timing different on purpose and compares bytes with an undisturbed solve:
//  - no helper thread at all (threads = 1: a one-core machine);
//  - a helper that always starts too late (the caller does everything);
//  - a helper that starts around the give-up time, so that some parts are split and some not;
//  - two busy threads beside the solve (a shared CI machine);
//  - OpenBLAS set to two threads by the process (what OPENBLAS_NUM_THREADS does);
//  - other CPU cache sizes for Eigen's product blocking (another CPU kind);
//  - OpenBLAS's worker threads ended by useOneBlasThread (what the strike command does).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "strike/fem/fem.hpp"
#include "strike/modal/modal.hpp"

// OpenBLAS thread control, weak so that another BLAS still links (then the case is skipped).
extern "C" __attribute__((weak)) void openblas_set_num_threads(int num_threads);
extern "C" __attribute__((weak)) int openblas_get_num_threads(void);

namespace strike {
namespace {

const Material kSteel{"steel", 2.0e11, 0.29, 7850.0, 0.0, 0.0};

struct Problem {
  Eigen::SparseMatrix<double> K, M;
};

/// A medium solid (2,295 degrees of freedom) and a 100-mode request: the block Lanczos path,
/// with its split solves and products.
const Problem& mediumSolid() {
  static const Problem problem = [] {
    Problem p;
    MeshOptions options;
    options.target_edge_m = 0.0125;
    const TetMesh mesh = makeBox(0.2, 0.1, 0.05, options).value();
    assembleStiffnessAndMass(mesh, kSteel, p.K, p.M);
    return p;
  }();
  return problem;
}

ModalSettings hundredModes() {
  ModalSettings settings;
  settings.max_freq_hz = 1e9;
  settings.max_modes = 100;
  return settings;
}

ModalResult solve(const ModalSettings& settings) {
  auto result = solveModes(mediumSolid().K, mediumSolid().M, settings);
  EXPECT_TRUE(result.ok()) << result.error().message;
  return result.ok() ? std::move(result.value()) : ModalResult{};
}

/// Empty when a and b are the same bits; else a one-line summary (no dump of the arrays).
std::string bitDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, const char* what) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return std::string(what) + ": sizes differ (" + std::to_string(a.rows()) + "x" + std::to_string(a.cols()) + " vs " +
           std::to_string(b.rows()) + "x" + std::to_string(b.cols()) + ")";
  }
  Eigen::Index differing = 0, first = -1;
  double worst = 0.0;
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    if (std::memcmp(a.data() + i, b.data() + i, sizeof(double)) == 0) continue;
    if (first < 0) first = i;
    ++differing;
    const double scale = std::max(std::abs(a.data()[i]), 1e-300);
    worst = std::max(worst, std::abs(a.data()[i] - b.data()[i]) / scale);
  }
  if (differing == 0) return {};
  return std::string(what) + ": " + std::to_string(differing) + " of " + std::to_string(a.size()) +
         " values differ, first at index " + std::to_string(first) + ", largest relative difference " +
         std::to_string(worst);
}

void expectSameBits(const ModalResult& reference, const ModalResult& other, const char* case_name) {
  EXPECT_EQ(bitDifference(reference.eigenvalues, other.eigenvalues, "eigenvalues"), "") << case_name;
  EXPECT_EQ(bitDifference(reference.shapes, other.shapes, "shapes"), "") << case_name;
  EXPECT_EQ(reference.operator_applications, other.operator_applications) << case_name;
}

TEST(Determinism, NoHelperThreadGivesTheSameBits) {
  const ModalResult reference = solve(hundredModes());
  ASSERT_EQ(reference.eigenvalues.size(), 100);
  ASSERT_EQ(reference.block_size, 16);  // the split block stage ran
  ModalSettings alone = hundredModes();
  alone.threads = 1;
  expectSameBits(reference, solve(alone), "threads = 1");
}

TEST(Determinism, LateOrErraticHelperGivesTheSameBits) {
  const ModalResult reference = solve(hundredModes());
  ModalSettings late = hundredModes();
  late.helper_delay_us = 2000;  // always past the give-up time: the caller does every part
  expectSameBits(reference, solve(late), "helper always late");
  // Around the give-up time (300 us): some parts split, some done by the caller alone, in an
  // order that changes from run to run.
  for (int delay_us : {150, 280, 320}) {
    ModalSettings erratic = hundredModes();
    erratic.helper_delay_us = delay_us;
    expectSameBits(reference, solve(erratic), ("helper delayed " + std::to_string(delay_us) + " us").c_str());
  }
}

TEST(Determinism, BusyThreadsBesideTheSolveGiveTheSameBits) {
  const ModalResult reference = solve(hundredModes());
  std::atomic<bool> stop{false};
  std::vector<std::thread> busy;
  for (int i = 0; i < 2; ++i) {
    busy.emplace_back([&stop] {
      volatile unsigned long spin = 0;
      while (!stop.load(std::memory_order_relaxed)) spin = spin + 1;
    });
  }
  const ModalResult loaded = solve(hundredModes());
  stop = true;
  for (std::thread& t : busy) t.join();
  expectSameBits(reference, loaded, "two busy threads");
}

TEST(Determinism, OpenBlasThreadCountDoesNotChangeTheBits) {
  if (openblas_set_num_threads == nullptr || openblas_get_num_threads == nullptr) {
    GTEST_SKIP() << "the BLAS is not OpenBLAS";
  }
  const int before = openblas_get_num_threads();
  openblas_set_num_threads(1);
  const ModalResult one = solve(hundredModes());
  openblas_set_num_threads(2);
  const ModalResult two = solve(hundredModes());
  openblas_set_num_threads(before);
  expectSameBits(one, two, "OpenBLAS 1 vs 2 threads");
}

/// The threads of this process now.
size_t threadsInProcess() {
  size_t count = 0;
  for ([[maybe_unused]] const auto& task : std::filesystem::directory_iterator("/proc/self/task")) ++count;
  return count;
}

TEST(Determinism, OneBlasThreadEndsOpenBlasWorkersAndSolvesTheSameBits) {
  if (openblas_set_num_threads == nullptr || openblas_get_num_threads == nullptr) {
    GTEST_SKIP() << "the BLAS is not OpenBLAS";
  }
  const ModalResult reference = solve(hundredModes());
  // A threaded OpenBLAS started a worker per extra core when it loaded (none on one core), idle
  // now; the process has other threads too (CHOLMOD's OpenMP pool). useOneBlasThread ends
  // exactly OpenBLAS's workers.
  const int blas_threads = openblas_get_num_threads();
  const size_t before = threadsInProcess();
  useOneBlasThread();
  EXPECT_EQ(openblas_get_num_threads(), 1);
  const size_t after = threadsInProcess();
  EXPECT_EQ(before - after, size_t(blas_threads - 1)) << before << " threads before, " << after << " after";
  // A solve afterwards starts none again (its one-thread scope has nothing to set) and gives
  // the same bits.
  const ModalResult again = solve(hundredModes());
  EXPECT_EQ(threadsInProcess(), after);
  expectSameBits(reference, again, "after useOneBlasThread");
}

TEST(Determinism, CpuCacheSizesDoNotChangeTheBits) {
  // Eigen blocks its matrix products by the CPU's cache sizes, read at run time: an AMD Zen 4
  // (32 KiB L1d) and an Intel Sapphire Rapids (48 KiB) would sum in different groupings.
  std::ptrdiff_t l1 = 0, l2 = 0, l3 = 0;
  Eigen::internal::manage_caching_sizes(Eigen::GetAction, &l1, &l2, &l3);
  Eigen::setCpuCacheSizes(48 * 1024, 2 * 1024 * 1024, 105 * 1024 * 1024);
  const ModalResult intel_like = solve(hundredModes());
  Eigen::setCpuCacheSizes(8 * 1024, 256 * 1024, 1024 * 1024);
  const ModalResult amd_like = solve(hundredModes());
  Eigen::setCpuCacheSizes(l1, l2, l3);
  expectSameBits(intel_like, amd_like, "Eigen blocking for 48 KiB vs 32 KiB L1");
}

}  // namespace
}  // namespace strike
