#pragma once
/// @file falcon.hpp
/// Falcon: the Device for a Novint Falcon over any FalconUsb. At
/// construction it sets the FTDI link up, checks whether the firmware runs
/// (the Falcon forgets it at every power-up) and otherwise uploads the
/// user's firmware file through the boot loader, retrying, as loading is
/// known to fail now and then. Each tick it sends one 16-byte command
/// (motor counts, LEDs, homing mode) and decodes the newest report:
/// encoders -> theta1 -> Newton forward kinematics (FalconKinematics).
/// docs/arms-falcon.md has the sources, the units and what never ran on a
/// real Falcon.

#include <time.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "hapticfield/arms/falcon/falcon_codec.hpp"
#include "hapticfield/arms/falcon/falcon_kinematics.hpp"
#include "hapticfield/arms/falcon/falcon_usb.hpp"
#include "hapticfield/core/error.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/device/device_error.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/transport.hpp"

namespace hapticfield {

/// A box the published geometry reaches everywhere (test_falcon checks a
/// grid over it), device frame [m]: 7 x 7 x 8 cm, deeper behind the
/// workspace centre than in front of it. Novint's own figure is a 4 in cube.
inline constexpr glm::dvec3 falcon_workspace_min{-0.035, -0.035, -0.065};
inline constexpr glm::dvec3 falcon_workspace_max{0.035, 0.035, 0.015};

/// Largest firmware file accepted (Novint's are about 8 KiB) [bytes].
inline constexpr std::uintmax_t falcon_max_firmware_bytes = 1u << 20;

/// Reads a firmware file whole; it is sent as it is (never parsed).
/// @throws FileError naming the file: missing, unreadable, empty or too large.
[[nodiscard]] inline std::vector<std::uint8_t> read_falcon_firmware(const std::string& path) {
  const std::uintmax_t size = check_file(path, falcon_max_firmware_bytes);
  if (size == 0) throw FileError("Falcon firmware '" + path + "': the file is empty");
  std::ifstream in(path, std::ios::binary);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size));
  if (!in || static_cast<std::uintmax_t>(in.gcount()) != size)
    throw FileError("Falcon firmware '" + path + "': could not read " + std::to_string(size) + " bytes");
  return bytes;
}

struct FalconConfig {
  /// Novint's firmware file (docs/arms-falcon.md says where their driver
  /// puts it); empty: the Falcon must already run a firmware.
  std::string firmware_path{};
  int firmware_attempts{10};     ///< uploads tried before giving up
  int handshake_attempts{100};   ///< boot loader check messages per upload
  int reply_timeout_us{100000};  ///< wait for each boot loader reply [us]
  int probe_packets{20};         ///< commands sent to see whether a firmware answers
  int probe_timeout_us{5000};    ///< wait for each answer [us]
  FalconGeometry geometry{};
  double max_force{8.0};                    ///< [N] (CHAI3D's Falcon figure; not measured)
  double counts_per_newton_metre{10000.0};  ///< motor command per joint torque [counts/(N m)] (libnifalcon)
  int max_motor_count{4096};                ///< |command| limit; larger torques are scaled down together [counts]
  double velocity_cutoff{100.0};            ///< first-order low-pass on the velocity estimate [Hz]
  double reach{0.1};                        ///< a pose with a component beyond this is impossible [m]
  int newton_iterations{FalconKinematics::default_max_iterations};
  TimeSource now{};  ///< host time [ns] for the velocity; empty: CLOCK_MONOTONIC

  /// @throws std::invalid_argument naming the first setting that makes no sense.
  void validate() const {
    geometry.validate();
    if (firmware_attempts < 1 || firmware_attempts > 100)
      throw std::invalid_argument("FalconConfig: firmware_attempts must be 1..100");
    if (handshake_attempts < 1 || handshake_attempts > 1000)
      throw std::invalid_argument("FalconConfig: handshake_attempts must be 1..1000");
    if (probe_packets < 1 || probe_packets > 10000)
      throw std::invalid_argument("FalconConfig: probe_packets must be 1..10000");
    if (reply_timeout_us < 0 || reply_timeout_us > 2000000 || probe_timeout_us < 0 || probe_timeout_us > 2000000)
      throw std::invalid_argument("FalconConfig: reply_timeout_us and probe_timeout_us must be 0..2000000 [us]");
    const auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
    if (!pos(max_force)) throw std::invalid_argument("FalconConfig: max_force must be finite and > 0 [N]");
    if (!pos(counts_per_newton_metre))
      throw std::invalid_argument("FalconConfig: counts_per_newton_metre must be finite and > 0");
    if (max_motor_count < 1 || max_motor_count > 32767)
      throw std::invalid_argument("FalconConfig: max_motor_count must be 1..32767 [counts]");
    if (!pos(velocity_cutoff)) throw std::invalid_argument("FalconConfig: velocity_cutoff must be finite and > 0 [Hz]");
    if (!pos(reach) || reach > 1.0) throw std::invalid_argument("FalconConfig: reach must be within (0, 1] [m]");
    if (newton_iterations < 1 || newton_iterations > 1000)
      throw std::invalid_argument("FalconConfig: newton_iterations must be 1..1000");
  }
};

/// Counts since construction.
struct FalconCounters {
  std::uint64_t reports{0};            ///< reports decoded
  std::uint64_t malformed{0};          ///< framed packets that did not decode
  std::uint64_t impossible{0};         ///< reports refused: no pose gives their angles, or beyond reach
  std::uint64_t commands{0};           ///< commands written
  std::uint64_t write_errors{0};       ///< commands not written (link busy or gone)
  std::uint64_t firmware_uploads{0};   ///< upload attempts made at construction
  std::uint64_t newton_iterations{0};  ///< summed over all reports
  int newton_worst{0};                 ///< most Newton steps one report took
};

class Falcon {
 public:
  /// Sets the link up and makes sure a firmware runs (uploading
  /// config.firmware_path when none answers).
  /// @throws std::invalid_argument for a bad configuration; FileError for a
  ///         firmware file that cannot be read; DeviceError when no firmware
  ///         runs and none was given, or the upload failed every attempt.
  explicit Falcon(FalconUsb& usb, FalconConfig config = {})
      : usb_(&usb), config_(std::move(config)), kin_(config_.geometry) {
    config_.validate();
    info_.name = "Novint Falcon";
    info_.max_force = config_.max_force;
    info_.continuous_force = config_.max_force;  // no continuous figure is published
    info_.workspace_min = falcon_workspace_min;
    info_.workspace_max = falcon_workspace_max;
    info_.validate();
    start();
  }

  [[nodiscard]] const DeviceInfo& info() const noexcept { return info_; }
  [[nodiscard]] const FalconKinematics& kinematics() const noexcept { return kin_; }
  [[nodiscard]] const FalconCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const FalconConfig& config() const noexcept { return config_; }
  /// True when the firmware was uploaded at construction (false: it already ran).
  [[nodiscard]] bool uploaded_firmware() const noexcept { return uploaded_; }
  /// The last command sent.
  [[nodiscard]] const falcon::Command& last_command() const noexcept { return command_; }

  /// Drains the link and decodes the newest report. ok when a newer state
  /// was decoded, no_data when none, impossible when any report drained has
  /// angles no pose gives (forward kinematics did not converge) or a pose
  /// beyond FalconConfig::reach (never used), disconnected when the link is gone.
  Status read(DeviceState& state) noexcept {
    bool gone = false;
    for (int i = 0; i < 16; ++i) {
      std::size_t n = 0;
      const Status s = usb_->read(rx_, n, 0);
      if (s == Status::disconnected) {
        gone = true;
        break;
      }
      if (s != Status::ok || n == 0) break;
      framer_.push(std::span<const std::uint8_t>(rx_.data(), n));
    }
    bool fresh = false;
    bool impossible = false;
    falcon::Report newest{};
    glm::dvec3 pose{0.0};
    std::array<std::uint8_t, falcon::packet_size> packet{};
    while (framer_.pop(packet)) {
      falcon::Report r;
      if (falcon::decode(packet, r) != Status::ok) {
        ++counters_.malformed;
        continue;
      }
      glm::dvec3 p{0.0};
      if (!solve(r, p)) {
        impossible = true;
        continue;
      }
      newest = r;
      pose = p;
      fresh = true;
    }
    if (fresh) update(newest, pose, state);
    if (gone) return Status::disconnected;
    if (impossible) return Status::impossible;
    return fresh ? Status::ok : Status::no_data;
  }

  /// Commands a handle force [N] in the device frame: tau = J^T F at the
  /// last pose, counts = -counts_per_newton_metre tau, all three scaled
  /// down together when one exceeds max_motor_count (the direction kept).
  /// Zero when disarmed, not homed, before the first state, for a
  /// non-finite force or at a singular pose.
  Status write(const glm::dvec3& force) noexcept {
    std::array<std::int16_t, 3> counts{};
    torque_ = glm::dvec3{0.0};
    const bool on =
        armed_ && homed_ && have_state_ && std::isfinite(force.x) && std::isfinite(force.y) && std::isfinite(force.z);
    glm::dvec3 tau{0.0};
    if (on && kin_.torques(position_, force, tau)) {
      glm::dvec3 c = -config_.counts_per_newton_metre * tau;
      const double worst = largest_component(c);
      const double limit = static_cast<double>(config_.max_motor_count);
      if (worst > limit) c *= limit / worst;
      if (std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z)) {
        for (int i = 0; i < 3; ++i)
          counts[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(std::lround(c[i]));
        torque_ = -c / config_.counts_per_newton_metre;
      }
    }
    return send(counts);
  }

  /// Motors on or off. Off sends a zero command at once and every later
  /// write() sends zero until armed again. On takes effect once homed.
  Status set_armed(bool on) noexcept {
    armed_ = on;
    if (!on) return send({});
    return Status::ok;
  }

  /// Homing mode in every command until all three encoders report homed
  /// (the user moves the grip all the way out, then straight in).
  Status request_home() noexcept {
    homing_ = true;
    return Status::ok;
  }

  /// LEDs chosen by the state (red: not homed; blue: homed, disarmed;
  /// green: homed and armed), or fixed falcon::led:: bits.
  void set_leds(std::uint8_t bits) noexcept {
    manual_leds_ = true;
    leds_ = static_cast<std::uint8_t>(bits & falcon::led::all);
  }
  void set_automatic_leds() noexcept { manual_leds_ = false; }

 private:
  void start() {
    setup_normal_mode();
    if (probe()) return;
    if (config_.firmware_path.empty())
      throw DeviceError(
          "Falcon: firmware file not given: the Falcon runs no firmware (it forgets it at every power-up); pass "
          "the path to the firmware of Novint's driver (docs/arms-falcon.md)" +
          where());
    const std::vector<std::uint8_t> firmware = read_falcon_firmware(config_.firmware_path);
    std::string last;
    for (int attempt = 1; attempt <= config_.firmware_attempts; ++attempt) {
      ++counters_.firmware_uploads;
      last = upload(firmware);
      if (last.empty()) {
        setup_normal_mode();
        if (probe()) {
          uploaded_ = true;
          return;
        }
        last = "the firmware was sent but does not answer";
      }
      if (last == "disconnected") break;
    }
    throw DeviceError("Falcon: the firmware '" + config_.firmware_path + "' did not load after " +
                      std::to_string(counters_.firmware_uploads) + " attempt(s) (last: " + last +
                      "); unplug the Falcon's power and USB, plug them back and try again" + where());
  }

  [[nodiscard]] std::string where() const {
    const std::string_view w = usb_->where();
    return w.empty() ? std::string() : " (" + std::string(w) + ")";
  }

  void control(std::uint8_t request, std::uint16_t value) {
    const Status s = usb_->control(request, value);
    if (s != Status::ok)
      throw DeviceError("Falcon: FTDI request " + std::to_string(request) + " failed: " + std::string(to_string(s)) +
                        where());
  }

  void setup_normal_mode() {
    control(falcon::sio::latency, falcon::sio::latency_normal);
    control(falcon::sio::baud_rate, falcon::sio::baud_normal);
    control(falcon::sio::reset, falcon::sio::purge_rx);
    control(falcon::sio::reset, falcon::sio::purge_tx);
    framer_.clear();
  }

  /// True when a firmware answers a zero command with a report.
  bool probe() {
    for (int i = 0; i < config_.probe_packets; ++i) {
      if (send({}) == Status::disconnected) return false;
      std::size_t n = 0;
      const Status s = usb_->read(rx_, n, config_.probe_timeout_us);
      if (s == Status::disconnected) return false;
      if (s != Status::ok) continue;
      framer_.push(std::span<const std::uint8_t>(rx_.data(), n));
      std::array<std::uint8_t, falcon::packet_size> packet{};
      while (framer_.pop(packet)) {
        falcon::Report r;
        if (falcon::decode(packet, r) == Status::ok) {
          framer_.clear();
          return true;
        }
      }
    }
    return false;
  }

  /// Reads exactly want.size() bytes; false on silence or loss.
  bool read_exact(std::span<std::uint8_t> want) {
    std::size_t got = 0;
    for (int tries = 0; got < want.size() && tries < static_cast<int>(want.size()) + 8; ++tries) {
      std::size_t n = 0;
      const Status s = usb_->read(want.subspan(got), n, config_.reply_timeout_us);
      if (s == Status::disconnected) return false;
      if (s == Status::ok) got += n;
    }
    return got == want.size();
  }

  /// One upload through the boot loader; "" on success, else why not.
  std::string upload(const std::vector<std::uint8_t>& firmware) {
    namespace sio = falcon::sio;
    const std::pair<std::uint8_t, std::uint16_t> setup[] = {
        {sio::reset, sio::purge_rx},      {sio::reset, sio::purge_tx},     {sio::latency, sio::latency_firmware},
        {sio::baud_rate, sio::baud_9600}, {sio::data, sio::line_8n1},      {sio::flow_ctrl, 0},
        {sio::modem_ctrl, sio::rts_low},  {sio::modem_ctrl, sio::dtr_low}, {sio::modem_ctrl, sio::dtr_high}};
    for (const auto& [request, value] : setup)
      if (usb_->control(request, value) != Status::ok) return "disconnected";
    bool checked = false;
    for (int i = 0; i < config_.handshake_attempts && !checked; ++i) {
      if (usb_->write(falcon::check_request) == Status::disconnected) return "disconnected";
      std::array<std::uint8_t, 64> reply{};
      std::size_t n = 0;
      const Status s = usb_->read(reply, n, config_.reply_timeout_us);
      if (s == Status::disconnected) return "disconnected";
      if (s != Status::ok) continue;
      std::size_t skip = (n == falcon::check_reply.size() + 1 && reply[0] == 0x00) ? 1 : 0;
      checked = n - skip == falcon::check_reply.size();
      for (std::size_t k = 0; checked && k < falcon::check_reply.size(); ++k)
        checked = reply[skip + k] == falcon::check_reply[k];
    }
    if (!checked) return "the boot loader did not answer its check message";
    if (usb_->control(sio::modem_ctrl, sio::dtr_low) != Status::ok ||
        usb_->control(sio::baud_rate, sio::baud_firmware) != Status::ok)
      return "disconnected";
    const std::array<std::uint8_t, 1> ack{falcon::firmware_ack};
    std::array<std::uint8_t, 1> echo{};
    if (usb_->write(ack) != Status::ok || !read_exact(echo) || echo[0] != falcon::firmware_ack)
      return "the boot loader did not echo its start byte";
    std::array<std::uint8_t, falcon::firmware_chunk> back{};
    for (std::size_t at = 0; at < firmware.size(); at += falcon::firmware_chunk) {
      const std::size_t n = std::min(falcon::firmware_chunk, firmware.size() - at);
      const std::span<const std::uint8_t> chunk(firmware.data() + at, n);
      if (usb_->write(chunk) != Status::ok) return "a firmware chunk could not be sent";
      if (!read_exact(std::span<std::uint8_t>(back.data(), n)))
        return "the boot loader stopped echoing at byte " + std::to_string(at);
      for (std::size_t k = 0; k < n; ++k)
        if (back[k] != chunk[k]) return "the echo differs at byte " + std::to_string(at + k);
    }
    return "";
  }

  /// Angles -> pose for one report; false (counted) when impossible.
  bool solve(const falcon::Report& r, glm::dvec3& p) noexcept {
    const glm::dvec3 theta = kin_.angles(r.encoder);
    FalconForward fk = kin_.forward(theta, have_state_ ? position_ : glm::dvec3{0.0}, config_.newton_iterations);
    if (!fk.converged && have_state_) fk = kin_.forward(theta, glm::dvec3{0.0}, config_.newton_iterations);
    counters_.newton_iterations += static_cast<std::uint64_t>(fk.iterations);
    if (fk.iterations > counters_.newton_worst) counters_.newton_worst = fk.iterations;
    const double far = largest_component(fk.position);
    if (!fk.converged || !(far <= config_.reach)) {
      ++counters_.impossible;
      return false;
    }
    p = fk.position;
    return true;
  }

  Status send(const std::array<std::int16_t, 3>& counts) noexcept {
    command_.motor = counts;
    command_.homing = homing_ && !homed_;
    if (!manual_leds_) leds_ = !homed_ ? falcon::led::red : (armed_ ? falcon::led::green : falcon::led::blue);
    command_.leds = leds_;
    falcon::encode(command_, tx_);
    const Status s = usb_->write(tx_);
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

  void update(const falcon::Report& r, const glm::dvec3& p, DeviceState& s) noexcept {
    const std::int64_t t = now_ns();
    const bool homed = (r.homed & falcon::all_homed) == falcon::all_homed;
    if (homed != homed_) have_state_ = false;  // homing moves the encoders' zero: no velocity across it
    homed_ = homed;
    if (homed_) homing_ = false;
    if (have_state_) {
      const double dt = static_cast<double>(t - last_time_ns_) * 1e-9;
      if (dt > 0.0 && dt < 0.1) {
        const double alpha = 1.0 - std::exp(-2.0 * std::numbers::pi * config_.velocity_cutoff * dt);
        velocity_ += alpha * ((p - position_) / dt - velocity_);
      } else if (dt > 0.0) {
        velocity_ = glm::dvec3{0.0};
      }
    } else {
      velocity_ = glm::dvec3{0.0};
    }
    s.device_time = static_cast<double>(t) * 1e-9;
    s.position = p;
    s.velocity = velocity_;
    s.joint_angles = kin_.angles(r.encoder);
    s.applied_torque = torque_;  // commanded, not measured
    for (std::size_t i = 0; i < 3; ++i)
      s.encoder[i] = r.encoder[i];
    s.gimbal = {};
    ++sequence_;
    s.sequence = sequence_;
    s.command_echo = 0;
    s.flags =
        static_cast<std::uint16_t>((homed_ ? status_bits::homed : 0) | (homed_ && armed_ ? status_bits::armed : 0));
    s.buttons = r.buttons;
    s.valid = true;
    ++counters_.reports;
    position_ = p;
    last_time_ns_ = t;
    have_state_ = true;
  }

  FalconUsb* usb_;
  FalconConfig config_;
  FalconKinematics kin_;
  DeviceInfo info_{};
  FalconCounters counters_{};
  falcon::PacketFramer framer_{};
  falcon::Command command_{};
  std::array<std::uint8_t, falcon::usb_packet_size> rx_{};
  std::array<std::uint8_t, falcon::packet_size> tx_{};
  glm::dvec3 position_{0.0};
  glm::dvec3 velocity_{0.0};
  glm::dvec3 torque_{0.0};
  std::int64_t last_time_ns_{0};
  std::uint16_t sequence_{0};
  std::uint8_t leds_{0};
  bool manual_leds_{false};
  bool have_state_{false};
  bool armed_{false};
  bool homed_{false};
  bool homing_{false};
  bool uploaded_{false};
};

static_assert(Device<Falcon>);

}  // namespace hapticfield
