#pragma once
/// @file crc16_reference.hpp
/// CRC-16/CCITT-FALSE computed bit by bit: the slow reference that the
/// protocol's table-driven crc16() is checked against (offline, tests only).

#include <cstdint>
#include <span>

namespace hapticfield::protocol {

/// Polynomial 0x1021, initial value 0xFFFF, no reflection, no final xor;
/// check value 0x29B1 for "123456789".
[[nodiscard]] constexpr std::uint16_t crc16_bitwise(std::span<const std::uint8_t> data) noexcept {
  std::uint16_t crc = 0xFFFF;
  for (const std::uint8_t byte : data) {
    crc = static_cast<std::uint16_t>(crc ^ (static_cast<std::uint16_t>(byte) << 8));
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 0x8000u) ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021u) : static_cast<std::uint16_t>(crc << 1);
  }
  return crc;
}

}  // namespace hapticfield::protocol
