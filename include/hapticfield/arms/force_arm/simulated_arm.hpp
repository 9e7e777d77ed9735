#pragma once
/// @file simulated_arm.hpp
/// A deterministic Phantom-class arm on a virtual clock, the firmware twin:
/// joint dynamics (inertia, viscous and Coulomb friction, joint stops) held
/// by the scripted hand (simulation/scripted_hand.hpp), encoders and
/// motors, and the reference firmware core (firmware/core.hpp) that runs
/// the protocol, the watchdog, homing, fault latching and the limits. It
/// speaks the report protocol through SimulatedTransport
/// (simulated_transport.hpp).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/arms/force_arm/kinematics.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/status.hpp"
#include "hapticfield/firmware/core.hpp"
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
/// SimulatedArm runs the reference firmware core on it.
class ArmPlant {
 public:
  /// @throws std::invalid_argument when the configuration makes no sense.
  explicit ArmPlant(const SimulatedArmConfig& config) : config_(config) {
    config_.validate();
    kin_ = PhantomKinematics(config_.kinematics);
    q_ = config_.initial_q;
    home_ = kin_.forward(q_);
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
  /// Docked, the hand (when it holds the handle) holds it at the home pose
  /// instead of following its path: the user docks the arm while it homes.
  /// Its path starts again from its beginning when it leaves the dock.
  void set_docked(bool docked) noexcept { docked_ = docked; }

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
      if (docked_) path_start_ = t + h;  // the path's clock starts when the hand leaves the dock
      const double s = t - path_start_;  // [s] along the path
      const glm::dvec3 target = docked_ ? home_ : config_.hand.path.at(s);
      const glm::dvec3 target_v = docked_ ? glm::dvec3{0.0} : (config_.hand.path.at(s + 1e-4) - target) / 1e-4;
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
  glm::dvec3 home_{0.0};    ///< handle position at the home pose [m]
  double path_start_{0.0};  ///< when the hand left the dock [s]
  bool docked_{false};
};

/// The firmware configuration that describes a simulated arm (geometry,
/// limits, rate, homing), with the given watchdog [us]. The current limit
/// is set so that it never cuts below the joint saturation.
/// @throws std::invalid_argument when the result fails FirmwareConfig::check().
[[nodiscard]] inline firmware::FirmwareConfig firmware_config_for(const SimulatedArmConfig& arm,
                                                                  std::uint16_t watchdog_us = 5000) {
  arm.validate();
  firmware::FirmwareConfig f;
  for (std::size_t i = 0; i < 3; ++i) {
    const int k = static_cast<int>(i);
    f.counts_per_rev[i] = static_cast<std::uint32_t>(arm.kinematics.counts_per_rev[i]);
    f.max_torque_mnm[i] =
        static_cast<std::uint16_t>(std::clamp(std::lround(arm.kinematics.max_torque[k] * 1e3), 1L, 65535L));
    f.q_min_mrad[i] = static_cast<std::int16_t>(std::lround(arm.kinematics.q_min[k] * 1e3));
    f.q_max_mrad[i] = static_cast<std::int16_t>(std::lround(arm.kinematics.q_max[k] * 1e3));
    // current [mA] = torque [uN m] / torque_constant [uN m/mA]; keep it within 16 bits
    const std::uint32_t saturation_unm = f.max_torque_mnm[i] * 1000u;
    const std::uint32_t constant = std::max<std::uint32_t>(100u, (saturation_unm + 32766u) / 32767u);
    f.torque_constant[i] = static_cast<std::uint16_t>(constant);
    f.max_current_ma[i] = static_cast<std::uint16_t>((saturation_unm + constant - 1u) / constant);
  }
  f.torque_unit_unm = static_cast<std::uint16_t>(std::clamp(std::lround(arm.torque_unit * 1e6), 0L, 65535L));
  f.l1_um = static_cast<std::uint32_t>(std::lround(arm.kinematics.l1 * 1e6));
  f.l2_um = static_cast<std::uint32_t>(std::lround(arm.kinematics.l2 * 1e6));
  f.max_force_mn = static_cast<std::uint16_t>(std::clamp(std::lround(arm.max_force * 1e3), 0L, 65535L));
  f.continuous_force_mn = static_cast<std::uint16_t>(std::clamp(std::lround(arm.continuous_force * 1e3), 0L, 65535L));
  f.period_us = static_cast<std::uint32_t>(std::lround(1e6 / arm.rate));
  f.watchdog_us = watchdog_us;
  f.homing_ticks = static_cast<std::uint16_t>(std::min(arm.homing_ticks, 65535));
  if (const char* e = f.check()) throw std::invalid_argument(std::string("FirmwareConfig: ") + e);
  return f;
}

/// The arm's firmware twin: the reference firmware core
/// (firmware/core.hpp) on the arm's mechanics (ArmPlant), one firmware
/// period per tick(), in the order a real board runs it (firmware/board.hpp,
/// step_hid): the commands received since the last period are decoded, the
/// board's inputs are read (encoders at the start of the period), the core
/// ticks, the limited torques drive the mechanics for one period, and the
/// state report carries the encoders read at its start. A command computed
/// from that report therefore acts one period later, as on the board
/// (docs/firmware.md, "The firmware twin").
class SimulatedArm {
 public:
  static constexpr double home_tolerance = 0.02;  ///< the dock sensor sees the arm at home within this [rad]

  /// The firmware watchdog is config.watchdog.
  /// @throws std::invalid_argument when the configuration makes no sense.
  explicit SimulatedArm(const SimulatedArmConfig& config = {})
      : SimulatedArm(config, firmware_config_for(config, watchdog_us(config))) {}
  /// @throws std::invalid_argument when the configuration makes no sense.
  SimulatedArm(const SimulatedArmConfig& config, std::uint16_t watchdog_us)
      : SimulatedArm(config, firmware_config_for(config, watchdog_us)) {}
  /// Any firmware configuration (limits, current, homing) on these mechanics.
  /// @throws std::invalid_argument when either configuration makes no sense.
  SimulatedArm(const SimulatedArmConfig& config, const firmware::FirmwareConfig& firmware)
      : config_(config), plant_(config), core_(firmware) {
    if (const char* e = firmware.check()) throw std::invalid_argument(std::string("FirmwareConfig: ") + e);
    period_us_ = firmware.period_us;
  }

  /// One firmware period: board inputs from the mechanics, core tick, the
  /// limited torques drive the mechanics.
  void tick() noexcept {
    ++ticks_;
    firmware::BoardInputs in;
    in.now_us = static_cast<std::uint32_t>((static_cast<std::uint64_t>(ticks_) * period_us_) & 0xFFFFFFFFu);
    const auto counts = plant_.kinematics().counts(plant_.q());
    for (std::size_t i = 0; i < 3; ++i)  // incremental counters start at an arbitrary value
      in.encoder[i] = static_cast<std::int32_t>(static_cast<std::uint32_t>(counts[i]) +
                                                static_cast<std::uint32_t>(config_.unhomed_offset[i]));
    in.at_home = true;  // no dock sensor: homing takes the pose it finds as home
    for (int i = 0; i < 3 && dock_sensor_; ++i)
      if (std::fabs(plant_.q()[i] - config_.initial_q[i]) > home_tolerance) in.at_home = false;
    in.buttons = buttons_;
    in.estop = estop_;
    in.over_current = over_current_;
    in.over_temperature = over_temperature_;
    over_current_ = over_temperature_ = false;  // the driver pulses its flag; the core latches it
    const firmware::MotorOutputs& out = core_.tick(in);
    const double unit = core_.config().torque_unit_unm * 1e-6;  // [N m]
    applied_ = glm::dvec3{out.torque[0] * unit, out.torque[1] * unit, out.torque[2] * unit};
    plant_.set_docked(core_.homing());  // the hand docks the arm while it homes, then follows its path
    plant_.period(applied_, time());
  }

  /// Handles an output (command) report; invalid ones are counted and ignored.
  void receive(std::span<const std::uint8_t> bytes) noexcept { core_.receive(bytes); }
  /// Gets a feature report (device info or configuration); buffer[0] is the id.
  Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) noexcept {
    size = 0;
    if (buffer.empty()) return Status::short_report;
    return core_.get_feature(buffer[0], buffer, size);
  }
  /// Sends a feature report (configuration or control).
  Status send_feature(std::span<const std::uint8_t> bytes) noexcept { return core_.set_feature(bytes); }

  /// The state report encoded by the last tick(), as on the wire.
  [[nodiscard]] std::span<const std::uint8_t> report_bytes() const noexcept { return core_.report(); }
  /// The state report of the last tick(), decoded.
  [[nodiscard]] protocol::StateReport report() const noexcept {
    protocol::StateReport r;
    if (protocol::decode(core_.report(), r) != Status::ok) return {};
    return r;
  }

  /// The firmware restarts (a brown-out, a reset button): sequence numbers
  /// and the timestamp start again from zero, the arm is unhomed and
  /// disarmed, latched faults are gone; the mechanics keep moving.
  void reboot() noexcept {
    core_.reset();
    ++boots_;
  }
  [[nodiscard]] int boots() const noexcept { return boots_; }

  /// Board inputs. E-stop holds while pressed; a driver flag latches in
  /// the core at the next tick.
  void set_estop(bool pressed) noexcept { estop_ = pressed; }
  void flag_over_current() noexcept { over_current_ = true; }
  void flag_over_temperature() noexcept { over_temperature_ = true; }
  /// e-stop (held until release_estop()), over-current, over-temperature
  /// (latched) as board inputs at the next tick; other bits are ignored.
  void inject_fault(std::uint16_t bits) noexcept {
    if (bits & status_bits::estop) estop_ = true;
    if (bits & status_bits::over_current) over_current_ = true;
    if (bits & status_bits::over_temperature) over_temperature_ = true;
  }
  void release_estop() noexcept { estop_ = false; }
  void set_buttons(std::uint8_t b) noexcept { buttons_ = b; }
  /// With a dock sensor, homing completes only while the arm rests within
  /// home_tolerance of its home pose; without one (the default) the board
  /// reports at home always, as a board whose user docks it before homing.
  void set_dock_sensor(bool on) noexcept { dock_sensor_ = on; }
  void set_hand(const Hand& hand) {
    plant_.set_hand(hand);
    config_.hand = hand;
  }

  /// Time of the last tick on the firmware clock [s].
  [[nodiscard]] double time() const noexcept { return static_cast<double>(ticks_) * period_us_ * 1e-6; }
  [[nodiscard]] std::int64_t ticks() const noexcept { return ticks_; }
  [[nodiscard]] std::uint32_t period_us() const noexcept { return period_us_; }
  [[nodiscard]] glm::dvec3 q() const noexcept { return plant_.q(); }
  [[nodiscard]] glm::dvec3 qdot() const noexcept { return plant_.qdot(); }
  [[nodiscard]] glm::dvec3 position() const noexcept { return plant_.position(); }
  [[nodiscard]] glm::dvec3 velocity() const noexcept { return plant_.velocity(); }
  /// Joint torques the core let through in the last tick [N m].
  [[nodiscard]] glm::dvec3 applied_torque() const noexcept { return applied_; }
  /// Force the scripted hand applies to the handle in the last substep [N].
  [[nodiscard]] glm::dvec3 hand_force() const noexcept { return plant_.hand_force(); }
  [[nodiscard]] double kinetic_energy() const noexcept { return plant_.kinetic_energy(); }
  [[nodiscard]] bool armed() const noexcept { return core_.armed(); }
  [[nodiscard]] bool homed() const noexcept { return core_.homed(); }
  [[nodiscard]] std::uint16_t faults() const noexcept { return core_.faults(); }
  [[nodiscard]] const protocol::CommandReport& last_command() const noexcept { return core_.last_command(); }
  [[nodiscard]] std::uint64_t commands_accepted() const noexcept { return core_.counters().commands; }
  /// Reports the core refused (bad CRC, short, unknown, wrong version, bad value).
  [[nodiscard]] std::uint64_t commands_rejected() const noexcept {
    const firmware::FirmwareCounters& c = core_.counters();
    return std::uint64_t{c.bad_crc} + c.short_report + c.unknown + c.bad_version + c.bad_value;
  }
  [[nodiscard]] const SimulatedArmConfig& config() const noexcept { return config_; }
  [[nodiscard]] const PhantomKinematics& kinematics() const noexcept { return plant_.kinematics(); }
  [[nodiscard]] ArmPlant& plant() noexcept { return plant_; }
  [[nodiscard]] const ArmPlant& plant() const noexcept { return plant_; }
  [[nodiscard]] firmware::FirmwareCore& core() noexcept { return core_; }
  [[nodiscard]] const firmware::FirmwareCore& core() const noexcept { return core_; }

 private:
  /// config.watchdog in whole microseconds (validated first: (0, 0.065] s).
  static std::uint16_t watchdog_us(const SimulatedArmConfig& config) {
    config.validate();
    return static_cast<std::uint16_t>(std::lround(config.watchdog * 1e6));
  }

  SimulatedArmConfig config_;
  ArmPlant plant_;
  firmware::FirmwareCore core_;
  glm::dvec3 applied_{0.0};
  std::int64_t ticks_{0};
  std::uint32_t period_us_{1000};
  int boots_{0};
  std::uint8_t buttons_{0};
  bool dock_sensor_{false};
  bool estop_{false};
  bool over_current_{false};
  bool over_temperature_{false};
};

}  // namespace hapticfield
