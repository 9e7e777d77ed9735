#pragma once
/// @file protocol.hpp
/// The force-arm HID report protocol (docs/device-protocol.md): report ids,
/// hand-written little-endian codecs and the CRC-16/CCITT-FALSE check.
/// Decoders never read past the buffer and return a Status for short,
/// unknown, bad-version and bad-CRC reports; encoders never allocate.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hapticfield/device/status.hpp"

namespace hapticfield {

/// Placeholder USB ids of the reference firmware (pid.codes test VID);
/// a product ships its own.
inline constexpr std::uint16_t default_vendor_id = 0x1209;
inline constexpr std::uint16_t default_product_id = 0x0001;

}  // namespace hapticfield

namespace hapticfield::protocol {

inline constexpr std::uint8_t version = 1;           ///< protocol version this code speaks
inline constexpr std::uint16_t usage_page = 0xFF48;  ///< vendor-defined usage page
inline constexpr std::uint16_t usage = 0x0001;       ///< usage in that page
inline constexpr std::size_t max_report_size = 64;   ///< largest report [bytes]

/// Report ids.
enum class ReportId : std::uint8_t {
  state = 0x01,            ///< input: streamed every device tick
  command = 0x02,          ///< output: written by the host every servo tick
  device_info = 0x10,      ///< feature (get): geometry, encoders, limits
  configuration = 0x11,    ///< feature (get/set): watchdog period
  control = 0x12,          ///< feature (set): arm, disarm, clear fault, home
  feature_request = 0x13,  ///< serial links only: host asks for a feature report (get)
  feature_reply = 0x14,    ///< serial links only: device answers a set (or a failed get)
};

/// Report sizes including the id byte and the trailing CRC [bytes].
inline constexpr std::size_t state_size = 40;
inline constexpr std::size_t command_size = 16;
inline constexpr std::size_t device_info_size = 50;
inline constexpr std::size_t configuration_size = 8;
inline constexpr std::size_t control_size = 4;
inline constexpr std::size_t feature_request_size = 4;
inline constexpr std::size_t feature_reply_size = 5;

/// Byte offsets of every field, named once for encoders and decoders alike
/// (docs/device-protocol.md has the same tables). Byte 0 is the report id,
/// byte 1 the protocol version (the control report: the operation), the
/// last two bytes the CRC.
namespace offset {
inline constexpr std::size_t id = 0;
inline constexpr std::size_t version = 1;
namespace state {
inline constexpr std::size_t sequence = 2;      ///< u16
inline constexpr std::size_t command_echo = 4;  ///< u16
inline constexpr std::size_t timestamp = 6;     ///< u32 [us]
inline constexpr std::size_t encoder = 10;      ///< 3 x i32
inline constexpr std::size_t gimbal = 22;       ///< 3 x i16
inline constexpr std::size_t status = 28;       ///< u16
inline constexpr std::size_t buttons = 30;      ///< u8
inline constexpr std::size_t torque = 31;       ///< 3 x i16 [mN m]
inline constexpr std::size_t reserved = 37;     ///< u8, zero
}  // namespace state
namespace command {
inline constexpr std::size_t sequence = 2;   ///< u16
inline constexpr std::size_t flags = 4;      ///< u8
inline constexpr std::size_t torque = 5;     ///< 3 x i16 [mN m]
inline constexpr std::size_t reserved = 11;  ///< 3 x u8, zero
}  // namespace command
namespace device_info {
inline constexpr std::size_t counts_per_rev = 2;     ///< 3 x u32
inline constexpr std::size_t max_torque = 14;        ///< 3 x u16 [mN m]
inline constexpr std::size_t l1 = 20;                ///< u32 [um]
inline constexpr std::size_t l2 = 24;                ///< u32 [um]
inline constexpr std::size_t q_min = 28;             ///< 3 x i16 [mrad]
inline constexpr std::size_t q_max = 34;             ///< 3 x i16 [mrad]
inline constexpr std::size_t max_force = 40;         ///< u16 [mN]
inline constexpr std::size_t continuous_force = 42;  ///< u16 [mN]
inline constexpr std::size_t rate = 44;              ///< u16 [Hz]
inline constexpr std::size_t torque_unit = 46;       ///< u16 [uN m]
}  // namespace device_info
namespace configuration {
inline constexpr std::size_t watchdog = 2;  ///< u16 [us]
inline constexpr std::size_t reserved = 4;  ///< u16, zero
}  // namespace configuration
namespace control {
inline constexpr std::size_t operation = 1;  ///< u8 ControlOp
}  // namespace control
namespace feature_request {
inline constexpr std::size_t requested = 1;  ///< u8 id of the feature report asked for
}  // namespace feature_request
namespace feature_reply {
inline constexpr std::size_t report = 1;  ///< u8 id of the feature report answered
inline constexpr std::size_t status = 2;  ///< u8 Status of the set (or why a get failed)
}  // namespace feature_reply
}  // namespace offset

namespace detail {
/// Byte-wise lookup table of CRC-16/CCITT-FALSE (polynomial 0x1021), built
/// at compile time.
inline constexpr std::array<std::uint16_t, 256> crc16_table = [] {
  std::array<std::uint16_t, 256> t{};
  for (unsigned i = 0; i < 256; ++i) {
    auto crc = static_cast<std::uint16_t>(i << 8);
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 0x8000u) ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021u) : static_cast<std::uint16_t>(crc << 1);
    t[i] = crc;
  }
  return t;
}();
}  // namespace detail

/// CRC-16/CCITT-FALSE: polynomial 0x1021, initial value 0xFFFF, no
/// reflection, no final xor; check value 0x29B1 for "123456789".
[[nodiscard]] constexpr std::uint16_t crc16(std::span<const std::uint8_t> data) noexcept {
  std::uint16_t crc = 0xFFFF;
  for (const std::uint8_t byte : data)
    crc = static_cast<std::uint16_t>((crc << 8) ^ detail::crc16_table[((crc >> 8) ^ byte) & 0xFFu]);
  return crc;
}

namespace detail {
inline void put_u8(std::span<std::uint8_t> b, std::size_t at, std::uint8_t v) noexcept {
  b[at] = v;
}
inline void put_u16(std::span<std::uint8_t> b, std::size_t at, std::uint16_t v) noexcept {
  b[at] = static_cast<std::uint8_t>(v & 0xFFu);
  b[at + 1] = static_cast<std::uint8_t>(v >> 8);
}
inline void put_u32(std::span<std::uint8_t> b, std::size_t at, std::uint32_t v) noexcept {
  for (std::size_t i = 0; i < 4; ++i)
    b[at + i] = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFFu);
}
inline void put_i16(std::span<std::uint8_t> b, std::size_t at, std::int16_t v) noexcept {
  put_u16(b, at, static_cast<std::uint16_t>(v));
}
inline void put_i32(std::span<std::uint8_t> b, std::size_t at, std::int32_t v) noexcept {
  put_u32(b, at, static_cast<std::uint32_t>(v));
}
[[nodiscard]] inline std::uint16_t get_u16(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  return static_cast<std::uint16_t>(b[at] | (b[at + 1] << 8));
}
[[nodiscard]] inline std::uint32_t get_u32(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i)
    v |= static_cast<std::uint32_t>(b[at + i]) << (8 * i);
  return v;
}
[[nodiscard]] inline std::int16_t get_i16(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  return static_cast<std::int16_t>(get_u16(b, at));
}
[[nodiscard]] inline std::int32_t get_i32(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  return static_cast<std::int32_t>(get_u32(b, at));
}
/// Writes the CRC of bytes [0, size-2) into the last two bytes.
inline void seal(std::span<std::uint8_t> b, std::size_t size) noexcept {
  put_u16(b, size - 2, crc16(b.first(size - 2)));
}
/// Common checks of every decoder: length, id, CRC, version (in that order).
[[nodiscard]] inline Status check(std::span<const std::uint8_t> b, ReportId id, std::size_t size) noexcept {
  if (b.empty()) return Status::short_report;
  if (b[offset::id] != static_cast<std::uint8_t>(id)) return Status::unknown_report;
  if (b.size() < size) return Status::short_report;
  if (get_u16(b, size - 2) != crc16(b.first(size - 2))) return Status::bad_crc;
  if (b[offset::version] != version) return Status::bad_version;
  return Status::ok;
}
}  // namespace detail

/// Input state report (id 0x01), streamed by the device every tick.
struct StateReport {
  std::uint16_t sequence{0};                 ///< increments by one per report (wraps)
  std::uint16_t command_echo{0};             ///< sequence of the last command applied
  std::uint32_t timestamp_us{0};             ///< device clock [us] (wraps)
  std::array<std::int32_t, 3> encoder{};     ///< joint encoder counts
  std::array<std::int16_t, 3> gimbal{};      ///< gimbal values (device units)
  std::uint16_t status{0};                   ///< status_bits
  std::uint8_t buttons{0};                   ///< button bit mask
  std::array<std::int16_t, 3> torque_mnm{};  ///< torques applied [mN m]
};

/// Output command report (id 0x02), written by the host every servo tick.
struct CommandReport {
  std::uint16_t sequence{0};                 ///< increments by one per command (wraps)
  std::uint8_t flags{0};                     ///< command_flags
  std::array<std::int16_t, 3> torque_mnm{};  ///< joint torques requested [mN m]
};

/// Flags of the command report.
namespace command_flags {
inline constexpr std::uint8_t arm = 1u << 0;   ///< keep the motors enabled (arms when homed)
inline constexpr std::uint8_t home = 1u << 1;  ///< start (or continue) homing
}  // namespace command_flags

/// Feature report device info (id 0x10).
struct DeviceInfoReport {
  std::array<std::uint32_t, 3> counts_per_rev{};  ///< encoder counts per joint turn
  std::array<std::uint16_t, 3> max_torque_mnm{};  ///< joint torque saturation [mN m]
  std::uint16_t torque_unit_unm{1000};            ///< size of one torque unit [uN m]
  std::uint32_t l1_um{0};                         ///< upper arm [um]
  std::uint32_t l2_um{0};                         ///< forearm [um]
  std::array<std::int16_t, 3> q_min_mrad{};       ///< joint lower limits [mrad]
  std::array<std::int16_t, 3> q_max_mrad{};       ///< joint upper limits [mrad]
  std::uint16_t max_force_mn{0};                  ///< peak force [mN]
  std::uint16_t continuous_force_mn{0};           ///< continuous force [mN]
  std::uint16_t rate_hz{0};                       ///< state report rate [Hz]
};

/// Feature report configuration (id 0x11).
struct ConfigurationReport {
  std::uint16_t watchdog_us{0};  ///< firmware watchdog period [us]; 0 is rejected
};

/// Operations of the control feature report (id 0x12).
enum class ControlOp : std::uint8_t { arm = 1, disarm = 2, clear_fault = 3, home = 4 };

/// Serialises a state report into out (>= state_size bytes); returns the size or 0.
inline std::size_t encode(const StateReport& r, std::span<std::uint8_t> out) noexcept {
  using namespace detail;
  namespace at = offset::state;
  if (out.size() < state_size) return 0;
  put_u8(out, offset::id, static_cast<std::uint8_t>(ReportId::state));
  put_u8(out, offset::version, version);
  put_u16(out, at::sequence, r.sequence);
  put_u16(out, at::command_echo, r.command_echo);
  put_u32(out, at::timestamp, r.timestamp_us);
  for (std::size_t i = 0; i < 3; ++i)
    put_i32(out, at::encoder + 4 * i, r.encoder[i]);
  for (std::size_t i = 0; i < 3; ++i)
    put_i16(out, at::gimbal + 2 * i, r.gimbal[i]);
  put_u16(out, at::status, r.status);
  put_u8(out, at::buttons, r.buttons);
  for (std::size_t i = 0; i < 3; ++i)
    put_i16(out, at::torque + 2 * i, r.torque_mnm[i]);
  put_u8(out, at::reserved, 0);
  seal(out, state_size);
  return state_size;
}

/// Parses a state report. Never reads outside in.
[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, StateReport& r) noexcept {
  using namespace detail;
  namespace at = offset::state;
  if (const Status s = check(in, ReportId::state, state_size); s != Status::ok) return s;
  r.sequence = get_u16(in, at::sequence);
  r.command_echo = get_u16(in, at::command_echo);
  r.timestamp_us = get_u32(in, at::timestamp);
  for (std::size_t i = 0; i < 3; ++i)
    r.encoder[i] = get_i32(in, at::encoder + 4 * i);
  for (std::size_t i = 0; i < 3; ++i)
    r.gimbal[i] = get_i16(in, at::gimbal + 2 * i);
  r.status = get_u16(in, at::status);
  r.buttons = in[at::buttons];
  for (std::size_t i = 0; i < 3; ++i)
    r.torque_mnm[i] = get_i16(in, at::torque + 2 * i);
  return in[at::reserved] == 0 ? Status::ok : Status::bad_value;  // not a version-1 report
}

inline std::size_t encode(const CommandReport& r, std::span<std::uint8_t> out) noexcept {
  using namespace detail;
  namespace at = offset::command;
  if (out.size() < command_size) return 0;
  put_u8(out, offset::id, static_cast<std::uint8_t>(ReportId::command));
  put_u8(out, offset::version, version);
  put_u16(out, at::sequence, r.sequence);
  put_u8(out, at::flags, r.flags);
  for (std::size_t i = 0; i < 3; ++i)
    put_i16(out, at::torque + 2 * i, r.torque_mnm[i]);
  for (std::size_t i = at::reserved; i < command_size - 2; ++i)
    put_u8(out, i, 0);
  seal(out, command_size);
  return command_size;
}

[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, CommandReport& r) noexcept {
  using namespace detail;
  namespace at = offset::command;
  if (const Status s = check(in, ReportId::command, command_size); s != Status::ok) return s;
  r.sequence = get_u16(in, at::sequence);
  r.flags = in[at::flags];
  if ((r.flags & ~(command_flags::arm | command_flags::home)) != 0) return Status::bad_value;
  for (std::size_t i = 0; i < 3; ++i)
    r.torque_mnm[i] = get_i16(in, at::torque + 2 * i);
  for (std::size_t i = at::reserved; i < command_size - 2; ++i)
    if (in[i] != 0) return Status::bad_value;  // not a version-1 report
  return Status::ok;
}

inline std::size_t encode(const DeviceInfoReport& r, std::span<std::uint8_t> out) noexcept {
  using namespace detail;
  namespace at = offset::device_info;
  if (out.size() < device_info_size) return 0;
  put_u8(out, offset::id, static_cast<std::uint8_t>(ReportId::device_info));
  put_u8(out, offset::version, version);
  for (std::size_t i = 0; i < 3; ++i)
    put_u32(out, at::counts_per_rev + 4 * i, r.counts_per_rev[i]);
  for (std::size_t i = 0; i < 3; ++i)
    put_u16(out, at::max_torque + 2 * i, r.max_torque_mnm[i]);
  put_u32(out, at::l1, r.l1_um);
  put_u32(out, at::l2, r.l2_um);
  for (std::size_t i = 0; i < 3; ++i)
    put_i16(out, at::q_min + 2 * i, r.q_min_mrad[i]);
  for (std::size_t i = 0; i < 3; ++i)
    put_i16(out, at::q_max + 2 * i, r.q_max_mrad[i]);
  put_u16(out, at::max_force, r.max_force_mn);
  put_u16(out, at::continuous_force, r.continuous_force_mn);
  put_u16(out, at::rate, r.rate_hz);
  put_u16(out, at::torque_unit, r.torque_unit_unm);
  seal(out, device_info_size);
  return device_info_size;
}

[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, DeviceInfoReport& r) noexcept {
  using namespace detail;
  namespace at = offset::device_info;
  if (const Status s = check(in, ReportId::device_info, device_info_size); s != Status::ok) return s;
  for (std::size_t i = 0; i < 3; ++i)
    r.counts_per_rev[i] = get_u32(in, at::counts_per_rev + 4 * i);
  for (std::size_t i = 0; i < 3; ++i)
    r.max_torque_mnm[i] = get_u16(in, at::max_torque + 2 * i);
  r.l1_um = get_u32(in, at::l1);
  r.l2_um = get_u32(in, at::l2);
  for (std::size_t i = 0; i < 3; ++i)
    r.q_min_mrad[i] = get_i16(in, at::q_min + 2 * i);
  for (std::size_t i = 0; i < 3; ++i)
    r.q_max_mrad[i] = get_i16(in, at::q_max + 2 * i);
  r.max_force_mn = get_u16(in, at::max_force);
  r.continuous_force_mn = get_u16(in, at::continuous_force);
  r.rate_hz = get_u16(in, at::rate);
  r.torque_unit_unm = get_u16(in, at::torque_unit);
  if (r.torque_unit_unm == 0 || r.rate_hz == 0) return Status::bad_value;
  for (std::size_t i = 0; i < 3; ++i)
    if (r.counts_per_rev[i] == 0 || r.counts_per_rev[i] > 0x7FFFFFFFu) return Status::bad_value;
  return Status::ok;
}

inline std::size_t encode(const ConfigurationReport& r, std::span<std::uint8_t> out) noexcept {
  using namespace detail;
  if (out.size() < configuration_size) return 0;
  put_u8(out, offset::id, static_cast<std::uint8_t>(ReportId::configuration));
  put_u8(out, offset::version, version);
  put_u16(out, offset::configuration::watchdog, r.watchdog_us);
  put_u16(out, offset::configuration::reserved, 0);
  seal(out, configuration_size);
  return configuration_size;
}

[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, ConfigurationReport& r) noexcept {
  using namespace detail;
  if (const Status s = check(in, ReportId::configuration, configuration_size); s != Status::ok) return s;
  r.watchdog_us = get_u16(in, offset::configuration::watchdog);
  if (get_u16(in, offset::configuration::reserved) != 0) return Status::bad_value;  // not a version-1 report
  return r.watchdog_us == 0 ? Status::bad_value : Status::ok;
}

inline std::size_t encode(ControlOp op, std::span<std::uint8_t> out) noexcept {
  using namespace detail;
  if (out.size() < control_size) return 0;
  put_u8(out, offset::id, static_cast<std::uint8_t>(ReportId::control));
  put_u8(out, offset::control::operation, static_cast<std::uint8_t>(op));
  seal(out, control_size);
  return control_size;
}

/// The control report has no version byte: byte 1 is the operation.
[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, ControlOp& op) noexcept {
  using namespace detail;
  if (in.empty()) return Status::short_report;
  if (in[offset::id] != static_cast<std::uint8_t>(ReportId::control)) return Status::unknown_report;
  if (in.size() < control_size) return Status::short_report;
  if (get_u16(in, control_size - 2) != crc16(in.first(control_size - 2))) return Status::bad_crc;
  const std::uint8_t operation = in[offset::control::operation];
  if (operation < 1 || operation > 4) return Status::bad_value;
  op = static_cast<ControlOp>(operation);
  return Status::ok;
}

/// Serial framing (docs/device-protocol.md, "Serial framing"): the host asks
/// for feature report `id` with this frame; the device answers with the
/// report itself, or a FeatureReply when it cannot.
inline std::size_t encode_feature_request(std::uint8_t id, std::span<std::uint8_t> out) noexcept {
  using namespace detail;
  if (out.size() < feature_request_size) return 0;
  put_u8(out, offset::id, static_cast<std::uint8_t>(ReportId::feature_request));
  put_u8(out, offset::feature_request::requested, id);
  seal(out, feature_request_size);
  return feature_request_size;
}

/// Parses a feature request; id is the feature report asked for.
[[nodiscard]] inline Status decode_feature_request(std::span<const std::uint8_t> in, std::uint8_t& id) noexcept {
  using namespace detail;
  if (in.empty()) return Status::short_report;
  if (in[offset::id] != static_cast<std::uint8_t>(ReportId::feature_request)) return Status::unknown_report;
  if (in.size() < feature_request_size) return Status::short_report;
  if (get_u16(in, feature_request_size - 2) != crc16(in.first(feature_request_size - 2))) return Status::bad_crc;
  id = in[offset::feature_request::requested];
  return Status::ok;
}

/// The device's answer to a set feature (or a get it cannot serve) on a
/// serial link: which report, and the Status the device returned.
struct FeatureReply {
  std::uint8_t report{0};     ///< id of the feature report answered
  Status status{Status::ok};  ///< outcome on the device
};

inline std::size_t encode(const FeatureReply& r, std::span<std::uint8_t> out) noexcept {
  using namespace detail;
  if (out.size() < feature_reply_size) return 0;
  put_u8(out, offset::id, static_cast<std::uint8_t>(ReportId::feature_reply));
  put_u8(out, offset::feature_reply::report, r.report);
  put_u8(out, offset::feature_reply::status, static_cast<std::uint8_t>(r.status));
  seal(out, feature_reply_size);
  return feature_reply_size;
}

[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, FeatureReply& r) noexcept {
  using namespace detail;
  if (in.empty()) return Status::short_report;
  if (in[offset::id] != static_cast<std::uint8_t>(ReportId::feature_reply)) return Status::unknown_report;
  if (in.size() < feature_reply_size) return Status::short_report;
  if (get_u16(in, feature_reply_size - 2) != crc16(in.first(feature_reply_size - 2))) return Status::bad_crc;
  const std::uint8_t status = in[offset::feature_reply::status];
  if (status > static_cast<std::uint8_t>(Status::resync)) return Status::bad_value;
  r.report = in[offset::feature_reply::report];
  r.status = static_cast<Status>(status);
  return Status::ok;
}

/// Size of the report whose id is the first byte, or 0 for an unknown id.
[[nodiscard]] constexpr std::size_t report_size(std::uint8_t id) noexcept {
  switch (static_cast<ReportId>(id)) {
    case ReportId::state:
      return state_size;
    case ReportId::command:
      return command_size;
    case ReportId::device_info:
      return device_info_size;
    case ReportId::configuration:
      return configuration_size;
    case ReportId::control:
      return control_size;
    case ReportId::feature_request:
      return feature_request_size;
    case ReportId::feature_reply:
      return feature_reply_size;
  }
  return 0;
}

}  // namespace hapticfield::protocol
