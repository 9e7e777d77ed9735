#pragma once
/// @file device_family.hpp
/// DeviceFamily: one line of the device front door's table
/// (hapticfield/devices/open_device.hpp): a family's name, the syntax of its
/// device strings, how to check one, whether one is present, how to open
/// one. Each family defines its line in its own folder under arms/.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "hapticfield/device/any_device.hpp"
#include "hapticfield/device/device_error.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/simulation/scripted_hand.hpp"

namespace hapticfield {

/// A device string that names no arm this build knows, or names one badly.
/// what() names the string and what is wrong with it.
class DeviceSpecError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// What the opener needs besides the device string.
struct DeviceOptions {
  /// The clock a simulated arm lives on [ns] (the loop's clock: a
  /// VirtualClock for simulated time); empty: the steady clock.
  TimeSource now;
  /// The scripted hand holding a simulated arm's handle (ignored by real arms).
  Hand hand{};
};

/// A device string, checked: its family and the text after "family:".
struct DeviceSpec {
  std::string text;       ///< as given, e.g. "woody:p4:/dev/ttyACM0"
  std::string family;     ///< the table line's name, e.g. "woody"
  std::string args;       ///< after "family:" ("" when none)
  bool simulated{false};  ///< a simulated twin: nothing moves, may run on simulated time
};

/// Whether a family's arm is there now, and if not, why not.
struct DeviceProbe {
  bool present{false};
  std::string detail;  ///< e.g. "/dev/ttyACM0" or "no HID device 1209:0001 found"
};

/// One family of the front door's table.
struct DeviceFamily {
  std::string_view name;     ///< the string before the first ':' ("sim", "hid", "woody", ...)
  std::string_view syntax;   ///< the strings it takes, e.g. "woody:p1|p2|p4[:PRESET][:sim|:PATH]"
  std::string_view summary;  ///< one line: what arm this is
  /// Checks the text after "name:" (empty when there is none) without
  /// opening anything; true for a simulated twin.
  /// @throws DeviceSpecError naming what is wrong (the caller adds the string).
  bool (*check)(std::string_view args);
  /// Present, or why not (library not found, no device, no permission);
  /// never throws, never moves an arm.
  DeviceProbe (*probe)();
  /// Opens the arm a checked spec names.
  /// @throws DeviceError (not found, no permission, silent), std::invalid_argument.
  AnyDevice (*open)(const DeviceSpec& spec, const DeviceOptions& options);
};

}  // namespace hapticfield
