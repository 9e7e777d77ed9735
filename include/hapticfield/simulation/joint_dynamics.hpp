#pragma once
/// @file joint_dynamics.hpp
/// The joints of a simulated arm: three independent joints with inertia,
/// viscous and Coulomb friction and hard stops, one explicit Euler step at
/// a time. Shared by the simulated Phantom-class arm (ArmPlant) and the
/// simulated WoodenHaptics arm (SimulatedWoody).

#include <cmath>

#include <glm/vec3.hpp>

namespace hapticfield {

/// Per-joint parameters, for joints 0..2.
struct JointModel {
  glm::dvec3 inertia;  ///< effective joint inertia [kg m^2], > 0
  glm::dvec3 viscous;  ///< viscous friction [N m s/rad]
  glm::dvec3 coulomb;  ///< Coulomb friction [N m]
  glm::dvec3 q_min;    ///< joint stops [rad]
  glm::dvec3 q_max;    ///< [rad]
};

/// One step of h [s] under joint torques tau [N m]: angles q [rad] and
/// rates qd [rad/s] in place. Coulomb friction opposes motion and sticks
/// when it would reverse it; a stop holds the angle and keeps only the rate
/// that leaves it.
inline void step_joints(const JointModel& m, const glm::dvec3& tau, double h, glm::dvec3& q, glm::dvec3& qd) noexcept {
  for (int i = 0; i < 3; ++i) {
    const double drive = tau[i] - m.viscous[i] * qd[i];
    double rate = qd[i] + h * drive / m.inertia[i];
    const double stick = h * m.coulomb[i] / m.inertia[i];
    if (rate > stick)
      rate -= stick;
    else if (rate < -stick)
      rate += stick;
    else
      rate = 0.0;
    double angle = q[i] + h * rate;
    if (angle < m.q_min[i]) {
      angle = m.q_min[i];
      rate = std::fmax(rate, 0.0);
    }
    if (angle > m.q_max[i]) {
      angle = m.q_max[i];
      rate = std::fmin(rate, 0.0);
    }
    q[i] = angle;
    qd[i] = rate;
  }
}

}  // namespace hapticfield
