#pragma once
/// @file tap.hpp
/// tap(field, ring): a HapticField that returns the field's force unchanged
/// and pushes one ContactSample per tick into the ring for the audio side.
/// The push never waits: when the ring is full the sample is dropped and
/// counted (ring.rejected()). The servo loop never knows vibration exists.
///
/// The contact comes from the field when it can tell: a ContactField
/// (core/contact.hpp) reports |Fc| and the normal of this tick through
/// last_contact(). Any other field: the probe's normal_force and
/// surface_normal when set, else |F| of the field's own output as the
/// contact force, and the full speed |v|.

#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/contact.hpp"
#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/vibration/contact_sample.hpp"

namespace hapticfield::vibration {

/// A field that reports the contact of its last force() call.
template <class F>
concept ReportsContact = requires(const F& field) {
  { field.last_contact() }
  noexcept->std::convertible_to<Contact>;
};

/// A field that says which material its last force() call touched.
template <class F>
concept ReportsMaterial = requires(const F& field) {
  { field.touched_material() }
  noexcept->std::convertible_to<std::uint32_t>;
};

struct TapConfig {
  std::uint32_t material{0};  ///< material id sent when the field does not report one
};

/// The decorator; build it with tap(field, ring).
template <HapticField F, std::size_t N>
class Tap {
 public:
  Tap(F field, ContactRing<N>& ring, TapConfig config = {}) : field_(std::move(field)), ring_(&ring), config_(config) {}

  /// The field's force, unchanged; one sample pushed (or counted as dropped).
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    const glm::dvec3 f = field_.force(probe);
    (void)ring_->try_push(sample(probe, f));
    return f;
  }

  void reset() noexcept { reset_if_stateful(field_); }
  /// The field's look-ahead (core/field.hpp); nothing is pushed.
  void anticipate(const Probe& next) const noexcept { anticipate_if_able(field_, next); }
  [[nodiscard]] bool looks_ahead() const noexcept { return field_looks_ahead(field_); }

  [[nodiscard]] F& field() noexcept { return field_; }
  [[nodiscard]] const F& field() const noexcept { return field_; }
  /// Samples dropped because the audio side had not drained the ring.
  [[nodiscard]] std::size_t dropped() const noexcept { return ring_->rejected(); }

 private:
  ContactSample sample(const Probe& probe, const glm::dvec3& f) const noexcept {
    ContactSample s;
    s.time = std::isfinite(probe.time) ? probe.time : 0.0;
    s.material = config_.material;
    if constexpr (ReportsMaterial<F>) s.material = field_.touched_material();
    glm::dvec3 n{0.0};
    double fc = 0.0;
    if constexpr (ReportsContact<F>) {
      const Contact c = field_.last_contact();
      if (c.touching) {
        fc = glm::length(c.force);
        n = c.normal;
      }
    } else {
      fc = probe.normal_force > 0.0 ? probe.normal_force : glm::length(f);
      n = probe.surface_normal;
    }
    glm::dvec3 v = probe.velocity;
    const double nn = glm::length(n);
    if (nn > 0.0) v -= glm::dot(v, n / nn) * (n / nn);
    const double speed = glm::length(v);
    if (!std::isfinite(fc) || !std::isfinite(speed)) return s;  // no contact rather than garbage
    s.normal_force = fc;
    s.speed = speed;
    return s;
  }

  F field_;
  ContactRing<N>* ring_;
  TapConfig config_;
};

/// tap(field, ring[, config]): field's force, and one contact sample per tick into ring.
template <HapticField F, std::size_t N>
[[nodiscard]] Tap<std::remove_cvref_t<F>, N> tap(F&& field, ContactRing<N>& ring, TapConfig config = {}) {
  return Tap<std::remove_cvref_t<F>, N>(std::forward<F>(field), ring, config);
}

}  // namespace hapticfield::vibration
