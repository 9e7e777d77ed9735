#pragma once
/// @file hid_device.hpp
/// The tools' "--device hid[:VID:PID]": a HID arm named by its USB ids.

#include <charconv>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "hapticfield/protocol/reports.hpp"

namespace hapticfield::cli {

/// USB vendor and product ids.
struct HidIds {
  std::uint16_t vendor{default_vendor_id};
  std::uint16_t product{default_product_id};
};

/// "hid" (the protocol's default ids) or "hid:VID:PID" with 1 to 4
/// hexadecimal digits per id; nothing for any other text.
[[nodiscard]] inline std::optional<HidIds> hid_device(std::string_view device) {
  if (device == "hid") return HidIds{};
  if (!device.starts_with("hid:")) return std::nullopt;
  const std::string_view ids = device.substr(4);
  const std::size_t colon = ids.find(':');
  if (colon == std::string_view::npos) return std::nullopt;
  const auto hex = [](std::string_view t, std::uint16_t& out) {
    if (t.empty() || t.size() > 4) return false;
    const auto [end, error] = std::from_chars(t.data(), t.data() + t.size(), out, 16);
    return error == std::errc{} && end == t.data() + t.size();
  };
  HidIds result;
  if (!hex(ids.substr(0, colon), result.vendor) || !hex(ids.substr(colon + 1), result.product)) return std::nullopt;
  return result;
}

}  // namespace hapticfield::cli
