#pragma once
/// @file constraints.hpp
/// Penalty constraints that report their contact: a plane (a wall, the
/// picture's plane) and a solid sphere. Each is a Constraint for
/// ContactField and also a HapticField on its own (force() = Fc).
///
///   Fc = max(0, k depth - b (v . n)) n      (only while depth > 0)
///
/// The damping b acts on the normal velocity only, and only while
/// penetrating; the max() keeps Fc from ever pulling the HIP into the
/// surface (Fc . n >= 0), also when it leaves the surface fast. A
/// non-finite velocity drops the damping term, never the spring term.

#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/contact.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield {

namespace detail {

inline void check_penalty(const char* who, double stiffness, double damping) {
  if (!std::isfinite(stiffness) || stiffness <= 0.0)
    throw std::invalid_argument(std::string(who) + ": stiffness must be finite and > 0 [N/m]");
  if (!std::isfinite(damping) || damping < 0.0)
    throw std::invalid_argument(std::string(who) + ": damping must be finite and >= 0 [N s/m]");
}

/// The contact at penetration `depth` > 0 along unit normal n. A
/// non-finite velocity drops the damping term only: Fc = k depth n.
[[nodiscard]] inline Contact penalty_contact(double depth, const glm::dvec3& n, const glm::dvec3& velocity,
                                             double stiffness, double damping) noexcept {
  const double damped = is_finite(velocity) ? damping * glm::dot(velocity, n) : 0.0;
  const double push = stiffness * depth - damped;  // [N]
  return Contact{true, depth, n, (push > 0.0 ? push : 0.0) * n};
}

}  // namespace detail

struct PlaneConstraintConfig {
  glm::dvec3 point{0.0};             ///< a point on the plane [m]
  glm::dvec3 normal{0.0, 0.0, 1.0};  ///< unit normal, out of the solid toward the user
  double stiffness{1500.0};          ///< k [N/m]
  double damping{0.0};               ///< b on the normal velocity while penetrating [N s/m]
};

/// A solid half-space behind a plane: touching where (p - point) . n < 0.
class PlaneConstraint {
 public:
  /// @throws std::invalid_argument for a non-finite point, a normal that is
  ///         not unit length, a stiffness <= 0 or a negative damping.
  explicit PlaneConstraint(const PlaneConstraintConfig& config) : config_(config) {
    if (!is_finite(config.point)) throw std::invalid_argument("PlaneConstraint: point must be finite [m]");
    const double n = glm::length(config.normal);
    if (!std::isfinite(n) || std::fabs(n - 1.0) > 1e-9)
      throw std::invalid_argument("PlaneConstraint: normal must be a unit vector");
    detail::check_penalty("PlaneConstraint", config.stiffness, config.damping);
  }

  [[nodiscard]] Contact contact(const Probe& probe) const noexcept {
    if (!is_finite(probe.position)) return Contact{};
    const double height = glm::dot(probe.position - config_.point, config_.normal);  // [m], < 0 inside
    if (!(height < 0.0)) return Contact{};
    return detail::penalty_contact(-height, config_.normal, probe.velocity, config_.stiffness, config_.damping);
  }

  /// Fc alone [N].
  [[nodiscard]] glm::dvec3 force(const Probe& probe) const noexcept { return contact(probe).force; }

  [[nodiscard]] const PlaneConstraintConfig& config() const noexcept { return config_; }

 private:
  PlaneConstraintConfig config_;
};

struct SphereConstraintConfig {
  glm::dvec3 centre{0.0};    ///< [m]
  double radius{0.02};       ///< [m]
  double stiffness{1500.0};  ///< k [N/m]
  double damping{0.0};       ///< b on the normal velocity while penetrating [N s/m]
};

/// A solid ball: touching where |p - centre| < radius; the normal points
/// radially out (+z at the exact centre).
class SphereConstraint {
 public:
  /// @throws std::invalid_argument for a non-finite centre, a radius <= 0,
  ///         a stiffness <= 0 or a negative damping.
  explicit SphereConstraint(const SphereConstraintConfig& config) : config_(config) {
    if (!is_finite(config.centre)) throw std::invalid_argument("SphereConstraint: centre must be finite [m]");
    if (!std::isfinite(config.radius) || config.radius <= 0.0)
      throw std::invalid_argument("SphereConstraint: radius must be finite and > 0 [m]");
    detail::check_penalty("SphereConstraint", config.stiffness, config.damping);
  }

  [[nodiscard]] Contact contact(const Probe& probe) const noexcept {
    if (!is_finite(probe.position)) return Contact{};
    const glm::dvec3 r = probe.position - config_.centre;
    const double distance = glm::length(r);  // [m]
    if (!(distance < config_.radius)) return Contact{};
    const glm::dvec3 n = distance > 0.0 ? r / distance : glm::dvec3{0.0, 0.0, 1.0};
    return detail::penalty_contact(config_.radius - distance, n, probe.velocity, config_.stiffness, config_.damping);
  }

  /// Fc alone [N].
  [[nodiscard]] glm::dvec3 force(const Probe& probe) const noexcept { return contact(probe).force; }

  [[nodiscard]] const SphereConstraintConfig& config() const noexcept { return config_; }

 private:
  SphereConstraintConfig config_;
};

static_assert(Constraint<PlaneConstraint> && HapticField<PlaneConstraint>);
static_assert(Constraint<SphereConstraint> && HapticField<SphereConstraint>);

}  // namespace hapticfield
