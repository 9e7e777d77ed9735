#pragma once
/// @file serial_transport.hpp
/// SerialTransport: the Transport seam over a serial port (USB CDC ACM such
/// as a Teensy or an RP2040, a UART adapter, a pseudo-terminal), POSIX only.
/// The port is put in raw mode, non-blocking, VMIN = 0 and VTIME = 0. Bytes
/// are cut into frames by a fixed StreamFramer: this protocol's reports
/// (found by id and CRC, resynchronising after garbage), '\n'-terminated
/// text lines for text-protocol arms, or fixed-size frames for binary
/// request/reply arms (set_frame_size() between exchanges; a read that
/// waits and times out mid-frame drops the partial frame). Nothing
/// allocates after construction.
///
/// Per call read() does one read(2) (and a poll(2) with zero timeout only
/// when that read returned nothing, to tell an idle port from a hung-up
/// one); write() one write(2). EAGAIN on write is an overflow, never a
/// block. EOF, EIO or a hang-up mean the device is gone: every later call
/// returns Status::disconnected. Feature reports travel in-band (setup
/// only): docs/device-protocol.md, "Serial framing".

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>

#include "hapticfield/device/device_error.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/protocol/reports.hpp"
#include "hapticfield/protocol/stream_framer.hpp"

namespace hapticfield {

/// Settings of a serial port.
struct SerialConfig {
  Framing framing{Framing::reports};  ///< binary reports, or text lines
  std::size_t max_line{256};          ///< longest text line [bytes] (line framing)
  std::size_t frame_size{0};          ///< frame size [bytes] (fixed framing; 0: set later with set_frame_size)
  int baud{115200};                   ///< line rate [baud] (USB CDC ignores it)
  int feature_timeout_us{200000};     ///< longest wait for a feature reply [us] (setup only)
};

class SerialTransport final : public Transport {
 public:
  static constexpr std::size_t buffer_capacity = 1024;  ///< bytes held between reads

  /// Opens and configures the port.
  /// @throws DeviceError naming the path: missing, permission denied (the
  ///         dialout group), not a terminal, or the port cannot be set up;
  ///         std::invalid_argument for bad settings.
  explicit SerialTransport(const std::string& path, SerialConfig config = {})
      : config_(config), framer_(config.framing, config.max_line) {
    if (config_.max_line < 1 || config_.max_line >= buffer_capacity)
      throw std::invalid_argument("SerialConfig: max_line must be 1..1023 [bytes]");
    if (config_.frame_size > buffer_capacity / 2)
      throw std::invalid_argument("SerialConfig: frame_size must be 0..512 [bytes]");
    if (config_.framing == Framing::fixed) framer_.set_frame_size(config_.frame_size);
    if (config_.feature_timeout_us < 1 || config_.feature_timeout_us > 10'000'000)
      throw std::invalid_argument("SerialConfig: feature_timeout_us must be 1..1e7 [us]");
    const speed_t speed = to_speed(config_.baud);
    if (speed == B0) throw std::invalid_argument("SerialConfig: baud must be a standard rate (9600..4000000)");
    fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) {
      const int e = errno;
      if (e == ENOENT)
        throw DeviceError("SerialTransport: no serial port at " + path + " (unplugged, or a wrong path)");
      if (e == EACCES || e == EPERM)
        throw DeviceError("SerialTransport: permission denied on " + path +
                          " (add the user to the group that owns it, usually dialout, then log in again)");
      throw DeviceError("SerialTransport: cannot open " + path + ": " + std::strerror(e));
    }
    if (!::isatty(fd_)) {
      ::close(fd_);
      throw DeviceError("SerialTransport: " + path + " is not a serial port (not a terminal)");
    }
    termios t{};
    if (::tcgetattr(fd_, &t) != 0) fail(path, "reading its settings");
    ::cfmakeraw(&t);
    t.c_cflag |= CLOCAL | CREAD;
    t.c_cc[VMIN] = 0;   // read() returns what is there...
    t.c_cc[VTIME] = 0;  // ...at once
    ::cfsetispeed(&t, speed);
    ::cfsetospeed(&t, speed);
    if (::tcsetattr(fd_, TCSANOW, &t) != 0) fail(path, "setting raw mode");
    ::tcflush(fd_, TCIOFLUSH);  // drop what arrived before we listened
    path_ = path;
  }

  ~SerialTransport() override {
    if (fd_ >= 0) ::close(fd_);
  }

  /// Next complete frame (report or line); no_data when none is complete.
  /// timeout_us > 0 waits up to that long for bytes. Fixed framing waits
  /// up to timeout_us for a whole frame, and when the wait ends mid-frame
  /// drops the partial frame (counted as skipped) and returns timeout.
  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept override {
    if (disconnected_) return Status::disconnected;
    if (framer_.next(buffer, size) == Status::ok) return Status::ok;
    if (config_.framing == Framing::fixed && timeout_us > 0) return read_fixed(buffer, size, timeout_us);
    if (const Status s = fill(timeout_us); s == Status::disconnected) return s;
    return framer_.next(buffer, size) == Status::ok ? Status::ok : Status::no_data;
  }

  /// Writes one frame without blocking; overflow when the port would block.
  Status write(std::span<const std::uint8_t> report) noexcept override {
    if (disconnected_) return Status::disconnected;
    const ssize_t n = ::write(fd_, report.data(), report.size());
    if (n == static_cast<ssize_t>(report.size())) return Status::ok;
    if (n >= 0 || errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
      ++overflows_;  // a partial frame: the device resynchronises on the next one
      return Status::overflow;
    }
    disconnected_ = true;
    return Status::disconnected;
  }

  /// Sends a feature request frame for report buffer[0] and waits (at most
  /// feature_timeout_us) for that report; frames of other ids meanwhile are
  /// dropped (setup only). A FeatureReply for it returns the device's status.
  Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) noexcept override {
    if (config_.framing != Framing::reports) return Status::unsupported;
    if (disconnected_) return Status::disconnected;
    if (buffer.empty()) return Status::short_report;
    const std::uint8_t id = buffer[0];
    std::array<std::uint8_t, protocol::feature_request_size> request{};
    protocol::encode_feature_request(id, request);
    if (const Status s = write_all(request); s != Status::ok) return s;
    return await(id, buffer, size, true);
  }

  /// Sends a set feature report frame and waits for the device's FeatureReply.
  Status send_feature(std::span<const std::uint8_t> report) noexcept override {
    if (config_.framing != Framing::reports) return Status::unsupported;
    if (disconnected_) return Status::disconnected;
    if (report.empty()) return Status::short_report;
    if (const Status s = write_all(report); s != Status::ok) return s;
    std::array<std::uint8_t, protocol::max_report_size> reply{};
    std::size_t size = 0;
    return await(report[0], reply, size, false);
  }

  /// Fixed framing: frames of n bytes (1..512) from now on; pending bytes
  /// are dropped. unsupported in the other framings.
  Status set_frame_size(std::size_t n) noexcept override {
    if (config_.framing != Framing::fixed) return Status::unsupported;
    if (n < 1 || !framer_.set_frame_size(n)) return Status::bad_value;
    return Status::ok;
  }
  std::size_t drop_pending() noexcept override { return framer_.drop_pending(); }
  [[nodiscard]] std::size_t pending() const noexcept override { return framer_.pending(); }
  [[nodiscard]] std::string_view where() const noexcept override { return path_; }

  [[nodiscard]] const std::string& path() const noexcept { return path_; }
  [[nodiscard]] bool disconnected() const noexcept { return disconnected_; }
  [[nodiscard]] const FramerCounters& framer_counters() const noexcept { return framer_.counters(); }
  [[nodiscard]] std::uint64_t overflows() const noexcept { return overflows_; }
  /// Frames dropped while waiting for a feature reply.
  [[nodiscard]] std::uint64_t dropped_while_waiting() const noexcept { return dropped_waiting_; }

 private:
  [[noreturn]] void fail(const std::string& path, const char* what) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw DeviceError("SerialTransport: " + path + ": " + what + " failed: " + std::strerror(e));
  }

  static speed_t to_speed(int baud) noexcept {
    switch (baud) {
      case 9600:
        return B9600;
      case 19200:
        return B19200;
      case 38400:
        return B38400;
      case 57600:
        return B57600;
      case 115200:
        return B115200;
      case 230400:
        return B230400;
      case 460800:
        return B460800;
      case 921600:
        return B921600;
      case 1000000:
        return B1000000;
      case 2000000:
        return B2000000;
      case 4000000:
        return B4000000;
      default:
        return B0;
    }
  }

  /// One read into the framer; waits up to timeout_us when nothing is there.
  Status fill(int timeout_us) noexcept {
    if (framer_.full()) framer_.discard();  // a full buffer without a frame holds nothing of use
    std::span<std::uint8_t> space = framer_.space();
    ssize_t n = ::read(fd_, space.data(), space.size());
    if (n > 0) {
      framer_.commit(static_cast<std::size_t>(n));
      return Status::ok;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return gone();
    pollfd p{fd_, POLLIN, 0};
    const int wait_ms = timeout_us > 0 ? (timeout_us + 999) / 1000 : 0;
    if (::poll(&p, 1, wait_ms) < 0) return errno == EINTR ? Status::no_data : gone();
    if (p.revents & (POLLHUP | POLLERR | POLLNVAL)) return gone();
    if (!(p.revents & POLLIN)) return Status::no_data;
    if (wait_ms == 0) return Status::no_data;  // bytes arrived just now: the next call reads them
    space = framer_.space();
    n = ::read(fd_, space.data(), space.size());
    if (n > 0) {
      framer_.commit(static_cast<std::size_t>(n));
      return Status::ok;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return gone();
    return Status::no_data;
  }

  /// Fixed framing, waiting: fills until a whole frame is there or the
  /// deadline passes (setup and request/reply exchanges, not the servo path).
  Status read_fixed(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept {
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::microseconds(timeout_us);
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
      if (left <= 0) break;
      if (fill(static_cast<int>(left)) == Status::disconnected) return Status::disconnected;
      if (framer_.next(buffer, size) == Status::ok) return Status::ok;
    }
    if (framer_.pending() == 0) return Status::no_data;
    framer_.drop_pending();  // timed out mid-frame: the rest will never line up
    return Status::timeout;
  }

  Status gone() noexcept {
    disconnected_ = true;
    return Status::disconnected;
  }

  Status write_all(std::span<const std::uint8_t> frame) noexcept {
    const Status s = write(frame);
    return s == Status::overflow ? Status::timeout : s;
  }

  /// Waits for the feature report `id` (get) or a FeatureReply for it.
  Status await(std::uint8_t id, std::span<std::uint8_t> buffer, std::size_t& size, bool get) noexcept {
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::microseconds(config_.feature_timeout_us);
    std::array<std::uint8_t, protocol::max_report_size> frame{};
    for (;;) {
      // Read once more after the deadline: a reply that arrived while this
      // thread was not scheduled is not a timeout.
      const bool last = Clock::now() >= deadline;
      std::size_t n = 0;
      const Status s = read(frame, n, 1000);
      if (s == Status::disconnected) return s;
      if (s == Status::ok) {
        if (get && frame[0] == id && n <= buffer.size()) {
          std::memcpy(buffer.data(), frame.data(), n);
          size = n;
          return Status::ok;
        }
        protocol::FeatureReply reply;
        if (protocol::decode(std::span<const std::uint8_t>(frame.data(), n), reply) == Status::ok && reply.report == id)
          return get && reply.status == Status::ok ? Status::bad_value : reply.status;
        ++dropped_waiting_;
      }
      if (last) return Status::timeout;
    }
  }

  SerialConfig config_;
  StreamFramer<buffer_capacity> framer_;
  std::string path_;
  int fd_{-1};
  std::uint64_t overflows_{0};
  std::uint64_t dropped_waiting_{0};
  bool disconnected_{false};
};

}  // namespace hapticfield
