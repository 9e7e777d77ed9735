#pragma once
/// @file simulated_falcon.hpp
/// SimulatedFalconUsb: a fake USB link that replays the Falcon's protocol
/// byte for byte (falcon_codec.hpp) with a simulated arm behind it, and
/// faults on demand, for tests and demos without a Falcon.
///
/// It powers up with no firmware: at 9600 Bd with DTR high the boot loader
/// answers the check message; at the firmware rate it echoes the start byte
/// and then every firmware byte; switched to the normal rate afterwards, the
/// firmware runs and answers each 16-byte command with one report, stepping
/// the arm one period. Faults: the first flaky_loads uploads get one echoed
/// byte wrong (as a flaky load looks to the host), lose() makes every call
/// fail as an unplugged device does, stall() stops the reports while
/// commands still go in, impossible_report() sends encoder counts no pose
/// gives, power_cycle() forgets the firmware and the homing.
///
/// The arm is ours, not Novint's: the handle is a point mass with viscous
/// damping, driven by F = (d theta/d p)^T tau from the commanded counts
/// (the inverse of the host's mapping), the scripted hand (when it holds)
/// and a constant push, held inside a box by stiff walls. Homing: each encoder reports homed once homing mode has
/// been on for homing_packets commands (standing in for the user's move
/// out and in); until then the counts carry a power-on offset.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string_view>

#include <glm/vec3.hpp>

#include "hapticfield/arms/falcon/falcon_codec.hpp"
#include "hapticfield/arms/falcon/falcon_kinematics.hpp"
#include "hapticfield/arms/falcon/falcon_usb.hpp"
#include "hapticfield/simulation/scripted_hand.hpp"

namespace hapticfield {

struct SimulatedFalconConfig {
  FalconGeometry geometry{};
  double mass{0.15};                           ///< handle and legs, lumped [kg]
  double damping{1.0};                         ///< viscous [N s/m]
  double period{1e-3};                         ///< time per command [s]
  double counts_per_newton_metre{10000.0};     ///< must match the host's
  glm::dvec3 box_min{-0.03, -0.03, -0.06};     ///< walls, device frame [m] (inside falcon_workspace_min)
  glm::dvec3 box_max{0.03, 0.03, 0.01};        ///< [m] (inside falcon_workspace_max)
  double wall_stiffness{5000.0};               ///< [N/m]
  glm::dvec3 initial_position{0.0, 0.0, 0.0};  ///< device frame [m]
  std::array<std::int16_t, 3> power_on_offset{-250, 130, 400};  ///< counts added until homed
  int homing_packets{50};                                       ///< commands in homing mode until homed
  bool firmware_running{false};                                 ///< true: as if a firmware were already loaded
  bool leading_zero_in_check_reply{false};                      ///< as some hosts see the reply
  int flaky_loads{0};                                           ///< uploads whose echo gets one byte wrong
  std::size_t expected_firmware_size{0};                        ///< 0: any non-empty file [bytes]
  Hand hand{.holding = false};  ///< the scripted hand on the handle (its time: commands x period)

  /// @throws std::invalid_argument naming the first setting that makes no sense.
  void validate() const {
    geometry.validate();
    const auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
    if (!pos(mass) || !pos(period) || !pos(counts_per_newton_metre) || !pos(wall_stiffness))
      throw std::invalid_argument(
          "SimulatedFalconConfig: mass, period, counts_per_newton_metre and wall_stiffness must be > 0");
    if (!std::isfinite(damping) || damping < 0.0)
      throw std::invalid_argument("SimulatedFalconConfig: damping must be finite and >= 0");
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(box_min[i]) || !std::isfinite(box_max[i]) || !(box_min[i] < box_max[i]))
        throw std::invalid_argument("SimulatedFalconConfig: box_min must be finite and < box_max [m]");
    for (int i = 0; i < 3; ++i)
      if (!(initial_position[i] >= box_min[i] && initial_position[i] <= box_max[i]))
        throw std::invalid_argument("SimulatedFalconConfig: initial_position must lie inside the box [m]");
    hand.path.validate();
    if (!std::isfinite(hand.stiffness) || hand.stiffness < 0.0 || !std::isfinite(hand.damping) || hand.damping < 0.0)
      throw std::invalid_argument("SimulatedFalconConfig: hand stiffness and damping must be finite and >= 0");
    if (homing_packets < 0 || flaky_loads < 0)
      throw std::invalid_argument("SimulatedFalconConfig: homing_packets and flaky_loads must be >= 0");
  }
};

/// What the simulated Falcon met.
struct SimulatedFalconCounters {
  std::uint64_t commands{0};      ///< commands decoded while the firmware ran
  std::uint64_t bad_commands{0};  ///< framed packets that did not decode
  std::uint64_t reports{0};       ///< reports queued
  std::uint64_t checks{0};        ///< boot loader check messages answered
  std::uint64_t uploads_started{0};
  std::uint64_t firmware_bytes{0};  ///< firmware bytes echoed (all uploads)
  std::uint64_t controls{0};        ///< FTDI requests
  std::uint64_t dropped_in{0};      ///< report bytes dropped: the host read too slowly
};

class SimulatedFalconUsb final : public FalconUsb {
 public:
  explicit SimulatedFalconUsb(SimulatedFalconConfig config = {}) : config_(config), kin_(config_.geometry) {
    config_.validate();
    position_ = config_.initial_position;
    running_ = config_.firmware_running;
    flaky_left_ = config_.flaky_loads;
  }

  // --- the USB link ----------------------------------------------------------
  Status control(std::uint8_t request, std::uint16_t value) noexcept override {
    if (lost_) return Status::disconnected;
    ++counters_.controls;
    switch (request) {
      case falcon::sio::reset:
        if (value == falcon::sio::purge_rx) in_size_ = 0;
        if (value == falcon::sio::purge_tx) framer_.clear();
        break;
      case falcon::sio::modem_ctrl:
        if (value == falcon::sio::dtr_high) dtr_ = true;
        if (value == falcon::sio::dtr_low) dtr_ = false;
        break;
      case falcon::sio::baud_rate:
        if (loading_ && value != falcon::sio::baud_firmware) finish_upload(value == falcon::sio::baud_normal);
        baud_ = value;
        break;
      default:
        break;
    }
    return Status::ok;
  }

  Status write(std::span<const std::uint8_t> bytes) noexcept override {
    if (lost_) return Status::disconnected;
    if (running_) {
      if (baud_ != falcon::sio::baud_normal) return Status::ok;  // noise at the wrong rate
      framer_.push(bytes);
      std::array<std::uint8_t, falcon::packet_size> packet{};
      while (framer_.pop(packet))
        serve(packet);
      return Status::ok;
    }
    // the boot loader
    if (baud_ == falcon::sio::baud_9600 && dtr_) {
      if (bytes.size() == falcon::check_request.size() &&
          std::equal(bytes.begin(), bytes.end(), falcon::check_request.begin())) {
        if (config_.leading_zero_in_check_reply) queue_in(std::array<std::uint8_t, 1>{0x00});
        queue_in(falcon::check_reply);
        checked_ = true;
        ++counters_.checks;
      }
      return Status::ok;
    }
    if (baud_ == falcon::sio::baud_firmware && checked_) {
      std::size_t from = 0;
      if (!loading_ && !bytes.empty() && bytes[0] == falcon::firmware_ack) {
        queue_in(std::array<std::uint8_t, 1>{falcon::firmware_ack});
        loading_ = true;
        load_good_ = true;
        loaded_ = 0;
        ++counters_.uploads_started;
        from = 1;
      }
      if (!loading_) return Status::ok;
      for (std::size_t i = from; i < bytes.size(); ++i) {
        std::uint8_t echo = bytes[i];
        if (flaky_left_ > 0 && loaded_ == 100) {  // a flaky load: one byte comes back wrong
          echo = static_cast<std::uint8_t>(echo ^ 0x5A);
          load_good_ = false;
        }
        queue_in(std::array<std::uint8_t, 1>{echo});
        ++loaded_;
        ++counters_.firmware_bytes;
      }
    }
    return Status::ok;
  }

  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept override {
    (void)timeout_us;  // everything queued is there at once
    size = 0;
    if (lost_) return Status::disconnected;
    if (in_size_ == 0) return Status::no_data;
    const std::size_t n = std::min(buffer.size(), in_size_);
    for (std::size_t i = 0; i < n; ++i)
      buffer[i] = in_[i];
    for (std::size_t i = n; i < in_size_; ++i)
      in_[i - n] = in_[i];
    in_size_ -= n;
    size = n;
    return Status::ok;
  }

  [[nodiscard]] std::string_view where() const noexcept override { return "simulated Falcon"; }

  // --- faults and the hand ----------------------------------------------------
  void lose() noexcept { lost_ = true; }           ///< unplugged: every call fails from now on
  void reconnect() noexcept { lost_ = false; }     ///< plugged back (the firmware is kept)
  void stall(bool on) noexcept { stalled_ = on; }  ///< reports stop while commands still go in
  /// The next report carries these counts (angles no pose gives, say).
  void impossible_report(std::array<std::int16_t, 3> counts) noexcept {
    forced_counts_ = counts;
    forced_ = true;
  }
  /// Power lost: the firmware and the homing are forgotten.
  void power_cycle() noexcept {
    running_ = false;
    checked_ = false;
    loading_ = false;
    homed_ = 0;
    homing_count_ = 0;
    in_size_ = 0;
    framer_.clear();
  }
  void set_push(const glm::dvec3& f) noexcept { push_ = f; }  ///< a constant force on the handle [N]
  void set_hand(const Hand& h) noexcept { config_.hand = h; }
  void set_buttons(std::uint8_t b) noexcept { buttons_ = static_cast<std::uint8_t>(b & 0xF); }

  // --- what it shows -----------------------------------------------------------
  [[nodiscard]] const glm::dvec3& position() const noexcept { return position_; }  ///< [m]
  [[nodiscard]] const glm::dvec3& velocity() const noexcept { return velocity_; }  ///< [m/s]
  /// Handle force of the last command, from its counts [N].
  [[nodiscard]] const glm::dvec3& motor_force() const noexcept { return motor_force_; }
  [[nodiscard]] const falcon::Command& last_command() const noexcept { return command_; }
  [[nodiscard]] bool firmware_running() const noexcept { return running_; }
  [[nodiscard]] bool homed() const noexcept { return homed_ == falcon::all_homed; }
  [[nodiscard]] const SimulatedFalconCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const FalconKinematics& kinematics() const noexcept { return kin_; }

 private:
  template <std::size_t N>
  void queue_in(const std::array<std::uint8_t, N>& bytes) noexcept {
    for (const std::uint8_t b : bytes) {
      if (in_size_ == in_.size()) {
        ++counters_.dropped_in;
        continue;
      }
      in_[in_size_++] = b;
    }
  }

  /// The upload ends: the firmware starts when switched to the normal rate
  /// after a good load; a new handshake instead abandons it.
  void finish_upload(bool start) noexcept {
    loading_ = false;
    const bool size_ok = config_.expected_firmware_size == 0 ? loaded_ > 0 : loaded_ == config_.expected_firmware_size;
    if (!load_good_) --flaky_left_;
    if (start && load_good_ && size_ok) running_ = true;
    checked_ = false;
  }

  void serve(std::span<const std::uint8_t, falcon::packet_size> packet) noexcept {
    falcon::Command c;
    if (falcon::decode(packet, c) != Status::ok) {
      ++counters_.bad_commands;
      return;
    }
    ++counters_.commands;
    command_ = c;
    if (c.homing && homed_ != falcon::all_homed && ++homing_count_ >= config_.homing_packets)
      homed_ = falcon::all_homed;
    step(c);
    if (stalled_) return;
    falcon::Report r;
    r.homed = homed_;
    r.buttons = buttons_;
    r.encoder = encoder_counts();
    if (forced_) {
      r.encoder = forced_counts_;
      forced_ = false;
    }
    std::array<std::uint8_t, falcon::packet_size> out{};
    falcon::encode(r, out);
    queue_in(out);
    ++counters_.reports;
  }

  [[nodiscard]] std::array<std::int16_t, 3> encoder_counts() const noexcept {
    glm::dvec3 theta{0.0};
    std::array<std::int16_t, 3> counts{};
    if (!kin_.inverse(position_, theta)) return counts;
    for (int i = 0; i < 3; ++i) {
      double c = std::round(kin_.count(theta[i]));
      if (homed_ != falcon::all_homed) c += config_.power_on_offset[static_cast<std::size_t>(i)];
      counts[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(std::fmax(-32768.0, std::fmin(32767.0, c)));
    }
    return counts;
  }

  void step(const falcon::Command& c) noexcept {
    glm::dvec3 tau{0.0};
    for (int i = 0; i < 3; ++i)
      tau[i] = -static_cast<double>(c.motor[static_cast<std::size_t>(i)]) / config_.counts_per_newton_metre;
    glm::dmat3 j{0.0};
    motor_force_ = glm::dvec3{0.0};
    if (kin_.angle_jacobian(position_, j)) motor_force_ = glm::transpose(j) * tau;  // F = (dtheta/dp)^T tau
    glm::dvec3 wall{0.0};
    for (int i = 0; i < 3; ++i) {
      if (position_[i] > config_.box_max[i]) wall[i] = -config_.wall_stiffness * (position_[i] - config_.box_max[i]);
      if (position_[i] < config_.box_min[i]) wall[i] = -config_.wall_stiffness * (position_[i] - config_.box_min[i]);
    }
    glm::dvec3 hand{0.0};
    if (config_.hand.holding) {
      const double t = static_cast<double>(counters_.commands) * config_.period;
      const glm::dvec3 target = config_.hand.path.at(t);
      const glm::dvec3 target_v = (config_.hand.path.at(t + config_.period) - target) / config_.period;
      hand = config_.hand.stiffness * (target - position_) + config_.hand.damping * (target_v - velocity_);
    }
    const glm::dvec3 f = motor_force_ + hand + push_ + wall - config_.damping * velocity_;
    velocity_ += f / config_.mass * config_.period;
    position_ += velocity_ * config_.period;
  }

  SimulatedFalconConfig config_;
  FalconKinematics kin_;
  SimulatedFalconCounters counters_{};
  falcon::PacketFramer framer_{};
  falcon::Command command_{};
  std::array<std::uint8_t, 1024> in_{};
  std::size_t in_size_{0};
  std::size_t loaded_{0};
  std::array<std::int16_t, 3> forced_counts_{};
  glm::dvec3 position_{0.0};
  glm::dvec3 velocity_{0.0};
  glm::dvec3 push_{0.0};
  glm::dvec3 motor_force_{0.0};
  std::uint16_t baud_{falcon::sio::baud_normal};
  int flaky_left_{0};
  int homing_count_{0};
  std::uint8_t homed_{0};
  std::uint8_t buttons_{0};
  bool dtr_{false};
  bool running_{false};
  bool checked_{false};
  bool loading_{false};
  bool load_good_{true};
  bool lost_{false};
  bool stalled_{false};
  bool forced_{false};
};

}  // namespace hapticfield
