#pragma once
/// @file friction.hpp
/// Friction Ff of the resultant F = Fc + Ft + Ff (Fritz & Barner 1996,
/// section 6): Coulomb, viscous and drag (v^2) terms, all opposing the
/// velocity of the HIP.
///
///   Ff = -(c s(|v|) + b |v| + d |v|^2) v / |v|,   s(u) = u / sqrt(u^2 + u0^2)
///
/// The Coulomb term is smoothed near zero speed by s(u) (a stick region of
/// width ~u0 where friction behaves like a stiff viscous damper c/u0), so it
/// does not flip sign every tick while the hand is nearly still (no chatter).
/// With scale_with_normal_force, c is a friction coefficient mu and the
/// Coulomb force is mu |Fc| (Probe::normal_force).

#include <cmath>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield::texture {

struct FrictionParams {
  double coulomb{0.0};          ///< c: Coulomb force [N], or mu [-] when scaled by |Fc|
  double viscous{0.0};          ///< b [N s/m]
  double drag{0.0};             ///< d [N s^2/m^2]
  double smoothing_speed{2e-3}; ///< u0 [m/s]: width of the smoothed stick region
  bool scale_with_normal_force{false};  ///< Coulomb force = c |Fc|
  glm::dvec3 surface_normal{0.0};       ///< unit normal: friction acts in the tangent plane; zero: 3D
};

class Friction {
 public:
  /// @throws std::invalid_argument for a negative or non-finite coefficient,
  ///         a non-positive smoothing speed, or a normal neither zero nor unit.
  explicit Friction(const FrictionParams& p) : p_(p) {
    const double v[] = {p.coulomb, p.viscous, p.drag};
    for (double x : v)
      if (!std::isfinite(x) || x < 0.0)
        throw std::invalid_argument("Friction: coulomb [N or -], viscous [N s/m] and drag [N s^2/m^2] must be finite and >= 0");
    if (!std::isfinite(p.smoothing_speed) || p.smoothing_speed <= 0.0)
      throw std::invalid_argument("Friction: smoothing_speed must be finite and > 0 [m/s]");
    const double n = glm::length(p.surface_normal);
    if (!std::isfinite(n) || (n != 0.0 && std::fabs(n - 1.0) > 1e-9))
      throw std::invalid_argument("Friction: surface_normal must be zero or a unit vector");
  }

  [[nodiscard]] glm::dvec3 force(const Probe& probe) const noexcept {
    if (!is_finite(probe.velocity) || !std::isfinite(probe.normal_force)) return glm::dvec3{0.0};
    glm::dvec3 v = probe.velocity;
    v -= glm::dot(v, p_.surface_normal) * p_.surface_normal;
    const double speed = glm::length(v);
    if (speed == 0.0) return glm::dvec3{0.0};
    const double c = p_.scale_with_normal_force ? p_.coulomb * std::fabs(probe.normal_force) : p_.coulomb;
    const double u0 = p_.smoothing_speed;
    // c s(u)/u = c / sqrt(u^2 + u0^2): finite as u -> 0, so no division by 0
    const double per_speed = c / std::sqrt(speed * speed + u0 * u0) + p_.viscous + p_.drag * speed;
    return -per_speed * v;
  }

  [[nodiscard]] const FrictionParams& params() const noexcept { return p_; }

 private:
  FrictionParams p_;
};

}  // namespace hapticfield::texture
