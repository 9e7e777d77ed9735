#pragma once
/// @file inverse3_codec.hpp
/// Wire format of the Haply Inverse3 over USB serial, limited to the three
/// well-sourced commands (arm-protocols.md section 4):
///   0x0A wake-up         request 1 byte;  reply 1 header + 21 bytes
///   0x1A joint torques   request 13 bytes; reply 1 header + 24 bytes
///   0x2A end-effector force request 13 bytes; reply 1 header + 24 bytes
/// Replies carry no length and no checksum; their header byte's value is
/// not published, so it is returned, never checked. Floats are IEEE-754
/// binary32, little-endian (inferred: no source states the byte order).
/// Host side (encode requests, decode replies) and device side (the
/// reverse, for the simulated arm). noexcept and allocation-free.

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "hapticfield/device/status.hpp"

namespace hapticfield::inverse3 {

static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559, "inverse3: float must be IEEE-754 binary32");

/// Request codes (section 4 table).
namespace code {
inline constexpr std::uint8_t wake = 0x0A;           ///< wake-up; resets the device's state
inline constexpr std::uint8_t joint_torques = 0x1A;  ///< 3 x f32 torques -> joint angles and velocities
inline constexpr std::uint8_t force = 0x2A;          ///< 3 x f32 force [N] -> position [m], velocity [m/s]
}  // namespace code

inline constexpr std::size_t wake_request_size = 1;      ///< [bytes]
inline constexpr std::size_t command_request_size = 13;  ///< code + 3 x f32 [bytes]
inline constexpr std::size_t wake_reply_size = 22;       ///< header + u16 + 3 x u8 + 16 bytes [bytes]
inline constexpr std::size_t state_reply_size = 25;      ///< header + 6 x f32 [bytes]
inline constexpr std::size_t max_frame_size = 25;        ///< largest request or reply [bytes]

/// The wake-up reply: who the device is.
struct Identity {
  std::uint8_t header{0};  ///< reply header byte (value unpublished: not checked)
  std::uint16_t device_id{0};
  std::uint8_t model{0};
  std::uint8_t hardware_version{0};
  std::uint8_t firmware_version{0};
  /// Last 16 bytes: a WXYZ quaternion (4 x f32) in early client code, a
  /// UUID in a later header; kept raw.
  std::array<std::uint8_t, 16> extra{};
};

/// A 0x2A reply, in the device's frame: position [m], velocity [m/s].
/// A 0x1A reply has the same shape: joint angles [deg], velocities [deg/s]
/// (units from Haply's API header; that the wire uses them is inferred).
struct StateReply {
  std::uint8_t header{0};         ///< reply header byte (not checked)
  std::array<float, 3> first{};   ///< position [m] or joint angles [deg]
  std::array<float, 3> second{};  ///< velocity [m/s] or joint velocities [deg/s]
};

namespace detail {
inline void put_f32(std::span<std::uint8_t> out, std::size_t at, float v) noexcept {
  const std::uint32_t u = std::bit_cast<std::uint32_t>(v);
  for (std::size_t i = 0; i < 4; ++i)
    out[at + i] = static_cast<std::uint8_t>(u >> (8 * i));
}
[[nodiscard]] inline float get_f32(std::span<const std::uint8_t> in, std::size_t at) noexcept {
  std::uint32_t u = 0;
  for (std::size_t i = 0; i < 4; ++i)
    u |= static_cast<std::uint32_t>(in[at + i]) << (8 * i);
  return std::bit_cast<float>(u);
}
}  // namespace detail

/// Host: the wake-up request. Returns the bytes written (0 if out is too small).
[[nodiscard]] inline std::size_t encode_wake(std::span<std::uint8_t> out) noexcept {
  if (out.size() < wake_request_size) return 0;
  out[0] = code::wake;
  return wake_request_size;
}

/// Host: a 0x1A or 0x2A request with three floats (device frame, device
/// units). Returns the bytes written (0 for another code or a short buffer).
[[nodiscard]] inline std::size_t encode_command(std::uint8_t request, const std::array<float, 3>& v,
                                                std::span<std::uint8_t> out) noexcept {
  if (out.size() < command_request_size || (request != code::force && request != code::joint_torques)) return 0;
  out[0] = request;
  for (std::size_t i = 0; i < 3; ++i)
    detail::put_f32(out, 1 + 4 * i, v[i]);
  return command_request_size;
}

/// Host: decodes a wake-up reply (exactly wake_reply_size bytes).
[[nodiscard]] inline Status decode_wake_reply(std::span<const std::uint8_t> in, Identity& id) noexcept {
  if (in.size() != wake_reply_size) return Status::short_report;
  id.header = in[0];
  id.device_id = static_cast<std::uint16_t>(in[1] | (in[2] << 8));
  id.model = in[3];
  id.hardware_version = in[4];
  id.firmware_version = in[5];
  for (std::size_t i = 0; i < 16; ++i)
    id.extra[i] = in[6 + i];
  return Status::ok;
}

/// Host: decodes a 0x1A or 0x2A reply (exactly state_reply_size bytes).
/// bad_value when a float is not finite (a misaligned or corrupt frame).
[[nodiscard]] inline Status decode_state_reply(std::span<const std::uint8_t> in, StateReply& r) noexcept {
  if (in.size() != state_reply_size) return Status::short_report;
  r.header = in[0];
  bool finite = true;
  for (std::size_t i = 0; i < 3; ++i) {
    r.first[i] = detail::get_f32(in, 1 + 4 * i);
    r.second[i] = detail::get_f32(in, 13 + 4 * i);
    // finite iff the exponent bits are not all ones
    finite = finite && (std::bit_cast<std::uint32_t>(r.first[i]) & 0x7F800000u) != 0x7F800000u &&
             (std::bit_cast<std::uint32_t>(r.second[i]) & 0x7F800000u) != 0x7F800000u;
  }
  return finite ? Status::ok : Status::bad_value;
}

/// Device: encodes a wake-up reply. Returns the bytes written.
[[nodiscard]] inline std::size_t encode_wake_reply(const Identity& id, std::span<std::uint8_t> out) noexcept {
  if (out.size() < wake_reply_size) return 0;
  out[0] = id.header;
  out[1] = static_cast<std::uint8_t>(id.device_id & 0xFF);
  out[2] = static_cast<std::uint8_t>(id.device_id >> 8);
  out[3] = id.model;
  out[4] = id.hardware_version;
  out[5] = id.firmware_version;
  for (std::size_t i = 0; i < 16; ++i)
    out[6 + i] = id.extra[i];
  return wake_reply_size;
}

/// Device: encodes a 0x1A or 0x2A reply. Returns the bytes written.
[[nodiscard]] inline std::size_t encode_state_reply(const StateReply& r, std::span<std::uint8_t> out) noexcept {
  if (out.size() < state_reply_size) return 0;
  out[0] = r.header;
  for (std::size_t i = 0; i < 3; ++i) {
    detail::put_f32(out, 1 + 4 * i, r.first[i]);
    detail::put_f32(out, 13 + 4 * i, r.second[i]);
  }
  return state_reply_size;
}

/// Device: decodes the three floats of a 0x1A or 0x2A request (exactly
/// command_request_size bytes, starting with its code).
[[nodiscard]] inline Status decode_command(std::span<const std::uint8_t> in, std::array<float, 3>& v) noexcept {
  if (in.size() != command_request_size) return Status::short_report;
  if (in[0] != code::force && in[0] != code::joint_torques) return Status::unknown_report;
  for (std::size_t i = 0; i < 3; ++i)
    v[i] = detail::get_f32(in, 1 + 4 * i);
  return Status::ok;
}

}  // namespace hapticfield::inverse3
