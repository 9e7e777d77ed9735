#pragma once
/// @file openhaptics_door.hpp
/// The OpenHaptics line of the device front door
/// (hapticfield/devices/open_device.hpp): "openhaptics[:NAME]", the HD
/// device NAME as configured with Touch_Setup (none: HD_DEFAULT_DEVICE).
/// libHD.so is loaded when the arm is opened ($HAPTICFIELD_HD_LIBRARY names
/// another); without OpenHaptics the open fails with one clear error.
/// Never run on a real arm: docs/arms-openhaptics.md.

#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "hapticfield/arms/openhaptics/openhaptics_device.hpp"
#include "hapticfield/device/device_family.hpp"

namespace hapticfield::openhaptics_door {

struct Parts {
  std::unique_ptr<OpenHapticsDevice> arm;
  OpenHapticsDevice& device() noexcept { return *arm; }
};

/// Any NAME is HD's to judge; only an empty one after the ':' is refused
/// (by the front door).
inline bool check(std::string_view) {
  return false;
}

/// Present when libHD loads (the device itself is not opened).
inline DeviceProbe probe() {
  try {
    const hd::Api api = hd::Api::load();
    return {true, api.library.name() + " loaded (the device is not opened until used)"};
  } catch (const Error& e) {
    return {false, e.what()};
  }
}

inline AnyDevice open(const DeviceSpec& spec, const DeviceOptions&) {
  auto parts = std::make_unique<Parts>();
  OpenHapticsConfig config;
  config.device_name = spec.args;
  parts->arm = std::make_unique<OpenHapticsDevice>(std::move(config));
  return AnyDevice::holding(std::move(parts));
}

}  // namespace hapticfield::openhaptics_door

namespace hapticfield {
/// 3D Systems Touch / Phantom arms through OpenHaptics.
inline constexpr DeviceFamily openhaptics_family{
    "openhaptics",
    "openhaptics[:NAME]",
    "a 3D Systems Touch or Phantom through OpenHaptics' libHD.so, loaded at run time (never run on a real one)",
    openhaptics_door::check,
    openhaptics_door::probe,
    openhaptics_door::open};
}  // namespace hapticfield
