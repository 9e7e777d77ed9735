#pragma once
/// @file simulated_woody.hpp
/// A simulated WoodenHaptics arm for tests and demos: the serial woody
/// kinematics, the joint dynamics (inertia, viscous and Coulomb friction,
/// joint stops) and the scripted Hand every simulated arm uses
/// (simulation/), and the firmware behaviour of each wire generation
/// (arm-protocols.md section 1):
///   P1: an 8-byte report every tick; 0.5 s watchdog; |I| saturates at 3 A.
///   P2: lock-step (one 14-byte report per command, one at power-up); the
///       calibrate command; 0.5 s watchdog; |I| saturates at 3 A.
///   P4: one reply line per PC frame, with error bits for malformed frames
///       and the last encoders on error; 100 ms watchdog; |mA| > 6000 -> 0.
/// SimulatedWoodyTransport connects it to a host on a time source; for P4
/// each read() returns one '\n'-terminated line and write() takes bytes.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <stdexcept>
#include <utility>

#include <glm/vec3.hpp>

#include "hapticfield/arms/woody/woody_codec.hpp"
#include "hapticfield/arms/woody/woody_kinematics.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/simulation/joint_dynamics.hpp"
#include "hapticfield/simulation/scripted_hand.hpp"

namespace hapticfield {

struct SimulatedWoodyConfig {
  woody::Generation generation{woody::Generation::p4_text};
  WoodyKinematicsConfig kinematics{};
  std::array<int, 3> encoder_sign{1, 1, 1};    ///< raw = sign * host counts (as the host expects)
  glm::dvec3 inertia{9.0e-4, 9.0e-4, 6.0e-4};  ///< effective joint inertia [kg m^2]
  glm::dvec3 viscous{2.0e-4, 2.0e-4, 2.0e-4};  ///< viscous friction [N m s/rad]
  glm::dvec3 coulomb{2.0e-3, 2.0e-3, 2.0e-3};  ///< Coulomb friction [N m]
  glm::dvec3 q_min{-1.2, -0.4, 0.0};           ///< joint stops [rad] (plausible, not published)
  glm::dvec3 q_max{1.2, 1.4, 2.2};             ///< joint stops [rad]
  /// Angles at the start [rad] (near the woody origin). The counters read
  /// zero at the rest pose (host counts = home_offset): the arm was powered
  /// on there and then moved here.
  glm::dvec3 initial_q{0.0, 0.345, 0.78};
  double rate{1000.0};  ///< firmware tick [Hz]
  int substeps{8};      ///< integration steps per tick
  Hand hand{};          ///< the scripted hand (device frame)

  /// @throws std::invalid_argument naming the first parameter that makes no sense.
  void validate() const {
    kinematics.validate();
    hand.path.validate();
    for (int i = 0; i < 3; ++i) {
      if (!(inertia[i] > 0.0) || !std::isfinite(inertia[i]))
        throw std::invalid_argument("SimulatedWoodyConfig: inertia must be finite and > 0 [kg m^2]");
      if (!(viscous[i] >= 0.0) || !(coulomb[i] >= 0.0) || !std::isfinite(viscous[i]) || !std::isfinite(coulomb[i]))
        throw std::invalid_argument("SimulatedWoodyConfig: friction must be finite and >= 0");
      if (!(q_min[i] < q_max[i])) throw std::invalid_argument("SimulatedWoodyConfig: q_min must be < q_max [rad]");
    }
    if (!(rate > 0.0 && rate <= 20000.0))
      throw std::invalid_argument("SimulatedWoodyConfig: rate must be in (0, 20000] [Hz]");
    if (substeps < 1 || substeps > 100) throw std::invalid_argument("SimulatedWoodyConfig: substeps must be 1..100");
  }
};

/// The arm and its firmware.
class SimulatedWoody {
 public:
  static constexpr double hid_watchdog = 0.5;   ///< P1/P2 watchdog [s] (section 1)
  static constexpr double text_watchdog = 0.1;  ///< P4 watchdog [s] (section 1)

  /// @throws std::invalid_argument when the configuration makes no sense.
  explicit SimulatedWoody(SimulatedWoodyConfig config = {}) : config_(std::move(config)) {
    config_.validate();
    kin_ = WoodyKinematics(config_.kinematics);
    q_ = config_.initial_q;
    const double wd = config_.generation == woody::Generation::p4_text ? text_watchdog : hid_watchdog;
    watchdog_ticks_ = static_cast<std::int64_t>(std::ceil(wd * config_.rate - 1e-9));
  }

  /// One firmware period: watchdog, current output, dynamics.
  void tick() noexcept {
    ++tick_;
    if (enabled_ && tick_ - last_valid_tick_ > watchdog_ticks_) {
      enabled_ = false;
      ++watchdog_trips_;
    }
    glm::dvec3 amps{0.0};
    if (enabled_) amps = command_amps_;
    applied_amps_ = amps;
    const glm::dvec3 tau = kin_.joint_torques(amps);
    const double h = 1.0 / (config_.rate * config_.substeps);
    for (int k = 0; k < config_.substeps; ++k)
      step(h, tau, k);
  }

  /// The P1 report of this tick (the firmware streams one per tick).
  [[nodiscard]] woody::P1In p1_report() noexcept {
    woody::P1In r;
    const auto raw = raw_counts();
    for (std::size_t i = 0; i < 3; ++i)
      r.encoder[i] = static_cast<std::int16_t>(raw[i]);
    r.debug = ++debug_;
    return r;
  }

  /// The P2 report (lock-step: after each command, and once at power-up).
  [[nodiscard]] woody::P2In p2_report() const noexcept {
    woody::P2In r;
    const auto raw = raw_counts();
    for (std::size_t i = 0; i < 3; ++i)
      r.encoder[i] = static_cast<std::int16_t>(raw[i]);
    for (std::size_t i = 0; i < 3; ++i)
      r.encoder[i + 3] = static_cast<std::int16_t>(extra_[i]);
    r.info = button_ ? 1 : 0;
    return r;
  }

  /// Handles a P1 write; false when it does not decode (ignored, no watchdog re-arm).
  bool receive_p1(std::span<const std::uint8_t> bytes) noexcept {
    woody::P1Out m;
    if (woody::decode(bytes, m) != Status::ok) {
      ++rejected_;
      return false;
    }
    set_currents(m.milliamps, 3000);
    return true;
  }

  /// Handles a P2 write (currents or calibrate).
  bool receive_p2(std::span<const std::uint8_t> bytes) noexcept {
    woody::P2Out m;
    if (woody::decode(bytes, m) != Status::ok) {
      ++rejected_;
      return false;
    }
    if (m.command == woody::p2_command::calibrate) {
      const auto raw = raw_counts();
      for (std::size_t i = 0; i < 3; ++i)
        offset_[i] += m.attr[i] - raw[i];
      for (std::size_t i = 0; i < 3; ++i)
        extra_[i] = m.milliamps[i];
      button_ = false;
      ++calibrations_;
      last_valid_tick_ = tick_;
      return true;
    }
    set_currents(m.milliamps, 3000);
    return true;
  }

  /// Handles one P4 PC frame (without its '\n') and returns the reply.
  [[nodiscard]] woody::P4Reply receive_p4(std::span<const std::uint8_t> frame) noexcept {
    std::array<std::int32_t, 3> ma{};
    const std::uint32_t err = woody::parse_p4_command(frame, ma);
    woody::P4Reply r;
    r.model = config_.kinematics.model_code;
    if (err != 0) {
      ++rejected_;
      r.encoder = last_reply_.encoder;  // the firmware returns its last encoders on error
      r.error = err;
      return r;
    }
    std::array<std::int16_t, 3> m{};
    for (std::size_t i = 0; i < 3; ++i)  // |mA| > 6000 gives zero (section 1, P4)
      m[i] = static_cast<std::int16_t>(std::abs(ma[i]) > 6000 ? 0 : ma[i]);
    set_currents(m, 6000);
    const auto raw = raw_counts();
    for (std::size_t i = 0; i < 3; ++i)
      r.encoder[i] = raw[i];
    last_reply_ = r;
    return r;
  }

  void press_calibration_button() noexcept { button_ = true; }
  void set_hand(const Hand& hand) {
    hand.path.validate();
    config_.hand = hand;
  }

  [[nodiscard]] const SimulatedWoodyConfig& config() const noexcept { return config_; }
  [[nodiscard]] const WoodyKinematics& kinematics() const noexcept { return kin_; }
  [[nodiscard]] std::int64_t ticks() const noexcept { return tick_; }
  [[nodiscard]] double time() const noexcept { return static_cast<double>(tick_) / config_.rate; }
  [[nodiscard]] glm::dvec3 q() const noexcept { return q_; }
  [[nodiscard]] glm::dvec3 position() const noexcept { return kin_.forward(q_); }
  [[nodiscard]] glm::dvec3 velocity() const noexcept { return kin_.velocity(q_, qd_); }
  [[nodiscard]] double kinetic_energy() const noexcept {
    return 0.5 *
           (config_.inertia.x * qd_.x * qd_.x + config_.inertia.y * qd_.y * qd_.y + config_.inertia.z * qd_.z * qd_.z);
  }
  /// Currents the drivers output in the last tick [A].
  [[nodiscard]] glm::dvec3 applied_current() const noexcept { return applied_amps_; }
  [[nodiscard]] glm::dvec3 hand_force() const noexcept { return hand_force_; }
  [[nodiscard]] bool enabled() const noexcept { return enabled_; }
  [[nodiscard]] std::uint64_t watchdog_trips() const noexcept { return watchdog_trips_; }
  [[nodiscard]] std::uint64_t rejected() const noexcept { return rejected_; }
  [[nodiscard]] std::uint64_t calibrations() const noexcept { return calibrations_; }
  /// Raw counters as the firmware reports them [counts].
  [[nodiscard]] std::array<std::int32_t, 3> raw_counts() const noexcept {
    auto raw = raw_from_angles();
    for (std::size_t i = 0; i < 3; ++i)
      raw[i] += offset_[i];
    return raw;
  }

 private:
  /// Raw counters from the angles alone (before the power-on / calibration offset).
  [[nodiscard]] std::array<std::int32_t, 3> raw_from_angles() const noexcept {
    auto host = kin_.counts(q_);  // host counts = sign * raw + home_offset
    for (std::size_t i = 0; i < 3; ++i)
      host[i] = config_.encoder_sign[i] * (host[i] - config_.kinematics.home_offset[i]);
    return host;
  }

  void set_currents(const std::array<std::int16_t, 3>& ma, int full_scale_ma) noexcept {
    for (std::size_t i = 0; i < 3; ++i) {
      const double a = std::fmax(-full_scale_ma, std::fmin(full_scale_ma, static_cast<double>(ma[i])));
      command_amps_[static_cast<int>(i)] = a * 1e-3;
    }
    enabled_ = true;
    last_valid_tick_ = tick_;
    ++accepted_;
  }

  void step(double h, const glm::dvec3& tau_motor, int substep) noexcept {
    glm::dvec3 tau_hand{0.0};
    hand_force_ = glm::dvec3{0.0};
    if (config_.hand.holding) {
      const double t = time() + substep * h;
      const glm::dvec3 target = config_.hand.path.at(t);
      const glm::dvec3 target_v = (config_.hand.path.at(t + 1e-4) - target) / 1e-4;
      hand_force_ = config_.hand.stiffness * (target - kin_.forward(q_)) +
                    config_.hand.damping * (target_v - kin_.velocity(q_, qd_));
      tau_hand = kin_.torques(q_, hand_force_);
    }
    step_joints({config_.inertia, config_.viscous, config_.coulomb, config_.q_min, config_.q_max}, tau_motor + tau_hand,
                h, q_, qd_);
  }

  SimulatedWoodyConfig config_;
  WoodyKinematics kin_{};
  glm::dvec3 q_{0.0};
  glm::dvec3 qd_{0.0};
  glm::dvec3 command_amps_{0.0};
  glm::dvec3 applied_amps_{0.0};
  glm::dvec3 hand_force_{0.0};
  std::array<std::int32_t, 3> offset_{};
  std::array<std::int32_t, 3> extra_{};
  woody::P4Reply last_reply_{};
  std::int64_t tick_{0};
  std::int64_t last_valid_tick_{0};
  std::int64_t watchdog_ticks_{500};
  std::uint64_t watchdog_trips_{0};
  std::uint64_t accepted_{0};
  std::uint64_t rejected_{0};
  std::uint64_t calibrations_{0};
  std::uint16_t debug_{0};
  bool enabled_{false};
  bool button_{false};
};

/// In-memory link between a host and a SimulatedWoody on a time source.
/// HID generations: one report per read(). P4: one line per read(), and
/// write() takes any bytes (frames end at '\n'; NUL padding is ignored).
class SimulatedWoodyTransport final : public Transport {
 public:
  static constexpr std::size_t queue_capacity = 64;  ///< queued reports / lines

  /// @param now time source [ns]; firmware tick k runs at start + k / rate.
  SimulatedWoodyTransport(SimulatedWoody& arm, TimeSource now) : arm_(&arm), now_(std::move(now)) {
    if (!now_) throw std::invalid_argument("SimulatedWoodyTransport: a time source is required");
    period_ns_ = static_cast<std::int64_t>(1e9 / arm.config().rate + 0.5);
    start_ns_ = now_();
  }

  /// Runs the arm up to now, queueing P1 reports (and P2's power-up report).
  void advance() noexcept {
    const std::int64_t now = now_();
    while (start_ns_ + (arm_->ticks() + 1) * period_ns_ <= now) {
      arm_->tick();
      const auto g = arm_->config().generation;
      if (g == woody::Generation::p1_hid8 && !stalled_) {
        Slot s;
        s.size = woody::encode(wild(arm_->p1_report()), s.bytes);
        push(s);
      }
      if (g == woody::Generation::p2_hid14 && !booted_) {
        booted_ = true;
        Slot s;
        s.size = woody::encode(wild(arm_->p2_report()), s.bytes);
        push(s);
      }
    }
  }

  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int /*timeout_us*/) noexcept override {
    advance();
    if (count_ == 0) return Status::no_data;
    const Slot& s = queue_[head_];
    if (buffer.size() < s.size) return Status::short_report;
    std::memcpy(buffer.data(), s.bytes.data(), s.size);
    size = s.size;
    head_ = (head_ + 1) % queue_capacity;
    --count_;
    return Status::ok;
  }

  Status write(std::span<const std::uint8_t> report) noexcept override {
    advance();
    ++writes_;
    if (stalled_) return Status::ok;  // lost on the wire
    switch (arm_->config().generation) {
      case woody::Generation::p1_hid8:
        arm_->receive_p1(report);
        break;
      case woody::Generation::p2_hid14:
        if (arm_->receive_p2(report)) {
          Slot s;
          s.size = woody::encode(wild(arm_->p2_report()), s.bytes);
          push(s);
        }
        break;
      case woody::Generation::p4_text:
        for (const std::uint8_t c : report) {
          if (c != '\n') {
            if (line_size_ < line_.size()) line_[line_size_] = c;
            ++line_size_;  // an overlong frame still ends at '\n'; the firmware says buffer full
            continue;
          }
          reply(std::span<const std::uint8_t>(line_.data(), std::min(line_size_, line_.size())),
                line_size_ > line_.size());
          line_size_ = 0;
        }
        break;
    }
    return Status::ok;
  }

  Status get_feature(std::span<std::uint8_t>, std::size_t&) noexcept override { return Status::unsupported; }
  Status send_feature(std::span<const std::uint8_t>) noexcept override { return Status::unsupported; }

  /// While stalled nothing passes either way (a hung USB link).
  void set_stalled(bool on) noexcept { stalled_ = on; }
  /// While on, every report carries encoder counts at the extremes of its
  /// field (P1/P2: +-32767, P4: +-2^31), well formed otherwise (a firmware
  /// bug, a corrupted counter).
  void set_wild_counts(bool on) noexcept { wild_ = on; }
  [[nodiscard]] std::uint64_t writes() const noexcept { return writes_; }
  [[nodiscard]] std::uint64_t overflows() const noexcept { return overflows_; }
  [[nodiscard]] SimulatedWoody& arm() noexcept { return *arm_; }

 private:
  struct Slot {
    std::array<std::uint8_t, woody::p4_max_line> bytes{};
    std::size_t size{0};
  };

  template <class Report>
  [[nodiscard]] Report wild(Report r) const noexcept {
    if (!wild_) return r;
    r.encoder[0] = 32767;
    r.encoder[1] = -32767;
    r.encoder[2] = 32767;
    return r;
  }

  void reply(std::span<const std::uint8_t> frame, bool overlong) noexcept {
    woody::P4Reply r = arm_->receive_p4(overlong ? std::span<const std::uint8_t>(overlong_frame_) : frame);
    if (wild_ && r.error == 0) r.encoder = {INT32_MAX, INT32_MIN, INT32_MAX, r.encoder[3], r.encoder[4], r.encoder[5]};
    Slot s;
    s.size = woody::encode(r, s.bytes);
    push(s);
  }

  void push(const Slot& s) noexcept {
    if (count_ == queue_capacity) {
      head_ = (head_ + 1) % queue_capacity;
      --count_;
      ++overflows_;
    }
    queue_[(head_ + count_) % queue_capacity] = s;
    ++count_;
  }

  SimulatedWoody* arm_;
  TimeSource now_;
  std::int64_t period_ns_{1'000'000};
  std::int64_t start_ns_{0};
  std::array<Slot, queue_capacity> queue_{};
  std::size_t head_{0};
  std::size_t count_{0};
  std::array<std::uint8_t, 2 * woody::p4_firmware_buffer> line_{};
  std::size_t line_size_{0};
  /// Stands in for a frame longer than line_: more than the firmware's buffer.
  std::array<std::uint8_t, woody::p4_firmware_buffer + 1> overlong_frame_ = [] {
    std::array<std::uint8_t, woody::p4_firmware_buffer + 1> a{};
    a.fill('0');
    return a;
  }();
  std::uint64_t writes_{0};
  std::uint64_t overflows_{0};
  bool stalled_{false};
  bool booted_{false};
  bool wild_{false};
};

}  // namespace hapticfield
