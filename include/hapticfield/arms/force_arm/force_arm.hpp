#pragma once
/// @file force_arm.hpp
/// ForceArm: the Device that speaks the report protocol over any Transport.
/// Converts encoder counts to a handle position (FK), forces to joint torques
/// (tau = J^T F), tracks the link (drops, duplicates, reordering, corruption).

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>

#include <glm/vec3.hpp>

#include "hapticfield/arms/force_arm/kinematics.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/protocol/reports.hpp"

namespace hapticfield {

/// Link events seen by the last ForceArm::read (bit mask).
namespace link_events {
inline constexpr std::uint32_t dropped = 1u << 0;       ///< sequence gap
inline constexpr std::uint32_t duplicate = 1u << 1;     ///< same sequence twice
inline constexpr std::uint32_t reordered = 1u << 2;     ///< older sequence after a newer one
inline constexpr std::uint32_t corrupt = 1u << 3;       ///< bad CRC
inline constexpr std::uint32_t malformed = 1u << 4;     ///< short, unknown id or bad version
inline constexpr std::uint32_t device_fault = 1u << 5;  ///< a fault bit is set
inline constexpr std::uint32_t jumped = 1u << 6;        ///< a report far off the sequence: held back
inline constexpr std::uint32_t resynced = 1u << 7;      ///< a new, consistent stream was taken up
inline constexpr std::uint32_t impossible = 1u << 8;    ///< a report beyond the joint limits: refused
}  // namespace link_events

/// Running counts of link events since construction.
struct LinkCounters {
  std::uint64_t reports{0};  ///< reports decoded
  std::uint64_t dropped{0};  ///< reports missing from the sequence
  std::uint64_t duplicates{0};
  std::uint64_t reordered{0};
  std::uint64_t corrupt{0};
  std::uint64_t malformed{0};
  std::uint64_t commands{0};  ///< command reports written
  std::uint64_t write_errors{0};
  std::uint64_t resyncs{0};     ///< times a new stream was taken up (device restart, long loss)
  std::uint64_t impossible{0};  ///< reports refused: joint angles the arm cannot reach
};

struct ForceArmConfig {
  /// Read the device-info feature report at construction and take geometry,
  /// encoder resolution and limits from it (else use kinematics and info).
  bool query_device{true};
  KinematicsConfig kinematics{};
  DeviceInfo info{};
  double velocity_cutoff{100.0};  ///< first-order low-pass on the velocity estimate [Hz]
  double torque_unit{1e-3};       ///< size of one torque unit on the wire [N m]
  /// A report more than this many sequence numbers ahead of the last one,
  /// or any behind it, starts a resynchronisation [reports].
  int max_sequence_gap{1000};
  /// Consecutive reports of a new stream needed to take it up (a device
  /// restart, a long loss); meanwhile read() returns Status::resync [reports].
  int resync_reports{3};
  /// Joint angles further than this beyond the joint limits (those of the
  /// device-info report when query_device) are impossible: the report is
  /// refused and read() returns Status::impossible [rad] (0.1 rad = 5.7 deg).
  /// Homed: q_min - margin <= q <= q_max + margin. Unhomed the counts are
  /// relative to an unknown pose within the limits, so |q| <= q_max - q_min
  /// + margin.
  double joint_margin{0.1};
};

class ForceArm {
 public:
  /// @throws std::invalid_argument for bad options, std::runtime_error when
  ///         the device-info feature report cannot be read or is invalid.
  explicit ForceArm(Transport& transport, ForceArmConfig options = {})
      : transport_(&transport), config_(std::move(options)) {
    if (config_.query_device) {
      std::array<std::uint8_t, protocol::max_report_size> buf{};
      buf[0] = static_cast<std::uint8_t>(protocol::ReportId::device_info);
      std::size_t size = 0;
      protocol::DeviceInfoReport r;
      Status s = transport_->get_feature(buf, size);
      if (s == Status::ok) s = protocol::decode(std::span<const std::uint8_t>(buf.data(), size), r);
      if (s != Status::ok)
        throw std::runtime_error(
            "ForceArm: reading the device-info feature report" +
            (transport_->where().empty() ? std::string() : " from " + std::string(transport_->where())) +
            " failed: " + std::string(to_string(s)));
      apply(r);
    }
    if (!std::isfinite(config_.velocity_cutoff) || config_.velocity_cutoff <= 0.0)
      throw std::invalid_argument("ForceArmConfig: velocity_cutoff must be finite and > 0 [Hz]");
    if (!std::isfinite(config_.torque_unit) || config_.torque_unit <= 0.0)
      throw std::invalid_argument("ForceArmConfig: torque_unit must be finite and > 0 [N m]");
    if (config_.max_sequence_gap < 1 || config_.max_sequence_gap > 30000)
      throw std::invalid_argument("ForceArmConfig: max_sequence_gap must be within 1..30000 [reports]");
    if (config_.resync_reports < 1 || config_.resync_reports > 100)
      throw std::invalid_argument("ForceArmConfig: resync_reports must be within 1..100 [reports]");
    if (!std::isfinite(config_.joint_margin) || config_.joint_margin < 0.0 || config_.joint_margin > 1.0)
      throw std::invalid_argument("ForceArmConfig: joint_margin must be within [0, 1] [rad]");
    config_.info.validate();
    kin_ = PhantomKinematics(config_.kinematics);
  }

  [[nodiscard]] const DeviceInfo& info() const noexcept { return config_.info; }
  [[nodiscard]] const PhantomKinematics& kinematics() const noexcept { return kin_; }
  [[nodiscard]] const LinkCounters& counters() const noexcept { return counters_; }
  /// Margin beyond the joint limits before a report is impossible [rad].
  [[nodiscard]] double joint_margin() const noexcept { return config_.joint_margin; }
  /// link_events bits of the last read().
  [[nodiscard]] std::uint32_t last_events() const noexcept { return events_; }

  /// Drains every queued input report and keeps the newest valid one.
  /// Returns ok when a newer state was decoded, no_data when none, resync
  /// while a jump in the sequence (a device restart, a long loss) waits for
  /// resync_reports consistent reports, impossible when any report drained
  /// has joint angles beyond the limits (joint_margin; such a report is
  /// never used), and disconnected when the transport is gone (state still
  /// takes any report that arrived before). state is untouched unless ok or
  /// disconnected.
  Status read(DeviceState& state) noexcept {
    events_ = 0;
    bool fresh = false;
    bool held = false;
    bool impossible = false;
    protocol::StateReport newest{};
    for (int i = 0; i < 256; ++i) {
      std::size_t size = 0;
      const Status s = transport_->read(buf_, size, 0);
      if (s == Status::no_data || s == Status::timeout) break;
      if (s == Status::disconnected) {  // keep what arrived before the end
        disconnected_ = true;
        if (fresh) update(newest, state);
        return Status::disconnected;
      }
      if (s != Status::ok) {
        events_ |= link_events::malformed;
        ++counters_.malformed;
        continue;
      }
      protocol::StateReport r;
      const Status d = protocol::decode(std::span<const std::uint8_t>(buf_.data(), size), r);
      if (d == Status::bad_crc) {
        events_ |= link_events::corrupt;
        ++counters_.corrupt;
        continue;
      }
      if (d != Status::ok) {
        events_ |= link_events::malformed;
        ++counters_.malformed;
        continue;
      }
      ++counters_.reports;
      if (!reachable(r)) {
        events_ |= link_events::impossible;
        ++counters_.impossible;
        impossible = true;
        continue;
      }
      const std::uint16_t reference = fresh ? newest.sequence : last_sequence_;
      const auto diff = static_cast<std::int16_t>(static_cast<std::uint16_t>(r.sequence - reference));
      if (have_last_ || fresh) {
        if (diff == 0) {
          events_ |= link_events::duplicate;
          ++counters_.duplicates;
          continue;
        }
        if (diff < 0 || diff > config_.max_sequence_gap) {
          // One stale report (reordering) or the start of a new stream: hold
          // it until resync_reports consecutive reports confirm a new stream.
          if (diff < 0) {
            events_ |= link_events::reordered;
            ++counters_.reordered;
          }
          events_ |= link_events::jumped;
          if (!(candidate_count_ > 0 && r.sequence == candidate_next_)) candidate_count_ = 0;
          ++candidate_count_;
          candidate_next_ = static_cast<std::uint16_t>(r.sequence + 1);
          if (candidate_count_ < config_.resync_reports) {
            held = true;
            continue;
          }
          events_ |= link_events::resynced;
          ++counters_.resyncs;
          candidate_count_ = 0;
          have_last_ = false;  // a new stream: no velocity across the jump
          newest = r;
          fresh = true;
          held = false;
          continue;
        }
        if (diff > 1) {
          events_ |= link_events::dropped;
          counters_.dropped += static_cast<std::uint64_t>(diff - 1);
        }
      }
      candidate_count_ = 0;
      held = false;
      newest = r;
      fresh = true;
    }
    if (impossible) return Status::impossible;
    if (!fresh) return held ? Status::resync : Status::no_data;
    update(newest, state);
    return Status::ok;
  }

  /// Commands a handle force [N]: tau = J^T F at the last read pose,
  /// quantised to the wire unit and saturated at the joint limits. A
  /// non-finite force, or no state read yet, sends zero torque.
  Status write(const glm::dvec3& force) noexcept {
    protocol::CommandReport c;
    c.sequence = ++command_sequence_;
    c.flags = static_cast<std::uint8_t>((armed_request_ ? protocol::command_flags::arm : 0) |
                                        (home_request_ ? protocol::command_flags::home : 0));
    const bool ok = have_last_ && std::isfinite(force.x) && std::isfinite(force.y) && std::isfinite(force.z);
    const glm::dvec3 tau = ok ? kin_.torques(angles_, force) : glm::dvec3{0.0};
    for (int i = 0; i < 3; ++i) {
      const double limit = config_.kinematics.max_torque[i];
      const double clamped = std::fmax(-limit, std::fmin(limit, std::isfinite(tau[i]) ? tau[i] : 0.0));
      const double units = std::fmax(-32767.0, std::fmin(32767.0, std::round(clamped / config_.torque_unit)));
      c.torque_mnm[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(units);
    }
    last_command_ = c;
    const std::size_t n = protocol::encode(c, out_);
    const Status s = transport_->write(std::span<const std::uint8_t>(out_.data(), n));
    if (s == Status::ok)
      ++counters_.commands;
    else
      ++counters_.write_errors;
    if (s == Status::disconnected) disconnected_ = true;
    return s;
  }

  /// Requests motors on (sent with every command; the device arms once homed).
  Status set_armed(bool on) noexcept {
    armed_request_ = on;
    if (on && have_last_ && !(flags_ & status_bits::homed)) return Status::not_homed;
    return Status::ok;
  }

  /// Requests homing (sent with every command until the device reports homed).
  Status request_home() noexcept {
    home_request_ = true;
    return Status::ok;
  }

  /// Clears a latched device fault (the device accepts it only while disarmed).
  Status clear_fault() noexcept { return control(protocol::ControlOp::clear_fault); }

  /// Sets the firmware watchdog period [s] (0 < period <= 65 ms).
  Status configure_watchdog(double period) noexcept {
    if (!std::isfinite(period) || period <= 0.0 || period > 0.065535) return Status::bad_value;
    protocol::ConfigurationReport r;
    r.watchdog_us = static_cast<std::uint16_t>(std::lround(period * 1e6));
    std::array<std::uint8_t, protocol::configuration_size> b{};
    const std::size_t n = protocol::encode(r, b);
    return transport_->send_feature(std::span<const std::uint8_t>(b.data(), n));
  }

  /// Sends a control feature report (arm, disarm, clear fault, home).
  Status control(protocol::ControlOp op) noexcept {
    std::array<std::uint8_t, protocol::control_size> b{};
    const std::size_t n = protocol::encode(op, b);
    return transport_->send_feature(std::span<const std::uint8_t>(b.data(), n));
  }

  /// The last command written (for tracing and tests).
  [[nodiscard]] const protocol::CommandReport& last_command() const noexcept { return last_command_; }
  [[nodiscard]] bool disconnected() const noexcept { return disconnected_; }
  [[nodiscard]] Transport& transport() noexcept { return *transport_; }

 private:
  void apply(const protocol::DeviceInfoReport& r) {
    for (std::size_t i = 0; i < 3; ++i) {
      config_.kinematics.counts_per_rev[i] = static_cast<std::int32_t>(r.counts_per_rev[i]);
      const int k = static_cast<int>(i);
      config_.kinematics.max_torque[k] = r.max_torque_mnm[i] * 1e-3;  // always mN m
      config_.kinematics.q_min[k] = r.q_min_mrad[i] * 1e-3;
      config_.kinematics.q_max[k] = r.q_max_mrad[i] * 1e-3;
    }
    config_.kinematics.l1 = r.l1_um * 1e-6;
    config_.kinematics.l2 = r.l2_um * 1e-6;
    config_.info.max_force = r.max_force_mn * 1e-3;
    config_.info.continuous_force = r.continuous_force_mn * 1e-3;
    config_.info.nominal_rate = r.rate_hz;
    config_.torque_unit = r.torque_unit_unm * 1e-6;
  }

  /// True when the report's joint angles are ones the arm can have (see
  /// ForceArmConfig::joint_margin).
  [[nodiscard]] bool reachable(const protocol::StateReport& r) const noexcept {
    const glm::dvec3 q = kin_.angles(r.encoder);
    const KinematicsConfig& k = kin_.config();
    const bool homed = (r.status & status_bits::homed) != 0;
    for (int i = 0; i < 3; ++i) {
      const double lo = homed ? k.q_min[i] : k.q_min[i] - k.q_max[i];
      const double hi = homed ? k.q_max[i] : k.q_max[i] - k.q_min[i];
      if (!(q[i] >= lo - config_.joint_margin && q[i] <= hi + config_.joint_margin)) return false;
    }
    return true;
  }

  void update(const protocol::StateReport& r, DeviceState& s) noexcept {
    const glm::dvec3 q = kin_.angles(r.encoder);
    const glm::dvec3 p = kin_.forward(q);
    const double t = r.timestamp_us * 1e-6;
    glm::dvec3 v = s.velocity;
    if (have_last_) {
      const std::uint32_t dt_us = r.timestamp_us - last_timestamp_us_;  // wraps correctly
      const double dt = dt_us * 1e-6;
      if (dt > 0.0 && dt < 0.1) {
        const double alpha = 1.0 - std::exp(-2.0 * std::numbers::pi * config_.velocity_cutoff * dt);
        velocity_ += alpha * ((p - position_) / dt - velocity_);
      } else {
        velocity_ = glm::dvec3{0.0};
      }
      v = velocity_;
    } else {
      velocity_ = v = glm::dvec3{0.0};
    }
    s.device_time = t;
    s.position = p;
    s.velocity = v;
    s.joint_angles = q;
    s.encoder = r.encoder;
    s.gimbal = r.gimbal;
    for (int i = 0; i < 3; ++i)
      s.applied_torque[i] = r.torque_mnm[static_cast<std::size_t>(i)] * config_.torque_unit;
    s.sequence = r.sequence;
    s.command_echo = r.command_echo;
    s.flags = r.status;
    s.buttons = r.buttons;
    s.valid = true;
    if (s.faulted()) events_ |= link_events::device_fault;
    if (s.homed()) home_request_ = false;
    flags_ = r.status;
    angles_ = q;
    position_ = p;
    last_sequence_ = r.sequence;
    last_timestamp_us_ = r.timestamp_us;
    have_last_ = true;
  }

  Transport* transport_;
  ForceArmConfig config_;
  PhantomKinematics kin_{};
  LinkCounters counters_{};
  std::array<std::uint8_t, protocol::max_report_size> buf_{};
  std::array<std::uint8_t, protocol::max_report_size> out_{};
  protocol::CommandReport last_command_{};
  glm::dvec3 angles_{0.0};
  glm::dvec3 position_{0.0};
  glm::dvec3 velocity_{0.0};
  std::uint32_t events_{0};
  std::uint32_t last_timestamp_us_{0};
  std::uint16_t last_sequence_{0};
  std::uint16_t candidate_next_{0};  ///< sequence a confirming report of a new stream must carry
  int candidate_count_{0};           ///< consecutive reports of a possible new stream seen
  std::uint16_t command_sequence_{0};
  std::uint16_t flags_{0};
  bool have_last_{false};
  bool armed_request_{false};
  bool home_request_{false};
  bool disconnected_{false};
};

static_assert(Device<ForceArm>);

}  // namespace hapticfield
