#pragma once
/// @file latest_value.hpp
/// LatestValue<T>: the newest value of a trivially copyable T handed from
/// one writer thread to one reader thread: the triple buffer
/// (rt/triple_buffer.hpp) over values, not over objects held by pointer.
/// Both sides are wait-free and never allocate, so either side may be a
/// servo tick. Values in between are dropped: the reader sees the newest
/// only. Standard library only.

#include <array>
#include <cstddef>
#include <type_traits>

#include "hapticfield/rt/triple_buffer.hpp"

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
    slots_[static_cast<std::size_t>(index_.back())] = value;
    index_.publish();
  }

  /// Reader thread: the newest value, or nullptr before the first publish().
  /// The pointer stays valid until the next latest() on this thread.
  [[nodiscard]] const T* latest() noexcept {
    if (index_.acquire()) seen_ = true;
    return seen_ ? &slots_[static_cast<std::size_t>(index_.front())] : nullptr;
  }

 private:
  std::array<T, 3> slots_{};
  bool seen_ = false;  ///< the reader has taken a value
  rt::TripleIndex index_;
};

}  // namespace hapticfield
