#pragma once
/// @file status.hpp
/// Results of device and transport calls on the servo path (never exceptions)
/// and the status bits of the state report. Freestanding: the firmware core
/// includes it too.

#include <cstdint>
#include <string_view>

namespace hapticfield {

/// Outcome of a device, transport or codec call.
enum class Status : std::uint8_t {
  ok,              ///< success
  no_data,         ///< nothing new to read (not an error)
  timeout,         ///< a blocking read timed out
  short_report,    ///< fewer bytes than the report needs
  unknown_report,  ///< report id not defined by the protocol
  bad_crc,         ///< CRC-16 mismatch
  bad_version,     ///< protocol version not supported
  bad_value,       ///< a field holds a value outside its range
  disconnected,    ///< the device is gone (unplugged or read error)
  not_homed,       ///< arming refused: the arm is not homed
  fault,           ///< the device reports a latched fault
  overflow,        ///< a buffer or queue was full
  unsupported,     ///< the transport does not implement the call
  resync,          ///< the report stream jumped (device restart, long loss): held back until consistent
  impossible,      ///< a decoded state the device cannot be in (beyond its joint limits, workspace or speed): held back
};

/// Status bits of the input state report (see docs/device-protocol.md).
namespace status_bits {
inline constexpr std::uint16_t homed = 1u << 0;             ///< encoders referenced
inline constexpr std::uint16_t armed = 1u << 1;             ///< motors enabled
inline constexpr std::uint16_t watchdog_tripped = 1u << 2;  ///< latched: no valid command in time
inline constexpr std::uint16_t over_current = 1u << 3;      ///< latched
inline constexpr std::uint16_t over_temperature = 1u << 4;  ///< latched
inline constexpr std::uint16_t estop = 1u << 5;             ///< emergency stop pressed
/// Any bit that forbids force output.
inline constexpr std::uint16_t any_fault = watchdog_tripped | over_current | over_temperature | estop;
}  // namespace status_bits

/// Short human-readable name of a status.
[[nodiscard]] constexpr std::string_view to_string(Status s) noexcept {
  switch (s) {
    case Status::ok:
      return "ok";
    case Status::no_data:
      return "no data";
    case Status::timeout:
      return "timeout";
    case Status::short_report:
      return "short report";
    case Status::unknown_report:
      return "unknown report";
    case Status::bad_crc:
      return "bad CRC";
    case Status::bad_version:
      return "bad protocol version";
    case Status::bad_value:
      return "bad value";
    case Status::disconnected:
      return "disconnected";
    case Status::not_homed:
      return "not homed";
    case Status::fault:
      return "device fault";
    case Status::overflow:
      return "overflow";
    case Status::unsupported:
      return "unsupported";
    case Status::resync:
      return "resynchronising";
    case Status::impossible:
      return "impossible state";
  }
  return "?";
}

}  // namespace hapticfield
