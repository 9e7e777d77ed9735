#pragma once
/// @file field.hpp
/// The HapticField concept: anything that turns a Probe into a force.

#include <cmath>
#include <concepts>

#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"

namespace hapticfield {

/// A haptic field: `glm::dvec3 force(const Probe&) noexcept`, the force on the
/// HIP [N] in the device frame. The call is the servo path: it must not
/// allocate, lock, throw or do I/O. Stateful fields (filters, local-sphere
/// sampling) may change their own state in force() and expose reset().
template <class F>
concept HapticField = requires(F& field, const Probe& probe) {
  { field.force(probe) }
  noexcept->std::convertible_to<glm::dvec3>;
};

/// A field with state that can be returned to its initial condition.
template <class F>
concept ResettableField = HapticField<F> && requires(F& field) {
  { field.reset() }
  noexcept;
};

/// Calls field.reset() when the field has one; otherwise does nothing.
template <HapticField F>
void reset_if_stateful(F& field) noexcept {
  if constexpr (ResettableField<F>) field.reset();
}

/// A field that can look ahead: `anticipate(probe)` runs, on a scratch copy
/// of its state, the tick the probe would make, and changes nothing the
/// next force() returns. What it gains is the memory that tick reads,
/// brought into cache before the tick comes (a proxy on a large mesh: its
/// tree's nodes and triangles where the HIP is going), and what the field
/// caches for itself, kept (a ball proxy's region of the tree). The servo
/// loop calls it in the slack before each deadline (LoopConfig::anticipate),
/// on the loop's thread. Like force(): no allocation, lock, exception or
/// I/O, and no effect on any answer of the next force().
/// `looks_ahead()` says whether anticipate() does anything (a wrapper's
/// answer is its parts'): a loop makes room for it only then. LooksAhead is
/// the pair alone, for what is not a field (a constraint, a loop callback).
template <class T>
concept LooksAhead = requires(const T& t, const Probe& probe) {
  { t.anticipate(probe) }
  noexcept;
  { t.looks_ahead() }
  noexcept->std::convertible_to<bool>;
};

template <class F>
concept AnticipatingField = HapticField<F> && LooksAhead<F>;

/// Calls field.anticipate(next) when the field has one; otherwise does
/// nothing.
template <HapticField F>
void anticipate_if_able(const F& field, const Probe& next) noexcept {
  if constexpr (AnticipatingField<F>) field.anticipate(next);
}

/// True when the field's anticipate() does something.
template <HapticField F>
[[nodiscard]] bool field_looks_ahead(const F& field) noexcept {
  if constexpr (AnticipatingField<F>)
    return static_cast<bool>(field.looks_ahead());
  else
    return false;
}

/// The probe one step of `seconds` after `probe`: its time moved on, its
/// position moved by its velocity (kept where the velocity is not finite).
/// What a loop anticipates for its next tick.
[[nodiscard]] inline Probe predicted_probe(const Probe& probe, double seconds) noexcept {
  Probe next = probe;
  next.time += seconds;
  const glm::dvec3 moved = probe.position + seconds * probe.velocity;
  if (std::isfinite(moved.x) && std::isfinite(moved.y) && std::isfinite(moved.z)) next.position = moved;
  return next;
}

/// The field that is zero everywhere.
struct ZeroField {
  [[nodiscard]] glm::dvec3 force(const Probe&) const noexcept { return glm::dvec3{0.0}; }
};

}  // namespace hapticfield
