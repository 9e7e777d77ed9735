#pragma once
/// @file core.hpp
/// FirmwareCore: the device side of the report protocol
/// (docs/device-protocol.md, docs/firmware.md), portable to a
/// microcontroller: no heap, no exceptions, no RTTI, no floating point,
/// only freestanding-friendly headers. It uses the host's own codecs
/// (protocol.hpp), so host and device cannot drift apart.
///
/// Per firmware period the board calls tick() with its inputs (encoder
/// counts, e-stop, driver flags) and applies the returned, already limited
/// torques/currents; then sends report(). Output reports go to receive(),
/// feature reports to get_feature()/set_feature() (USB HID), or whole
/// frames of a byte stream to handle_frame() (USB serial, StreamPort).
/// It implements sequence numbers, CRC checks, homing before arming, the
/// command watchdog, torque and current limiting and fault latching.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hapticfield/device/status.hpp"
#include "hapticfield/protocol/reports.hpp"

namespace hapticfield::firmware {

/// What the firmware is and how it limits. Defaults: an Omni-like arm
/// (the figures of docs/device-protocol.md), not a datasheet.
struct FirmwareConfig {
  std::array<std::uint32_t, 3> counts_per_rev{15000, 15000, 15000};  ///< encoder counts per joint turn
  std::array<std::uint16_t, 3> max_torque_mnm{450, 450, 450};        ///< joint torque saturation [mN m]
  std::array<std::uint16_t, 3> torque_constant{100, 100, 100};       ///< joint torque per motor current [uN m/mA]
  std::array<std::uint16_t, 3> max_current_ma{4500, 4500, 4500};     ///< motor current limit [mA]
  std::uint32_t l1_um{133000};                                       ///< upper arm [um]
  std::uint32_t l2_um{133000};                                       ///< forearm [um]
  std::array<std::int16_t, 3> q_min_mrad{-1000, -600, -500};         ///< joint lower limits [mrad]
  std::array<std::int16_t, 3> q_max_mrad{1000, 1200, 1400};          ///< joint upper limits [mrad]
  std::uint16_t max_force_mn{3300};                                  ///< peak force [mN]
  std::uint16_t continuous_force_mn{880};                            ///< continuous force [mN]
  std::uint16_t torque_unit_unm{1000};                               ///< one torque unit on the wire [uN m]
  std::uint32_t period_us{1000};    ///< firmware tick and report period [us] (50..65535)
  std::uint16_t watchdog_us{5000};  ///< command watchdog [us] (>= period_us)
  std::uint16_t homing_ticks{50};   ///< ticks the arm must rest at home to home

  /// nullptr when the configuration is usable, else what is wrong.
  [[nodiscard]] constexpr const char* check() const noexcept {
    if (period_us < 50 || period_us > 65535) return "period_us must be 50..65535 [us]";
    if (watchdog_us < period_us) return "watchdog_us must be >= period_us [us]";
    if (torque_unit_unm == 0) return "torque_unit_unm must be > 0 [uN m]";
    for (std::size_t i = 0; i < 3; ++i) {
      if (counts_per_rev[i] == 0 || counts_per_rev[i] > 0x7FFFFFFFu) return "counts_per_rev must be 1..2^31-1";
      if (torque_constant[i] == 0) return "torque_constant must be > 0 [uN m/mA]";
      if (q_min_mrad[i] >= q_max_mrad[i]) return "q_min_mrad must be < q_max_mrad [mrad]";
    }
    if (continuous_force_mn == 0 || continuous_force_mn > max_force_mn)
      return "continuous_force_mn must be > 0 and <= max_force_mn [mN]";
    return nullptr;
  }
};

/// What the board measured this period.
struct BoardInputs {
  std::uint32_t now_us{0};                ///< free-running board clock [us] (wraps)
  std::array<std::int32_t, 3> encoder{};  ///< raw encoder counts since power-up
  std::array<std::int16_t, 3> gimbal{};   ///< gimbal values (device units)
  std::uint8_t buttons{0};                ///< button bit mask
  bool at_home{true};                     ///< home switch / dock sensor; true on boards without one (rest at home)
  bool estop{false};                      ///< emergency stop pressed (held, not latched)
  bool over_current{false};               ///< motor driver over-current flag (latches)
  bool over_temperature{false};           ///< over-temperature flag (latches)
};

/// What the board applies this period.
struct MotorOutputs {
  std::array<std::int16_t, 3> torque{};      ///< joint torques applied [torque units]
  std::array<std::int16_t, 3> current_ma{};  ///< motor currents to drive [mA]
  bool enable{false};                        ///< motor driver enable
};

/// Reports the core refused, by reason.
struct FirmwareCounters {
  std::uint32_t commands{0};  ///< valid commands accepted
  std::uint32_t bad_crc{0};
  std::uint32_t short_report{0};
  std::uint32_t unknown{0};  ///< unknown report id
  std::uint32_t bad_version{0};
  std::uint32_t bad_value{0};  ///< unknown flags or operations, zero watchdog
  std::uint32_t watchdog_trips{0};
};

class FirmwareCore {
 public:
  /// A configuration that fails check() leaves the core refusing to home
  /// and arm (config_error() says why): zero torque, never a crash.
  explicit FirmwareCore(const FirmwareConfig& config = {}) noexcept : config_(config) {
    config_error_ = config_.check();
    reset();
  }

  /// Power-on state: unhomed, disarmed, latched faults cleared, sequence
  /// and timestamp from zero, watchdog back to the configured period.
  void reset() noexcept {
    sequence_ = 0;
    boot_set_ = false;
    homed_ = false;
    homing_left_ = -1;
    armed_ = false;
    faults_ = 0;
    command_ = {};
    fresh_command_ = false;
    watchdog_us_ = config_.watchdog_us;
    outputs_ = {};
    offset_ = {};
  }

  /// Handles one output report (a command). Invalid reports are counted and
  /// ignored; they do not feed the watchdog.
  void receive(std::span<const std::uint8_t> bytes) noexcept {
    protocol::CommandReport c;
    const Status s = protocol::decode(bytes, c);
    if (s != Status::ok) {
      count(s);
      return;
    }
    ++counters_.commands;
    command_ = c;
    fresh_command_ = true;
    if (!(c.flags & protocol::command_flags::arm)) armed_ = false;  // disarm at once; arming waits for tick()
  }

  /// Fills out with feature report id (device info or configuration).
  Status get_feature(std::uint8_t id, std::span<std::uint8_t> out, std::size_t& size) noexcept {
    size = 0;
    if (id == static_cast<std::uint8_t>(protocol::ReportId::device_info)) {
      protocol::DeviceInfoReport r;
      r.counts_per_rev = config_.counts_per_rev;
      r.max_torque_mnm = config_.max_torque_mnm;
      r.torque_unit_unm = config_.torque_unit_unm;
      r.l1_um = config_.l1_um;
      r.l2_um = config_.l2_um;
      r.q_min_mrad = config_.q_min_mrad;
      r.q_max_mrad = config_.q_max_mrad;
      r.max_force_mn = config_.max_force_mn;
      r.continuous_force_mn = config_.continuous_force_mn;
      if (config_error_) return Status::bad_value;  // never describe an arm it will not drive
      r.rate_hz = static_cast<std::uint16_t>((1000000u + config_.period_us / 2) / config_.period_us);
      size = protocol::encode(r, out);
      return size ? Status::ok : Status::short_report;
    }
    if (id == static_cast<std::uint8_t>(protocol::ReportId::configuration)) {
      protocol::ConfigurationReport r;
      r.watchdog_us = watchdog_us_;
      size = protocol::encode(r, out);
      return size ? Status::ok : Status::short_report;
    }
    ++counters_.unknown;
    return Status::unknown_report;
  }

  /// Applies a set feature report (configuration or control).
  Status set_feature(std::span<const std::uint8_t> bytes) noexcept {
    if (bytes.empty()) {
      count(Status::short_report);
      return Status::short_report;
    }
    if (bytes[0] == static_cast<std::uint8_t>(protocol::ReportId::configuration)) {
      protocol::ConfigurationReport r;
      if (const Status s = protocol::decode(bytes, r); s != Status::ok) {
        count(s);
        return s;
      }
      if (r.watchdog_us < config_.period_us) {
        count(Status::bad_value);
        return Status::bad_value;
      }
      watchdog_us_ = r.watchdog_us;
      return Status::ok;
    }
    protocol::ControlOp op;
    if (const Status s = protocol::decode(bytes, op); s != Status::ok) {
      count(s);
      return s;
    }
    switch (op) {
      case protocol::ControlOp::arm:
        if (!homed_) return Status::not_homed;
        if (faults_ & status_bits::any_fault) return Status::fault;
        armed_ = true;
        last_valid_us_ = now_us_;
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
        start_homing();
        return Status::ok;
    }
    return Status::bad_value;
  }

  /// One frame from a byte stream (StreamPort): a command, a feature
  /// request or a set feature report. Writes the answer, if any, into reply
  /// (>= max_report_size bytes) and returns its size (0: no answer).
  std::size_t handle_frame(std::span<const std::uint8_t> frame, std::span<std::uint8_t> reply) noexcept {
    if (frame.empty()) return 0;
    const auto id = static_cast<protocol::ReportId>(frame[0]);
    if (id == protocol::ReportId::command) {
      receive(frame);
      return 0;
    }
    if (id == protocol::ReportId::feature_request) {
      std::uint8_t wanted = 0;
      if (const Status s = protocol::decode_feature_request(frame, wanted); s != Status::ok) {
        count(s);
        return 0;
      }
      std::size_t size = 0;
      const Status s = get_feature(wanted, reply, size);
      return s == Status::ok ? size : protocol::encode(protocol::FeatureReply{wanted, s}, reply);
    }
    if (id == protocol::ReportId::configuration || id == protocol::ReportId::control) {
      const Status s = set_feature(frame);
      return protocol::encode(protocol::FeatureReply{frame[0], s}, reply);
    }
    count(Status::unknown_report);
    return 0;
  }

  /// Runs one firmware period: applies the newest command, homing, the
  /// watchdog, fault latching and the limits; encodes the state report.
  /// Returns what the board must drive now.
  const MotorOutputs& tick(const BoardInputs& in) noexcept {
    now_us_ = in.now_us;
    if (!boot_set_) {
      boot_us_ = in.now_us;
      last_valid_us_ = in.now_us;
      boot_set_ = true;
    }
    if (in.over_current) faults_ |= status_bits::over_current;
    if (in.over_temperature) faults_ |= status_bits::over_temperature;
    faults_ = static_cast<std::uint16_t>(in.estop ? faults_ | status_bits::estop : faults_ & ~status_bits::estop);
    if (fresh_command_) {
      fresh_command_ = false;
      last_valid_us_ = in.now_us;
      if (command_.flags & protocol::command_flags::home) start_homing();
      if (!(command_.flags & protocol::command_flags::arm))
        armed_ = false;
      else if (homed_ && !(faults_ & status_bits::any_fault))
        armed_ = true;
    }
    if (homing_left_ >= 0) {  // the arm must rest at home for homing_ticks ticks
      if (!in.at_home)
        homing_left_ = config_.homing_ticks;
      else if (homing_left_-- == 0) {
        homed_ = true;
        offset_ = in.encoder;
      }
    }
    if (armed_ && in.now_us - last_valid_us_ > watchdog_us_) {  // wraps correctly
      armed_ = false;
      faults_ |= status_bits::watchdog_tripped;
      ++counters_.watchdog_trips;
    }
    if (faults_ & status_bits::any_fault) armed_ = false;
    outputs_ = {};
    if (armed_) {
      outputs_.enable = true;
      for (std::size_t i = 0; i < 3; ++i)
        limit(i, command_.torque_mnm[i]);
    }
    protocol::StateReport r;
    r.sequence = ++sequence_;
    r.command_echo = command_.sequence;
    r.timestamp_us = in.now_us - boot_us_;
    for (std::size_t i = 0; i < 3; ++i)
      r.encoder[i] = static_cast<std::int32_t>(static_cast<std::uint32_t>(in.encoder[i]) -
                                               static_cast<std::uint32_t>(homed_ ? offset_[i] : 0));
    r.gimbal = in.gimbal;
    r.status =
        static_cast<std::uint16_t>(faults_ | (homed_ ? status_bits::homed : 0) | (armed_ ? status_bits::armed : 0));
    r.buttons = in.buttons;
    r.torque_mnm = outputs_.torque;
    report_size_ = protocol::encode(r, report_);
    return outputs_;
  }

  /// The state report encoded by the last tick().
  [[nodiscard]] std::span<const std::uint8_t> report() const noexcept { return {report_.data(), report_size_}; }
  [[nodiscard]] const MotorOutputs& outputs() const noexcept { return outputs_; }
  [[nodiscard]] const FirmwareCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const FirmwareConfig& config() const noexcept { return config_; }
  /// nullptr, or why the configuration was refused.
  [[nodiscard]] const char* config_error() const noexcept { return config_error_; }
  [[nodiscard]] bool armed() const noexcept { return armed_; }
  [[nodiscard]] bool homed() const noexcept { return homed_; }
  /// Homing started and not yet complete.
  [[nodiscard]] bool homing() const noexcept { return homing_left_ >= 0; }
  [[nodiscard]] std::uint16_t faults() const noexcept { return faults_; }
  [[nodiscard]] std::uint16_t watchdog_us() const noexcept { return watchdog_us_; }
  [[nodiscard]] const protocol::CommandReport& last_command() const noexcept { return command_; }

 private:
  void start_homing() noexcept {
    if (!homed_ && homing_left_ < 0 && !config_error_) homing_left_ = config_.homing_ticks;
  }

  /// Torque saturation, then the current limit; what is applied is what
  /// the clamped current gives (truncated toward zero) [torque units].
  void limit(std::size_t i, std::int16_t requested) noexcept {
    const std::uint32_t unit = config_.torque_unit_unm;
    const std::uint32_t saturation = config_.max_torque_mnm[i] * 1000u / unit;  // [torque units]
    const bool negative = requested < 0;
    std::uint32_t magnitude = negative ? static_cast<std::uint32_t>(-static_cast<std::int32_t>(requested))
                                       : static_cast<std::uint32_t>(requested);
    if (magnitude > saturation) magnitude = saturation;
    std::uint32_t current = magnitude * unit / config_.torque_constant[i];  // [mA]; < 2^31
    if (current > config_.max_current_ma[i]) {
      current = config_.max_current_ma[i];
      magnitude = current * config_.torque_constant[i] / unit;  // < 2^32
    }
    if (current > 32767u) current = 32767u;
    if (magnitude > 32767u) magnitude = 32767u;
    const auto t = static_cast<std::int16_t>(magnitude);
    const auto c = static_cast<std::int16_t>(current);
    outputs_.torque[i] = negative ? static_cast<std::int16_t>(-t) : t;
    outputs_.current_ma[i] = negative ? static_cast<std::int16_t>(-c) : c;
  }

  void count(Status s) noexcept {
    switch (s) {
      case Status::bad_crc:
        ++counters_.bad_crc;
        break;
      case Status::short_report:
        ++counters_.short_report;
        break;
      case Status::unknown_report:
        ++counters_.unknown;
        break;
      case Status::bad_version:
        ++counters_.bad_version;
        break;
      default:
        ++counters_.bad_value;
        break;
    }
  }

  FirmwareConfig config_;
  const char* config_error_{nullptr};
  FirmwareCounters counters_{};
  protocol::CommandReport command_{};
  MotorOutputs outputs_{};
  std::array<std::int32_t, 3> offset_{};  ///< raw counts at the home pose
  std::array<std::uint8_t, protocol::state_size> report_{};
  std::size_t report_size_{0};
  std::uint32_t now_us_{0};
  std::uint32_t boot_us_{0};
  std::uint32_t last_valid_us_{0};
  std::uint16_t watchdog_us_{5000};
  std::uint16_t sequence_{0};
  std::uint16_t faults_{0};
  std::int32_t homing_left_{-1};
  bool boot_set_{false};
  bool fresh_command_{false};
  bool homed_{false};
  bool armed_{false};
};

}  // namespace hapticfield::firmware
