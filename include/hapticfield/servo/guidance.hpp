#pragma once
/// @file guidance.hpp
/// GuidanceField: couples one arm to another's handle (teacher/student
/// guidance on a MultiArmLoop): a spring-damper toward where the leader's
/// handle is, and no force at all while the leader's pose is not one to
/// act on (ServoLoop::trusted(): unhomed at start-up or after a reboot,
/// stale, resynchronising, impossible, latched).

#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"

namespace hapticfield {

/// F = stiffness (p_leader - p) - damping v when the leader is trusted,
/// else zero. Leader: anything with trusted() and state().position [m]
/// (a ServoLoop, MultiArmLoop::arm(i)); it must tick before the follower in
/// the same thread (MultiArmLoop ticks arms in order), or be read under the
/// caller's own synchronisation.
template <class Leader>
struct GuidanceField {
  const Leader* leader{nullptr};
  double stiffness{150.0};  ///< [N/m]
  double damping{1.0};      ///< [N s/m]

  [[nodiscard]] glm::dvec3 force(const Probe& p) const noexcept {
    if (leader == nullptr || !leader->trusted()) return glm::dvec3{0.0};
    return stiffness * (leader->state().position - p.position) - damping * p.velocity;
  }
};

}  // namespace hapticfield
