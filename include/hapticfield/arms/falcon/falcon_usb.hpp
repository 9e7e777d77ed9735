#pragma once
/// @file falcon_usb.hpp
/// FalconUsb: the seam between the Falcon's protocol and its USB link (an
/// FTDI chip driven with raw vendor requests and bulk transfers).
/// Implementations: LibusbFalconUsb (arms/falcon/falcon_libusb.hpp, the only
/// code that includes libusb.h) and SimulatedFalconUsb
/// (arms/falcon/simulated_falcon.hpp), which replays the protocol.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "hapticfield/device/status.hpp"

namespace hapticfield {

class FalconUsb {
 public:
  virtual ~FalconUsb() = default;
  FalconUsb() = default;
  FalconUsb(const FalconUsb&) = delete;
  FalconUsb& operator=(const FalconUsb&) = delete;

  /// One FTDI vendor request (falcon::sio::*) to interface 0. Setup only:
  /// may block up to a second. disconnected when the device is gone.
  virtual Status control(std::uint8_t request, std::uint16_t value) noexcept = 0;

  /// Queues bytes for the bulk OUT endpoint. Up to 16 bytes (a command)
  /// never wait; longer writes (firmware chunks) wait for the transfer.
  /// overflow when the previous short write has not gone out yet (the bytes
  /// are dropped), disconnected when the device is gone.
  virtual Status write(std::span<const std::uint8_t> bytes) noexcept = 0;

  /// Copies received bytes (FTDI status bytes removed) into buffer and sets
  /// size. Waits at most timeout_us [us] for the first byte (0: do not
  /// wait). no_data when none arrived, disconnected when the device is gone.
  virtual Status read(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept = 0;

  /// Where the link leads (bus and address), for messages; empty if unknown.
  [[nodiscard]] virtual std::string_view where() const noexcept { return {}; }
};

}  // namespace hapticfield
