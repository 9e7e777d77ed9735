#pragma once
/// @file falcon_codec.hpp
/// Wire format of the Novint Falcon with the firmware of Novint's driver
/// (docs/arms-falcon.md): the FTDI setup constants, the boot loader's
/// handshake, and the 16-byte packets of the 1 kHz exchange.
///
/// A packet is '<', 14 bytes each holding 0x41 + a 4-bit value, '>'.
///   host -> Falcon: bytes 1..12 three int16 motor commands, low nibble
///                   first; byte 13 the LED bits | the homing-mode bit.
///   Falcon -> host: bytes 1..12 three int16 encoder counts, low nibble
///                   first; byte 13 (minus 0x41) holds the grip's buttons in
///                   bits 0..3 and one "homed" bit per encoder in bits 4..6.
/// Byte 14 carries nothing we know of (sent as 0x41, ignored on receipt).
/// Sources: libnifalcon's FalconFirmwareNovintSDK and FalconCommLibUSB
/// (read to interoperate). Host side (encode commands, decode reports) and
/// device side (the reverse, for the simulated Falcon). noexcept and
/// allocation-free.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hapticfield/device/status.hpp"

namespace hapticfield::falcon {

/// USB identity: an FTDI chip with Novint's product id.
inline constexpr std::uint16_t vendor_id = 0x0403;
inline constexpr std::uint16_t product_id = 0xCB48;
inline constexpr std::uint8_t endpoint_out = 0x02;  ///< bulk OUT
inline constexpr std::uint8_t endpoint_in =
    0x81;  ///< bulk IN; every 64-byte USB packet starts with 2 FTDI status bytes
inline constexpr std::size_t ftdi_status_bytes = 2;
inline constexpr std::size_t usb_packet_size = 64;  ///< full-speed bulk packet [bytes]

/// FTDI "SIO" vendor requests (bmRequestType 0x40, wIndex 0) and values.
namespace sio {
inline constexpr std::uint8_t reset = 0;       ///< value: purge_rx or purge_tx
inline constexpr std::uint8_t modem_ctrl = 1;  ///< value: dtr_high, dtr_low, rts_low
inline constexpr std::uint8_t flow_ctrl = 2;   ///< value 0: no flow control
inline constexpr std::uint8_t baud_rate = 3;   ///< value: a divisor below
inline constexpr std::uint8_t data = 4;        ///< value: line_8n1
inline constexpr std::uint8_t latency = 9;     ///< value: the latency timer [ms]
inline constexpr std::uint16_t purge_rx = 1;
inline constexpr std::uint16_t purge_tx = 2;
inline constexpr std::uint16_t dtr_high = 0x0101;
inline constexpr std::uint16_t dtr_low = 0x0100;
inline constexpr std::uint16_t rts_low = 0x0200;
inline constexpr std::uint16_t line_8n1 = 8;
inline constexpr std::uint16_t baud_9600 = 0x4138;     ///< boot loader handshake
inline constexpr std::uint16_t baud_firmware = 0x15;   ///< firmware upload (about 140 kBd)
inline constexpr std::uint16_t baud_normal = 0x2;      ///< the 1 kHz exchange (about 1.5 MBd, inferred)
inline constexpr std::uint16_t latency_firmware = 16;  ///< [ms]
inline constexpr std::uint16_t latency_normal = 1;     ///< [ms]
}  // namespace sio

/// Boot loader handshake at 9600 Bd: the host sends check_request, the
/// boot loader answers check_reply (some hosts see one leading 0x00 more);
/// then, at the firmware rate, the host sends firmware_ack and it echoes it.
inline constexpr std::array<std::uint8_t, 3> check_request{0x0A, 0x43, 0x0D};
inline constexpr std::array<std::uint8_t, 4> check_reply{0x0A, 0x44, 0x2C, 0x0D};
inline constexpr std::uint8_t firmware_ack = 0x41;  ///< 'A'
/// The firmware goes over in chunks the boot loader echoes back byte for byte.
inline constexpr std::size_t firmware_chunk = 62;  ///< [bytes]

inline constexpr std::size_t packet_size = 16;  ///< [bytes]
inline constexpr std::uint8_t packet_start = '<';
inline constexpr std::uint8_t packet_end = '>';
inline constexpr std::uint8_t nibble_base = 0x41;  ///< 'A': each payload byte is 0x41 + a 4-bit value

/// LED bits of the command (the grip's ring of light).
namespace led {
inline constexpr std::uint8_t green = 0x2;
inline constexpr std::uint8_t blue = 0x4;
inline constexpr std::uint8_t red = 0x8;
inline constexpr std::uint8_t all = green | blue | red;
}  // namespace led
inline constexpr std::uint8_t homing_mode_bit = 0x1;  ///< command byte 13: search the encoders' index
inline constexpr std::uint8_t all_homed = 0x7;        ///< report: one bit per encoder

/// What the host sends each tick.
struct Command {
  std::array<std::int16_t, 3> motor{};  ///< motor commands [counts] (see FalconKinematics::motor_counts)
  std::uint8_t leds{0};                 ///< led:: bits
  bool homing{false};                   ///< homing mode on
};

/// What the Falcon answers.
struct Report {
  std::array<std::int16_t, 3> encoder{};  ///< encoder counts [counts]
  std::uint8_t homed{0};                  ///< bit i: encoder i homed
  std::uint8_t buttons{0};                ///< grip buttons (4 bits)
};

namespace detail {
inline void put_int16(std::int16_t value, std::span<std::uint8_t> out) noexcept {
  const auto u = static_cast<std::uint16_t>(value);
  for (std::size_t i = 0; i < 4; ++i)
    out[i] = static_cast<std::uint8_t>(nibble_base + ((u >> (4 * i)) & 0xFu));
}
/// False when a byte is not 0x41 + a nibble.
inline bool get_int16(std::span<const std::uint8_t> in, std::int16_t& value) noexcept {
  std::uint16_t u = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    const int n = static_cast<int>(in[i]) - nibble_base;
    if (n < 0 || n > 0xF) return false;
    u = static_cast<std::uint16_t>(u | (static_cast<unsigned>(n) << (4 * i)));
  }
  value = static_cast<std::int16_t>(u);
  return true;
}
inline bool framed(std::span<const std::uint8_t> bytes) noexcept {
  return bytes.size() >= packet_size && bytes[0] == packet_start && bytes[packet_size - 1] == packet_end;
}
}  // namespace detail

/// Host side: the command's 16 bytes.
inline void encode(const Command& c, std::span<std::uint8_t, packet_size> out) noexcept {
  out[0] = packet_start;
  for (std::size_t i = 0; i < 3; ++i)
    detail::put_int16(c.motor[i], out.subspan(1 + 4 * i, 4));
  const unsigned flags = (c.leds & led::all) | (c.homing ? homing_mode_bit : 0u);
  out[13] = static_cast<std::uint8_t>(nibble_base + flags);
  out[14] = nibble_base;
  out[15] = packet_end;
}

/// Host side: one report from its first 16 bytes. short_report when fewer,
/// unknown_report when not framed by '<' and '>', bad_value when a payload
/// byte is not 0x41 + a nibble (encoders) or below 0x41 (byte 13).
[[nodiscard]] inline Status decode(std::span<const std::uint8_t> bytes, Report& r) noexcept {
  if (bytes.size() < packet_size) return Status::short_report;
  if (!detail::framed(bytes)) return Status::unknown_report;
  Report out;
  for (std::size_t i = 0; i < 3; ++i)
    if (!detail::get_int16(bytes.subspan(1 + 4 * i, 4), out.encoder[i])) return Status::bad_value;
  if (bytes[13] < nibble_base) return Status::bad_value;
  const unsigned status = static_cast<unsigned>(bytes[13] - nibble_base);
  out.buttons = static_cast<std::uint8_t>(status & 0xFu);
  out.homed = static_cast<std::uint8_t>((status >> 4) & all_homed);
  r = out;
  return Status::ok;
}

/// Device side: the report's 16 bytes (the simulated Falcon).
inline void encode(const Report& r, std::span<std::uint8_t, packet_size> out) noexcept {
  out[0] = packet_start;
  for (std::size_t i = 0; i < 3; ++i)
    detail::put_int16(r.encoder[i], out.subspan(1 + 4 * i, 4));
  out[13] = static_cast<std::uint8_t>(nibble_base + (((r.homed & all_homed) << 4) | (r.buttons & 0xFu)));
  out[14] = nibble_base;
  out[15] = packet_end;
}

/// Device side: a command from its first 16 bytes; as decode(Report).
[[nodiscard]] inline Status decode(std::span<const std::uint8_t> bytes, Command& c) noexcept {
  if (bytes.size() < packet_size) return Status::short_report;
  if (!detail::framed(bytes)) return Status::unknown_report;
  Command out;
  for (std::size_t i = 0; i < 3; ++i)
    if (!detail::get_int16(bytes.subspan(1 + 4 * i, 4), out.motor[i])) return Status::bad_value;
  const int flags = static_cast<int>(bytes[13]) - nibble_base;
  if (flags < 0 || flags > 0xF) return Status::bad_value;
  out.leds = static_cast<std::uint8_t>(flags & led::all);
  out.homing = (flags & homing_mode_bit) != 0;
  c = out;
  return Status::ok;
}

/// Cuts a byte stream into 16-byte packets: bytes before a '<', and a '<'
/// whose 16th byte is not '>', are dropped (resynchronisation). Fixed
/// capacity; push() drops the oldest bytes when full. noexcept, no allocation.
class PacketFramer {
 public:
  static constexpr std::size_t capacity = 256;  ///< [bytes]

  /// Appends bytes; returns how many older bytes were dropped to make room.
  std::size_t push(std::span<const std::uint8_t> bytes) noexcept {
    std::size_t dropped = 0;
    for (const std::uint8_t b : bytes) {
      if (size_ == capacity) {
        shift(1);
        ++dropped;
      }
      buf_[size_++] = b;
    }
    dropped_ += dropped;
    return dropped;
  }

  /// Copies the oldest whole packet into out; false when none is complete.
  bool pop(std::span<std::uint8_t, packet_size> out) noexcept {
    for (;;) {
      std::size_t start = 0;
      while (start < size_ && buf_[start] != packet_start)
        ++start;
      if (start > 0) {
        dropped_ += start;
        shift(start);
      }
      if (size_ < packet_size) return false;
      if (buf_[packet_size - 1] == packet_end) {
        for (std::size_t i = 0; i < packet_size; ++i)
          out[i] = buf_[i];
        shift(packet_size);
        return true;
      }
      ++dropped_;
      shift(1);  // a '<' that starts no packet
    }
  }

  void clear() noexcept { size_ = 0; }
  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  /// Bytes dropped since construction (noise, resynchronisation, overflow).
  [[nodiscard]] std::size_t dropped() const noexcept { return dropped_; }

 private:
  void shift(std::size_t n) noexcept {
    for (std::size_t i = n; i < size_; ++i)
      buf_[i - n] = buf_[i];
    size_ -= n;
  }

  std::array<std::uint8_t, capacity> buf_{};
  std::size_t size_{0};
  std::size_t dropped_{0};
};

}  // namespace hapticfield::falcon
