#pragma once
/// @file live_field.hpp
/// Fields that another thread replaces while the servo loop runs (a new
/// picture, a new video frame, new parameters), picked up without a lock
/// through a TripleBuffer (rt/triple_buffer.hpp) at the start of a tick.

#include <memory>
#include <utility>

#include "hapticfield/core/field.hpp"
#include "hapticfield/rt/triple_buffer.hpp"

namespace hapticfield {

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

  /// Servo thread: the look-ahead (core/field.hpp) of the field the last
  /// tick used; a field published since is not looked at before its first
  /// tick.
  void anticipate(const Probe& next) const noexcept {
    if (const Field* field = buffer_.held()) anticipate_if_able(*field, next);
  }
  /// Servo thread: whether the field the last tick used looks ahead.
  [[nodiscard]] bool looks_ahead() const noexcept {
    const Field* field = buffer_.held();
    return field != nullptr && field_looks_ahead(*field);
  }

 private:
  TripleBuffer<Field> buffer_;
};

}  // namespace hapticfield
