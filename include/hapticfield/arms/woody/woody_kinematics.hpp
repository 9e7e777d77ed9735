#pragma once
/// @file woody_kinematics.hpp
/// Kinematics of the serial 3-DOF WoodenHaptics ("woody") arm: encoder
/// counts to joint angles, forward kinematics, analytic Jacobian,
/// tau = J^T F and joint torque to motor current, with the published
/// presets (docs/woodenhaptics.md; facts in arm-protocols.md section 2).
///
/// Frames. The published model uses a source frame S with x toward the
/// user, y to the user's right, z up. hapticfield's device frame D has x to
/// the right, y up, z toward the user. So D = (S.y, S.z, S.x) and
/// S = (D.z, D.x, D.y), for positions and forces alike. The origin is the
/// preset's origin point (the published origin offset is subtracted).
///
/// Model (arm-protocols.md section 2), with S_r = Lb sin(tB) + Lc sin(tC):
///   x_S = cos(tA) S_r - ox,  y_S = sin(tA) S_r - oy,
///   z_S = Ln + Lb cos(tB) - Lc cos(tC) - oz
///   t_i = dir_i 2 pi enc_i / cpr_i (d_capstan_i / d_body_i),
///   dir_i = -1 when motor and body are aligned, else +1
///   I_i = tau_i dir_i (d_capstan_i / d_body_i) / Kt_i   [A]

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>
#include <string_view>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

namespace hapticfield {

/// Geometry, drive and limits of one serial woody-structure arm.
struct WoodyKinematicsConfig {
  std::string name{"woody_v2015"};
  double ln{0.080};                                              ///< height of the shoulder axis (La) [m]
  double lb{0.205};                                              ///< first link [m]
  double lc{0.245};                                              ///< second link [m]
  glm::dvec3 origin{0.220, 0.0, 0.080};                          ///< origin offset, source frame [m]
  glm::dvec3 capstan{0.010, 0.010, 0.010};                       ///< capstan diameters [m]
  glm::dvec3 body{0.160, 0.120, 0.120};                          ///< driven body diameters [m]
  glm::dvec3 torque_constant{0.0259, 0.0259, 0.0259};            ///< motor Kt [N m/A]
  std::array<std::int32_t, 3> counts_per_rev{2000, 2000, 2000};  ///< quadrature counts per motor turn
  std::array<bool, 3> aligned{false, true, true};                ///< motor_and_body_aligned (dir = -1 when true)
  std::array<std::int32_t, 3> home_offset{0, 0, -6000};          ///< added to the host's encoder counts [counts]
  int model_code{3};                                             ///< P4 model number (1 Polhem, 2 vintage, 3 Woody)
  double max_force{5.0};                                         ///< peak handle force [N]

  /// @throws std::invalid_argument naming the parameter that makes no sense.
  void validate() const {
    const auto bad = [](double v) { return !std::isfinite(v) || v <= 0.0; };
    if (bad(ln) || bad(lb) || bad(lc))
      throw std::invalid_argument("WoodyKinematicsConfig: ln, lb, lc must be finite and > 0 [m]");
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(origin[i])) throw std::invalid_argument("WoodyKinematicsConfig: origin must be finite [m]");
      if (bad(capstan[i]) || bad(body[i]))
        throw std::invalid_argument("WoodyKinematicsConfig: capstan and body diameters must be finite and > 0 [m]");
      if (bad(torque_constant[i]))
        throw std::invalid_argument("WoodyKinematicsConfig: torque_constant must be finite and > 0 [N m/A]");
      if (counts_per_rev[static_cast<std::size_t>(i)] <= 0)
        throw std::invalid_argument("WoodyKinematicsConfig: counts_per_rev must be > 0");
    }
    if (bad(max_force)) throw std::invalid_argument("WoodyKinematicsConfig: max_force must be finite and > 0 [N]");
  }
};

/// Published presets (arm-protocols.md section 2). Parameters the sources do
/// not state for a preset are taken from woody_v2015; docs/woodenhaptics.md
/// lists which.
namespace woody_presets {

/// woody (default / v2015): La/Lb/Lc 80/205/245 mm, Kt 0.0259 N m/A, cpr 2000.
[[nodiscard]] inline WoodyKinematicsConfig woody_v2015() {
  return {};
}

/// woodenhaptics_v2019: as v2015 with Kt 0.321 / 0.0603 / 0.0603 [N m/A].
[[nodiscard]] inline WoodyKinematicsConfig woodenhaptics_v2019() {
  WoodyKinematicsConfig c;
  c.name = "woodenhaptics_v2019";
  c.torque_constant = {0.321, 0.0603, 0.0603};
  return c;
}

/// aluhaptics_v2: capstans 13.8/9.8/9.8 mm, links 111/140/111 mm, bodies
/// 116/76/76 mm, origin (0.140, 0, 0) m.
[[nodiscard]] inline WoodyKinematicsConfig aluhaptics_v2() {
  WoodyKinematicsConfig c;
  c.name = "aluhaptics_v2";
  c.capstan = {0.0138, 0.0098, 0.0098};
  c.ln = 0.111;
  c.lb = 0.140;
  c.lc = 0.111;
  c.body = {0.116, 0.076, 0.076};
  c.origin = {0.140, 0.0, 0.0};
  return c;
}

/// vintage (Phantom, P4 model 2): cpr 4000, Kt 0.0234 [N m/A], home offset
/// {0, 7700, 0} [counts].
[[nodiscard]] inline WoodyKinematicsConfig vintage() {
  WoodyKinematicsConfig c;
  c.name = "vintage";
  c.counts_per_rev = {4000, 4000, 4000};
  c.torque_constant = {0.0234, 0.0234, 0.0234};
  c.home_offset = {0, 7700, 0};
  c.model_code = 2;
  return c;
}

/// A preset by name: woody, woody_v2015, woodenhaptics_v2019, aluhaptics_v2,
/// vintage.
/// @throws std::invalid_argument for polhem_v3 (its closed-chain linkage is
///         not implemented) and for unknown names.
[[nodiscard]] inline WoodyKinematicsConfig by_name(std::string_view name) {
  if (name == "woody" || name == "woody_v2015" || name == "v2015") return woody_v2015();
  if (name == "woodenhaptics_v2019" || name == "v2019") return woodenhaptics_v2019();
  if (name == "aluhaptics_v2") return aluhaptics_v2();
  if (name == "vintage") return vintage();
  if (name == "polhem" || name == "polhem_v3")
    throw std::invalid_argument("woody preset '" + std::string(name) +
                                "': the Polhem closed-chain linkage is not implemented (serial woody structure only)");
  throw std::invalid_argument("woody preset '" + std::string(name) +
                              "' is unknown; use woody_v2015, woodenhaptics_v2019, aluhaptics_v2 or vintage");
}

}  // namespace woody_presets

/// Source frame (x toward the user, y right, z up) to device frame.
[[nodiscard]] constexpr glm::dvec3 woody_to_device(const glm::dvec3& s) noexcept {
  return {s.y, s.z, s.x};
}
/// Device frame (x right, y up, z toward the user) to source frame.
[[nodiscard]] constexpr glm::dvec3 woody_to_source(const glm::dvec3& d) noexcept {
  return {d.z, d.x, d.y};
}

/// Kinematics of a serial woody-structure arm. Angles tA (base), tB, tC [rad].
class WoodyKinematics {
 public:
  WoodyKinematics() = default;
  /// @throws std::invalid_argument when the configuration makes no sense.
  explicit WoodyKinematics(const WoodyKinematicsConfig& config) : config_(config) { config_.validate(); }

  [[nodiscard]] const WoodyKinematicsConfig& config() const noexcept { return config_; }

  /// dir_i (d_capstan_i / d_body_i): joint turns per motor turn, signed.
  [[nodiscard]] double ratio(int i) const noexcept {
    const double dir = config_.aligned[static_cast<std::size_t>(i)] ? -1.0 : 1.0;
    return dir * config_.capstan[i] / config_.body[i];
  }

  /// Joint angles [rad] from host encoder counts (sign conventions and home
  /// offsets already applied).
  [[nodiscard]] glm::dvec3 angles(const std::array<std::int32_t, 3>& counts) const noexcept {
    glm::dvec3 q{0.0};
    for (int i = 0; i < 3; ++i) {
      const auto k = static_cast<std::size_t>(i);
      q[i] = 2.0 * std::numbers::pi * counts[k] / config_.counts_per_rev[k] * ratio(i);
    }
    return q;
  }

  /// Host encoder counts (nearest) at joint angles q [rad]; the inverse of angles().
  [[nodiscard]] std::array<std::int32_t, 3> counts(const glm::dvec3& q) const noexcept {
    std::array<std::int32_t, 3> c{};
    for (int i = 0; i < 3; ++i) {
      const auto k = static_cast<std::size_t>(i);
      c[k] = static_cast<std::int32_t>(
          std::lround(q[i] / ratio(i) * config_.counts_per_rev[k] / (2.0 * std::numbers::pi)));
    }
    return c;
  }

  /// Handle position in the source frame [m].
  [[nodiscard]] glm::dvec3 forward_source(const glm::dvec3& q) const noexcept {
    const double r = config_.lb * std::sin(q.y) + config_.lc * std::sin(q.z);
    return {std::cos(q.x) * r - config_.origin.x, std::sin(q.x) * r - config_.origin.y,
            config_.ln + config_.lb * std::cos(q.y) - config_.lc * std::cos(q.z) - config_.origin.z};
  }

  /// Handle position in the device frame [m].
  [[nodiscard]] glm::dvec3 forward(const glm::dvec3& q) const noexcept { return woody_to_device(forward_source(q)); }

  /// d p_S / d q in the source frame; column i is d p_S / d q_i [m/rad].
  [[nodiscard]] glm::dmat3 jacobian_source(const glm::dvec3& q) const noexcept {
    const double sa = std::sin(q.x), ca = std::cos(q.x), sb = std::sin(q.y), cb = std::cos(q.y);
    const double sc = std::sin(q.z), cc = std::cos(q.z);
    const double r = config_.lb * sb + config_.lc * sc;
    glm::dmat3 j{0.0};
    j[0] = glm::dvec3{-sa * r, ca * r, 0.0};
    j[1] = glm::dvec3{config_.lb * ca * cb, config_.lb * sa * cb, -config_.lb * sb};
    j[2] = glm::dvec3{config_.lc * ca * cc, config_.lc * sa * cc, config_.lc * sc};
    return j;
  }

  /// Handle velocity in the device frame [m/s] from joint rates [rad/s].
  [[nodiscard]] glm::dvec3 velocity(const glm::dvec3& q, const glm::dvec3& qdot) const noexcept {
    return woody_to_device(jacobian_source(q) * qdot);
  }

  /// Joint torques [N m] for a handle force in the device frame [N]: tau = J^T F.
  [[nodiscard]] glm::dvec3 torques(const glm::dvec3& q, const glm::dvec3& force) const noexcept {
    const glm::dmat3 j = jacobian_source(q);
    const glm::dvec3 f = woody_to_source(force);
    return {j[0].x * f.x + j[0].y * f.y + j[0].z * f.z, j[1].x * f.x + j[1].y * f.y + j[1].z * f.z,
            j[2].x * f.x + j[2].y * f.y + j[2].z * f.z};
  }

  /// Motor currents [A] for joint torques [N m]: I = tau dir (d_cap/d_body) / Kt.
  [[nodiscard]] glm::dvec3 currents(const glm::dvec3& tau) const noexcept {
    glm::dvec3 a{0.0};
    for (int i = 0; i < 3; ++i)
      a[i] = tau[i] * ratio(i) / config_.torque_constant[i];
    return a;
  }

  /// Joint torques [N m] that motor currents [A] produce (the inverse of currents()).
  [[nodiscard]] glm::dvec3 joint_torques(const glm::dvec3& amps) const noexcept {
    glm::dvec3 t{0.0};
    for (int i = 0; i < 3; ++i)
      t[i] = amps[i] * config_.torque_constant[i] / ratio(i);
    return t;
  }

 private:
  WoodyKinematicsConfig config_{};
};

}  // namespace hapticfield
