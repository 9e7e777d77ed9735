#pragma once
/// @file dhd_door.hpp
/// The Force Dimension line of the device front door
/// (hapticfield/devices/open_device.hpp): "dhd[:INDEX]", the INDEX-th
/// device the DHD SDK finds (0 the first). libdhd.so.3 (else libdhd.so) is
/// loaded when the arm is opened ($HAPTICFIELD_DHD_LIBRARY names another);
/// without the SDK the open fails with one clear error. Never run on a
/// real arm: docs/arms-dhd.md.

#include <charconv>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "hapticfield/arms/dhd/dhd_device.hpp"
#include "hapticfield/device/device_family.hpp"

namespace hapticfield::dhd_door {

struct Parts {
  std::unique_ptr<DhdDevice> arm;
  DhdDevice& device() noexcept { return *arm; }
};

/// The text after "dhd:" as an index ("" is 0).
/// @throws DeviceSpecError naming what is wrong.
inline int parse(std::string_view args) {
  if (args.empty()) return 0;
  int index = -1;
  const auto [end, error] = std::from_chars(args.data(), args.data() + args.size(), index);
  if (error != std::errc{} || end != args.data() + args.size() || index < 0 || index > 126)
    throw DeviceSpecError("dhd takes a device index 0..126 (dhd:0), got '" + std::string(args) + "'");
  return index;
}

inline bool check(std::string_view args) {
  (void)parse(args);
  return false;
}

/// Present when libdhd loads and counts at least one device (nothing is opened).
inline DeviceProbe probe() {
  try {
    const dhd::Api api = dhd::Api::load();
    const int count = api.get_device_count();
    if (count <= 0) return {false, api.library.name() + " loaded; no device found"};
    return {true, api.library.name() + ": " + std::to_string(count) + " device(s)"};
  } catch (const Error& e) {
    return {false, e.what()};
  }
}

inline AnyDevice open(const DeviceSpec& spec, const DeviceOptions& options) {
  auto parts = std::make_unique<Parts>();
  DhdConfig config;
  config.index = parse(spec.args);
  config.now = options.now;
  parts->arm = std::make_unique<DhdDevice>(std::move(config));
  return AnyDevice::holding(std::move(parts));
}

}  // namespace hapticfield::dhd_door

namespace hapticfield {
/// Force Dimension arms (and the Falcon) through the DHD SDK.
inline constexpr DeviceFamily dhd_family{
    "dhd",
    "dhd[:INDEX]",
    "a Force Dimension arm (or a Falcon) through the DHD SDK's libdhd.so.3, loaded at run time (never run on a "
    "real one)",
    dhd_door::check,
    dhd_door::probe,
    dhd_door::open};
}  // namespace hapticfield
