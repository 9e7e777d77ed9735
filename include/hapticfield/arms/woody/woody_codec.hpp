#pragma once
/// @file woody_codec.hpp
/// Wire formats of the WoodenHaptics / Polhem arms (arm-protocols.md
/// section 1): P1, the 8-byte USB HID reports; P2, the 14-byte USB HID
/// reports with the calibrate command; P4, the bracketed text over USB
/// serial. Host side (encode commands, decode states) and device side
/// (the reverse, for the simulated arm). Multi-byte fields little-endian
/// (inferred, section 1). All functions are noexcept and allocation-free.

#include <array>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <system_error>

#include "hapticfield/device/status.hpp"

namespace hapticfield::woody {

/// Wire generation (arm-protocols.md section 1). P3 is not implemented.
enum class Generation : std::uint8_t {
  p1_hid8,   ///< mbed USB HID, 8-byte reports, no report id (2016-2019)
  p2_hid14,  ///< mbed USB HID, 14-byte reports (Polhem USB, 2019)
  p4_text,   ///< Teensy USB serial, "[ma0,ma1,ma2]" / "[model,e0..e5,err]" (2022+)
};

[[nodiscard]] constexpr std::string_view to_string(Generation g) noexcept {
  switch (g) {
    case Generation::p1_hid8:
      return "p1";
    case Generation::p2_hid14:
      return "p2";
    case Generation::p4_text:
      return "p4";
  }
  return "?";
}

inline constexpr std::size_t p1_in_size = 8;           ///< P1 IN report [bytes]
inline constexpr std::size_t p1_out_size = 9;          ///< P1 host write: 0x00 + 8 bytes [bytes]
inline constexpr std::size_t p2_in_size = 14;          ///< P2 IN report [bytes]
inline constexpr std::size_t p2_out_size = 15;         ///< P2 host write: 0x00 + 14 bytes [bytes]
inline constexpr std::size_t p4_min_command = 16;      ///< P4 host frames are NUL-padded to this [bytes]
inline constexpr std::size_t p4_max_line = 128;        ///< longest P4 line this codec handles [bytes]
inline constexpr std::size_t p4_firmware_buffer = 64;  ///< device line buffer in the simulated firmware [bytes]

/// P1 IN (section 1, P1): three encoder counters and a send counter.
struct P1In {
  std::array<std::int16_t, 3> encoder{};  ///< raw counts [counts]
  std::uint16_t debug{0};                 ///< incremented on every send
};
/// P1 OUT: three currents; the debug field is ignored by the firmware.
struct P1Out {
  std::array<std::int16_t, 3> milliamps{};  ///< [mA]
  std::int16_t debug{0};
};
/// P2 IN (section 1, P2): six encoder counters and the calibration-button flag.
struct P2In {
  std::array<std::int16_t, 6> encoder{};  ///< [counts]
  std::int16_t info{0};                   ///< 1: calibration button pressed
};
/// P2 commands.
namespace p2_command {
inline constexpr std::int16_t currents = 0;   ///< milliamps are currents
inline constexpr std::int16_t calibrate = 1;  ///< enc_a..c = attr0..2, enc_d..f = milliamps[0..2]
}  // namespace p2_command
/// P2 OUT: three currents (or d..f counter values), command, three attributes.
struct P2Out {
  std::array<std::int16_t, 3> milliamps{};  ///< [mA] (counts for enc_d..f under calibrate)
  std::int16_t command{p2_command::currents};
  std::array<std::int16_t, 3> attr{};  ///< counts for enc_a..c under calibrate
};

/// P4 error bits in the last field of a device reply (section 1, P4).
namespace p4_error {
inline constexpr std::uint32_t gimbal_i2c_1 = 1u;         ///< gimbal I2C error
inline constexpr std::uint32_t gimbal_i2c_2 = 2u;         ///< gimbal I2C error
inline constexpr std::uint32_t gimbal_i2c_4 = 4u;         ///< gimbal I2C error
inline constexpr std::uint32_t trailing_characters = 8u;  ///< characters after ']'
inline constexpr std::uint32_t buffer_full = 128u;        ///< frame longer than the firmware buffer
inline constexpr std::uint32_t close_before_open = 256u;  ///< ']' before '['
inline constexpr std::uint32_t comma_count = 512u;        ///< not exactly two commas
inline constexpr std::uint32_t parse_error = 1024u;       ///< a field is not an integer
inline constexpr std::uint32_t frame_errors =
    trailing_characters | buffer_full | close_before_open | comma_count | parse_error;
}  // namespace p4_error

/// P4 model numbers.
namespace p4_model {
inline constexpr std::int32_t polhem_2022 = 1;
inline constexpr std::int32_t vintage_phantom = 2;
inline constexpr std::int32_t woody = 3;
}  // namespace p4_model

/// P4 device reply "[model,e0,e1,e2,e3,e4,e5,err]".
struct P4Reply {
  std::int32_t model{0};
  std::array<std::int32_t, 6> encoder{};  ///< [counts]
  std::uint32_t error{0};                 ///< p4_error bits
};

namespace detail {
inline void put16(std::span<std::uint8_t> b, std::size_t at, std::int16_t v) noexcept {
  const auto u = static_cast<std::uint16_t>(v);
  b[at] = static_cast<std::uint8_t>(u & 0xFFu);
  b[at + 1] = static_cast<std::uint8_t>(u >> 8);
}
[[nodiscard]] inline std::int16_t get16(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(b[at] | (b[at + 1] << 8)));
}
/// Appends the decimal text of v at b[n]; returns the new length, 0 when it does not fit.
[[nodiscard]] inline std::size_t put_int(std::span<std::uint8_t> b, std::size_t n, long long v) noexcept {
  std::array<char, 24> text{};
  const auto r = std::to_chars(text.data(), text.data() + text.size(), v);
  const auto len = static_cast<std::size_t>(r.ptr - text.data());
  if (r.ec != std::errc{} || n + len > b.size()) return 0;
  for (std::size_t i = 0; i < len; ++i)
    b[n + i] = static_cast<std::uint8_t>(text[i]);
  return n + len;
}
/// Strict integer: optional '-', then 1..11 digits, the whole of [first, last).
[[nodiscard]] inline bool parse_int(const char* first, const char* last, long long& out) noexcept {
  if (first == last || last - first > 12 || *first == '+') return false;
  const auto r = std::from_chars(first, last, out);
  return r.ec == std::errc{} && r.ptr == last;
}
}  // namespace detail

// ------------------------------------------------------------------- P1

/// Host: the 9-byte P1 write (0x00 report id, then mA_a, mA_b, mA_c, debug).
/// Returns the size, 0 when out is too small.
[[nodiscard]] inline std::size_t encode(const P1Out& m, std::span<std::uint8_t> out) noexcept {
  if (out.size() < p1_out_size) return 0;
  out[0] = 0x00;
  for (std::size_t i = 0; i < 3; ++i)
    detail::put16(out, 1 + 2 * i, m.milliamps[i]);
  detail::put16(out, 7, m.debug);
  return p1_out_size;
}
/// Device: decodes the host's 9-byte P1 write (leading 0x00).
[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, P1Out& m) noexcept {
  if (in.size() != p1_out_size) return Status::short_report;
  if (in[0] != 0x00) return Status::unknown_report;
  for (std::size_t i = 0; i < 3; ++i)
    m.milliamps[i] = detail::get16(in, 1 + 2 * i);
  m.debug = detail::get16(in, 7);
  return Status::ok;
}
/// Device: the 8-byte P1 IN report (no report id on the wire).
[[nodiscard]] inline std::size_t encode(const P1In& r, std::span<std::uint8_t> out) noexcept {
  if (out.size() < p1_in_size) return 0;
  for (std::size_t i = 0; i < 3; ++i)
    detail::put16(out, 2 * i, r.encoder[i]);
  detail::put16(out, 6, static_cast<std::int16_t>(r.debug));
  return p1_in_size;
}
/// Host: decodes an 8-byte P1 IN report.
[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, P1In& r) noexcept {
  if (in.size() != p1_in_size) return Status::short_report;
  for (std::size_t i = 0; i < 3; ++i)
    r.encoder[i] = detail::get16(in, 2 * i);
  r.debug = static_cast<std::uint16_t>(detail::get16(in, 6));
  return Status::ok;
}

// ------------------------------------------------------------------- P2

/// Host: the 15-byte P2 write (0x00, mA_a..c, command, attr0..2).
[[nodiscard]] inline std::size_t encode(const P2Out& m, std::span<std::uint8_t> out) noexcept {
  if (out.size() < p2_out_size) return 0;
  out[0] = 0x00;
  for (std::size_t i = 0; i < 3; ++i)
    detail::put16(out, 1 + 2 * i, m.milliamps[i]);
  detail::put16(out, 7, m.command);
  for (std::size_t i = 0; i < 3; ++i)
    detail::put16(out, 9 + 2 * i, m.attr[i]);
  return p2_out_size;
}
/// Device: decodes the host's 15-byte P2 write.
[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, P2Out& m) noexcept {
  if (in.size() != p2_out_size) return Status::short_report;
  if (in[0] != 0x00) return Status::unknown_report;
  for (std::size_t i = 0; i < 3; ++i)
    m.milliamps[i] = detail::get16(in, 1 + 2 * i);
  m.command = detail::get16(in, 7);
  for (std::size_t i = 0; i < 3; ++i)
    m.attr[i] = detail::get16(in, 9 + 2 * i);
  return Status::ok;
}
/// Device: the 14-byte P2 IN report.
[[nodiscard]] inline std::size_t encode(const P2In& r, std::span<std::uint8_t> out) noexcept {
  if (out.size() < p2_in_size) return 0;
  for (std::size_t i = 0; i < 6; ++i)
    detail::put16(out, 2 * i, r.encoder[i]);
  detail::put16(out, 12, r.info);
  return p2_in_size;
}
/// Host: decodes a 14-byte P2 IN report.
[[nodiscard]] inline Status decode(std::span<const std::uint8_t> in, P2In& r) noexcept {
  if (in.size() != p2_in_size) return Status::short_report;
  for (std::size_t i = 0; i < 6; ++i)
    r.encoder[i] = detail::get16(in, 2 * i);
  r.info = detail::get16(in, 12);
  return Status::ok;
}

// ------------------------------------------------------------------- P4

/// Host: "[ma0,ma1,ma2]\n" NUL-padded to at least 16 bytes. Returns the size,
/// 0 when out is too small.
[[nodiscard]] inline std::size_t encode_p4_command(const std::array<std::int16_t, 3>& milliamps,
                                                   std::span<std::uint8_t> out) noexcept {
  if (out.size() < p4_min_command) return 0;
  std::size_t n = 0;
  out[n++] = '[';
  for (std::size_t i = 0; i < 3; ++i) {
    if (i > 0) {
      if (n >= out.size()) return 0;
      out[n++] = ',';
    }
    n = detail::put_int(out, n, milliamps[i]);
    if (n == 0) return 0;
  }
  if (n + 2 > out.size()) return 0;
  out[n++] = ']';
  out[n++] = '\n';
  while (n < p4_min_command)
    out[n++] = 0x00;
  return n;
}

/// Device: the reply line "[model,e0,...,e5,err]\n". Returns the size, 0 when out is too small.
[[nodiscard]] inline std::size_t encode(const P4Reply& r, std::span<std::uint8_t> out) noexcept {
  std::size_t n = 0;
  if (out.empty()) return 0;
  out[n++] = '[';
  std::array<long long, 8> v{r.model,      r.encoder[0], r.encoder[1], r.encoder[2],
                             r.encoder[3], r.encoder[4], r.encoder[5], static_cast<long long>(r.error)};
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i > 0) {
      if (n >= out.size()) return 0;
      out[n++] = ',';
    }
    n = detail::put_int(out, n, v[i]);
    if (n == 0) return 0;
  }
  if (n + 2 > out.size()) return 0;
  out[n++] = ']';
  out[n++] = '\n';
  return n;
}

/// Host: parses one reply line strictly: '[' then eight comma-separated
/// integers (model and err >= 0, every value within int32) then ']', and an
/// optional "\n" or "\r\n"; nothing else (no spaces, no NULs).
/// bad_value for anything else, short_report for an empty line.
[[nodiscard]] inline Status decode(std::span<const std::uint8_t> line, P4Reply& r) noexcept {
  std::size_t end = line.size();
  if (end > 0 && line[end - 1] == '\n') --end;
  if (end > 0 && line[end - 1] == '\r') --end;
  if (end == 0) return Status::short_report;
  if (end < 2 || line[0] != '[' || line[end - 1] != ']') return Status::bad_value;
  const char* p = reinterpret_cast<const char*>(line.data()) + 1;
  const char* const stop = reinterpret_cast<const char*>(line.data()) + end - 1;
  std::array<long long, 8> v{};
  for (std::size_t i = 0; i < v.size(); ++i) {
    const char* q = p;
    while (q < stop && *q != ',')
      ++q;
    if ((i + 1 < v.size()) != (q < stop)) return Status::bad_value;  // seven commas, exactly
    if (!detail::parse_int(p, q, v[i]) || v[i] < INT32_MIN || v[i] > INT32_MAX) return Status::bad_value;
    p = q + 1;
  }
  if (v[0] < 0 || v[7] < 0) return Status::bad_value;
  r.model = static_cast<std::int32_t>(v[0]);
  for (std::size_t i = 0; i < 6; ++i)
    r.encoder[i] = static_cast<std::int32_t>(v[i + 1]);
  r.error = static_cast<std::uint32_t>(v[7]);
  return Status::ok;
}

/// Device (the simulated firmware's parser, our model of the published error
/// bits): parses one PC frame, the bytes up to and without its '\n', NUL bytes
/// ignored. Returns the p4_error bits (0: milliamps holds the three values).
[[nodiscard]] inline std::uint32_t parse_p4_command(std::span<const std::uint8_t> frame,
                                                    std::array<std::int32_t, 3>& milliamps) noexcept {
  std::array<char, p4_firmware_buffer> text{};
  std::size_t n = 0;
  for (const std::uint8_t c : frame) {
    if (c == 0x00 || c == '\r') continue;
    if (n == text.size()) return p4_error::buffer_full;
    text[n++] = static_cast<char>(c);
  }
  const std::string_view s(text.data(), n);
  const std::size_t open = s.find('[');
  const std::size_t close = s.find(']');
  std::uint32_t err = 0;
  if (close != std::string_view::npos && (open == std::string_view::npos || close < open))
    return p4_error::close_before_open;
  if (open == std::string_view::npos || close == std::string_view::npos) return p4_error::parse_error;
  if (close + 1 < s.size()) err |= p4_error::trailing_characters;
  const std::string_view body = s.substr(open + 1, close - open - 1);
  std::size_t commas = 0;
  for (const char c : body)
    commas += c == ',' ? 1 : 0;
  if (commas != 2) return err | p4_error::comma_count;
  std::array<std::int32_t, 3> v{};
  std::size_t from = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const std::size_t to = i < 2 ? body.find(',', from) : body.size();
    long long x = 0;
    if (!detail::parse_int(body.data() + from, body.data() + to, x) || x < INT32_MIN || x > INT32_MAX)
      return err | p4_error::parse_error;
    v[i] = static_cast<std::int32_t>(x);
    from = to + 1;
  }
  if (err == 0) milliamps = v;
  return err;
}

}  // namespace hapticfield::woody
