#pragma once
/// @file live_field.hpp
/// Fields that another thread replaces while the servo loop runs (a new
/// picture, a new video frame, new parameters), picked up without a lock.
///
/// TripleBuffer hands whole objects from one writer thread to one reader
/// thread through three slots and one atomic index: the writer fills its back
/// slot and swaps it with the middle one; the reader, at the start of a tick,
/// swaps its front slot with the middle one when something new is there. The
/// reader never allocates, frees, waits or locks; old objects come back to
/// the writer, which destroys them on its own thread.

#include <atomic>
#include <memory>
#include <utility>

#include "hapticfield/core/field.hpp"

namespace hapticfield {

template <class T>
class TripleBuffer {
 public:
  explicit TripleBuffer(std::unique_ptr<T> initial = nullptr) { slots_[0] = std::move(initial); }
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  /// Writer thread: makes next the newest object. Returns an object the
  /// reader no longer uses (or nullptr), for the writer to destroy.
  [[nodiscard]] std::unique_ptr<T> publish(std::unique_ptr<T> next) {
    std::unique_ptr<T> old = std::exchange(slots_[back_], std::move(next));
    back_ = state_.exchange(back_ | fresh, std::memory_order_acq_rel) & index_mask;
    return old;
  }

  /// Reader thread: the newest published object (nullptr before the first
  /// when built empty). Wait-free, no allocation.
  [[nodiscard]] T* acquire() noexcept {
    if (state_.load(std::memory_order_relaxed) & fresh)
      front_ = state_.exchange(front_, std::memory_order_acq_rel) & index_mask;
    return slots_[front_].get();
  }

 private:
  static constexpr int index_mask = 3;
  static constexpr int fresh = 4;  ///< set when the middle slot holds something the reader has not seen

  std::unique_ptr<T> slots_[3];
  int front_ = 0;              ///< reader's slot
  int back_ = 2;               ///< writer's slot
  std::atomic<int> state_{1};  ///< middle slot index | fresh
};

/// A field that another thread can replace at any time: `publish()` from the
/// writer, `force()` from the servo thread (one of each). Zero force until a
/// field exists.
template <HapticField Field>
class LiveField {
 public:
  LiveField() = default;
  explicit LiveField(Field initial) : buffer_(std::make_unique<Field>(std::move(initial))) {}

  /// Writer thread: the servo thread uses field from its next tick on.
  /// Allocates and destroys the replaced field here, never in a tick.
  void publish(Field field) { (void)buffer_.publish(std::make_unique<Field>(std::move(field))); }

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    Field* field = buffer_.acquire();
    return field ? glm::dvec3(field->force(probe)) : glm::dvec3{0.0};
  }

  void reset() noexcept {
    if (Field* field = buffer_.acquire()) reset_if_stateful(*field);
  }

 private:
  TripleBuffer<Field> buffer_;
};

}  // namespace hapticfield
