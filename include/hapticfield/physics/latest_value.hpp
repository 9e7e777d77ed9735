#pragma once
/// @file latest_value.hpp
/// LatestValue<T>: the newest value of a trivially copyable T handed from
/// one writer thread to one reader thread through three slots and one
/// atomic index (a triple buffer of values, not of pointers). Both sides are
/// wait-free and never allocate, so either side may be a servo tick: the
/// writer copies into its back slot and swaps it with the middle one; the
/// reader swaps its front slot with the middle one when something new is
/// there. Values in between are dropped: the reader sees the newest only.

#include <array>
#include <atomic>
#include <type_traits>

namespace hapticfield {

template <class T>
requires std::is_trivially_copyable_v<T>
class LatestValue {
 public:
  LatestValue() = default;
  LatestValue(const LatestValue&) = delete;
  LatestValue& operator=(const LatestValue&) = delete;

  /// Writer thread: makes value the newest. Wait-free, no allocation.
  void publish(const T& value) noexcept {
    slots_[back_] = value;
    back_ = state_.exchange(back_ | fresh, std::memory_order_acq_rel) & index_mask;
  }

  /// Reader thread: the newest value, or nullptr before the first publish().
  /// The pointer stays valid until the next latest() on this thread.
  [[nodiscard]] const T* latest() noexcept {
    if (state_.load(std::memory_order_relaxed) & fresh) {
      front_ = state_.exchange(front_, std::memory_order_acq_rel) & index_mask;
      seen_ = true;
    }
    return seen_ ? &slots_[front_] : nullptr;
  }

 private:
  static constexpr int index_mask = 3;
  static constexpr int fresh = 4;  ///< set when the middle slot holds a value the reader has not seen

  std::array<T, 3> slots_{};
  int front_ = 0;              ///< reader's slot
  int back_ = 2;               ///< writer's slot
  bool seen_ = false;          ///< the reader has taken a value
  std::atomic<int> state_{1};  ///< middle slot index | fresh
};

}  // namespace hapticfield
