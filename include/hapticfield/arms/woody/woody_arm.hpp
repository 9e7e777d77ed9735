#pragma once
/// @file woody_arm.hpp
/// WoodyArm: the Device for WoodenHaptics-family arms over any Transport,
/// speaking P1 (8-byte HID), P2 (14-byte HID) or P4 (bracketed text, one
/// line per transport read) (arm-protocols.md section 1). Encoders to
/// position with the serial woody kinematics (section 2), force to motor
/// currents, clamped to the generation's current limit.

#include <time.h>

#include <array>
#include <climits>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include <glm/vec3.hpp>

#include "hapticfield/arms/woody/woody_codec.hpp"
#include "hapticfield/arms/woody/woody_kinematics.hpp"
#include "hapticfield/core/error.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/transport.hpp"

namespace hapticfield {

/// Largest current the host sends, per generation [A].
/// P1: the host clamps to +-3 A (section 1, P1). P2: the mbed firmware's
/// PWM reaches full scale at 3 A (section 1, P2). P4: the firmware zeroes
/// |mA| > 6000, so the host stays at 5999 mA (section 1, P2 Teensy / P4).
[[nodiscard]] constexpr double woody_current_limit(woody::Generation g) noexcept {
  return g == woody::Generation::p4_text ? 5.999 : 3.0;
}

/// Host encoder signs per generation: P1 negates enc_a (section 1, P1); the
/// sources state no flip for P2 and P4.
[[nodiscard]] constexpr std::array<int, 3> woody_encoder_sign(woody::Generation g) noexcept {
  return g == woody::Generation::p1_hid8 ? std::array<int, 3>{-1, 1, 1} : std::array<int, 3>{1, 1, 1};
}

struct WoodyArmConfig {
  woody::Generation generation{woody::Generation::p4_text};
  WoodyKinematicsConfig kinematics{};                ///< a woody_presets:: preset
  std::array<int, 3> encoder_sign{1, 1, 1};          ///< host sign of each raw encoder (+1 or -1)
  double max_current{5.999};                         ///< current clamp [A], at most woody_current_limit()
  double velocity_cutoff{100.0};                     ///< first-order low-pass on the velocity estimate [Hz]
  TimeSource now{};                                  ///< host time [ns] for the velocity; empty: CLOCK_MONOTONIC
  int wake_attempts{50};                             ///< P2/P4: zero frames sent at construction before giving up
  int wake_timeout_us{10000};                        ///< P2/P4: wait for a reply after each [us]
  std::array<std::int16_t, 6> calibration_counts{};  ///< P2: counters set by the calibrate command [counts]
  /// The joints' range [rad] as we assume it: the sources publish no joint
  /// limits, so these are the simulated arm's stops widened by 0.3-0.4 rad;
  /// set your arm's. A report whose angles lie further than joint_margin
  /// outside is impossible: refused, read() returns Status::impossible.
  glm::dvec3 q_min{-1.5, -0.8, -0.4};
  glm::dvec3 q_max{1.5, 1.8, 2.6};
  double joint_margin{0.1};  ///< [rad] (5.7 deg)

  /// Defaults for a generation: its encoder signs and current limit.
  [[nodiscard]] static WoodyArmConfig defaults(woody::Generation g, WoodyKinematicsConfig k = {}) {
    WoodyArmConfig c;
    c.generation = g;
    c.kinematics = std::move(k);
    c.encoder_sign = woody_encoder_sign(g);
    c.max_current = woody_current_limit(g);
    return c;
  }

  /// @throws std::invalid_argument naming the first setting that makes no sense.
  void validate() const {
    kinematics.validate();
    for (const int s : encoder_sign)
      if (s != 1 && s != -1) throw std::invalid_argument("WoodyArmConfig: encoder_sign entries must be +1 or -1");
    if (!std::isfinite(max_current) || max_current <= 0.0 || max_current > woody_current_limit(generation))
      throw std::invalid_argument("WoodyArmConfig: max_current must be finite, > 0 and <= " +
                                  std::to_string(woody_current_limit(generation)) + " [A] for this generation");
    if (!std::isfinite(velocity_cutoff) || velocity_cutoff <= 0.0)
      throw std::invalid_argument("WoodyArmConfig: velocity_cutoff must be finite and > 0 [Hz]");
    if (wake_attempts < 1 || wake_attempts > 10000)
      throw std::invalid_argument("WoodyArmConfig: wake_attempts must be 1..10000");
    if (wake_timeout_us < 0 || wake_timeout_us > 1000000)
      throw std::invalid_argument("WoodyArmConfig: wake_timeout_us must be 0..1000000 [us]");
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(q_min[i]) || !std::isfinite(q_max[i]) || !(q_min[i] < q_max[i]))
        throw std::invalid_argument("WoodyArmConfig: q_min must be finite and < q_max [rad]");
    if (!std::isfinite(joint_margin) || joint_margin < 0.0 || joint_margin > 1.0)
      throw std::invalid_argument("WoodyArmConfig: joint_margin must be within [0, 1] [rad]");
  }
};

/// Counts since construction.
struct WoodyCounters {
  std::uint64_t reports{0};        ///< states decoded
  std::uint64_t malformed{0};      ///< reports or lines that did not decode
  std::uint64_t error_replies{0};  ///< P4 replies with error bits (encoders ignored)
  std::uint64_t commands{0};       ///< frames written
  std::uint64_t write_errors{0};
  std::uint64_t calibrations{0};  ///< P2 calibrate commands sent
  std::uint64_t impossible{0};    ///< reports refused: joint angles beyond q_min/q_max and the margin
};

class WoodyArm {
 public:
  /// For P2 and P4, sends zero-current frames until a reply arrives (the
  /// wake-up rule of section 1), at most wake_attempts times.
  /// @throws std::invalid_argument for a bad configuration; hapticfield::Error
  ///         when the arm does not answer.
  explicit WoodyArm(Transport& transport, WoodyArmConfig config = WoodyArmConfig::defaults(woody::Generation::p4_text))
      : transport_(&transport), config_(std::move(config)) {
    config_.validate();
    kin_ = WoodyKinematics(config_.kinematics);
    info_.name =
        "WoodenHaptics " + config_.kinematics.name + " (" + std::string(woody::to_string(config_.generation)) + ")";
    info_.max_force = config_.kinematics.max_force;
    info_.continuous_force = config_.kinematics.max_force;  // the sources state no continuous figure
    info_.validate();
    if (config_.generation != woody::Generation::p1_hid8) wake();
  }

  [[nodiscard]] const DeviceInfo& info() const noexcept { return info_; }
  [[nodiscard]] const WoodyKinematics& kinematics() const noexcept { return kin_; }
  [[nodiscard]] const WoodyCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const WoodyArmConfig& config() const noexcept { return config_; }
  /// p4_error bits of the last P4 reply that carried any.
  [[nodiscard]] std::uint32_t last_error() const noexcept { return last_error_; }
  /// P4 model number of the last reply (0 before one).
  [[nodiscard]] std::int32_t model() const noexcept { return model_; }
  /// Currents of the last frame written [mA].
  [[nodiscard]] const std::array<std::int16_t, 3>& last_milliamps() const noexcept { return last_milliamps_; }

  /// Drains the transport and decodes the newest report. ok when a newer
  /// state was decoded, no_data when none, impossible when any report
  /// drained has joint angles beyond the range (WoodyArmConfig::q_min,
  /// q_max, joint_margin; never used), disconnected when the transport is
  /// gone. A P4 reply with error bits is counted and its encoders ignored.
  Status read(DeviceState& state) noexcept {
    bool fresh = false;
    bool impossible = false;
    Raw newest{};
    for (int i = 0; i < 256; ++i) {
      std::size_t size = 0;
      const Status s = transport_->read(buf_, size, 0);
      if (s == Status::no_data || s == Status::timeout) break;
      if (s == Status::disconnected) {
        if (fresh) update(newest, state);
        return Status::disconnected;
      }
      Raw r{};
      if (s != Status::ok || !decode(std::span<const std::uint8_t>(buf_.data(), size), r)) continue;
      if (!reachable(r)) {
        impossible = true;
        continue;
      }
      newest = r;
      fresh = true;
    }
    if (!fresh && pending_ && reachable(pending_raw_)) {
      newest = pending_raw_;
      fresh = true;
    }
    pending_ = false;
    if (impossible) return Status::impossible;
    if (!fresh) return Status::no_data;
    update(newest, state);
    return Status::ok;
  }

  /// Commands a handle force [N] in the device frame: tau = J^T F at the
  /// last pose, I = tau dir (d_cap/d_body) / Kt, clamped to max_current.
  /// Zero current when disarmed, before the first state, or for a
  /// non-finite force. P2: a pending calibration is sent instead.
  Status write(const glm::dvec3& force) noexcept {
    std::array<std::int16_t, 3> ma{};
    const bool ok = armed_ && have_state_ && std::isfinite(force.x) && std::isfinite(force.y) && std::isfinite(force.z);
    if (ok) {
      const glm::dvec3 amps = kin_.currents(kin_.torques(angles_, force));
      for (int i = 0; i < 3; ++i) {
        const double a =
            std::isfinite(amps[i]) ? std::fmax(-config_.max_current, std::fmin(config_.max_current, amps[i])) : 0.0;
        ma[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(std::lround(a * 1000.0));
      }
    }
    return send(ma);
  }

  /// Motors on or off. Off sends a zero-current frame at once, and every
  /// later write() sends zero until armed again.
  Status set_armed(bool on) noexcept {
    armed_ = on;
    if (!on) return send(std::array<std::int16_t, 3>{});
    return Status::ok;
  }

  /// P2: while the arm's calibration button flag is set, the next write
  /// sends the calibrate command (counters := calibration_counts) instead
  /// of currents; returns ok. P1 and P4 have no homing on the wire: the
  /// position is referenced to the power-on pose plus the preset's home
  /// offset; returns unsupported.
  Status request_home() noexcept {
    if (config_.generation != woody::Generation::p2_hid14) return Status::unsupported;
    if (button_flag_) calibrate_pending_ = true;
    return Status::ok;
  }

  /// P2: sends the calibrate command with the next write, whatever the
  /// button flag (the arm must be in its calibration pose). unsupported for P1/P4.
  Status calibrate() noexcept {
    if (config_.generation != woody::Generation::p2_hid14) return Status::unsupported;
    calibrate_pending_ = true;
    return Status::ok;
  }

 private:
  struct Raw {
    std::array<std::int32_t, 6> encoder{};
    std::uint8_t buttons{0};
    bool button_flag{false};
  };

  void wake() {
    for (int attempt = 0; attempt < config_.wake_attempts; ++attempt) {
      if (send(std::array<std::int16_t, 3>{}) == Status::disconnected) break;
      std::size_t size = 0;
      const Status s = transport_->read(buf_, size, config_.wake_timeout_us);
      if (s == Status::disconnected) break;
      if (s != Status::ok) continue;
      if (config_.generation == woody::Generation::p4_text && size <= 8) continue;  // "more than 8 bytes"
      Raw r{};
      if (decode(std::span<const std::uint8_t>(buf_.data(), size), r)) {
        pending_raw_ = r;
        pending_ = true;
        return;
      }
    }
    throw Error("WoodyArm: no reply from the arm after " + std::to_string(config_.wake_attempts) + " zero-current " +
                std::string(woody::to_string(config_.generation)) +
                " frames; check the port, the cable and the firmware");
  }

  /// Decodes one report; counts what does not decode or carries error bits.
  bool decode(std::span<const std::uint8_t> bytes, Raw& r) noexcept {
    switch (config_.generation) {
      case woody::Generation::p1_hid8: {
        woody::P1In in;
        if (woody::decode(bytes, in) != Status::ok) {
          ++counters_.malformed;
          return false;
        }
        for (std::size_t i = 0; i < 3; ++i)
          r.encoder[i] = in.encoder[i];
        return true;
      }
      case woody::Generation::p2_hid14: {
        woody::P2In in;
        if (woody::decode(bytes, in) != Status::ok) {
          ++counters_.malformed;
          return false;
        }
        for (std::size_t i = 0; i < 6; ++i)
          r.encoder[i] = in.encoder[i];
        r.button_flag = in.info == 1;
        r.buttons = r.button_flag ? 1 : 0;
        return true;
      }
      case woody::Generation::p4_text: {
        woody::P4Reply in;
        if (woody::decode(bytes, in) != Status::ok) {
          ++counters_.malformed;
          return false;
        }
        model_ = in.model;
        if (in.error != 0) {  // the firmware sent its last encoders: ignore them
          ++counters_.error_replies;
          last_error_ = in.error;
          return false;
        }
        r.encoder = in.encoder;
        return true;
      }
    }
    return false;
  }

  Status send(const std::array<std::int16_t, 3>& ma) noexcept {
    std::size_t n = 0;
    std::array<std::int16_t, 3> sent = ma;
    switch (config_.generation) {
      case woody::Generation::p1_hid8:
        n = woody::encode(woody::P1Out{ma, 0}, out_);
        break;
      case woody::Generation::p2_hid14: {
        woody::P2Out m;
        m.milliamps = ma;
        if (calibrate_pending_) {
          m.command = woody::p2_command::calibrate;
          for (std::size_t i = 0; i < 3; ++i) {
            m.attr[i] = config_.calibration_counts[i];
            m.milliamps[i] = config_.calibration_counts[i + 3];
          }
          sent = {};
          calibrate_pending_ = false;
          button_flag_ = false;
          have_state_ = false;  // the counters jump: no velocity across it
          ++counters_.calibrations;
        }
        n = woody::encode(m, out_);
        break;
      }
      case woody::Generation::p4_text:
        n = woody::encode_p4_command(ma, out_);
        break;
    }
    last_milliamps_ = sent;
    const Status s = transport_->write(std::span<const std::uint8_t>(out_.data(), n));
    if (s == Status::ok)
      ++counters_.commands;
    else
      ++counters_.write_errors;
    return s;
  }

  [[nodiscard]] std::int64_t now_ns() const noexcept {
    if (config_.now) return config_.now();
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  }

  /// Host counts: sign * raw + home offset, saturated to int32 (never
  /// overflows, whatever the wire says).
  [[nodiscard]] std::array<std::int32_t, 3> host_counts(const Raw& r) const noexcept {
    std::array<std::int32_t, 3> counts{};
    for (std::size_t i = 0; i < 3; ++i) {
      const std::int64_t c = static_cast<std::int64_t>(config_.encoder_sign[i]) * r.encoder[i] +
                             static_cast<std::int64_t>(config_.kinematics.home_offset[i]);
      counts[i] = static_cast<std::int32_t>(c < INT32_MIN ? INT32_MIN : (c > INT32_MAX ? INT32_MAX : c));
    }
    return counts;
  }

  /// True when the report's joint angles lie within the assumed range (and
  /// the margin); counts the ones that do not.
  bool reachable(const Raw& r) noexcept {
    const glm::dvec3 q = kin_.angles(host_counts(r));
    for (int i = 0; i < 3; ++i)
      if (!(q[i] >= config_.q_min[i] - config_.joint_margin && q[i] <= config_.q_max[i] + config_.joint_margin)) {
        ++counters_.impossible;
        return false;
      }
    return true;
  }

  void update(const Raw& r, DeviceState& s) noexcept {
    const std::array<std::int32_t, 3> counts = host_counts(r);
    const glm::dvec3 q = kin_.angles(counts);
    const glm::dvec3 p = kin_.forward(q);
    const std::int64_t t = now_ns();
    if (have_state_) {
      const double dt = static_cast<double>(t - last_time_ns_) * 1e-9;
      if (dt > 0.0 && dt < 0.1) {
        const double alpha = 1.0 - std::exp(-2.0 * std::numbers::pi * config_.velocity_cutoff * dt);
        velocity_ += alpha * ((p - position_) / dt - velocity_);
      } else if (!(dt > 0.0)) {
        // same instant: keep the estimate
      } else {
        velocity_ = glm::dvec3{0.0};
      }
    } else {
      velocity_ = glm::dvec3{0.0};
    }
    s.device_time = static_cast<double>(t) * 1e-9;
    s.position = p;
    s.velocity = velocity_;
    s.joint_angles = q;
    s.applied_torque = glm::dvec3{0.0};  // the arms do not report it
    s.encoder = counts;
    for (std::size_t i = 0; i < 3; ++i)
      s.gimbal[i] = static_cast<std::int16_t>(std::fmax(-32768.0, std::fmin(32767.0, r.encoder[i + 3])));
    ++sequence_;
    s.sequence = sequence_;
    s.command_echo = 0;
    s.flags = static_cast<std::uint16_t>(status_bits::homed | (armed_ ? status_bits::armed : 0));
    s.buttons = r.buttons;
    s.valid = true;
    button_flag_ = r.button_flag;
    ++counters_.reports;
    angles_ = q;
    position_ = p;
    last_time_ns_ = t;
    have_state_ = true;
  }

  Transport* transport_;
  WoodyArmConfig config_;
  WoodyKinematics kin_{};
  DeviceInfo info_{};
  WoodyCounters counters_{};
  std::array<std::uint8_t, woody::p4_max_line> buf_{};
  std::array<std::uint8_t, woody::p4_max_line> out_{};
  std::array<std::int16_t, 3> last_milliamps_{};
  Raw pending_raw_{};
  glm::dvec3 angles_{0.0};
  glm::dvec3 position_{0.0};
  glm::dvec3 velocity_{0.0};
  std::int64_t last_time_ns_{0};
  std::uint32_t last_error_{0};
  std::int32_t model_{0};
  std::uint16_t sequence_{0};
  bool pending_{false};
  bool have_state_{false};
  bool armed_{false};
  bool button_flag_{false};
  bool calibrate_pending_{false};
};

static_assert(Device<WoodyArm>);

}  // namespace hapticfield
