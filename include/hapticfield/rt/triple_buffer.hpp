#pragma once
/// @file triple_buffer.hpp
/// The triple buffer: the newest of whatever one writer thread makes, handed
/// to one reader thread through three slots and one atomic index, without a
/// lock. The writer fills its back slot and swaps it with the middle one;
/// the reader, when it wants the newest, swaps its front slot with the
/// middle one if something new is there. Objects in between are dropped.
///
/// rt::TripleIndex is that swap alone (LatestValue<T> runs it over values);
/// TripleBuffer<T> runs it over whole objects held by unique_ptr. Standard
/// library only (the ground floor: any room may use it).

#include <atomic>
#include <memory>
#include <utility>

namespace hapticfield {
namespace rt {

/// Which of three slots the writer fills, the reader reads, and which is in
/// the middle. Both sides are wait-free; one writer thread, one reader.
class TripleIndex {
 public:
  /// Writer thread: the slot it fills next (the reader never touches it).
  [[nodiscard]] int back() const noexcept { return back_; }
  /// Writer thread: makes the back slot the newest; the old middle slot
  /// becomes the writer's back slot.
  void publish() noexcept { back_ = state_.exchange(back_ | fresh, std::memory_order_acq_rel) & index_mask; }
  /// Reader thread: takes the middle slot when it holds something the
  /// reader has not seen. True when it did.
  bool acquire() noexcept {
    if (!(state_.load(std::memory_order_relaxed) & fresh)) return false;
    front_ = state_.exchange(front_, std::memory_order_acq_rel) & index_mask;
    return true;
  }
  /// Reader thread: the slot it reads.
  [[nodiscard]] int front() const noexcept { return front_; }

 private:
  static constexpr int index_mask = 3;
  static constexpr int fresh = 4;  ///< set when the middle slot holds something the reader has not seen

  int front_ = 0;              ///< reader's slot
  int back_ = 2;               ///< writer's slot
  std::atomic<int> state_{1};  ///< middle slot index | fresh
};

}  // namespace rt

/// Whole objects from one writer thread to one reader thread (a new picture,
/// a new frame, new parameters). The reader never allocates, frees, waits or
/// locks; old objects come back to the writer, which destroys them on its
/// own thread.
template <class T>
class TripleBuffer {
 public:
  explicit TripleBuffer(std::unique_ptr<T> initial = nullptr) { slots_[0] = std::move(initial); }
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  /// Writer thread: makes next the newest object. Returns an object the
  /// reader no longer uses (or nullptr), for the writer to destroy.
  [[nodiscard]] std::unique_ptr<T> publish(std::unique_ptr<T> next) {
    std::unique_ptr<T> old = std::exchange(slots_[index_.back()], std::move(next));
    index_.publish();
    return old;
  }

  /// Reader thread: the newest published object (nullptr before the first
  /// when built empty). Wait-free, no allocation.
  [[nodiscard]] T* acquire() noexcept {
    (void)index_.acquire();
    return slots_[index_.front()].get();
  }

  /// Reader thread: the object the last acquire() gave (the initial one
  /// before any), without taking a newer one.
  [[nodiscard]] const T* held() const noexcept { return slots_[index_.front()].get(); }

 private:
  std::unique_ptr<T> slots_[3];
  rt::TripleIndex index_;
};

}  // namespace hapticfield
