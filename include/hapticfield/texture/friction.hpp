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
///
/// Friction acts in the tangent plane of the surface being touched: the
/// probe's surface_normal when it has one (a ContactField sets it, with |Fc|
/// of the same tick), otherwise the configured surface_normal (zero: in 3D,
/// for friction in free space).

#include <cmath>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/surface_frame.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield::texture {

struct FrictionConfig {
  double coulomb{0.0};                  ///< c: Coulomb force [N], or mu [-] when scaled by |Fc|
  double viscous{0.0};                  ///< b [N s/m]
  double drag{0.0};                     ///< d [N s^2/m^2]
  double smoothing_speed{2e-3};         ///< u0 [m/s]: width of the smoothed stick region
  bool scale_with_normal_force{false};  ///< Coulomb force = c |Fc|
  glm::dvec3 surface_normal{0.0};       ///< unit normal used when the probe has none: tangent-plane friction; zero: 3D
};

class Friction {
 public:
  /// @throws std::invalid_argument for a negative or non-finite coefficient,
  ///         a non-positive smoothing speed, or a normal neither zero nor unit.
  explicit Friction(const FrictionConfig& p) : config_(p) {
    const double v[] = {p.coulomb, p.viscous, p.drag};
    for (double x : v)
      if (!std::isfinite(x) || x < 0.0)
        throw std::invalid_argument(
            "Friction: coulomb [N or -], viscous [N s/m] and drag [N s^2/m^2] must be finite and >= 0");
    if (!std::isfinite(p.smoothing_speed) || p.smoothing_speed <= 0.0)
      throw std::invalid_argument("Friction: smoothing_speed must be finite and > 0 [m/s]");
    const double n = glm::length(p.surface_normal);
    if (!std::isfinite(n) || (n != 0.0 && std::fabs(n - 1.0) > 1e-9))
      throw std::invalid_argument("Friction: surface_normal must be zero or a unit vector");
  }

  [[nodiscard]] glm::dvec3 force(const Probe& probe) const noexcept {
    if (!is_finite(probe.velocity) || !std::isfinite(probe.normal_force) || !is_finite(probe.surface_normal))
      return glm::dvec3{0.0};
    const glm::dvec3 n = surface_normal_of(probe, config_.surface_normal);
    const glm::dvec3 v = probe.velocity - glm::dot(probe.velocity, n) * n;  // tangential velocity [m/s]
    const double speed = glm::length(v);
    if (speed == 0.0) return glm::dvec3{0.0};
    const double c =
        config_.scale_with_normal_force ? config_.coulomb * std::fabs(probe.normal_force) : config_.coulomb;
    const double u0 = config_.smoothing_speed;
    // c s(u)/u = c / sqrt(u^2 + u0^2): finite as u -> 0, so no division by 0
    const double per_speed = c / std::sqrt(speed * speed + u0 * u0) + config_.viscous + config_.drag * speed;
    return -per_speed * v;
  }

  [[nodiscard]] const FrictionConfig& params() const noexcept { return config_; }

 private:
  FrictionConfig config_;
};

/// Parameters of the stick-slip (spring-anchor) friction model.
struct StickSlipConfig {
  double stiffness{2000.0};                  ///< k of the stick spring [N/m]
  double static_coefficient{0.5};            ///< breakaway: mu_s [-] (x |Fc|) or force [N]
  double kinetic_coefficient{0.4};           ///< sliding: mu_k [-] (x |Fc|) or force [N], <= static
  bool scale_with_normal_force{true};        ///< limits proportional to |Fc|
  glm::dvec3 surface_normal{0.0, 0.0, 1.0};  ///< unit normal used when the probe has none; zero: 3D
};

/// Stick-slip Coulomb friction with a virtual anchor (the friction-cone /
/// "god-object" model of Salisbury et al. 1995 and Hayward & Armstrong,
/// "A new computational model of friction applied to haptic rendering",
/// 2000). While sticking, a spring k pulls the HIP back to the anchor; when
/// the spring force exceeds the static limit the contact slips and the anchor
/// is dragged behind the HIP so the force stays at the kinetic limit,
/// opposing the motion. The force is a continuous function of position, so
/// a hand at rest or jittering feels a stiff, quiet stick instead of a
/// Coulomb force flipping sign each tick. Like Friction, it works in the
/// tangent plane of the probe's surface normal when the probe has one.
class StickSlipFriction {
 public:
  /// @throws std::invalid_argument for a non-positive stiffness, negative
  ///         coefficients, kinetic above static, or a bad normal.
  explicit StickSlipFriction(const StickSlipConfig& p) : config_(p) {
    if (!std::isfinite(p.stiffness) || p.stiffness <= 0.0)
      throw std::invalid_argument("StickSlipFriction: stiffness must be finite and > 0 [N/m]");
    if (!std::isfinite(p.static_coefficient) || !std::isfinite(p.kinetic_coefficient) || p.kinetic_coefficient < 0.0 ||
        p.kinetic_coefficient > p.static_coefficient)
      throw std::invalid_argument(
          "StickSlipFriction: need 0 <= kinetic_coefficient <= static_coefficient (mu [-] or force [N])");
    const double n = glm::length(p.surface_normal);
    if (!std::isfinite(n) || (n != 0.0 && std::fabs(n - 1.0) > 1e-9))
      throw std::invalid_argument("StickSlipFriction: surface_normal must be zero or a unit vector");
  }

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    if (!is_finite(probe.position) || !std::isfinite(probe.normal_force) || !is_finite(probe.surface_normal))
      return glm::dvec3{0.0};
    if (!started_) {
      started_ = true;
      anchor_ = probe.position;
      sliding_ = false;
      return glm::dvec3{0.0};
    }
    glm::dvec3 d = probe.position - anchor_;
    const glm::dvec3 n = surface_normal_of(probe, config_.surface_normal);
    d -= glm::dot(d, n) * n;  // tangent plane of the touched surface
    const double fn = config_.scale_with_normal_force ? std::fabs(probe.normal_force) : 1.0;
    const double static_limit = config_.static_coefficient * fn;
    const double kinetic_limit = config_.kinetic_coefficient * fn;
    const double stretch = glm::length(d);
    const double spring = config_.stiffness * stretch;
    if (!sliding_ && spring > static_limit) sliding_ = true;
    if (sliding_) {
      if (spring > kinetic_limit) {
        // drag the anchor so that the spring force is exactly the kinetic limit
        const glm::dvec3 dir = d / stretch;
        const double keep = kinetic_limit / config_.stiffness;
        anchor_ += (stretch - keep) * dir;
        return -kinetic_limit * dir;
      }
      sliding_ = false;  // the spring relaxed below the kinetic limit: stuck again
    }
    return -config_.stiffness * d;
  }

  void reset() noexcept {
    started_ = false;
    sliding_ = false;
  }
  [[nodiscard]] bool sliding() const noexcept { return sliding_; }
  [[nodiscard]] const glm::dvec3& anchor() const noexcept { return anchor_; }

 private:
  StickSlipConfig config_;
  glm::dvec3 anchor_{0.0};
  bool started_{false};
  bool sliding_{false};
};

}  // namespace hapticfield::texture
