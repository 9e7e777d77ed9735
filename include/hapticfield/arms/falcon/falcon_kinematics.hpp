#pragma once
/// @file falcon_kinematics.hpp
/// FalconKinematics: the Novint Falcon's three-leg parallel arm (a delta-like
/// translational manipulator, R. E. Stamper, "A three degree of freedom
/// parallel manipulator with only translational degrees of freedom", PhD
/// thesis, University of Maryland, 1997), with the dimensions libnifalcon
/// publishes (FalconGeometry.h). Pure and allocation-free.
///
/// Each leg i has its own frame (u, v, w): the base frame turned by -phi_i
/// about z, shifted by (-r, -s, 0). The thigh (length a) turns by theta1
/// about the leg's v axis; the shin's parallelogram (sides b) makes angle
/// theta3 with v, the knee joint angle is theta2. The handle centre in the
/// leg frame (the chain written forward, the oracle of the tests) is
///   u = a cos theta1 + k cos theta2 - c
///   v = b cos theta3 - f
///   w = a sin theta1 + k sin theta2,     k = d + e + b sin theta3.
/// Inverse: theta3 from v, then theta1 from the two-link circle
/// intersection (the outward knee), closed form. Forward: Newton's method
/// on the inverse with the exact Jacobian (implicit differentiation of the
/// chain), a bounded number of iterations, and a failure result. Forces:
/// tau = J^T F with J = d position / d theta1, i.e. tau = (d theta/d p)^-T F.
///
/// Frame: base frame of the geometry (x right, y up, z out of the Falcon's
/// face toward the user, inferred from the legs' order "from the top,
/// clockwise, seen from the front"), shifted so the workspace centre
/// (z = 0.150 m in the base frame) is the origin.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/vector_math.hpp"

namespace hapticfield {

/// Published dimensions (libnifalcon FalconGeometry.h; Stamper's figure).
struct FalconGeometry {
  double a{0.060};          ///< thigh length [m]
  double b{0.1025};         ///< shin parallelogram side [m]
  double c{0.01443};        ///< shin joint to handle centre, u [m]
  double d{0.01125};        ///< shin to handle joint [m]
  double e{0.01125};        ///< knee to shin joint [m]
  double f{-0.025};         ///< shin joint to handle centre, v [m]
  double r{0.040};          ///< base centre to leg base, u [m]
  double s{-0.02309};       ///< base centre to leg base, v [m]
  std::array<double, 3> phi{///< legs' directions [rad]: 90, -30, -150 deg, each + 15 deg
                            std::numbers::pi / 2 + std::numbers::pi / 12, -std::numbers::pi / 6 + std::numbers::pi / 12,
                            -5 * std::numbers::pi / 6 + std::numbers::pi / 12};
  double origin_z{0.150};                                ///< workspace centre in the base frame [m]
  double shaft_diameter{0.01425};                        ///< motor capstan [m]
  double arm_diameter{0.110};                            ///< thigh drum [m]
  double wheel_slots{320.0};                             ///< encoder wheel slots (x4 quadrature counts per turn)
  double theta_offset{35.0 * std::numbers::pi / 180.0};  ///< theta1 at encoder count 0 [rad] (libnifalcon, approx.)

  /// theta1 per encoder count [rad/count].
  [[nodiscard]] double radians_per_count() const noexcept {
    return 2.0 * std::numbers::pi * (shaft_diameter / arm_diameter) / (4.0 * wheel_slots);
  }

  /// @throws std::invalid_argument naming the first dimension that makes no sense.
  void validate() const {
    const auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
    if (!pos(a) || !pos(b) || !pos(d) || !pos(e) || !pos(shaft_diameter) || !pos(arm_diameter) || !pos(wheel_slots))
      throw std::invalid_argument("FalconGeometry: a, b, d, e, shaft_diameter, arm_diameter, wheel_slots must be > 0");
    if (!std::isfinite(c) || !std::isfinite(f) || !std::isfinite(r) || !std::isfinite(s) || !std::isfinite(origin_z) ||
        !std::isfinite(theta_offset))
      throw std::invalid_argument("FalconGeometry: c, f, r, s, origin_z, theta_offset must be finite");
    for (const double p : phi)
      if (!std::isfinite(p)) throw std::invalid_argument("FalconGeometry: phi must be finite [rad]");
  }
};

/// All three angles of one leg [rad].
struct FalconLegAngles {
  double theta1{0.0};  ///< thigh (the motor's joint)
  double theta2{0.0};  ///< knee
  double theta3{0.0};  ///< shin parallelogram
};

/// Result of the forward kinematics.
struct FalconForward {
  glm::dvec3 position{0.0};  ///< handle centre, device frame [m]
  int iterations{0};         ///< Newton steps taken
  bool converged{false};     ///< false: no pose gives these angles within the iteration bound
};

class FalconKinematics {
 public:
  static constexpr int default_max_iterations = 30;
  static constexpr double angle_tolerance = 1e-11;  ///< Newton stops below this max |theta error| [rad]
  static constexpr double max_step = 0.02;          ///< longest Newton step [m]

  explicit FalconKinematics(FalconGeometry g = {}) : g_(g) {
    g_.validate();
    for (std::size_t i = 0; i < 3; ++i) {
      cos_phi_[i] = std::cos(g_.phi[i]);
      sin_phi_[i] = std::sin(g_.phi[i]);
    }
  }

  [[nodiscard]] const FalconGeometry& geometry() const noexcept { return g_; }

  /// A device-frame point in leg i's frame (u, v, w) [m].
  [[nodiscard]] glm::dvec3 to_leg(std::size_t i, const glm::dvec3& p) const noexcept {
    const double z = p.z + g_.origin_z;
    return {cos_phi_[i] * p.x + sin_phi_[i] * p.y - g_.r, -sin_phi_[i] * p.x + cos_phi_[i] * p.y - g_.s, z};
  }
  /// Leg i's frame back to the device frame [m].
  [[nodiscard]] glm::dvec3 from_leg(std::size_t i, const glm::dvec3& q) const noexcept {
    const double u = q.x + g_.r;
    const double v = q.y + g_.s;
    return {cos_phi_[i] * u - sin_phi_[i] * v, sin_phi_[i] * u + cos_phi_[i] * v, q.z - g_.origin_z};
  }

  /// The chain written forward: leg i's handle centre for its three angles,
  /// device frame [m]. The oracle the inverse is tested against.
  [[nodiscard]] glm::dvec3 leg_chain(std::size_t i, const FalconLegAngles& t) const noexcept {
    const double k = g_.d + g_.e + g_.b * std::sin(t.theta3);
    const glm::dvec3 q{g_.a * std::cos(t.theta1) + k * std::cos(t.theta2) - g_.c, g_.b * std::cos(t.theta3) - g_.f,
                       g_.a * std::sin(t.theta1) + k * std::sin(t.theta2)};
    return from_leg(i, q);
  }

  /// Closed-form inverse for leg i; false (angles untouched) when the leg
  /// cannot reach p.
  bool leg_inverse(std::size_t i, const glm::dvec3& p, FalconLegAngles& out) const noexcept {
    const glm::dvec3 q = to_leg(i, p);
    const double c3 = (q.y + g_.f) / g_.b;
    if (!(c3 > -1.0 && c3 < 1.0)) return false;
    const double t3 = std::acos(c3);
    const double k = g_.d + g_.e + g_.b * std::sin(t3);
    const double tu = q.x + g_.c;  // target of the two-link chain in (u, w)
    const double tw = q.z;
    const double dist = std::hypot(tu, tw);
    if (!(dist > 0.0)) return false;
    const double cos_in = (g_.a * g_.a + dist * dist - k * k) / (2.0 * g_.a * dist);
    if (!(cos_in > -1.0 && cos_in < 1.0)) return false;
    const double t1 = std::atan2(tw, tu) - std::acos(cos_in);  // the outward knee
    const double t2 = std::atan2(tw - g_.a * std::sin(t1), tu - g_.a * std::cos(t1));
    out = {t1, t2, t3};
    return true;
  }

  /// Motor joint angles theta1 of the three legs for a handle position;
  /// false when a leg cannot reach it.
  bool inverse(const glm::dvec3& p, glm::dvec3& theta) const noexcept {
    glm::dvec3 t{0.0};
    for (std::size_t i = 0; i < 3; ++i) {
      FalconLegAngles a;
      if (!leg_inverse(i, p, a)) return false;
      t[static_cast<int>(i)] = a.theta1;
    }
    theta = t;
    return true;
  }

  /// d theta1_i / d p at p (row i: leg i) [rad/m], by implicit
  /// differentiation of the leg's closure g = |(u + c, w) - a(cos t1, sin t1)|^2 - k(v)^2;
  /// false when p is unreachable or singular (a thigh in line with its shin).
  bool angle_jacobian(const glm::dvec3& p, glm::dmat3& rows) const noexcept {
    glm::dvec3 theta{0.0};
    return inverse_and_jacobian(p, theta, rows);
  }

  /// inverse() and angle_jacobian() in one pass over the legs; false (both
  /// untouched) when p is unreachable or singular.
  bool inverse_and_jacobian(const glm::dvec3& p, glm::dvec3& theta, glm::dmat3& rows) const noexcept {
    glm::dmat3 jt{0.0};  // column i: row i of the Jacobian
    glm::dvec3 t{0.0};
    for (std::size_t i = 0; i < 3; ++i) {
      FalconLegAngles a;
      if (!leg_inverse(i, p, a)) return false;
      t[static_cast<int>(i)] = a.theta1;
      const glm::dvec3 q = to_leg(i, p);
      const double s1 = std::sin(a.theta1), c1 = std::cos(a.theta1);
      const double k = g_.d + g_.e + g_.b * std::sin(a.theta3);
      const double dg_dt = 2.0 * g_.a * ((q.x + g_.c) * s1 - q.z * c1);
      if (!(std::fabs(dg_dt) > 1e-12)) return false;
      const double dk_dv = -std::cos(a.theta3) / std::sin(a.theta3);
      const double dg_du = 2.0 * (q.x + g_.c - g_.a * c1);
      const double dg_dv = -2.0 * k * dk_dv;
      const double dg_dw = 2.0 * (q.z - g_.a * s1);
      // d(u, v, w)/d(x, y, z) is the rotation by -phi (z unchanged)
      const double du = -dg_du / dg_dt, dv = -dg_dv / dg_dt, dw = -dg_dw / dg_dt;
      jt[static_cast<int>(i)] =
          glm::dvec3{du * cos_phi_[i] - dv * sin_phi_[i], du * sin_phi_[i] + dv * cos_phi_[i], dw};
    }
    rows = glm::transpose(jt);
    theta = t;
    return true;
  }

  /// Forward kinematics: the handle position whose inverse gives theta,
  /// by Newton's method from guess (the last pose, or the origin), at most
  /// max_iterations steps, each at most max_step long (without that bound a
  /// far guess can leap to the edge of the reach and stall there) and halved
  /// up to 8 times while it leaves the reachable set. converged is false when no step gets the angles within
  /// angle_tolerance: the angles are impossible (or the guess too far).
  [[nodiscard]] FalconForward forward(const glm::dvec3& theta, glm::dvec3 guess = glm::dvec3{0.0},
                                      int max_iterations = default_max_iterations) const noexcept {
    FalconForward out;
    glm::dvec3 t{0.0};
    glm::dmat3 j{0.0};
    if (!inverse_and_jacobian(guess, t, j)) {
      guess = glm::dvec3{0.0};
      if (!inverse_and_jacobian(guess, t, j)) return out;
    }
    glm::dvec3 p = guess;
    for (int it = 0; it < max_iterations; ++it) {
      const glm::dvec3 err = theta - t;
      if (largest_component(err) < angle_tolerance) {
        out.position = p;
        out.iterations = it;
        out.converged = true;
        return out;
      }
      if (!(std::fabs(glm::determinant(j)) > 1e-9)) break;
      glm::dvec3 step = glm::inverse(j) * err;
      const double length = glm::length(step);
      if (length > max_step) step *= max_step / length;  // a trust region: no leap across the workspace
      bool moved = false;
      for (int h = 0; h < 8 && !moved; ++h) {
        glm::dvec3 tn{0.0};
        glm::dmat3 jn{0.0};
        if (inverse_and_jacobian(p + step, tn, jn)) {
          p += step;
          t = tn;
          j = jn;
          moved = true;
        } else {
          step *= 0.5;
        }
      }
      out.iterations = it + 1;
      if (!moved) break;
    }
    const glm::dvec3 err = theta - t;
    out.position = p;
    out.converged = largest_component(err) < angle_tolerance;
    return out;
  }

  /// Motor joint torques for a handle force F [N] at p: tau = J^T F with
  /// J = dp/dtheta = (dtheta/dp)^-1 [N m]. false at an unreachable or
  /// singular pose.
  bool torques(const glm::dvec3& p, const glm::dvec3& force, glm::dvec3& tau) const noexcept {
    glm::dmat3 j{0.0};
    if (!angle_jacobian(p, j) || !(std::fabs(glm::determinant(j)) > 1e-9)) return false;
    tau = glm::inverse(glm::transpose(j)) * force;
    return true;
  }

  /// theta1 for an encoder count [rad].
  [[nodiscard]] double angle(std::int32_t count) const noexcept {
    return g_.theta_offset + static_cast<double>(count) * g_.radians_per_count();
  }
  [[nodiscard]] glm::dvec3 angles(const std::array<std::int16_t, 3>& counts) const noexcept {
    return {angle(counts[0]), angle(counts[1]), angle(counts[2])};
  }
  /// The encoder count nearest theta1 [counts] (unclamped).
  [[nodiscard]] double count(double theta1) const noexcept {
    return (theta1 - g_.theta_offset) / g_.radians_per_count();
  }

 private:
  FalconGeometry g_;
  std::array<double, 3> cos_phi_{};
  std::array<double, 3> sin_phi_{};
};

}  // namespace hapticfield
