#pragma once
/// @file transport.hpp
/// The one seam between the protocol and the wire: read an input report
/// (with a timeout), write an output report, get/send feature reports.
/// Implementations: HidTransport (transport/hid_transport.hpp, the only
/// code that includes hidapi.h), SerialTransport, ReplayTransport,
/// RecordingTransport (a decorator; all in transport/) and each arm
/// family's simulated transport (arms/<family>/).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string_view>

#include "hapticfield/device/status.hpp"

namespace hapticfield {

/// Monotonic time source for transports that need one (simulation, replay) [ns].
using TimeSource = std::function<std::int64_t()>;

class Transport {
 public:
  virtual ~Transport() = default;
  Transport() = default;
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  /// Reads the oldest queued input report into buffer (>= 64 bytes) and sets
  /// size. Waits at most timeout_us [us] (0: do not wait). no_data when none
  /// is queued, disconnected when the device is gone. Never allocates.
  virtual Status read(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept = 0;

  /// Queues one output report (the first byte is the report id); never waits
  /// for a reply.
  virtual Status write(std::span<const std::uint8_t> report) noexcept = 0;

  /// Gets the feature report whose id is buffer[0]; sets size.
  virtual Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) noexcept = 0;

  /// Sends one feature report (the first byte is the report id).
  virtual Status send_feature(std::span<const std::uint8_t> report) noexcept = 0;

  // Byte-stream transports with fixed-size framing (Framing::fixed) also
  // implement the three calls below; the others keep these defaults.

  /// Every later read() returns frames of n bytes; pending bytes are
  /// dropped. unsupported when the transport has no fixed framing, bad_value
  /// when n is out of its range.
  virtual Status set_frame_size(std::size_t n) noexcept {
    (void)n;
    return Status::unsupported;
  }
  /// Drops received bytes not yet returned as a frame (resynchronisation);
  /// returns how many.
  virtual std::size_t drop_pending() noexcept { return 0; }
  /// Bytes received but not yet returned as a frame.
  [[nodiscard]] virtual std::size_t pending() const noexcept { return 0; }
  /// Where the transport leads (a tty path), for messages; empty if unknown.
  [[nodiscard]] virtual std::string_view where() const noexcept { return {}; }
};

}  // namespace hapticfield
