// SPDX-License-Identifier: MIT
// Bounded lock-free queue of trivially copyable values over caller-provided storage.
//
// Dmitry Vyukov's bounded MPMC queue (1024cores.net, "Bounded MPMC queue", 2010): each cell
// carries a sequence number that says whose turn it is, so producers claim cells with one CAS on
// the enqueue counter and never wait for each other or for the consumer. A full queue fails at
// once (the caller drops and counts). Used here as multi-producer single-consumer for impacts
// and single-producer single-consumer for main -> audio commands.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>

namespace strike::detail {

// Why 64 and not std::hardware_destructive_interference_size: GCC warns that the latter may
// change between compiler versions, and it would then change this type's layout.
constexpr size_t kCacheLine = 64;

template <typename T>
class BoundedQueue {
  static_assert(std::is_trivially_copyable<T>::value, "queue items are copied as plain values");

 public:
  struct alignas(kCacheLine) Cell {
    std::atomic<size_t> sequence;
    T value;
  };

  /// capacity must be a power of two >= 2; cells points to capacity uninitialized Cells.
  void init(Cell* cells, size_t capacity) {
    cells_ = cells;
    mask_ = capacity - 1;
    for (size_t i = 0; i < capacity; ++i) new (&cells_[i].sequence) std::atomic<size_t>(i);
    enqueue_.store(0, std::memory_order_relaxed);
    dequeue_.store(0, std::memory_order_relaxed);
  }
  size_t capacity() const { return mask_ + 1; }
  /// Items claimed by producers so far (any thread): a mark between what came before and after.
  size_t pushedCount() const { return enqueue_.load(std::memory_order_acquire); }
  /// Items taken so far (the consumer's thread).
  size_t poppedCount() const { return dequeue_.load(std::memory_order_relaxed); }

  /// Lock-free; false when full.
  bool push(const T& value) {
    size_t pos = enqueue_.load(std::memory_order_relaxed);
    for (;;) {
      Cell& cell = cells_[pos & mask_];
      const size_t seq = cell.sequence.load(std::memory_order_acquire);
      const intptr_t diff = static_cast<intptr_t>(seq) - static_cast<intptr_t>(pos);
      if (diff == 0) {
        if (enqueue_.compare_exchange_weak(pos, pos + 1, std::memory_order_relaxed)) {
          cell.value = value;
          cell.sequence.store(pos + 1, std::memory_order_release);
          return true;
        }
      } else if (diff < 0) {
        return false;  // full: the consumer has not freed this cell yet
      } else {
        pos = enqueue_.load(std::memory_order_relaxed);
      }
    }
  }

  /// Lock-free; false when empty (or when the oldest item is still being written).
  bool pop(T& out) {
    size_t pos = dequeue_.load(std::memory_order_relaxed);
    for (;;) {
      Cell& cell = cells_[pos & mask_];
      const size_t seq = cell.sequence.load(std::memory_order_acquire);
      const intptr_t diff = static_cast<intptr_t>(seq) - static_cast<intptr_t>(pos + 1);
      if (diff == 0) {
        if (dequeue_.compare_exchange_weak(pos, pos + 1, std::memory_order_relaxed)) {
          out = cell.value;
          cell.sequence.store(pos + mask_ + 1, std::memory_order_release);
          return true;
        }
      } else if (diff < 0) {
        return false;
      } else {
        pos = dequeue_.load(std::memory_order_relaxed);
      }
    }
  }

 private:
  Cell* cells_ = nullptr;
  size_t mask_ = 0;
  alignas(kCacheLine) std::atomic<size_t> enqueue_{0};
  alignas(kCacheLine) std::atomic<size_t> dequeue_{0};
};

}  // namespace strike::detail
