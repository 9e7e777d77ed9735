#pragma once
/// @file field.hpp
/// The HapticField concept: anything that turns a Probe into a force.

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

/// The field that is zero everywhere.
struct ZeroField {
  [[nodiscard]] glm::dvec3 force(const Probe&) const noexcept { return glm::dvec3{0.0}; }
};

}  // namespace hapticfield
