#pragma once
/// @file simulated_inverse3.hpp
/// A simulated Haply Inverse3 for tests and demos, at the byte level: it
/// takes the request bytes a host writes (arm-protocols.md section 4) and
/// produces exactly the reply bytes of inverse3_codec.hpp. Its mechanics
/// are ours, not Haply's: the handle is a point mass with viscous damping
/// in a box (device frame), stepped one period per force request; the
/// joints of a 0x1A request are three independent rotors (no kinematics:
/// Haply's are not published). Our assumptions where the sources are
/// silent: requests before the first wake-up get no reply, unknown bytes
/// are skipped one at a time, the reply header bytes are configurable.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>

#include <glm/vec3.hpp>

#include "hapticfield/arms/inverse3/inverse3_codec.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/protocol/stream_framer.hpp"

namespace hapticfield {

struct SimulatedInverse3Config {
  inverse3::Identity identity{0x0B, 0x1234, 3, 2, 7, {}};  ///< the wake-up reply (header 0x0B: code + 1, a guess)
  std::uint8_t force_header{0x2B};                         ///< header of 0x2A replies (a guess)
  std::uint8_t joint_header{0x1B};                         ///< header of 0x1A replies (a guess)
  double mass{0.3};                                        ///< handle mass [kg]
  double damping{2.0};                                     ///< viscous damping [N s/m]
  double period{1e-3};                                     ///< time per force request [s]
  glm::dvec3 initial_position{0.0, 0.1, 0.05};             ///< device frame [m]
  double box{0.15};                                        ///< |position component| limit [m] (a stop)
  double joint_inertia{1e-4};                              ///< per joint [kg m^2]
  double joint_damping{1e-3};                              ///< per joint [N m s/rad]

  /// @throws std::invalid_argument naming the first parameter that makes no sense.
  void validate() const {
    const auto bad = [](double v) { return !std::isfinite(v) || v <= 0.0; };
    if (bad(mass) || bad(period) || bad(box) || bad(joint_inertia))
      throw std::invalid_argument(
          "SimulatedInverse3Config: mass, period, box and joint_inertia must be finite and > 0");
    if (!std::isfinite(damping) || damping < 0.0 || !std::isfinite(joint_damping) || joint_damping < 0.0)
      throw std::invalid_argument("SimulatedInverse3Config: damping must be finite and >= 0");
    for (int i = 0; i < 3; ++i)
      if (!(std::fabs(initial_position[i]) <= box))
        throw std::invalid_argument("SimulatedInverse3Config: initial_position must lie in the box [m]");
  }
};

/// Counts of what the simulated device met.
struct SimulatedInverse3Counters {
  std::uint64_t wakes{0};
  std::uint64_t forces{0};       ///< 0x2A requests served
  std::uint64_t torques{0};      ///< 0x1A requests served
  std::uint64_t before_wake{0};  ///< requests ignored before the first wake-up
  std::uint64_t skipped{0};      ///< unknown bytes skipped
};

class SimulatedInverse3 {
 public:
  explicit SimulatedInverse3(SimulatedInverse3Config config = {}) : config_(config) {
    config_.validate();
    position_ = config_.initial_position;
  }

  /// Takes request bytes as they come (any split); calls reply(span) once
  /// per whole request with its reply bytes.
  template <class Reply>
  void feed(std::span<const std::uint8_t> bytes, Reply&& reply) {
    for (const std::uint8_t b : bytes) {
      if (size_ == 0 && b != inverse3::code::wake && b != inverse3::code::force && b != inverse3::code::joint_torques) {
        ++counters_.skipped;
        continue;
      }
      rx_[size_++] = b;
      const std::size_t need =
          rx_[0] == inverse3::code::wake ? inverse3::wake_request_size : inverse3::command_request_size;
      if (size_ < need) continue;
      size_ = 0;
      std::array<std::uint8_t, inverse3::max_frame_size> out{};
      const std::size_t n = serve(std::span<const std::uint8_t>(rx_.data(), need), out);
      if (n) reply(std::span<const std::uint8_t>(out.data(), n));
    }
  }

  [[nodiscard]] const glm::dvec3& position() const noexcept { return position_; }
  [[nodiscard]] const glm::dvec3& velocity() const noexcept { return velocity_; }
  /// Last force applied, device frame [N].
  [[nodiscard]] const glm::dvec3& force() const noexcept { return force_; }
  /// The largest force applied so far, device frame [N].
  [[nodiscard]] const glm::dvec3& peak_force() const noexcept { return peak_force_; }
  /// Last joint torques applied [N mm].
  [[nodiscard]] const glm::dvec3& torque() const noexcept { return torque_; }
  [[nodiscard]] const glm::dvec3& joint_angles_deg() const noexcept { return q_deg_; }
  [[nodiscard]] const SimulatedInverse3Counters& counters() const noexcept { return counters_; }

 private:
  std::size_t serve(std::span<const std::uint8_t> req, std::span<std::uint8_t> out) {
    if (req[0] == inverse3::code::wake) {
      ++counters_.wakes;
      awake_ = true;
      position_ = config_.initial_position;  // "resets the device's state" (section 4)
      velocity_ = glm::dvec3{0.0};
      q_deg_ = qd_deg_ = force_ = peak_force_ = torque_ = glm::dvec3{0.0};
      return inverse3::encode_wake_reply(config_.identity, out);
    }
    if (!awake_) {
      ++counters_.before_wake;
      return 0;
    }
    std::array<float, 3> v{};
    if (inverse3::decode_command(req, v) != Status::ok) return 0;
    const glm::dvec3 in{v[0], v[1], v[2]};
    inverse3::StateReply r;
    if (req[0] == inverse3::code::force) {
      ++counters_.forces;
      force_ = in;
      if (std::isfinite(in.x + in.y + in.z) &&
          in.x * in.x + in.y * in.y + in.z * in.z >
              peak_force_.x * peak_force_.x + peak_force_.y * peak_force_.y + peak_force_.z * peak_force_.z)
        peak_force_ = in;
      step_handle();
      r.header = config_.force_header;
      for (std::size_t i = 0; i < 3; ++i) {
        r.first[i] = static_cast<float>(position_[static_cast<int>(i)]);
        r.second[i] = static_cast<float>(velocity_[static_cast<int>(i)]);
      }
    } else {
      ++counters_.torques;
      torque_ = in;
      step_joints();
      r.header = config_.joint_header;
      for (std::size_t i = 0; i < 3; ++i) {
        r.first[i] = static_cast<float>(q_deg_[static_cast<int>(i)]);
        r.second[i] = static_cast<float>(qd_deg_[static_cast<int>(i)]);
      }
    }
    return inverse3::encode_state_reply(r, out);
  }

  /// Semi-implicit Euler, one period: m a = F - b v, stops at the box.
  void step_handle() noexcept {
    const glm::dvec3 f = glm::dvec3(std::isfinite(force_.x) ? force_.x : 0.0, std::isfinite(force_.y) ? force_.y : 0.0,
                                    std::isfinite(force_.z) ? force_.z : 0.0);
    velocity_ += (f - config_.damping * velocity_) / config_.mass * config_.period;
    position_ += velocity_ * config_.period;
    for (int i = 0; i < 3; ++i)
      if (std::fabs(position_[i]) > config_.box) {
        position_[i] = std::copysign(config_.box, position_[i]);
        velocity_[i] = 0.0;
      }
  }

  void step_joints() noexcept {
    constexpr double deg = 180.0 / 3.14159265358979323846;  // [deg/rad]
    for (int i = 0; i < 3; ++i) {
      const double tau = std::isfinite(torque_[i]) ? torque_[i] * 1e-3 : 0.0;  // [N m]
      double qd = qd_deg_[i] / deg;                                            // [rad/s]
      qd += (tau - config_.joint_damping * qd) / config_.joint_inertia * config_.period;
      qd_deg_[i] = qd * deg;
      q_deg_[i] += qd_deg_[i] * config_.period;
    }
  }

  SimulatedInverse3Config config_;
  SimulatedInverse3Counters counters_{};
  std::array<std::uint8_t, inverse3::max_frame_size> rx_{};
  std::size_t size_{0};
  glm::dvec3 position_{0.0};
  glm::dvec3 velocity_{0.0};
  glm::dvec3 force_{0.0};
  glm::dvec3 peak_force_{0.0};
  glm::dvec3 torque_{0.0};
  glm::dvec3 q_deg_{0.0};
  glm::dvec3 qd_deg_{0.0};
  bool awake_{false};
};

/// In-memory link between a host and a SimulatedInverse3: write() hands the
/// request bytes to the device, which answers at once; its reply bytes go
/// through the same fixed-size framing as SerialTransport with
/// Framing::fixed (a read that waits and ends mid-frame drops the partial
/// frame; a read that does not wait leaves it). Deterministic: no threads,
/// no clock.
class SimulatedInverse3Transport final : public Transport {
 public:
  explicit SimulatedInverse3Transport(SimulatedInverse3& device) : device_(&device) {}

  /// State replies (0x1A/0x2A, 1-based count) number `reply` and on are cut
  /// to their first `keep` bytes, `replies` of them: the rest of each is
  /// lost on the wire (a USB packet lost, a device reset mid-reply).
  void truncate_replies(std::uint64_t reply, std::size_t keep, std::uint64_t replies = 1) noexcept {
    truncate_from_ = reply;
    truncate_count_ = replies;
    keep_ = keep;
  }

  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept override {
    const Status s = framer_.next(buffer, size);
    if (s == Status::ok) return s;
    if (timeout_us > 0 && framer_.pending() > 0) {  // the wait ends mid-frame: what came cannot be a whole reply
      framer_.drop_pending();
      return Status::timeout;
    }
    return timeout_us > 0 ? Status::timeout : Status::no_data;
  }

  Status write(std::span<const std::uint8_t> report) noexcept override {
    device_->feed(report, [this](std::span<const std::uint8_t> reply) {
      std::size_t n = reply.size();
      if (n == inverse3::state_reply_size) {
        ++state_replies_;
        if (state_replies_ >= truncate_from_ && state_replies_ < truncate_from_ + truncate_count_ && keep_ < n) {
          n = keep_;
          ++truncated_;
        }
      }
      framer_.push(reply.first(n));
    });
    return Status::ok;
  }

  Status get_feature(std::span<std::uint8_t>, std::size_t&) noexcept override { return Status::unsupported; }
  Status send_feature(std::span<const std::uint8_t>) noexcept override { return Status::unsupported; }
  Status set_frame_size(std::size_t n) noexcept override {
    return n >= 1 && framer_.set_frame_size(n) ? Status::ok : Status::bad_value;
  }
  std::size_t drop_pending() noexcept override { return framer_.drop_pending(); }
  [[nodiscard]] std::size_t pending() const noexcept override { return framer_.pending(); }
  [[nodiscard]] std::string_view where() const noexcept override { return "simulated Inverse3"; }

  /// State replies the device sent, and how many of them were cut short.
  [[nodiscard]] std::uint64_t state_replies() const noexcept { return state_replies_; }
  [[nodiscard]] std::uint64_t truncated() const noexcept { return truncated_; }

 private:
  SimulatedInverse3* device_;
  StreamFramer<512> framer_{Framing::fixed};
  std::uint64_t state_replies_{0};
  std::uint64_t truncate_from_{0};
  std::uint64_t truncate_count_{0};
  std::uint64_t truncated_{0};
  std::size_t keep_{inverse3::state_reply_size};
};

}  // namespace hapticfield
