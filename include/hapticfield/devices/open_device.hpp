#pragma once
/// @file open_device.hpp
/// The device front door: open_device("sim" | "hid[:VID:PID]" |
/// "serial:PATH" | "woody:GEN[:PRESET][:sim|:PATH]" | "inverse3:PATH|sim" |
/// "falcon[:INDEX[:FIRMWARE]]|falcon:sim")
/// returns an AnyDevice; list_devices() says, one line a family, which
/// arms are present and why the others are not. Every tool and the Python
/// module open their arms here.
///
/// A new family is its folder under arms/ (with a DeviceFamily line of its
/// own, see device/device_family.hpp) and one line in device_families below.

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "hapticfield/arms/dhd/dhd_door.hpp"
#include "hapticfield/arms/falcon/falcon_door.hpp"
#include "hapticfield/arms/force_arm/force_arm_door.hpp"
#include "hapticfield/arms/inverse3/inverse3_door.hpp"
#include "hapticfield/arms/openhaptics/openhaptics_door.hpp"
#include "hapticfield/arms/woody/woody_door.hpp"
#include "hapticfield/device/any_device.hpp"
#include "hapticfield/device/device_family.hpp"

namespace hapticfield {

/// Every family the front door opens, one line each.
inline constexpr std::array device_families{
    sim_family,          //
    hid_family,          //
    serial_family,       //
    woody_family,        //
    inverse3_family,     //
    openhaptics_family,  //
    dhd_family,          //
    falcon_family,       //
};

/// Families whose support is not in this version: their names give a clear
/// error instead of "unknown". A family that gets its line leaves this list.
inline constexpr std::array<std::string_view, 0> planned_device_families{};

/// The syntax of every family, "sim, hid[:VID:PID], ...", for messages and --help.
[[nodiscard]] inline std::string device_syntaxes() {
  std::string all;
  for (const DeviceFamily& f : device_families) {
    if (!all.empty()) all += ", ";
    all += f.syntax;
  }
  return all;
}

/// The family line of a name, or nullptr.
[[nodiscard]] inline const DeviceFamily* find_device_family(std::string_view name) noexcept {
  for (const DeviceFamily& f : device_families)
    if (f.name == name) return &f;
  return nullptr;
}

/// Checks a device string without opening anything.
/// @throws DeviceSpecError: "device 'TEXT': what is wrong".
[[nodiscard]] inline DeviceSpec parse_device_spec(std::string_view text) {
  const std::size_t colon = text.find(':');
  DeviceSpec spec;
  spec.text = std::string(text);
  spec.family = std::string(text.substr(0, colon));
  spec.args = colon == std::string_view::npos ? std::string() : std::string(text.substr(colon + 1));
  const std::string named = "device '" + spec.text + "': ";
  const DeviceFamily* family = find_device_family(spec.family);
  if (!family) {
    for (const std::string_view planned : planned_device_families)
      if (spec.family == planned)
        throw DeviceSpecError(named + spec.family + " is not built in this version (this build opens " +
                              device_syntaxes() + ")");
    throw DeviceSpecError(named + "unknown device (choose " + device_syntaxes() + ")");
  }
  if (colon != std::string_view::npos && spec.args.empty())
    throw DeviceSpecError(named + "nothing after '" + spec.family + ":' (" + std::string(family->syntax) + ")");
  try {
    spec.simulated = family->check(spec.args);
  } catch (const DeviceSpecError& e) {
    throw DeviceSpecError(named + e.what());
  }
  return spec;
}

/// Opens the arm a device string names.
/// @throws DeviceSpecError for a bad string; DeviceError (naming the device
///         and the cause) when the arm is not there, may not be opened, or
///         stays silent.
[[nodiscard]] inline AnyDevice open_device(const DeviceSpec& spec, const DeviceOptions& options = {}) {
  const DeviceFamily* family = find_device_family(spec.family);
  if (!family) return open_device(parse_device_spec(spec.text), options);
  return family->open(spec, options);
}
[[nodiscard]] inline AnyDevice open_device(std::string_view text, const DeviceOptions& options = {}) {
  return open_device(parse_device_spec(text), options);
}

/// One family's presence: "NAME (SYNTAX): present: DETAIL" or
/// "NAME (SYNTAX): not present: WHY".
struct DeviceListing {
  std::string family;
  bool present{false};
  std::string line;
};

/// Every family, present or why not, one line each (planned ones say they
/// are not built in this version). Probes only: nothing moves.
[[nodiscard]] inline std::vector<DeviceListing> list_devices() {
  std::vector<DeviceListing> out;
  for (const DeviceFamily& f : device_families) {
    const DeviceProbe p = f.probe();
    out.push_back({std::string(f.name), p.present,
                   std::string(f.syntax) + ": " + (p.present ? "present: " : "not present: ") + p.detail});
  }
  for (const std::string_view planned : planned_device_families)
    out.push_back({std::string(planned), false, std::string(planned) + ": not built in this version"});
  return out;
}

}  // namespace hapticfield
