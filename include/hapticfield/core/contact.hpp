#pragma once
/// @file contact.hpp
/// Contact composition F = Fc + Ft + Ff (Fritz & Barner, "Stochastic models
/// for haptic texture", SPIE 2901, 1996), computed in one order each tick:
///
///   1. the constraint (a plane, a sphere, any Constraint) gives the contact
///      of this tick: touching or not, depth, unit surface normal n, Fc;
///   2. the parts (textures, friction, data-modulated fields) get a copy of
///      the probe with normal_force = |Fc| and surface_normal = n of this
///      tick, whatever the incoming probe carried;
///   3. the result is Fc + the sum of the parts. Not touching: zero, and the
///      parts are not called (no contact, no texture, no friction).
///
/// So a force-scaled texture or friction, or a HaTT model chosen by normal
/// force, sees the constraint force alone, never its own output. Where the
/// constraint knows it (a proxy on a mesh or height field, surface/), the
/// parts also see where the contact is: uv, tangent frame, primitive and
/// material of the touched point (Probe's surface fields).

#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <tuple>
#include <type_traits>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield {

/// What a constraint reports about the HIP this tick.
struct Contact {
  bool touching{false};                   ///< the HIP is inside the surface (depth > 0)
  double depth{0.0};                      ///< penetration depth [m], >= 0
  glm::dvec3 normal{0.0};                 ///< unit surface normal toward the user; zero when not touching
  glm::dvec3 force{0.0};                  ///< constraint force Fc [N]; zero when not touching
  glm::dvec2 surface_uv{0.0};             ///< texture coordinates of the touched point [-]
  glm::dvec3 surface_tangent{0.0};        ///< unit direction of increasing u in the tangent plane; zero: no uv
  glm::dvec3 surface_bitangent{0.0};      ///< unit direction of increasing v in the tangent plane; zero: no uv
  std::uint32_t primitive{no_primitive};  ///< touched triangle / grid cell id; no_primitive: none
  std::uint32_t material{0};              ///< material index of the touched primitive
};

/// The probe a contact's constraint is asked with (ContactField,
/// MaterialSurface), into `on`: `probe` with a non-finite velocity (a glitch
/// of the device's differentiation) set to zero, so only what depends on it
/// is lost. False for a non-finite position: there is no contact to ask for.
[[nodiscard]] inline bool constraint_probe(const Probe& probe, Probe& on) noexcept {
  if (!is_finite(probe.position)) return false;
  on = probe;
  if (!is_finite(on.velocity)) on.velocity = glm::dvec3{0.0};
  return true;
}

/// Tells `on` of this tick's contact, for the parts a contact's force is
/// summed with: |Fc|, the normal, and where on the surface it touches.
inline void tell_contact(Probe& on, const Contact& c) noexcept {
  on.normal_force = glm::length(c.force);
  on.surface_normal = c.normal;
  on.surface_uv = c.surface_uv;
  on.surface_tangent = c.surface_tangent;
  on.surface_bitangent = c.surface_bitangent;
  on.primitive = c.primitive;
  on.material = c.material;
}

/// A constraint: a surface that reports the contact of the HIP with it.
/// `contact()` is on the servo path: noexcept, no allocation; a non-finite
/// probe gives a Contact that is not touching. It may change the
/// constraint's own state (a proxy remembers where it is) and then has a
/// `reset()` that ContactField::reset() calls.
template <class C>
concept Constraint = requires(C& constraint, const Probe& probe) {
  { constraint.contact(probe) }
  noexcept->std::same_as<Contact>;
};

/// Fc + parts, in that order (see the file comment). Itself a HapticField,
/// and a ResettableField: reset() forwards to the parts that have state.
template <Constraint C, HapticField... Parts>
class ContactField {
 public:
  explicit ContactField(C constraint, Parts... parts)
      : constraint_(std::move(constraint)), parts_(std::move(parts)...) {}

  /// F = Fc + sum of parts(probe with |Fc| and n of this tick) [N]; zero for
  /// a non-finite position or a non-finite result. A non-finite velocity
  /// (a glitch of the device's differentiation) drops only what depends on
  /// it: the constraint and the parts see a zero velocity, so Fc keeps its
  /// spring term and loses its damping.
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    Probe on;
    if (!constraint_probe(probe, on)) {
      last_ = Contact{};
      return glm::dvec3{0.0};
    }
    last_ = constraint_.contact(on);
    if (!last_.touching) return glm::dvec3{0.0};
    tell_contact(on, last_);
    const glm::dvec3 f =
        std::apply([&on, this](auto&... part) { return (last_.force + ... + glm::dvec3(part.force(on))); }, parts_);
    return is_finite(f) ? f : glm::dvec3{0.0};
  }

  /// The constraint's look-ahead (core/field.hpp) on the probe force() would
  /// give it; nothing changes. The parts are not run.
  void anticipate(const Probe& next) const noexcept {
    if constexpr (anticipating) {
      Probe on;
      if (constraint_probe(next, on)) constraint_.anticipate(on);
    }
  }
  [[nodiscard]] bool looks_ahead() const noexcept {
    if constexpr (anticipating)
      return static_cast<bool>(constraint_.looks_ahead());
    else
      return false;
  }

  void reset() noexcept {
    if constexpr (requires { constraint_.reset(); }) constraint_.reset();
    std::apply([](auto&... part) { (reset_if_stateful(part), ...); }, parts_);
    last_ = Contact{};
  }

  /// The contact found by the last force() call.
  [[nodiscard]] const Contact& last_contact() const noexcept { return last_; }
  [[nodiscard]] const C& constraint() const noexcept { return constraint_; }
  [[nodiscard]] C& constraint() noexcept { return constraint_; }
  /// The i-th part.
  template <std::size_t I>
  [[nodiscard]] auto& part() noexcept {
    return std::get<I>(parts_);
  }

 private:
  /// The constraint has a look-ahead (core/field.hpp).
  static constexpr bool anticipating = LooksAhead<C>;

  C constraint_;
  std::tuple<Parts...> parts_;
  Contact last_{};
};

/// contact(constraint, texture, friction, ...): the field Fc + Ft + Ff.
template <Constraint C, HapticField... Parts>
[[nodiscard]] ContactField<std::remove_cvref_t<C>, std::remove_cvref_t<Parts>...> contact(C&& constraint,
                                                                                          Parts&&... parts) {
  return ContactField<std::remove_cvref_t<C>, std::remove_cvref_t<Parts>...>(std::forward<C>(constraint),
                                                                             std::forward<Parts>(parts)...);
}

}  // namespace hapticfield
