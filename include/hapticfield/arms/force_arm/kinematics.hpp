#pragma once
/// @file kinematics.hpp
/// Phantom-class arm kinematics: three revolute joints (base yaw, shoulder,
/// parallelogram elbow), forward kinematics, Jacobian, tau = J^T F, encoder
/// counts to angles.
///
/// Frame: x to the user's right, y up, z toward the user; origin at the home
/// pose q = (0, 0, 0) (upper arm horizontal pointing at the user, forearm
/// hanging straight down). q1 turns the arm about +y (positive swings the
/// handle to +x), q2 raises the upper arm, q3 is the forearm's absolute angle
/// from the downward vertical (the parallelogram drives it from the base, so
/// it does not add to q2). With r = l1 cos q2 + l2 sin q3 (reach from the
/// yaw axis) and h = l1 sin q2 - l2 cos q3 (height above the shoulder):
///
///   p = (r sin q1, h + l2, r cos q1 - l1)
///
/// which is the usual Phantom Omni model (e.g. Silva, Sanchez & Hohl, 2009)
/// with the home pose as origin.

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

namespace hapticfield {

/// Geometry and encoder parameters (Omni-like defaults, not datasheet facts).
struct KinematicsConfig {
  double l1{0.133};                                                 ///< upper arm length [m] (default)
  double l2{0.133};                                                 ///< forearm length [m] (default)
  glm::dvec3 q_min{-1.0, -0.6, -0.5};                               ///< joint lower limits [rad] (default)
  glm::dvec3 q_max{1.0, 1.2, 1.4};                                  ///< joint upper limits [rad] (default)
  std::array<std::int32_t, 3> counts_per_rev{15000, 15000, 15000};  ///< encoder counts per joint turn (default)
  glm::dvec3 max_torque{0.45, 0.45, 0.45};  ///< motor torque saturation at the joint [N m] (default)

  /// @throws std::invalid_argument naming the parameter that makes no sense.
  void validate() const {
    const auto bad = [](double v) { return !std::isfinite(v) || v <= 0.0; };
    if (bad(l1)) throw std::invalid_argument("KinematicsConfig: l1 must be finite and > 0 [m]");
    if (bad(l2)) throw std::invalid_argument("KinematicsConfig: l2 must be finite and > 0 [m]");
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(q_min[i]) || !std::isfinite(q_max[i]) || q_min[i] >= q_max[i])
        throw std::invalid_argument("KinematicsConfig: q_min must be finite and < q_max [rad]");
      if (counts_per_rev[static_cast<std::size_t>(i)] <= 0)
        throw std::invalid_argument("KinematicsConfig: counts_per_rev must be > 0");
      if (bad(max_torque[i])) throw std::invalid_argument("KinematicsConfig: max_torque must be finite and > 0 [N m]");
    }
  }
};

/// Forward kinematics, Jacobian and force mapping of a Phantom-class arm.
class PhantomKinematics {
 public:
  PhantomKinematics() = default;
  /// @throws std::invalid_argument when the configuration makes no sense.
  explicit PhantomKinematics(const KinematicsConfig& config) : config_(config) { config_.validate(); }

  [[nodiscard]] const KinematicsConfig& config() const noexcept { return config_; }

  /// Handle position p(q) [m].
  [[nodiscard]] glm::dvec3 forward(const glm::dvec3& q) const noexcept {
    const double r = config_.l1 * std::cos(q[1]) + config_.l2 * std::sin(q[2]);
    const double h = config_.l1 * std::sin(q[1]) - config_.l2 * std::cos(q[2]);
    return {r * std::sin(q[0]), h + config_.l2, r * std::cos(q[0]) - config_.l1};
  }

  /// Jacobian J = dp/dq [m/rad]; column j is dp/dq_j.
  [[nodiscard]] glm::dmat3 jacobian(const glm::dvec3& q) const noexcept {
    const double s1 = std::sin(q[0]), c1 = std::cos(q[0]);
    const double s2 = std::sin(q[1]), c2 = std::cos(q[1]);
    const double s3 = std::sin(q[2]), c3 = std::cos(q[2]);
    const double r = config_.l1 * c2 + config_.l2 * s3;
    glm::dmat3 j{0.0};
    j[0] = glm::dvec3{r * c1, 0.0, -r * s1};
    j[1] = glm::dvec3{-config_.l1 * s2 * s1, config_.l1 * c2, -config_.l1 * s2 * c1};
    j[2] = glm::dvec3{config_.l2 * c3 * s1, config_.l2 * s3, config_.l2 * c3 * c1};
    return j;
  }

  /// Joint torques that produce the handle force F: tau = J^T F [N m].
  [[nodiscard]] glm::dvec3 torques(const glm::dvec3& q, const glm::dvec3& force) const noexcept {
    const glm::dmat3 j = jacobian(q);
    return {dot(j[0], force), dot(j[1], force), dot(j[2], force)};
  }

  /// Handle velocity v = J qdot [m/s].
  [[nodiscard]] glm::dvec3 velocity(const glm::dvec3& q, const glm::dvec3& qdot) const noexcept {
    return jacobian(q) * qdot;
  }

  /// Encoder counts -> joint angles [rad] (counts are zero at the home pose).
  [[nodiscard]] glm::dvec3 angles(const std::array<std::int32_t, 3>& counts) const noexcept {
    glm::dvec3 q{0.0};
    for (std::size_t i = 0; i < 3; ++i)
      q[static_cast<int>(i)] = 2.0 * std::numbers::pi * counts[i] / config_.counts_per_rev[i];
    return q;
  }

  /// Joint angles [rad] -> encoder counts (floor, as an incremental encoder reads).
  [[nodiscard]] std::array<std::int32_t, 3> counts(const glm::dvec3& q) const noexcept {
    std::array<std::int32_t, 3> n{};
    for (std::size_t i = 0; i < 3; ++i) {
      const double c = std::floor(q[static_cast<int>(i)] * config_.counts_per_rev[i] / (2.0 * std::numbers::pi));
      n[i] = static_cast<std::int32_t>(std::fmax(-2.0e9, std::fmin(2.0e9, std::isfinite(c) ? c : 0.0)));
    }
    return n;
  }

 private:
  static double dot(const glm::dvec3& a, const glm::dvec3& b) noexcept { return a.x * b.x + a.y * b.y + a.z * b.z; }
  KinematicsConfig config_{};
};

}  // namespace hapticfield
