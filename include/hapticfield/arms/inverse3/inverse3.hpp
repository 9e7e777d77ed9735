#pragma once
/// @file inverse3.hpp
/// Inverse3: the Device for a Haply Inverse3 over a Transport with
/// fixed-size framing (SerialTransport with Framing::fixed), limited to the
/// well-sourced commands of arm-protocols.md section 4: wake-up (0x0A),
/// end-effector force (0x2A) with its state reply, joint torques (0x1A).
/// Request/reply in lock step: every write() sends one request, whose
/// reply the next read() decodes. The frame between the device's axes and
/// ours is a configurable signed rotation (the device's axes are not
/// published). Never checked on a device: docs/inverse3.md.

#include <time.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/arms/inverse3/inverse3_codec.hpp"
#include "hapticfield/core/error.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/transport.hpp"

namespace hapticfield {

/// The map from the device's frame to ours (x right, y up, z toward the
/// user): p_ours = rotation (p_device - origin), v_ours = rotation v_device,
/// F_device = rotation^T F_ours. The default (identity, origin 0) is a
/// placeholder: the Inverse3's axes and origin are not published, and the
/// device's handedness setting is said to change them.
struct Inverse3Frame {
  glm::dmat3 rotation{1.0};  ///< ours from device; must be orthonormal with det +1
  glm::dvec3 origin{0.0};    ///< device-frame point that becomes our origin [m]

  /// A signed axis permutation: our axis i is sign(a[i]) times device axis
  /// |a[i]| (1 = x, 2 = y, 3 = z). E.g. {1, 3, -2}: our x = device x, our
  /// y = device z, our z = -device y.
  /// @throws std::invalid_argument unless a names each device axis once and
  ///         the result is a rotation (det +1).
  [[nodiscard]] static Inverse3Frame axes(std::array<int, 3> a, glm::dvec3 origin = glm::dvec3{0.0}) {
    Inverse3Frame f;
    f.rotation = glm::dmat3(0.0);
    for (int i = 0; i < 3; ++i) {
      const int k = a[static_cast<std::size_t>(i)];
      const int axis = k < 0 ? -k : k;
      if (axis < 1 || axis > 3) throw std::invalid_argument("Inverse3Frame: axes entries must be +-1, +-2 or +-3");
      f.rotation[axis - 1][i] = k < 0 ? -1.0 : 1.0;  // glm: [column][row]
    }
    f.origin = origin;
    f.validate();
    return f;
  }

  /// @throws std::invalid_argument naming what is wrong: non-finite, not
  ///         orthonormal (|R^T R - I| > 1e-9) or a reflection (det -1).
  void validate() const {
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r)
        if (!std::isfinite(rotation[c][r]))
          throw std::invalid_argument("Inverse3Frame: rotation entries must be finite");
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(origin[i])) throw std::invalid_argument("Inverse3Frame: origin must be finite [m]");
    const glm::dmat3 g = glm::transpose(rotation) * rotation;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r)
        if (std::fabs(g[c][r] - (c == r ? 1.0 : 0.0)) > 1e-9)
          throw std::invalid_argument("Inverse3Frame: rotation must be orthonormal (R^T R = I within 1e-9)");
    if (glm::determinant(rotation) < 0.0)
      throw std::invalid_argument("Inverse3Frame: rotation is a reflection (det -1); both frames are right-handed");
  }

  [[nodiscard]] glm::dvec3 position_to_ours(const glm::dvec3& p) const noexcept { return rotation * (p - origin); }
  [[nodiscard]] glm::dvec3 vector_to_ours(const glm::dvec3& v) const noexcept { return rotation * v; }
  [[nodiscard]] glm::dvec3 vector_to_device(const glm::dvec3& v) const noexcept { return glm::transpose(rotation) * v; }
};

struct Inverse3Config {
  Inverse3Frame frame{};  ///< device axes to ours (default unverified)
  /// Force clamp and DeviceInfo::max_force [N]: a conservative figure of
  /// ours, not a datasheet value (unverified).
  double max_force{3.0};
  /// Clamp of write_joint_torques() [N mm]; the sourced API states torques
  /// in N mm and about 20 N mm to overcome friction (conservative, unverified).
  double max_joint_torque{100.0};
  glm::dvec3 workspace_min{-0.2, -0.2, -0.2};  ///< [m] our frame (unverified)
  glm::dvec3 workspace_max{0.2, 0.2, 0.2};     ///< [m] our frame (unverified)
  /// A decoded position component beyond this is a corrupt or misaligned
  /// frame, dropped [m].
  double plausible_position{1.0};
  double plausible_velocity{20.0};  ///< same for velocity [m/s]
  /// Fastest the handle can move [m/s]: ours (a fast hand), Haply publishes
  /// no figure. A reply whose velocity exceeds it, or whose position is
  /// further from the last accepted one than max_speed times the time
  /// between their requests plus jump_tolerance, cannot be the arm's:
  /// read() returns Status::impossible (the loop latches) and the stream is
  /// resynchronised. The replies carry no checksum: this continuity is what
  /// shows a misassembled frame whose header byte happens to be right.
  double max_speed{3.0};
  double jump_tolerance{0.002};  ///< [m] on top of max_speed x time (rounding, request-time jitter)
  int wake_attempts{3};          ///< wake-up requests sent at construction before giving up
  int reply_timeout_us{200000};  ///< wait for each setup reply [us]
  /// Requests whose replies have not come: beyond this many the replies
  /// count as lost; the stream is resynchronised (pending bytes dropped).
  int max_outstanding{16};
  std::string port{};  ///< named in errors; empty: the transport's where()
  TimeSource now{};    ///< host time [ns] for the state stamps; empty: CLOCK_MONOTONIC

  /// @throws std::invalid_argument naming the first setting that makes no sense.
  void validate() const {
    frame.validate();
    const auto bad = [](double v) { return !std::isfinite(v) || v <= 0.0; };
    if (bad(max_force)) throw std::invalid_argument("Inverse3Config: max_force must be finite and > 0 [N]");
    if (bad(max_joint_torque))
      throw std::invalid_argument("Inverse3Config: max_joint_torque must be finite and > 0 [N mm]");
    if (bad(plausible_position) || bad(plausible_velocity))
      throw std::invalid_argument("Inverse3Config: plausible_position and plausible_velocity must be finite and > 0");
    if (bad(max_speed) || bad(jump_tolerance))
      throw std::invalid_argument("Inverse3Config: max_speed [m/s] and jump_tolerance [m] must be finite and > 0");
    if (wake_attempts < 1 || wake_attempts > 100)
      throw std::invalid_argument("Inverse3Config: wake_attempts must be 1..100");
    if (reply_timeout_us < 1000 || reply_timeout_us > 5'000'000)
      throw std::invalid_argument("Inverse3Config: reply_timeout_us must be 1000..5000000 [us]");
    if (max_outstanding < 1 || max_outstanding > 32)
      throw std::invalid_argument("Inverse3Config: max_outstanding must be 1..32");
  }
};

/// Counts since construction.
struct Inverse3Counters {
  std::uint64_t replies{0};        ///< state and joint replies decoded
  std::uint64_t implausible{0};    ///< replies dropped: non-finite or beyond the plausible bounds
  std::uint64_t wrong_header{0};   ///< replies dropped: header byte not the one this request's replies carry
  std::uint64_t impossible{0};     ///< replies refused: faster than max_speed, or a jump (continuity)
  std::uint64_t unexpected{0};     ///< whole frames with no request outstanding
  std::uint64_t resyncs{0};        ///< times pending bytes were dropped
  std::uint64_t dropped_bytes{0};  ///< bytes dropped by those
  std::uint64_t lost_replies{0};   ///< requests given up on (max_outstanding)
  std::uint64_t commands{0};       ///< requests written
  std::uint64_t write_errors{0};
  /// Replies seen per header byte value (the values are unpublished).
  std::array<std::uint64_t, 256> headers{};
};

class Inverse3 {
  /// What the frames of one read() were: all in line, one dropped as out
  /// of line (resynchronised), or one describing an impossible motion.
  enum class Verdict : std::uint8_t { good, out_of_line, impossible };
  /// A request in flight: its code and when it was sent [ns].
  struct Request {
    std::uint8_t code{0};
    std::int64_t sent{0};
  };

 public:
  static constexpr std::size_t queue_capacity = 32;  ///< requests tracked in flight

  /// Wakes the device (0x0A, at most wake_attempts times, each reply waited
  /// for reply_timeout_us), then sends a zero force and waits for the first
  /// state.
  /// @throws std::invalid_argument for a bad configuration or a transport
  ///         without fixed-size framing; hapticfield::Error naming the port
  ///         when the device does not answer or is gone.
  explicit Inverse3(Transport& transport, Inverse3Config config = {})
      : transport_(&transport), config_(std::move(config)) {
    config_.validate();
    if (config_.port.empty()) config_.port = std::string(transport.where());
    if (config_.port.empty()) config_.port = "its transport";
    info_.name = "Haply Inverse3";
    info_.max_force = config_.max_force;
    info_.continuous_force = config_.max_force;  // no sourced figure
    info_.workspace_min = config_.workspace_min;
    info_.workspace_max = config_.workspace_max;
    info_.nominal_rate = 1000.0;  // "at least 1 kHz recommended" (section 4)
    info_.degrees_of_freedom = 3;
    info_.validate();
    wake();
  }

  [[nodiscard]] const DeviceInfo& info() const noexcept { return info_; }
  [[nodiscard]] const Inverse3Config& config() const noexcept { return config_; }
  [[nodiscard]] const Inverse3Counters& counters() const noexcept { return counters_; }
  /// What the wake-up reply said.
  [[nodiscard]] const inverse3::Identity& identity() const noexcept { return identity_; }
  /// Joint velocities of the last joint reply [rad/s] (device joint order).
  [[nodiscard]] const glm::dvec3& joint_velocities() const noexcept { return joint_velocity_; }
  /// Force of the last 0x2A request, in the device frame [N].
  [[nodiscard]] const glm::dvec3& last_device_force() const noexcept { return last_device_force_; }
  /// Requests sent whose replies have not been read yet.
  [[nodiscard]] std::size_t outstanding() const noexcept { return count_; }

  /// Reads every whole reply there is and decodes the newest into state,
  /// in our frame. ok when a newer end-effector state came, no_data when
  /// none, disconnected when the transport is gone. A joint reply updates
  /// joint_angles (and joint_velocities()) only. Once every request has its
  /// reply, bytes left over cannot be a reply: they are dropped.
  /// A frame that cannot be a reply (non-finite, beyond the plausible
  /// bounds, a header byte other than the one the first reply of its kind
  /// carried) is dropped and the stream resynchronised (pending bytes
  /// dropped, outstanding requests given up): resync when no good state
  /// came. A frame that looks like a reply but describes a motion the arm
  /// cannot make (Inverse3Config::max_speed) is refused likewise, and
  /// read() returns impossible: the loop latches rather than guess.
  Status read(DeviceState& state) noexcept {
    bool fresh = pending_;
    pending_ = false;
    verdict_ = Verdict::good;
    for (int i = 0; i < 256; ++i) {
      std::size_t size = 0;
      const Status s = transport_->read(buf_, size, 0);
      if (s == Status::no_data || s == Status::timeout) break;
      if (s == Status::disconnected) {
        if (fresh) publish(state);
        return Status::disconnected;
      }
      if (s != Status::ok) continue;
      fresh = take(std::span<const std::uint8_t>(buf_.data(), size)) || fresh;
    }
    if (count_ == 0 && transport_->pending() > 0) resync();
    if (verdict_ == Verdict::impossible) return Status::impossible;
    if (!fresh) return verdict_ == Verdict::out_of_line ? Status::resync : Status::no_data;
    publish(state);
    return Status::ok;
  }

  /// Sends 0x2A with force [N] (our frame) turned into the device's frame,
  /// its magnitude clamped to max_force. Zero when disarmed or non-finite.
  Status write(const glm::dvec3& force) noexcept {
    glm::dvec3 f{0.0};
    if (armed_ && std::isfinite(force.x) && std::isfinite(force.y) && std::isfinite(force.z)) {
      f = force;
      const double m = std::sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
      if (m > config_.max_force) f *= config_.max_force / m;
    }
    last_device_force_ = config_.frame.vector_to_device(f);
    return send(inverse3::code::force, last_device_force_);
  }

  /// Sends 0x1A with joint torques [N mm] (device joint order), each
  /// clamped to +-max_joint_torque. Zero when disarmed or non-finite. Its
  /// reply updates the joint angles only: a loop using it sees no new
  /// end-effector state.
  Status write_joint_torques(const glm::dvec3& torque_nmm) noexcept {
    glm::dvec3 t{0.0};
    if (armed_ && std::isfinite(torque_nmm.x) && std::isfinite(torque_nmm.y) && std::isfinite(torque_nmm.z))
      for (int i = 0; i < 3; ++i)
        t[i] = std::fmax(-config_.max_joint_torque, std::fmin(config_.max_joint_torque, torque_nmm[i]));
    return send(inverse3::code::joint_torques, t);
  }

  /// Motors on or off; off sends a zero force at once and every later write
  /// sends zero until armed again. The wire has no arming command: this is
  /// the host's own gate.
  Status set_armed(bool on) noexcept {
    armed_ = on;
    if (on) return Status::ok;
    last_device_force_ = glm::dvec3{0.0};
    return send(inverse3::code::force, last_device_force_);
  }

  /// No homing on the wire (the wake-up resets the device's state): unsupported.
  Status request_home() noexcept { return Status::unsupported; }

 private:
  void wake() {
    const std::string where = " on " + config_.port;
    if (transport_->set_frame_size(inverse3::wake_reply_size) != Status::ok)
      throw std::invalid_argument("Inverse3: the transport" + where +
                                  " has no fixed-size framing (use SerialTransport with Framing::fixed)");
    transport_->drop_pending();  // whatever came before the wake-up
    bool awake = false;
    for (int attempt = 0; attempt < config_.wake_attempts && !awake; ++attempt) {
      std::array<std::uint8_t, inverse3::wake_request_size> req{};
      const Status w = transport_->write(std::span<const std::uint8_t>(req.data(), inverse3::encode_wake(req)));
      if (w == Status::disconnected)
        throw Error("Inverse3: the device" + where + " is gone (disconnected during the wake-up)");
      std::size_t size = 0;
      const Status s = transport_->read(buf_, size, config_.reply_timeout_us);
      if (s == Status::disconnected)
        throw Error("Inverse3: the device" + where + " is gone (disconnected during the wake-up)");
      awake = s == Status::ok &&
              inverse3::decode_wake_reply(std::span<const std::uint8_t>(buf_.data(), size), identity_) == Status::ok;
    }
    if (!awake)
      throw Error("Inverse3: no reply to the wake-up (0x0A)" + where + " after " +
                  std::to_string(config_.wake_attempts) + " attempts of " +
                  std::to_string(config_.reply_timeout_us / 1000) +
                  " ms; check the port, the cable, and that no other program holds it");
    ++counters_.headers[identity_.header];
    if (transport_->set_frame_size(inverse3::state_reply_size) != Status::ok)
      throw std::invalid_argument("Inverse3: the transport" + where + " refused the state frame size");
    // The early client's order: wake, zero force, first state (section 4).
    if (send(inverse3::code::force, glm::dvec3{0.0}) == Status::disconnected)
      throw Error("Inverse3: the device" + where + " is gone (disconnected after the wake-up)");
    std::size_t size = 0;
    const Status s = transport_->read(buf_, size, config_.reply_timeout_us);
    if (s == Status::disconnected)
      throw Error("Inverse3: the device" + where + " is gone (disconnected after the wake-up)");
    if (s != Status::ok || !take(std::span<const std::uint8_t>(buf_.data(), size)) || verdict_ != Verdict::good)
      throw Error("Inverse3: the device" + where +
                  " answered the wake-up but sent no valid state for a zero force within " +
                  std::to_string(config_.reply_timeout_us / 1000) + " ms");
    pending_ = true;
  }

  /// Writes one request and remembers what its reply will be.
  Status send(std::uint8_t code, const glm::dvec3& v) noexcept {
    const std::array<float, 3> f{static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
    const std::size_t n = inverse3::encode_command(code, f, out_);
    if (count_ >= static_cast<std::size_t>(config_.max_outstanding)) {  // the replies are not coming
      counters_.lost_replies += count_;
      count_ = 0;
      resync();
    }
    const Status s = transport_->write(std::span<const std::uint8_t>(out_.data(), n));
    if (s != Status::ok) {
      ++counters_.write_errors;
      return s;
    }
    ++counters_.commands;
    queue_[(head_ + count_) % queue_capacity] = Request{code, now_ns()};
    ++count_;
    return s;
  }

  void resync() noexcept {
    const std::size_t n = transport_->drop_pending();
    if (n == 0) return;
    ++counters_.resyncs;
    counters_.dropped_bytes += n;
  }

  /// Drops a frame that is not a reply in line: resynchronises the stream
  /// (pending bytes and outstanding requests go: their bytes would be
  /// misaligned) and notes the worst verdict of this read.
  bool refuse(Verdict v) noexcept {
    if (v == Verdict::impossible || verdict_ == Verdict::good) verdict_ = v;
    counters_.lost_replies += count_;
    count_ = 0;
    resync();
    return false;
  }

  /// Decodes one whole reply frame against the oldest request in flight.
  /// True when it gave a new end-effector state.
  bool take(std::span<const std::uint8_t> frame) noexcept {
    Request request{inverse3::code::force, now_ns()};
    if (count_ > 0) {
      request = queue_[head_];
      head_ = (head_ + 1) % queue_capacity;
      --count_;
    } else {
      ++counters_.unexpected;  // a reply nobody asked for: most likely a late one to a request given up on
    }
    const bool joints = request.code == inverse3::code::joint_torques;
    inverse3::StateReply r;
    if (frame.size() != inverse3::state_reply_size) return false;
    ++counters_.headers[frame[0]];
    if (inverse3::decode_state_reply(frame, r) != Status::ok) {
      ++counters_.implausible;
      return refuse(Verdict::out_of_line);
    }
    // The header values are unpublished: the first reply of each kind
    // (taken in line, right after the wake-up's resynchronisation) names it.
    int& header = joints ? joint_header_ : force_header_;
    if (header < 0) header = r.header;
    if (r.header != header) {
      ++counters_.wrong_header;
      return refuse(Verdict::out_of_line);
    }
    const glm::dvec3 a{r.first[0], r.first[1], r.first[2]};
    const glm::dvec3 b{r.second[0], r.second[1], r.second[2]};
    if (joints) {
      constexpr double rad = 3.14159265358979323846 / 180.0;  // [rad/deg]
      joint_angle_ = a * rad;
      joint_velocity_ = b * rad;
      ++counters_.replies;
      return false;
    }
    for (int i = 0; i < 3; ++i)
      if (std::fabs(a[i]) > config_.plausible_position || std::fabs(b[i]) > config_.plausible_velocity) {
        ++counters_.implausible;
        return refuse(Verdict::out_of_line);
      }
    if (have_position_) {  // continuity: no faster than the arm can move
      const double dt = std::fmax(0.0, static_cast<double>(request.sent - last_sent_) * 1e-9);  // [s]
      const glm::dvec3 d = a - last_device_position_;
      const double jump = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
      const double speed = std::sqrt(b.x * b.x + b.y * b.y + b.z * b.z);
      if (!(jump <= config_.max_speed * dt + config_.jump_tolerance) || !(speed <= config_.max_speed)) {
        ++counters_.impossible;
        return refuse(Verdict::impossible);
      }
    }
    last_device_position_ = a;
    last_sent_ = request.sent;
    have_position_ = true;
    position_ = config_.frame.position_to_ours(a);
    velocity_ = config_.frame.vector_to_ours(b);
    ++counters_.replies;
    return true;
  }

  void publish(DeviceState& s) noexcept {
    s.device_time = static_cast<double>(now_ns()) * 1e-9;
    s.position = position_;
    s.velocity = velocity_;
    s.joint_angles = joint_angle_;
    s.applied_torque = glm::dvec3{0.0};  // not reported
    s.encoder = {};
    s.gimbal = {};
    ++sequence_;
    s.sequence = sequence_;
    s.command_echo = 0;
    // Neither homing nor arming is on the wire: homed always, armed as requested.
    s.flags = static_cast<std::uint16_t>(status_bits::homed | (armed_ ? status_bits::armed : 0));
    s.buttons = 0;
    s.valid = true;
  }

  [[nodiscard]] std::int64_t now_ns() const noexcept {
    if (config_.now) return config_.now();
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  }

  Transport* transport_;
  Inverse3Config config_;
  DeviceInfo info_{};
  Inverse3Counters counters_{};
  inverse3::Identity identity_{};
  std::array<std::uint8_t, 64> buf_{};
  std::array<std::uint8_t, inverse3::command_request_size> out_{};
  std::array<Request, queue_capacity> queue_{};  ///< requests in flight, oldest at head_
  std::size_t head_{0};
  std::size_t count_{0};
  glm::dvec3 position_{0.0};
  glm::dvec3 velocity_{0.0};
  glm::dvec3 joint_angle_{0.0};
  glm::dvec3 joint_velocity_{0.0};
  glm::dvec3 last_device_force_{0.0};
  glm::dvec3 last_device_position_{0.0};  ///< of the last accepted force reply, device frame [m]
  std::int64_t last_sent_{0};             ///< when its request was sent [ns]
  int force_header_{-1};                  ///< header byte of 0x2A replies; -1: not seen yet
  int joint_header_{-1};                  ///< header byte of 0x1A replies; -1: not seen yet
  Verdict verdict_{Verdict::good};
  bool have_position_{false};
  std::uint16_t sequence_{0};
  bool pending_{false};
  bool armed_{false};
};

static_assert(Device<Inverse3>);

}  // namespace hapticfield
