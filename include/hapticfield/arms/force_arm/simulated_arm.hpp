#pragma once
/// @file simulated_arm.hpp
/// A deterministic Phantom-class arm with its firmware, on a virtual clock:
/// joint dynamics (inertia, viscous and Coulomb friction, joint stops),
/// encoder and torque quantisation and saturation, the firmware watchdog,
/// homing before arming, held by the scripted hand
/// (simulation/scripted_hand.hpp). It speaks the report
/// protocol through SimulatedTransport (simulated_transport.hpp).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/arms/force_arm/kinematics.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/protocol/reports.hpp"
#include "hapticfield/simulation/joint_dynamics.hpp"
#include "hapticfield/simulation/scripted_hand.hpp"

namespace hapticfield {

/// Parameters of the simulated arm. Figures are plausible defaults for a
/// desktop Phantom-class arm, not measurements.
struct SimulatedArmConfig {
  KinematicsConfig kinematics{};
  glm::dvec3 inertia{9.0e-4, 9.0e-4, 6.0e-4};  ///< effective joint inertia [kg m^2] (about 50 g at the handle)
  glm::dvec3 viscous{2.0e-4, 2.0e-4, 2.0e-4};  ///< viscous friction [N m s/rad]
  glm::dvec3 coulomb{2.0e-3, 2.0e-3, 2.0e-3};  ///< Coulomb friction [N m]
  double rate{1000.0};                         ///< firmware tick and report rate [Hz]
  int substeps{8};                             ///< integration steps per firmware tick
  double watchdog{0.02};                       ///< firmware watchdog period [s]
  int homing_ticks{50};                        ///< firmware ticks homing takes
  double torque_unit{1e-3};                    ///< size of one torque unit on the wire [N m]
  double max_force{3.3};                       ///< peak force reported in device info [N] (default)
  double continuous_force{0.88};               ///< continuous force reported in device info [N] (default)
  glm::dvec3 initial_q{0.0, 0.0, 0.0};         ///< joint angles at power-up [rad] (the home pose)
  std::array<std::int32_t, 3> unhomed_offset{1234, -567, 89};  ///< encoder offset until homed [counts]
  Hand hand{};

  /// @throws std::invalid_argument naming the first parameter that makes no sense.
  void validate() const {
    kinematics.validate();
    hand.path.validate();
    const auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
    for (int i = 0; i < 3; ++i) {
      if (!pos(inertia[i])) throw std::invalid_argument("SimulatedArmConfig: inertia must be finite and > 0 [kg m^2]");
      if (!std::isfinite(viscous[i]) || viscous[i] < 0.0)
        throw std::invalid_argument("SimulatedArmConfig: viscous must be finite and >= 0 [N m s/rad]");
      if (!std::isfinite(coulomb[i]) || coulomb[i] < 0.0)
        throw std::invalid_argument("SimulatedArmConfig: coulomb must be finite and >= 0 [N m]");
    }
    if (!pos(rate) || rate > 20000.0)
      throw std::invalid_argument("SimulatedArmConfig: rate must be in (0, 20000] [Hz]");
    if (substeps < 1 || substeps > 100) throw std::invalid_argument("SimulatedArmConfig: substeps must be 1..100");
    if (!pos(watchdog) || watchdog > 0.065)
      throw std::invalid_argument("SimulatedArmConfig: watchdog must be in (0, 0.065] [s]");
    if (homing_ticks < 0) throw std::invalid_argument("SimulatedArmConfig: homing_ticks must be >= 0");
    if (!pos(torque_unit)) throw std::invalid_argument("SimulatedArmConfig: torque_unit must be finite and > 0 [N m]");
    if (!pos(max_force) || !pos(continuous_force) || continuous_force > max_force)
      throw std::invalid_argument("SimulatedArmConfig: forces must be finite, > 0, continuous <= max [N]");
    if (!pos(hand.stiffness) && hand.holding)
      throw std::invalid_argument("Hand: stiffness must be finite and > 0 [N/m]");
    if (!std::isfinite(hand.damping) || hand.damping < 0.0)
      throw std::invalid_argument("Hand: damping must be finite and >= 0 [N s/m]");
  }
};

/// The arm's mechanics alone: joint dynamics (inertia, viscous and Coulomb
/// friction, joint stops) under applied torques and the scripted hand.
/// SimulatedArm runs its own firmware model on it; FirmwareLoopback
/// (firmware_loopback.hpp) runs the reference firmware core on it.
class ArmPlant {
 public:
  /// @throws std::invalid_argument when the configuration makes no sense.
  explicit ArmPlant(const SimulatedArmConfig& config) : config_(config) {
    config_.validate();
    kin_ = PhantomKinematics(config_.kinematics);
    q_ = config_.initial_q;
  }

  /// Integrates one firmware period (config().substeps steps) under the
  /// joint torques tau [N m], starting at time t [s] (the hand's clock).
  void period(const glm::dvec3& tau, double t) noexcept {
    const double h = 1.0 / (config_.rate * config_.substeps);
    for (int k = 0; k < config_.substeps; ++k)
      step(tau, t + k * h, h);
  }

  void set_hand(const Hand& hand) {
    hand.path.validate();
    config_.hand = hand;
  }

  [[nodiscard]] glm::dvec3 q() const noexcept { return q_; }
  [[nodiscard]] glm::dvec3 qdot() const noexcept { return qd_; }
  [[nodiscard]] glm::dvec3 position() const noexcept { return kin_.forward(q_); }
  [[nodiscard]] glm::dvec3 velocity() const noexcept { return kin_.velocity(q_, qd_); }
  /// Force the scripted hand applies to the handle in the last substep [N].
  [[nodiscard]] glm::dvec3 hand_force() const noexcept { return hand_force_; }
  [[nodiscard]] double kinetic_energy() const noexcept {
    return 0.5 *
           (config_.inertia.x * qd_.x * qd_.x + config_.inertia.y * qd_.y * qd_.y + config_.inertia.z * qd_.z * qd_.z);
  }
  [[nodiscard]] const SimulatedArmConfig& config() const noexcept { return config_; }
  [[nodiscard]] const PhantomKinematics& kinematics() const noexcept { return kin_; }

 private:
  void step(const glm::dvec3& applied, double t, double h) noexcept {
    const glm::dvec3 p = kin_.forward(q_);
    const glm::dvec3 v = kin_.velocity(q_, qd_);
    glm::dvec3 tau_hand{0.0};
    hand_force_ = glm::dvec3{0.0};
    if (config_.hand.holding) {
      const glm::dvec3 target = config_.hand.path.at(t);
      const glm::dvec3 target_v = (config_.hand.path.at(t + 1e-4) - target) / 1e-4;
      hand_force_ = config_.hand.stiffness * (target - p) + config_.hand.damping * (target_v - v);
      tau_hand = kin_.torques(q_, hand_force_);
    }
    step_joints({config_.inertia, config_.viscous, config_.coulomb, config_.kinematics.q_min, config_.kinematics.q_max},
                applied + tau_hand, h, q_, qd_);
  }

  SimulatedArmConfig config_;
  PhantomKinematics kin_{};
  glm::dvec3 q_{0.0};
  glm::dvec3 qd_{0.0};
  glm::dvec3 hand_force_{0.0};
};

/// The simulated arm and its firmware. tick() runs one firmware period.
class SimulatedArm {
 public:
  /// @throws std::invalid_argument when the configuration makes no sense.
  explicit SimulatedArm(SimulatedArmConfig config = {}) : config_(std::move(config)), plant_(config_) {
    watchdog_ticks_ = static_cast<std::int64_t>(std::ceil(config_.watchdog * config_.rate - 1e-9));
  }

  /// Handles an output (command) report; invalid ones are counted and ignored.
  void receive(std::span<const std::uint8_t> bytes) noexcept {
    protocol::CommandReport cmd;
    if (protocol::decode(bytes, cmd) != Status::ok) {
      ++rejected_;
      return;
    }
    ++accepted_;
    last_command_ = cmd;
    last_valid_tick_ = tick_;
    if ((cmd.flags & protocol::command_flags::home) && !homed_ && homing_left_ < 0) homing_left_ = config_.homing_ticks;
    if (cmd.flags & protocol::command_flags::arm) {
      if (homed_ && !(faults_ & status_bits::any_fault)) armed_ = true;
    } else {
      armed_ = false;
    }
    for (std::size_t i = 0; i < 3; ++i)
      command_torque_[static_cast<int>(i)] = cmd.torque_mnm[i] * config_.torque_unit;
  }

  /// Gets a feature report (device info or configuration); buffer[0] is the id.
  Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) const noexcept {
    if (buffer.empty()) return Status::short_report;
    if (buffer[0] == static_cast<std::uint8_t>(protocol::ReportId::device_info)) {
      protocol::DeviceInfoReport r;
      for (std::size_t i = 0; i < 3; ++i) {
        const int k = static_cast<int>(i);
        r.counts_per_rev[i] = static_cast<std::uint32_t>(config_.kinematics.counts_per_rev[i]);
        r.max_torque_mnm[i] = static_cast<std::uint16_t>(std::lround(config_.kinematics.max_torque[k] * 1e3));
        r.q_min_mrad[i] = static_cast<std::int16_t>(std::lround(config_.kinematics.q_min[k] * 1e3));
        r.q_max_mrad[i] = static_cast<std::int16_t>(std::lround(config_.kinematics.q_max[k] * 1e3));
      }
      r.torque_unit_unm = static_cast<std::uint16_t>(std::lround(config_.torque_unit * 1e6));
      r.l1_um = static_cast<std::uint32_t>(std::lround(config_.kinematics.l1 * 1e6));
      r.l2_um = static_cast<std::uint32_t>(std::lround(config_.kinematics.l2 * 1e6));
      r.max_force_mn = static_cast<std::uint16_t>(std::lround(config_.max_force * 1e3));
      r.continuous_force_mn = static_cast<std::uint16_t>(std::lround(config_.continuous_force * 1e3));
      r.rate_hz = static_cast<std::uint16_t>(std::lround(config_.rate));
      size = protocol::encode(r, buffer);
      return size ? Status::ok : Status::short_report;
    }
    if (buffer[0] == static_cast<std::uint8_t>(protocol::ReportId::configuration)) {
      protocol::ConfigurationReport r;
      r.watchdog_us =
          static_cast<std::uint16_t>(std::lround(static_cast<double>(watchdog_ticks_) / config_.rate * 1e6));
      size = protocol::encode(r, buffer);
      return size ? Status::ok : Status::short_report;
    }
    return Status::unknown_report;
  }

  /// Sends a feature report (configuration or control).
  Status send_feature(std::span<const std::uint8_t> bytes) noexcept {
    if (bytes.empty()) return Status::short_report;
    if (bytes[0] == static_cast<std::uint8_t>(protocol::ReportId::configuration)) {
      protocol::ConfigurationReport r;
      if (const Status s = protocol::decode(bytes, r); s != Status::ok) return s;
      watchdog_ticks_ = std::max<std::int64_t>(1, std::llround(r.watchdog_us * 1e-6 * config_.rate));
      return Status::ok;
    }
    protocol::ControlOp op;
    if (const Status s = protocol::decode(bytes, op); s != Status::ok) return s;
    switch (op) {
      case protocol::ControlOp::arm:
        if (!homed_) return Status::not_homed;
        if (faults_ & status_bits::any_fault) return Status::fault;
        armed_ = true;
        last_valid_tick_ = tick_;
        return Status::ok;
      case protocol::ControlOp::disarm:
        armed_ = false;
        return Status::ok;
      case protocol::ControlOp::clear_fault:
        if (armed_) return Status::bad_value;  // only while disarmed
        faults_ &= static_cast<std::uint16_t>(
            ~(status_bits::watchdog_tripped | status_bits::over_current | status_bits::over_temperature));
        return Status::ok;
      case protocol::ControlOp::home:
        if (!homed_ && homing_left_ < 0) homing_left_ = config_.homing_ticks;
        return Status::ok;
    }
    return Status::bad_value;
  }

  /// Runs one firmware period: watchdog, homing, torque output, dynamics.
  void tick() noexcept {
    ++tick_;
    if (homing_left_ >= 0 && homing_left_-- == 0) homed_ = true;
    if (armed_ && tick_ - last_valid_tick_ > watchdog_ticks_) {
      armed_ = false;
      faults_ |= status_bits::watchdog_tripped;
    }
    if (faults_ & status_bits::any_fault) armed_ = false;
    glm::dvec3 tau{0.0};
    if (armed_) {
      for (int i = 0; i < 3; ++i) {
        const double limit = config_.kinematics.max_torque[i];
        tau[i] = std::round(std::clamp(command_torque_[i], -limit, limit) / config_.torque_unit) * config_.torque_unit;
      }
    }
    applied_torque_ = tau;
    plant_.period(tau, time());
  }

  /// The state report for the current tick (sequence increments each call).
  [[nodiscard]] protocol::StateReport report() noexcept {
    protocol::StateReport r;
    r.sequence = ++sequence_;
    r.command_echo = last_command_.sequence;
    const double since_boot = static_cast<double>(tick_ - boot_tick_) / config_.rate;  // [s]
    r.timestamp_us =
        static_cast<std::uint32_t>(static_cast<std::uint64_t>(std::llround(since_boot * 1e6)) & 0xFFFFFFFFu);
    r.encoder = plant_.kinematics().counts(plant_.q());
    if (!homed_)
      for (std::size_t i = 0; i < 3; ++i)
        r.encoder[i] += config_.unhomed_offset[i];
    r.status =
        static_cast<std::uint16_t>(faults_ | (homed_ ? status_bits::homed : 0) | (armed_ ? status_bits::armed : 0));
    r.buttons = buttons_;
    for (std::size_t i = 0; i < 3; ++i)
      r.torque_mnm[i] =
          static_cast<std::int16_t>(std::lround(applied_torque_[static_cast<int>(i)] / config_.torque_unit));
    return r;
  }

  /// The firmware restarts (a brown-out, a reset button): sequence numbers
  /// and the timestamp start again from zero, the arm is unhomed and
  /// disarmed, latched faults are gone; the mechanics keep moving.
  void reboot() noexcept {
    sequence_ = 0;
    boot_tick_ = tick_;
    homed_ = false;
    homing_left_ = -1;
    armed_ = false;
    faults_ &= status_bits::estop;
    last_command_ = {};
    last_valid_tick_ = tick_;
    ++boots_;
  }
  [[nodiscard]] int boots() const noexcept { return boots_; }

  /// Latches a fault bit (over-current, over-temperature) or holds e-stop.
  void inject_fault(std::uint16_t bits) noexcept { faults_ |= bits; }
  void release_estop() noexcept { faults_ &= static_cast<std::uint16_t>(~status_bits::estop); }
  void set_buttons(std::uint8_t b) noexcept { buttons_ = b; }
  void set_hand(const Hand& hand) {
    plant_.set_hand(hand);
    config_.hand = hand;
  }

  [[nodiscard]] double time() const noexcept { return static_cast<double>(tick_) / config_.rate; }
  [[nodiscard]] std::int64_t ticks() const noexcept { return tick_; }
  [[nodiscard]] glm::dvec3 q() const noexcept { return plant_.q(); }
  [[nodiscard]] glm::dvec3 qdot() const noexcept { return plant_.qdot(); }
  [[nodiscard]] glm::dvec3 position() const noexcept { return plant_.position(); }
  [[nodiscard]] glm::dvec3 velocity() const noexcept { return plant_.velocity(); }
  [[nodiscard]] glm::dvec3 applied_torque() const noexcept { return applied_torque_; }
  /// Force the scripted hand applies to the handle in the last substep [N].
  [[nodiscard]] glm::dvec3 hand_force() const noexcept { return plant_.hand_force(); }
  [[nodiscard]] double kinetic_energy() const noexcept { return plant_.kinetic_energy(); }
  [[nodiscard]] bool armed() const noexcept { return armed_; }
  [[nodiscard]] bool homed() const noexcept { return homed_; }
  [[nodiscard]] std::uint16_t faults() const noexcept { return faults_; }
  [[nodiscard]] const protocol::CommandReport& last_command() const noexcept { return last_command_; }
  [[nodiscard]] std::uint64_t commands_accepted() const noexcept { return accepted_; }
  [[nodiscard]] std::uint64_t commands_rejected() const noexcept { return rejected_; }
  [[nodiscard]] const SimulatedArmConfig& config() const noexcept { return config_; }
  [[nodiscard]] const PhantomKinematics& kinematics() const noexcept { return plant_.kinematics(); }
  [[nodiscard]] const ArmPlant& plant() const noexcept { return plant_; }

 private:
  SimulatedArmConfig config_;
  ArmPlant plant_;
  glm::dvec3 command_torque_{0.0};
  glm::dvec3 applied_torque_{0.0};
  protocol::CommandReport last_command_{};
  std::int64_t tick_{0};
  std::int64_t last_valid_tick_{0};
  std::int64_t watchdog_ticks_{20};
  std::uint64_t accepted_{0};
  std::uint64_t rejected_{0};
  int homing_left_{-1};
  std::uint16_t sequence_{0};
  std::int64_t boot_tick_{0};
  int boots_{0};
  std::uint16_t faults_{0};
  std::uint8_t buttons_{0};
  bool homed_{false};
  bool armed_{false};
};

}  // namespace hapticfield
