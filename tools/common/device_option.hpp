#pragma once
/// @file device_option.hpp
/// The tools' "--device D" and "--list-devices", through the device front
/// door (hapticfield/devices/open_device.hpp), and the link counters of
/// whichever arm was opened.

#include <cstdio>
#include <string>

#include "cli.hpp"
#include "hapticfield/devices/open_device.hpp"

namespace hapticfield::cli {

/// The usage lines of --device and --list-devices (26 columns of option).
inline constexpr const char* device_help =
    "  --device D            sim (default), hid, hid:VID:PID (hexadecimal ids) or serial:PATH (a\n"
    "                        tty such as /dev/ttyACM0): our protocol; woody:GEN[:PRESET][:sim|:PATH]:\n"
    "                        a WoodenHaptics arm, GEN p1 or p2 (USB HID) or p4 (serial text, on the\n"
    "                        tty PATH), PRESET woody_v2015 (default), woodenhaptics_v2019,\n"
    "                        aluhaptics_v2 or vintage; :sim simulates it; inverse3:PATH: a Haply\n"
    "                        Inverse3 on the tty PATH (never run on a real one: check its frame),\n"
    "                        inverse3:sim its simulated twin\n"
    "  --list-devices        one line per arm family: present, or why not; then exit\n";

/// A --device value checked by the front door; a bad one is a usage error
/// ("--device: device 'X': what is wrong").
[[nodiscard]] inline DeviceSpec device_option(const std::string& value) {
  try {
    return parse_device_spec(value);
  } catch (const DeviceSpecError& e) {
    throw UsageError(std::string("--device: ") + e.what());
  }
}

/// --list-devices: one line per family on stdout; exit status 0.
inline int print_device_list() {
  for (const DeviceListing& listing : list_devices())
    std::printf("%s\n", listing.line.c_str());
  std::fflush(stdout);
  return exit_ok;
}

/// The link counters of the arm, whichever protocol it speaks.
inline void print_link(const AnyDevice& device) {
  const auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  if (const ForceArm* arm = device.target<ForceArm>()) {
    const LinkCounters& c = arm->counters();
    std::printf("link: %llu reports, %llu dropped, %llu corrupt, %llu resyncs, %llu commands\n", u(c.reports),
                u(c.dropped), u(c.corrupt), u(c.resyncs), u(c.commands));
  } else if (const Inverse3* inverse3 = device.target<Inverse3>()) {
    const Inverse3Counters& c = inverse3->counters();
    std::printf("link: %llu replies, %llu implausible, %llu resyncs, %llu bytes dropped, %llu lost, %llu commands\n",
                u(c.replies), u(c.implausible), u(c.resyncs), u(c.dropped_bytes), u(c.lost_replies), u(c.commands));
  } else if (const WoodyArm* woody = device.target<WoodyArm>()) {
    const WoodyCounters& c = woody->counters();
    std::printf("link: %llu replies, %llu with firmware error bits, %llu malformed, %llu commands\n", u(c.reports),
                u(c.error_replies), u(c.malformed), u(c.commands));
  }
}

}  // namespace hapticfield::cli
