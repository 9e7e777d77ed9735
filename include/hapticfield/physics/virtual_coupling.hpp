#pragma once
/// @file virtual_coupling.hpp
/// VirtualCoupling: a spring-damper between the handle and a simulated tool
/// body (Colgate, Stanley & Brown, "Issues in the haptic display of tool use",
/// IROS 1995):
///
///   F_handle = K (x_tool - x_handle) + B (v_tool - v_handle),  F_tool = -F_handle
///
/// A simulator that updates the tool every T seconds sees the coupling as a
/// sampled spring; Adams & Hannaford ("Stable haptic interaction with
/// virtual environments", IEEE T-RA 15(3), 1999) give B >= T K / 2 for the
/// coupling to stay passive, so the stiffest coupling a damping B allows at
/// period T is K = 2 B / T. validate() refuses couplings that break it.

#include <cmath>
#include <stdexcept>

#include <glm/vec3.hpp>

namespace hapticfield {

struct VirtualCoupling {
  double stiffness{200.0};  ///< K [N/m]
  double damping{2.0};      ///< B on the relative velocity [N s/m]

  /// @throws std::invalid_argument for K <= 0, B < 0 (or non-finite), or
  ///         B < T K / 2 at the simulator period T [s].
  void validate(double period) const {
    if (!std::isfinite(stiffness) || stiffness <= 0.0)
      throw std::invalid_argument("VirtualCoupling: stiffness must be finite and > 0 [N/m]");
    if (!std::isfinite(damping) || damping < 0.0)
      throw std::invalid_argument("VirtualCoupling: damping must be finite and >= 0 [N s/m]");
    if (damping < period * stiffness / 2.0 * (1.0 - 1e-12))  // (rounding of T K / 2 aside)
      throw std::invalid_argument(
          "VirtualCoupling: damping must be >= T K / 2 at the simulator period T (Adams & Hannaford 1999)");
  }

  /// The force on the handle [N] (the tool gets its opposite).
  [[nodiscard]] glm::dvec3 force(const glm::dvec3& handle, const glm::dvec3& handle_velocity, const glm::dvec3& tool,
                                 const glm::dvec3& tool_velocity) const noexcept {
    return stiffness * (tool - handle) + damping * (tool_velocity - handle_velocity);
  }
};

/// The stiffest coupling damping B [N s/m] keeps passive at period T [s]:
/// K = 2 B / T [N/m] (Adams & Hannaford 1999).
[[nodiscard]] inline double coupling_max_stiffness(double damping, double period) noexcept {
  return 2.0 * damping / period;
}

}  // namespace hapticfield
